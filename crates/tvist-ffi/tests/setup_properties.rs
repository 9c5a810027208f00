//! Property tests of the setup paths: the C constructors and the map-file parser, fed
//! arbitrary values, always return (an error code or a handle), never abort or unwind; a
//! handle they return steps with finite output. Bounded case counts keep this to seconds.

use proptest::prelude::*;
use std::ffi::CString;
use std::ptr;
use tvist::{
    tvist_shaper_free, tvist_shaper_new_constant_ex, tvist_shaper_new_map_ex, tvist_shaper_step,
    TvistShaper, TvistShaperOptions, ERROR_CODES, TVIST_OK,
};
use tvist_core::files::map_file::{MapFile, MapForm};
use tvist_core::DynamicMap;

/// Doubles that matter at a boundary: signs, zeros, tiny, huge, non-finite, ordinary values.
fn edgy_f64() -> impl Strategy<Value = f64> {
    prop_oneof![
        Just(0.0),
        Just(-0.0),
        Just(f64::NAN),
        Just(f64::INFINITY),
        Just(f64::NEG_INFINITY),
        Just(f64::MIN_POSITIVE),
        Just(1e-300),
        Just(1e300),
        Just(f64::MAX),
        -1e3..1e3f64,
        0.0..1.0f64,
    ]
}

fn known_code(code: i32) -> bool {
    ERROR_CODES.iter().any(|&(_, c)| c == code)
}

/// Steps a fresh handle a few times: output must be finite for finite input.
fn exercise(handle: *mut TvistShaper, n_dof: usize) {
    let x: Vec<f64> = (0..n_dof).map(|i| 0.01 * i as f64).collect();
    let mut y = vec![0.0; n_dof];
    for _ in 0..3 {
        // SAFETY: a live handle of `n_dof` channels; both arrays hold `n_dof` doubles.
        let status = unsafe { tvist_shaper_step(handle, x.as_ptr(), y.as_mut_ptr(), n_dof) };
        assert!(status >= 0, "status {status}");
        assert!(y.iter().all(|v| v.is_finite()));
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 400, ..ProptestConfig::default() })]

    #[test]
    fn constant_setup_never_aborts(
        modes in prop::collection::vec((edgy_f64(), edgy_f64()), 0..4),
        dt_s in edgy_f64(),
        n_dof in prop_oneof![Just(0usize), 1usize..8, Just(4096usize), Just(4097usize),
                             Just(usize::MAX)],
        shaper in prop::sample::select(vec!["zv", "zvd", "ei", "3hump_ei", "bogus"]),
        interpolation in -1i32..3,
        ei_tolerance in prop_oneof![Just(0.0), edgy_f64()],
        safety_factor in prop_oneof![Just(0.0), edgy_f64()],
    ) {
        let wn: Vec<f64> = modes.iter().map(|m| m.0).collect();
        let zeta: Vec<f64> = modes.iter().map(|m| m.1).collect();
        let name = CString::new(shaper).expect("name");
        let options = TvistShaperOptions { interpolation, ei_tolerance, safety_factor,
                                           allow_other_robot: 0 };
        let mut out = ptr::dangling_mut::<TvistShaper>();
        // SAFETY: arrays of `modes.len()` doubles (dangling but aligned when empty), a
        // NUL-terminated name, readable options, a writable `out`.
        let code = unsafe {
            tvist_shaper_new_constant_ex(wn.as_ptr(), zeta.as_ptr(), modes.len(), dt_s, n_dof,
                                         name.as_ptr(), &options, &mut out)
        };
        prop_assert!(known_code(code), "unknown code {code}");
        prop_assert_eq!(code == TVIST_OK, !out.is_null());
        if code == TVIST_OK {
            exercise(out, n_dof);
            // SAFETY: from the constructor, freed once.
            unsafe { tvist_shaper_free(out) };
        }
    }

    #[test]
    fn map_setup_never_aborts(
        robot in prop::sample::select(vec!["ur3e", "ur5e", "ur10e", "ur16e", "ur20", "ur99", ""]),
        map_robot in prop::sample::select(vec!["ur5e", "ur10e", "ur3e"]),
        payload_kg in edgy_f64(),
        com in (edgy_f64(), edgy_f64(), edgy_f64()),
        dt_s in edgy_f64(),
        allow_other_robot in 0i32..2,
    ) {
        let path = std::env::temp_dir()
            .join(format!("tvist-prop-{}-{map_robot}.json", std::process::id()));
        let meta = serde_json::json!({"robot": map_robot});
        let file = MapFile::new(MapForm::Paper10(DynamicMap::paper_ur5e()), &meta).expect("map");
        std::fs::write(&path, file.to_json()).expect("write");
        let (robot_c, path_c, zv) = (
            CString::new(robot).expect("robot"),
            CString::new(path.to_str().expect("UTF-8")).expect("path"),
            CString::new("zv").expect("zv"),
        );
        let options = TvistShaperOptions { allow_other_robot, ..TvistShaperOptions::default() };
        let com = [com.0, com.1, com.2];
        let mut out = ptr::dangling_mut::<TvistShaper>();
        // SAFETY: NUL-terminated strings, a 3-double CoM, readable options, a writable `out`.
        let code = unsafe {
            tvist_shaper_new_map_ex(robot_c.as_ptr(), payload_kg, com.as_ptr(),
                                    path_c.as_ptr(), dt_s, zv.as_ptr(), &options, &mut out)
        };
        prop_assert!(known_code(code), "unknown code {code}");
        prop_assert_eq!(code == TVIST_OK, !out.is_null());
        if code == TVIST_OK {
            prop_assert!(robot == map_robot || allow_other_robot != 0);
            exercise(out, 6);
            // SAFETY: from the constructor, freed once.
            unsafe { tvist_shaper_free(out) };
        }
    }
}

