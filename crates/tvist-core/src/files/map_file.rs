//! The map file (feature `json`): parsing, validation and writing of dynamic maps, for every
//! binding (Rust, Python, C).
//!
//! ```text
//! {"schema_version": 1,
//!  "kind": "paper10",
//!  "metadata": {"robot": "ur5e" | null, "payload": {...} | null, "source": "..." | null,
//!               "fit_statistics": {...} | null, ...other keys kept as given},
//!  "modes": [{"k_0": ..., "k_j": ..., "k_g": ..., "k_p": ..., "c_0": ..., "c_1": ...,
//!             "c_2": ..., "c_tau": ..., "frequency_joint": 1, "damping_joint": 0,
//!             "damping_gain_exponent": 1.0, "frequency_gain_exponent": -0.5,
//!             "frequency_inertia_range_kg_m2": [0.7, 9.1] | null,     (optional)
//!             "damping_inertia_range_kg_m2": [0.2, 9.3] | null}, ...]} (optional)
//!
//! {"schema_version": 1,
//!  "kind": "modal",
//!  "metadata": {...as above...},
//!  "mode_joints": [0, 1]   |   "shaped_modes": 3,
//!  "flex_joints": [{"joint": 0, "stiffness_nm_per_rad": [k_0, k_1, k_2],
//!                   "damping_nms_per_rad": [c_0, c_1, c_2], "damping_load_joint": 1}, ...],
//!  "link_hinges": [{"link": 1, "at_fraction": 0.5, "stiffness_nm_per_rad": k_h,
//!                   "damping_nms_per_rad": c_h}, ...]}                        (optional)
//! ```
//!
//! - `schema_version` is the integer 1 (not `1.0`, not `true`).
//! - `kind` names the form of the map. `"paper10"`: the ten-coefficient physical map of
//!   [`crate::modes::paper10::dynamic_map`] ([`MapForm::Paper10`]); `"modal"`: the modal map of
//!   [`crate::modes::modal::modal_map`] ([`MapForm::Modal`]: load laws `[at_zero, per_nm, per_nm2]` of
//!   every flexible joint, and which modes are shaped: exactly one of `mode_joints`, the
//!   joints naming the shaped modes in cascade order, or `shaped_modes`, the number of
//!   lowest-frequency modes shaped, 1 to the number of flexible coordinates). The optional
//!   `link_hinges` makes links bend ([`crate::modes::modal::modal_map::LinkHinge`]: a hinge pair about the
//!   two axes perpendicular to link `link` at `at_fraction` of its length, stiffness and
//!   damping per axis); the flexible coordinates are then the joints plus two per hinge, at
//!   most [`crate::modes::modal::modal_map::MAX_FLEX_JOINTS`]. Without it (every file written before it
//!   existed) the links are rigid. Files
//!   written before `kind` named the form carry
//!   `"tvist.dynamic_map"` or no `kind`; both are read as `"paper10"` (and written back as it).
//!   Each form's fields are read and written by its own module ([`super::paper10_doc`],
//!   [`super::modal_doc`]); another form is one more [`MapForm`] variant, one more arm in
//!   `MapForm::parse` and `MapForm::to_value`, and its module; the file layout around it
//!   stays.
//! - `metadata.robot` names the robot the map was identified on; a map is refused for
//!   another robot ([`crate::MapDynamics::new`], [`crate::ModalDynamics::new`]). `metadata.payload` is `{"mass_kg",
//!   "com_m", "inertia_kg_m2"}` (inertia `null` for a point mass).
//! - Strict JSON: no `NaN` or `Infinity` tokens are read or written. `null` means "none" for a
//!   range (unbounded) and "not available" for metadata; a statistic that could not be
//!   computed (NaN) is written as `null`. Numbers that overflow a double, documents nested
//!   deeper than 128 levels and an object with a repeated key are refused with an error naming
//!   the problem (the key). A leading UTF-8 byte-order mark is accepted.
//! - A `paper10` map has at most [`crate::limits::MAX_MODES`] modes, each physical at every
//!   inertia it reads ([`crate::modes::paper10::dynamic_map::ModeMap::check_physical`]: the rules of every
//!   [`DynamicMap`]); a `modal` map's laws follow the signs of [`ModalMap::new`].
//! - A file is at most [`crate::limits::MAX_MAP_FILE_BYTES`] (1 MiB) long; a longer one, or a
//!   device such as `/dev/zero`, is refused without being read whole.
//!
//! Every error is an [`Error::Document`] whose path names the field (`modes[1].k_0`,
//! `metadata.payload.com_m`, `schema_version`) and whose reason says what is wrong.

