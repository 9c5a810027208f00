//! The committed header `include/tvist.h` agrees with the library: status bits (read from
//! the core's `Status`), error codes, limits, and the set of exported functions.

use std::collections::BTreeMap;
use tvist::{
    ERROR_CODES, TVIST_INTERP_CUBIC, TVIST_INTERP_LINEAR, TVIST_MAX_DELAY_LINE_BYTES,
    TVIST_MAX_DOF, TVIST_MAX_MODES,
};
use tvist_core::Status;

const HEADER: &str = include_str!("../../../include/tvist.h");
const SOURCES: [&str; 2] = [
    include_str!("../src/shaper.rs"),
    include_str!("../src/codes.rs"),
];

/// `#define NAME VALUE` lines of the header whose name starts with `prefix`.
fn defines(prefix: &str) -> BTreeMap<String, i64> {
    HEADER
        .lines()
        .filter_map(|line| {
            let mut words = line.split_whitespace();
            match (words.next(), words.next(), words.next()) {
                (Some("#define"), Some(name), Some(value)) if name.starts_with(prefix) => {
                    Some((name.to_owned(), value.parse().expect("integer #define")))
                }
                _ => None,
            }
        })
        .collect()
}

/// `NAME = VALUE` entries of the `TvistError` enum.
fn enum_entries() -> BTreeMap<String, i64> {
    let start = HEADER
        .find("typedef enum TvistError {")
        .expect("TvistError enum");
    let end = start + HEADER[start..].find('}').expect("end of enum");
    HEADER[start..end]
        .lines()
        .filter(|line| line.trim_start().starts_with("TVIST_"))
        .filter_map(|line| {
            let (name, value) = line.split_once('=')?;
            let value = value.trim().trim_end_matches(',');
            Some((name.trim().to_owned(), value.parse().expect("integer")))
        })
        .collect()
}

/// Names of the `tvist_*` functions declared in the header (`name(` after a return type).
fn declared_functions() -> Vec<String> {
    let mut names: Vec<String> = HEADER
        .lines()
        .filter(|line| !line.trim_start().starts_with('*') && !line.starts_with("/*"))
        .filter_map(|line| {
            let open = line.find("tvist_")?;
            let rest = &line[open..];
            let paren = rest.find('(')?;
            let name = &rest[..paren];
            name.chars()
                .all(|c| c.is_ascii_alphanumeric() || c == '_')
                .then(|| name.to_owned())
        })
        .collect();
    names.sort();
    names
}

/// Names of the `extern "C"` functions of the crate's sources.
fn exported_functions() -> Vec<String> {
    let marker = "pub unsafe extern \"C\" fn ";
    let mut names: Vec<String> = SOURCES
        .iter()
        .flat_map(|src| {
            src.match_indices(marker)
                .map(move |(i, _)| &src[i + marker.len()..])
        })
        .map(|rest| rest[..rest.find('(').expect("argument list")].to_owned())
        .collect();
    names.sort();
    names
}

#[test]
fn status_defines_equal_the_core_status_flags() {
    // The core's flag list is the one definition: every flag has its define and nothing else.
    let header = defines("TVIST_STATUS_");
    let expected: BTreeMap<String, i64> = Status::FLAGS
        .iter()
        .map(|(name, status)| (format!("TVIST_STATUS_{name}"), i64::from(status.0)))
        .collect();
    assert_eq!(header, expected);
    assert_eq!(
        defines("TVIST_N_STATUS_FLAGS").get("TVIST_N_STATUS_FLAGS"),
        Some(&(Status::FLAGS.len() as i64))
    );
}

#[test]
fn interpolation_defines_equal_the_library() {
    let header = defines("TVIST_INTERP_");
    let expected: BTreeMap<String, i64> = [
        (
            "TVIST_INTERP_LINEAR".to_string(),
            i64::from(TVIST_INTERP_LINEAR),
        ),
        (
            "TVIST_INTERP_CUBIC".to_string(),
            i64::from(TVIST_INTERP_CUBIC),
        ),
    ]
    .into_iter()
    .collect();
    assert_eq!(header, expected);
}

#[test]
fn error_enum_equals_the_library_codes() {
    let expected: BTreeMap<String, i64> = ERROR_CODES
        .iter()
        .map(|&(name, code)| (name.to_owned(), i64::from(code)))
        .collect();
    assert_eq!(enum_entries(), expected);
}

#[test]
fn limits_equal_the_library_limits() {
    let limits = defines("TVIST_MAX_");
    assert_eq!(limits.get("TVIST_MAX_DOF"), Some(&(TVIST_MAX_DOF as i64)));
    assert_eq!(
        limits.get("TVIST_MAX_MODES"),
        Some(&(TVIST_MAX_MODES as i64))
    );
    assert_eq!(
        limits.get("TVIST_MAX_DELAY_LINE_BYTES"),
        Some(&(TVIST_MAX_DELAY_LINE_BYTES as i64))
    );
    assert_eq!(limits.len(), 3);
}

#[test]
fn every_exported_function_is_declared_and_nothing_else() {
    let exported = exported_functions();
    assert!(exported.len() >= 8, "{exported:?}");
    assert_eq!(declared_functions(), exported);
}

#[test]
fn unknown_robot_comment_lists_every_robot_the_library_accepts() {
    // The comment block just above `TVIST_ERR_UNKNOWN_ROBOT = ` names the accepted robots in
    // double quotes; it must name each robot of the robot data, and nothing else.
    let entry = HEADER
        .find("TVIST_ERR_UNKNOWN_ROBOT =")
        .expect("TVIST_ERR_UNKNOWN_ROBOT");
    let comment_start = HEADER[..entry]
        .rfind("/*")
        .expect("comment above the entry");
    let listed: std::collections::BTreeSet<&str> = HEADER[comment_start..entry]
        .split('"')
        .skip(1)
        .step_by(2)
        .collect();
    let known: std::collections::BTreeSet<&str> =
        tvist_core::files::robot_data::ur_e_series_entries()
            .expect("robot data")
            .iter()
            .map(|e| e.name.as_str())
            .collect();
    assert_eq!(listed, known);
}