/// A valid map document as a JSON value, for mutation.
fn valid_doc() -> serde_json::Value {
    let meta = serde_json::json!({"robot": "ur5e"});
    MapFile::new(MapForm::Paper10(DynamicMap::paper_ur5e()), &meta)
        .expect("map")
        .to_value()
}

/// Arbitrary JSON values (bounded depth and size).
fn any_json() -> impl Strategy<Value = serde_json::Value> {
    use serde_json::Value;
    let leaf = prop_oneof![
        Just(Value::Null),
        any::<bool>().prop_map(Value::Bool),
        any::<i64>().prop_map(Value::from),
        edgy_f64().prop_map(Value::from),
        "[a-z_]{0,8}".prop_map(Value::String),
    ];
    leaf.prop_recursive(3, 24, 4, |inner| {
        prop_oneof![
            prop::collection::vec(inner.clone(), 0..4).prop_map(Value::Array),
            prop::collection::btree_map("[a-z_0-9]{1,8}", inner, 0..4)
                .prop_map(|m| Value::Object(m.into_iter().collect())),
        ]
    })
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 600, ..ProptestConfig::default() })]

    /// One field of a valid document replaced by an arbitrary value: the parser either
    /// accepts a document that writes back to itself, or names a field in its error.
    #[test]
    fn the_map_parser_accepts_round_trips_or_names_the_field(
        field in prop::sample::select(vec![
            "schema_version", "kind", "metadata", "modes", "modes.0", "modes.0.k_0",
            "modes.0.frequency_joint", "modes.1.damping_gain_exponent",
            "modes.1.frequency_inertia_range_kg_m2", "metadata.payload", "metadata.robot",
        ]),
        value in any_json(),
    ) {
        let mut doc = valid_doc();
        let mut slot = &mut doc;
        for key in field.split('.') {
            slot = match key.parse::<usize>() {
                Ok(i) => &mut slot[i],
                Err(_) => &mut slot[key],
            };
        }
        *slot = value;
        let text = serde_json::to_string(&doc).expect("serialize");
        match MapFile::parse(&text) {
            Ok(file) => {
                let again = MapFile::parse(&file.to_json()).expect("a written map reads back");
                prop_assert_eq!(again, file);
            }
            Err(tvist_core::Error::Document { path, reason }) => {
                prop_assert!(!path.is_empty() && !reason.is_empty());
            }
            Err(other) => prop_assert!(false, "not a document error: {other}"),
        }
    }

    /// Arbitrary bytes never crash the parser.
    #[test]
    fn the_map_parser_survives_arbitrary_text(text in ".{0,200}") {
        let _ = MapFile::parse(&text);
    }
}