use crate::error::Error;
use crate::files::modal_doc::{flex_to_value, hinge_to_value, modal_from};
use crate::files::paper10_doc::{mode_to_value, paper10_from};
use crate::files::strict_json::{float, number, read_limited, UniqueKeys};
use crate::modes::modal::modal_map::{ModalMap, ShapedModes};
use crate::modes::paper10::dynamic_map::DynamicMap;
use serde_json::{Map, Value};
use std::path::Path;

/// The `schema_version` of the files this module reads and writes.
pub const SCHEMA_VERSION: u64 = 1;

/// `kind` of the ten-coefficient physical map ([`MapForm::Paper10`]).
pub const KIND_PAPER10: &str = "paper10";

/// `kind` of the modal map ([`MapForm::Modal`]).
pub const KIND_MODAL: &str = "modal";

/// `kind` of files written before `kind` named the map form; read as [`KIND_PAPER10`].
pub const LEGACY_KIND: &str = "tvist.dynamic_map";

/// Metadata fields every map has (`null` when not available), in the order they are written.
pub const METADATA_FIELDS: [&str; 4] = ["robot", "payload", "source", "fit_statistics"];

/// Fields of every map document; each form adds its own ([`MapForm::fields`]).
const COMMON_FIELDS: [&str; 3] = ["schema_version", "kind", "metadata"];

/// The form of a map: how its modes follow from the robot's state.
#[derive(Debug, Clone, PartialEq)]
pub enum MapForm {
    /// The ten-coefficient physical map from joint inertias (paper eqs. 42–51).
    Paper10(DynamicMap),
    /// Modes from the mass matrix and the flexible joints' load laws ([`crate::modes::modal::modal_map`]).
    Modal(ModalMap),
}

impl MapForm {
    /// The `kind` written for this form.
    pub fn kind(&self) -> &'static str {
        match self {
            MapForm::Paper10(_) => KIND_PAPER10,
            MapForm::Modal(_) => KIND_MODAL,
        }
    }

    /// The document fields of form `kind` besides [`COMMON_FIELDS`] (`None`: unknown kind).
    fn fields(kind: &str) -> Option<&'static [&'static str]> {
        match kind {
            KIND_PAPER10 | LEGACY_KIND => Some(&["modes"]),
            KIND_MODAL => Some(&["mode_joints", "shaped_modes", "flex_joints", "link_hinges"]),
            _ => None,
        }
    }

    /// The paper10 map, if this is one.
    pub fn as_paper10(&self) -> Option<&DynamicMap> {
        match self {
            MapForm::Paper10(map) => Some(map),
            MapForm::Modal(_) => None,
        }
    }

    /// The modal map, if this is one.
    pub fn as_modal(&self) -> Option<&ModalMap> {
        match self {
            MapForm::Modal(map) => Some(map),
            MapForm::Paper10(_) => None,
        }
    }

    /// The robot the map was identified on, if known.
    pub fn robot(&self) -> Option<&str> {
        match self {
            MapForm::Paper10(map) => map.robot(),
            MapForm::Modal(map) => map.robot(),
        }
    }

    /// The form named `kind`, built from the document's `modes`.
    fn parse(kind: &str, doc: &Map<String, Value>) -> Result<MapForm, Error> {
        match kind {
            KIND_PAPER10 | LEGACY_KIND => Ok(MapForm::Paper10(paper10_from(doc)?)),
            KIND_MODAL => Ok(MapForm::Modal(modal_from(doc)?)),
            other => Err(Error::document(
                "kind",
                format!(
                    "unknown map kind {other:?}; this version reads {KIND_PAPER10:?} and \
                     {KIND_MODAL:?}"
                ),
            )),
        }
    }

    /// The form's own fields of the document (`modes`).
    fn to_value(&self) -> Vec<(&'static str, Value)> {
        match self {
            MapForm::Paper10(map) => vec![(
                "modes",
                Value::Array(map.mode_maps().iter().map(mode_to_value).collect()),
            )],
            MapForm::Modal(map) => vec![
                match map.shaped_modes() {
                    ShapedModes::ByJoint(joints) => ("mode_joints", Value::from(joints.clone())),
                    ShapedModes::Lowest(k) => ("shaped_modes", Value::from(*k)),
                },
                (
                    "flex_joints",
                    Value::Array(map.flex_joints().iter().map(flex_to_value).collect()),
                ),
            ]
            .into_iter()
            .chain((!map.link_hinges().is_empty()).then(|| {
                (
                    "link_hinges",
                    Value::Array(map.link_hinges().iter().map(hinge_to_value).collect()),
                )
            }))
            .collect(),
        }
    }

    fn set_robot(self, robot: Option<&str>) -> MapForm {
        match (self, robot) {
            (MapForm::Paper10(map), Some(name)) => MapForm::Paper10(map.for_robot(name)),
            (MapForm::Modal(map), Some(name)) => MapForm::Modal(map.for_robot(name)),
            (form, _) => form,
        }
    }
}

/// A validated map file: the map and its metadata.
#[derive(Debug, Clone, PartialEq)]
pub struct MapFile {
    form: MapForm,
    metadata: Map<String, Value>,
}

impl MapFile {
    /// A map with `metadata` (`null` or an object; checked as in a file). The map is marked
    /// as identified on `metadata.robot`.
    pub fn new(form: MapForm, metadata: &Value) -> Result<MapFile, Error> {
        let metadata = checked_metadata(metadata)?;
        let form = form.set_robot(metadata.get("robot").and_then(Value::as_str));
        Ok(MapFile { form, metadata })
    }

    /// Parses and validates a map document (strict JSON text, optionally after a UTF-8
    /// byte-order mark).
    pub fn parse(text: &str) -> Result<MapFile, Error> {
        let text = text.strip_prefix('\u{feff}').unwrap_or(text);
        let UniqueKeys(doc) = serde_json::from_str(text)
            .map_err(|e| Error::document("(document)", format!("not valid JSON: {e}")))?;
        Self::from_value(&doc)
    }

    /// Reads and validates the map file at `path`; errors start with the path. A file longer
    /// than [`crate::limits::MAX_MAP_FILE_BYTES`] is refused after reading at most that many
    /// bytes.
    pub fn load(path: &Path) -> Result<MapFile, Error> {
        let in_file = |path_in_doc: &str| format!("{}: {path_in_doc}", path.display());
        let text = read_limited(path)
            .map_err(|reason| Error::document(path.display().to_string(), reason))?;
        Self::parse(&text).map_err(|e| match e {
            Error::Document { path, reason } => Error::Document {
                path: in_file(&path),
                reason,
            },
            other => other,
        })
    }

    /// Validates a parsed document.
    pub fn from_value(doc: &Value) -> Result<MapFile, Error> {
        let doc = doc
            .as_object()
            .ok_or_else(|| Error::document("(document)", "top level must be a JSON object"))?;
        match doc.get("schema_version") {
            Some(Value::Number(n)) if n.as_u64() == Some(SCHEMA_VERSION) => {}
            Some(other) => {
                return Err(Error::document(
                    "schema_version",
                    format!("must be the integer {SCHEMA_VERSION}, got {other}"),
                ))
            }
            None => return Err(Error::document("schema_version", "missing")),
        }
        let kind = match doc.get("kind") {
            None | Some(Value::Null) => LEGACY_KIND,
            Some(Value::String(kind)) => kind.as_str(),
            Some(other) => {
                return Err(Error::document(
                    "kind",
                    format!("must be a string, got {other}"),
                ))
            }
        };
        // An unknown kind is reported by `MapForm::parse`; its fields are not judged.
        let form_fields = MapForm::fields(kind).unwrap_or(&[]);
        let unknown: Vec<&str> = doc
            .keys()
            .map(String::as_str)
            .filter(|k| !COMMON_FIELDS.contains(k) && !form_fields.contains(k))
            .collect();
        if !unknown.is_empty() && MapForm::fields(kind).is_some() {
            return Err(Error::document(
                "(document)",
                format!("unknown field(s) {}", unknown.join(", ")),
            ));
        }
        let form = MapForm::parse(kind, doc)?;
        Self::new(form, doc.get("metadata").unwrap_or(&Value::Null))
    }

    /// The document: `schema_version`, `kind`, `metadata`, then the form's fields.
    pub fn to_value(&self) -> Value {
        let mut doc = Map::new();
        doc.insert("schema_version".into(), Value::from(SCHEMA_VERSION));
        doc.insert("kind".into(), Value::from(self.form.kind()));
        doc.insert("metadata".into(), Value::Object(self.metadata.clone()));
        for (key, value) in self.form.to_value() {
            doc.insert(key.into(), value);
        }
        Value::Object(doc)
    }

    /// The document as strict JSON text, indented, with a final newline.
    pub fn to_json(&self) -> String {
        // A `Value` holds no NaN or infinity, so the text is strict JSON; serializing a
        // `Value` to a `String` cannot fail.
        let mut text = serde_json::to_string_pretty(&self.to_value()).unwrap_or_default();
        text.push('\n');
        text
    }

    /// Writes [`Self::to_json`] to `path`.
    pub fn save(&self, path: &Path) -> Result<(), Error> {
        std::fs::write(path, self.to_json())
            .map_err(|e| Error::document(path.display().to_string(), format!("cannot write: {e}")))
    }

    pub fn form(&self) -> &MapForm {
        &self.form
    }

    pub fn into_form(self) -> MapForm {
        self.form
    }

    /// The `kind` of the map's form.
    pub fn kind(&self) -> &'static str {
        self.form.kind()
    }

    /// The robot the map was identified on (`metadata.robot`), if named.
    pub fn robot(&self) -> Option<&str> {
        self.metadata.get("robot").and_then(Value::as_str)
    }

    /// The checked metadata: [`METADATA_FIELDS`] first (`null` when not given), then any
    /// other keys as given.
    pub fn metadata(&self) -> &Map<String, Value> {
        &self.metadata
    }
}

/// `metadata` checked and normalized: [`METADATA_FIELDS`] first, then the other keys.
fn checked_metadata(metadata: &Value) -> Result<Map<String, Value>, Error> {
    let given = match metadata {
        Value::Null => Map::new(),
        Value::Object(m) => m.clone(),
        other => {
            return Err(Error::document(
                "metadata",
                format!("must be an object or null, got {other}"),
            ))
        }
    };
    let mut out = Map::new();
    for key in METADATA_FIELDS {
        out.insert(key.into(), given.get(key).cloned().unwrap_or(Value::Null));
    }
    for (key, value) in &given {
        if !METADATA_FIELDS.contains(&key.as_str()) {
            out.insert(key.clone(), value.clone());
        }
    }
    for key in ["robot", "source"] {
        match &out[key] {
            Value::Null => {}
            Value::String(s) if !s.is_empty() || key == "source" => {}
            other => {
                return Err(Error::document(
                    format!("metadata.{key}"),
                    format!("must be a non-empty string or null, got {other}"),
                ))
            }
        }
    }
    if !matches!(out["fit_statistics"], Value::Null | Value::Object(_)) {
        return Err(Error::document(
            "metadata.fit_statistics",
            "must be an object or null",
        ));
    }
    let payload = checked_payload(&out["payload"])?;
    out.insert("payload".into(), payload);
    Ok(out)
}

/// A payload `{"mass_kg", "com_m", "inertia_kg_m2"}` (defaults 0, `[0, 0, 0]`, `null`).
fn checked_payload(payload: &Value) -> Result<Value, Error> {
    let path = "metadata.payload";
    let given = match payload {
        Value::Null => return Ok(Value::Null),
        Value::Object(m) => m,
        other => {
            return Err(Error::document(
                path,
                format!("must be an object or null, got {other}"),
            ))
        }
    };
    let fields = ["mass_kg", "com_m", "inertia_kg_m2"];
    if let Some(key) = given.keys().find(|k| !fields.contains(&k.as_str())) {
        return Err(Error::document(path, format!("unknown field {key}")));
    }
    let mass = match given.get("mass_kg") {
        None => 0.0,
        v => number(v, &format!("{path}.mass_kg"))?,
    };
    if mass < 0.0 {
        return Err(Error::document(
            format!("{path}.mass_kg"),
            format!("must be >= 0, got {mass}"),
        ));
    }
    let list = |key: &str, len: usize| -> Result<Option<Vec<f64>>, Error> {
        let p = format!("{path}.{key}");
        match given.get(key) {
            None | Some(Value::Null) => Ok(None),
            Some(Value::Array(v)) if v.len() == len => v
                .iter()
                .enumerate()
                .map(|(i, x)| number(Some(x), &format!("{p}[{i}]")))
                .collect::<Result<Vec<_>, _>>()
                .map(Some),
            Some(other) => Err(Error::document(
                p,
                format!("must be a list of {len} numbers, got {other}"),
            )),
        }
    };
    let com = list("com_m", 3)?.unwrap_or_else(|| vec![0.0; 3]);
    let inertia = list("inertia_kg_m2", 6)?;
    let to_list = |v: Vec<f64>| Value::Array(v.into_iter().map(float).collect());
    let mut out = Map::new();
    out.insert("mass_kg".into(), float(mass));
    out.insert("com_m".into(), to_list(com));
    out.insert("inertia_kg_m2".into(), inertia.map_or(Value::Null, to_list));
    Ok(Value::Object(out))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::modes::paper10::dynamic_map::{MapCoefficients, ModeMap};

    fn paper_file() -> MapFile {
        let meta = serde_json::json!({"robot": "ur5e", "source": "paper"});
        MapFile::new(MapForm::Paper10(DynamicMap::paper_ur5e()), &meta).expect("valid")
    }

    fn reason_of(text: &str) -> String {
        match MapFile::parse(text) {
            Ok(_) => "accepted".into(),
            Err(e) => e.to_string(),
        }
    }

    #[test]
    fn a_written_map_reads_back_identically() {
        let file = paper_file();
        let text = file.to_json();
        let back = MapFile::parse(&text).expect("round trip");
        assert_eq!(back, file);
        assert_eq!(back.kind(), KIND_PAPER10);
        assert_eq!(back.robot(), Some("ur5e"));
        let map = back.form().as_paper10().expect("paper10");
        assert_eq!(map.robot(), Some("ur5e"));
        assert_eq!(map.mode_maps(), DynamicMap::paper_ur5e().mode_maps());
    }

    #[test]
    fn files_of_the_legacy_kind_or_without_kind_read_as_paper10() {
        let text = paper_file().to_json();
        for replacement in [r#""kind": "tvist.dynamic_map","#, ""] {
            let old = text.replace(r#""kind": "paper10","#, replacement);
            assert_ne!(old, text);
            let file = MapFile::parse(&old).expect("legacy file");
            assert_eq!(file.kind(), KIND_PAPER10);
        }
    }

    #[test]
    fn errors_name_the_field_and_the_reason() {
        let text = paper_file().to_json();
        let cases = [
            (
                text.replace(r#""schema_version": 1"#, r#""schema_version": 1.0"#),
                "schema_version: must be the integer 1",
            ),
            (
                text.replace(r#""schema_version": 1"#, r#""schema_version": true"#),
                "schema_version: must be the integer 1",
            ),
            (
                text.replace(r#""kind": "paper10""#, r#""kind": "modal9""#),
                "kind: unknown map kind \"modal9\"",
            ),
            (
                text.replacen(r#""k_0": 10000.0"#, r#""k_0": "x""#, 1),
                "modes[0].k_0: must be a number",
            ),
            (
                text.replacen(
                    r#""damping_gain_exponent": 1.0"#,
                    r#""damping_gain_exponent": -1000000.0"#,
                    1,
                ),
                "modes[0].damping_gain_exponent: -1000000 is outside",
            ),
            (
                text.replacen(r#""frequency_joint": 1"#, r#""frequency_joint": 1.5"#, 1),
                "modes[0].frequency_joint: must be a joint index",
            ),
            (
                text.replacen(
                    r#""k_0": 10000.0"#,
                    &format!(r#""k_0": 1{}"#, "0".repeat(400)),
                    1,
                ),
                "(document): not valid JSON: number out of range",
            ),
            (
                text.replacen(r#""k_0": 10000.0"#, r#""k_0": NaN"#, 1),
                "(document): not valid JSON",
            ),
            (
                format!("{}1{}", "[".repeat(100_000), "]".repeat(100_000)),
                "recursion limit",
            ),
            (
                text.replace(r#""robot": "ur5e""#, r#""robot": 5"#),
                "metadata.robot: must be a non-empty string or null",
            ),
            (
                text.replace(r#""payload": null"#, r#""payload": {"com_m": [1, 2]}"#),
                "metadata.payload.com_m: must be a list of 3 numbers",
            ),
            (
                text.replace(r#""metadata""#, r#""metdata""#),
                "(document): unknown field(s) metdata",
            ),
        ];
        for (doc, expected) in cases {
            let msg = reason_of(&doc);
            assert!(msg.contains(expected), "{msg:?} lacks {expected:?}");
        }
    }

    #[test]
    fn a_physically_invalid_map_is_refused_at_load_naming_the_mode_and_the_rule() {
        let text = paper_file().to_json();
        // Each was read before, and its modes came out as (NaN, NaN) or with ζ < 0.
        for (from, to, expected) in [
            (
                r#""k_0": 10000.0"#,
                r#""k_0": -10000.0"#,
                "modes[0]: the stiffness k_0 + k_j J_f must be > 0",
            ),
            (
                r#""c_0": 0.27"#,
                r#""c_0": -5.0"#,
                "modes[1]: the damping c_0 + c_1 √J_d + c_2 J_d must be >= 0",
            ),
            (r#""k_p": 1.73"#, r#""k_p": -1.73"#, "modes[1]: the gain"),
            (
                r#""k_g": 0.0"#,
                r#""k_g": -2.0"#,
                "modes[0]: k_g = -2 must be >= 0",
            ),
            (
                r#""c_tau": 47.2"#,
                r#""c_tau": -47.2"#,
                "modes[1]: the torque factor",
            ),
        ] {
            let bad = text.replacen(from, to, 1);
            assert_ne!(bad, text, "{from}");
            let msg = reason_of(&bad);
            assert!(msg.contains(expected), "{msg:?} lacks {expected:?}");
        }
    }

    /// The paper map's file with its modes repeated to `n` (cycling base, shoulder).
    fn file_with_modes(n: usize) -> String {
        let mut doc = paper_file().to_value();
        let modes = doc["modes"].as_array().expect("modes").clone();
        doc["modes"] = Value::Array(modes.iter().cycle().take(n).cloned().collect());
        serde_json::to_string(&doc).expect("json")
    }

    #[test]
    fn more_modes_than_the_shared_limit_are_refused_before_they_are_parsed() {
        let limit = crate::limits::MAX_MODES;
        let file = MapFile::parse(&file_with_modes(limit)).expect("at the limit");
        assert_eq!(
            file.form().as_paper10().map(DynamicMap::n_modes),
            Some(limit)
        );
        for n in [limit + 1, 10_000] {
            let msg = reason_of(&file_with_modes(n));
            let expected = format!("modes: the map has {n} modes, more than the limit of {limit}");
            assert!(msg.contains(&expected), "{msg}");
        }
    }

    #[test]
    fn a_repeated_key_is_refused_naming_it() {
        let text = paper_file().to_json();
        for (from, to, key) in [
            (r#""k_0": 10000.0"#, r#""k_0": 10000.0, "k_0": -1.0"#, "k_0"),
            (
                r#""robot": "ur5e""#,
                r#""robot": "ur5e", "robot": "ur10e""#,
                "robot",
            ),
            (
                r#""kind": "paper10""#,
                r#""kind": "paper10", "kind": "modal""#,
                "kind",
            ),
        ] {
            let doubled = text.replacen(from, to, 1);
            assert_ne!(doubled, text);
            let msg = reason_of(&doubled);
            let expected = format!("(document): not valid JSON: the key \"{key}\" appears twice");
            assert!(msg.contains(&expected), "{msg}");
        }
        // The same key in different objects is no repetition.
        assert!(text.matches(r#""k_0""#).count() == 2 && MapFile::parse(&text).is_ok());
    }

    #[test]
    fn a_byte_order_mark_is_accepted() {
        let file = paper_file();
        let with_bom = format!("\u{feff}{}", file.to_json());
        assert_eq!(MapFile::parse(&with_bom), Ok(file.clone()));
        let path = std::env::temp_dir().join(format!("tvist-bom-{}.json", std::process::id()));
        std::fs::write(&path, with_bom.as_bytes()).expect("write");
        let loaded = MapFile::load(&path);
        let _ = std::fs::remove_file(&path);
        assert_eq!(loaded, Ok(file));
    }

    #[test]
    fn a_file_beyond_the_size_limit_is_refused() {
        let limit = crate::limits::MAX_MAP_FILE_BYTES as usize;
        let text = paper_file().to_json();
        let path = std::env::temp_dir().join(format!("tvist-size-{}.json", std::process::id()));
        // A valid map padded with trailing whitespace: exactly at the limit it loads, one
        // byte more and it is refused by its size.
        let padded = |len: usize| format!("{text}{}", " ".repeat(len - text.len()));
        std::fs::write(&path, padded(limit)).expect("write");
        let at_limit = MapFile::load(&path);
        std::fs::write(&path, padded(limit + 1)).expect("write");
        let beyond = MapFile::load(&path);
        let _ = std::fs::remove_file(&path);
        assert!(at_limit.is_ok(), "{at_limit:?}");
        let msg = beyond.expect_err("beyond the limit").to_string();
        assert!(
            msg.contains(&format!("{} bytes is more than the 1 MiB", limit + 1)),
            "{msg}"
        );
    }

    /// An endless device is refused after at most the limit plus one byte (reading it whole
    /// would never end).
    #[cfg(unix)]
    #[test]
    fn an_endless_device_is_refused() {
        let msg = MapFile::load(Path::new("/dev/zero"))
            .expect_err("not a map")
            .to_string();
        assert!(
            msg.contains("/dev/zero: its content is more than the 1 MiB"),
            "{msg}"
        );
    }

    #[test]
    fn non_finite_metadata_is_written_as_null() {
        let mut meta = Map::new();
        meta.insert("robot".into(), Value::from("ur10e"));
        // A Value cannot hold NaN: `from_f64` gives None, which the bindings write as null.
        meta.insert("rms".into(), float(f64::NAN));
        let file = MapFile::new(
            MapForm::Paper10(DynamicMap::paper_ur5e()),
            &Value::Object(meta),
        )
        .expect("valid");
        let text = file.to_json();
        assert!(text.contains(r#""rms": null"#), "{text}");
        assert!(!text.contains("NaN"));
        // The metadata's robot is the map's robot.
        let map = file.form().as_paper10().expect("paper10");
        assert_eq!(map.robot(), Some("ur10e"));
    }

    proptest::proptest! {
        #![proptest_config(proptest::test_runner::Config::with_cases(500))]

        /// Every finite coefficient reads back bit-identical (the serde_json parser is set to
        /// round-trip floats exactly; its default is not correctly rounded). The sign bit is
        /// cleared (and `k_0 = 0` made 1) so that the map is physical; the other 63 bits are
        /// arbitrary.
        #[test]
        fn every_double_reads_back_bit_identical(
            bits in proptest::collection::vec(proptest::prelude::any::<u64>(), 8),
        ) {
            let mut finite: Vec<f64> = bits
                .iter()
                .map(|&b| f64::from_bits(b).abs())
                .map(|x| if x.is_finite() { x } else { 1.0 })
                .collect();
            if finite[0] == 0.0 {
                finite[0] = 1.0;
            }
            let c = MapCoefficients {
                k_0: finite[0], k_j: finite[1], k_g: finite[2], k_p: finite[3],
                c_0: finite[4], c_1: finite[5], c_2: finite[6], c_tau: finite[7],
            };
            let map = DynamicMap::new(vec![ModeMap::general(c, 1)]).expect("finite");
            let file = MapFile::new(MapForm::Paper10(map), &Value::Null).expect("valid");
            let back = MapFile::parse(&file.to_json()).expect("round trip");
            let read = back.form().as_paper10().expect("paper10");
            let got = read.mode_maps()[0].coefficients;
            for (a, b) in [(got.k_0, c.k_0), (got.k_j, c.k_j), (got.k_g, c.k_g), (got.k_p, c.k_p),
                           (got.c_0, c.c_0), (got.c_1, c.c_1), (got.c_2, c.c_2),
                           (got.c_tau, c.c_tau)] {
                proptest::prop_assert_eq!(a.to_bits(), b.to_bits());
            }
        }
    }
}
