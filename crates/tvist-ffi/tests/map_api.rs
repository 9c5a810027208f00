//! Map files from C (`tvist_shaper_new_map[_ex]`), setup options, the memory limit and the
//! per-flag status counts, called as C would and compared with the Rust core.

mod ffi_support;

use ffi_support::{c, last_error, Handle, DT_S, PAYLOAD_COM_M, PAYLOAD_KG};
use std::ffi::CString;
use std::path::PathBuf;
use std::ptr;
use tvist::{
    tvist_shaper_new_constant, tvist_shaper_new_constant_ex, tvist_shaper_new_map,
    tvist_shaper_new_map_ex, tvist_shaper_new_ur_map, tvist_shaper_reset, tvist_shaper_set_map,
    tvist_shaper_set_shaped_modes, tvist_shaper_status_counts, TvistShaper, TvistShaperOptions,
    TVIST_ERR_INVALID_PARAMETER, TVIST_ERR_MAP_FILE, TVIST_ERR_MID_MOVE, TVIST_ERR_NULL,
    TVIST_ERR_ROBOT_MISMATCH, TVIST_ERR_TOO_LARGE, TVIST_ERR_UNKNOWN_ROBOT, TVIST_INTERP_CUBIC,
    TVIST_MAX_MODES, TVIST_N_STATUS_FLAGS, TVIST_OK,
};
use tvist_core::files::map_file::{MapFile, MapForm};
use tvist_core::files::robot_data::ur_e_series;
use tvist_core::{
    ConstantModes, DynamicMap, Dynamics, FlexJoint, Interpolation, LoadLaw, MapDynamics,
    ModalDynamics, ModalMap, Mode, RigidBody, ShapedModes, ShaperKind, Status, TvShaper,
    TvShaperConfig,
};

const PI: f64 = std::f64::consts::PI;
const Q1: [f64; 6] = [0.0, -PI, 0.0, -PI / 2.0, 0.0, 0.0];

impl Handle {
    fn counts(&self) -> Vec<u64> {
        let mut counts = vec![u64::MAX; TVIST_N_STATUS_FLAGS + 2];
        // SAFETY: live handle; `counts` is writable for its length.
        let n = unsafe { tvist_shaper_status_counts(self.0, counts.as_mut_ptr(), counts.len()) };
        assert_eq!(n, TVIST_N_STATUS_FLAGS);
        assert_eq!(
            &counts[n..],
            &[u64::MAX; 2],
            "nothing written past the flags"
        );
        counts.truncate(n);
        counts
    }
}

/// A map file in the temporary directory, removed on drop.
struct TempMap(PathBuf);

impl TempMap {
    fn new(tag: &str, text: &str) -> TempMap {
        let path =
            std::env::temp_dir().join(format!("tvist-ffi-{}-{tag}.json", std::process::id()));
        std::fs::write(&path, text).expect("write map file");
        TempMap(path)
    }

    fn of_robot(tag: &str, robot: &str) -> TempMap {
        let meta = serde_json::json!({"robot": robot, "source": "test"});
        let file = MapFile::new(MapForm::Paper10(DynamicMap::paper_ur5e()), &meta).expect("map");
        TempMap::new(tag, &file.to_json())
    }

    /// A modal map file (base and shoulder flexible; the laws read gravity torques).
    fn modal_of_robot(tag: &str, robot: &str) -> TempMap {
        let flex = |joint: usize, k: f64, c: f64| FlexJoint {
            joint,
            stiffness_nm_per_rad: LoadLaw {
                at_zero: k,
                per_nm: 0.0,
                per_nm2: 0.2,
            },
            damping_nms_per_rad: LoadLaw {
                at_zero: c,
                per_nm: 0.5,
                per_nm2: 0.0,
            },
            damping_load_joint: 1,
        };
        let map = ModalMap::new(
            vec![flex(0, 22_000.0, 5.0), flex(1, 18_000.0, 60.0)],
            &[0, 1],
        )
        .expect("modal map");
        let meta = serde_json::json!({"robot": robot, "source": "test"});
        let file = MapFile::new(MapForm::Modal(map), &meta).expect("modal file");
        TempMap::new(tag, &file.to_json())
    }

    fn c_path(&self) -> CString {
        c(self.0.to_str().expect("UTF-8 temp path"))
    }
}

impl Drop for TempMap {
    fn drop(&mut self) {
        let _ = std::fs::remove_file(&self.0);
    }
}

fn new_map(
    robot: &str,
    map: &TempMap,
    shaper: &str,
    options: Option<&TvistShaperOptions>,
) -> (i32, Handle) {
    let (robot, shaper, path) = (c(robot), c(shaper), map.c_path());
    let mut out = ptr::dangling_mut::<TvistShaper>();
    let options = options.map_or(ptr::null(), |o| o as *const TvistShaperOptions);
    // SAFETY: NUL-terminated strings, a 3-double CoM, readable options, a writable `out`.
    let code = unsafe {
        tvist_shaper_new_map_ex(
            robot.as_ptr(),
            PAYLOAD_KG,
            PAYLOAD_COM_M.as_ptr(),
            path.as_ptr(),
            DT_S,
            shaper.as_ptr(),
            options,
            &mut out,
        )
    };
    (code, Handle(out))
}

/// A smooth 0.6 s move of joints 0–2 from Q1, then rest: `n` samples of 6 joints.
fn a_move(n: usize) -> Vec<[f64; 6]> {
    (0..n)
        .map(|k| {
            let s = (k as f64 * DT_S / 0.6).min(1.0);
            let blend = s * s * s * (10.0 - 15.0 * s + 6.0 * s * s);
            let mut q = Q1;
            q[0] += 0.8 * blend;
            q[1] += 0.5 * blend;
            q[2] -= 0.4 * blend;
            q
        })
        .collect()
}

/// Runs `h` and `core` on the same move; both must give bit-identical outputs.
fn assert_same_as_core<D: tvist_core::Dynamics>(h: &mut Handle, core: &mut TvShaper<D>) {
    let (mut from_c, mut from_core) = ([0.0; 6], [0.0; 6]);
    // SAFETY: live handle, 6 doubles.
    assert_eq!(unsafe { tvist_shaper_reset(h.0, Q1.as_ptr(), 6) }, TVIST_OK);
    core.reset(&Q1);
    for q in a_move(600) {
        let status = h.step(&q, &mut from_c);
        assert_eq!(status, core.step(&q, &mut from_core).0);
        assert_eq!(from_c, from_core);
    }
}

#[test]
fn a_map_file_from_c_shapes_exactly_as_the_core() {
    for robot in ["ur5e", "ur10e"] {
        let map = TempMap::of_robot(robot, robot);
        let (code, mut h) = new_map(robot, &map, "zv", None);
        assert_eq!(code, TVIST_OK, "{}", last_error());
        let ur = ur_e_series(robot, RigidBody::point(PAYLOAD_KG, PAYLOAD_COM_M)).expect("robot");
        let file = MapFile::load(&map.0).expect("map");
        let dynmap = match file.into_form() {
            MapForm::Paper10(map) => Some(map),
            MapForm::Modal(_) => None,
        }
        .expect("a paper10 map");
        let dynamics = MapDynamics::new(ur, dynmap).expect("provider");
        let config = TvShaperConfig::new(DT_S, 6, ShaperKind::Zv);
        let mut core = TvShaper::new(dynamics, &config).expect("shaper");
        assert_same_as_core(&mut h, &mut core);
    }
}

#[test]
fn the_plain_constructor_equals_the_ex_form_with_default_options() {
    let map = TempMap::of_robot("plain", "ur5e");
    let (robot, shaper, path) = (c("ur5e"), c("zvd"), map.c_path());
    let mut out = ptr::null_mut();
    // SAFETY: NUL-terminated strings, a 3-double CoM, a writable `out`.
    let code = unsafe {
        tvist_shaper_new_map(
            robot.as_ptr(),
            PAYLOAD_KG,
            PAYLOAD_COM_M.as_ptr(),
            path.as_ptr(),
            DT_S,
            shaper.as_ptr(),
            &mut out,
        )
    };
    assert_eq!(code, TVIST_OK, "{}", last_error());
    let mut plain = Handle(out);
    let (_, mut ex) = new_map("ur5e", &map, "zvd", Some(&TvistShaperOptions::default()));
    let (mut a, mut b) = ([0.0; 6], [0.0; 6]);
    for q in a_move(300) {
        assert_eq!(plain.step(&q, &mut a), ex.step(&q, &mut b));
        assert_eq!(a, b);
    }
}

#[test]
fn a_modal_map_file_from_c_shapes_exactly_as_the_core_modal_provider() {
    for robot in ["ur5e", "ur10e"] {
        let map = TempMap::modal_of_robot(&format!("modal-{robot}"), robot);
        let (code, mut h) = new_map(robot, &map, "zv", None);
        assert_eq!(code, TVIST_OK, "{}", last_error());
        let ur = ur_e_series(robot, RigidBody::point(PAYLOAD_KG, PAYLOAD_COM_M)).expect("robot");
        let modal = match MapFile::load(&map.0).expect("map").into_form() {
            MapForm::Modal(map) => Some(map),
            MapForm::Paper10(_) => None,
        }
        .expect("a modal map");
        let dynamics = ModalDynamics::new(ur, modal).expect("provider");
        let config = TvShaperConfig::new(DT_S, 6, ShaperKind::Zv);
        let mut core = TvShaper::new(dynamics, &config).expect("shaper");
        assert_same_as_core(&mut h, &mut core);
    }
}

#[test]
fn a_map_of_another_robot_is_refused_naming_both_unless_allowed() {
    let paper10 = TempMap::of_robot("mismatch", "ur5e");
    let modal = TempMap::modal_of_robot("mismatch-modal", "ur5e");
    for map in [&paper10, &modal] {
        let (code, h) = new_map("ur10e", map, "zv", None);
        assert_eq!((code, h.0.is_null()), (TVIST_ERR_ROBOT_MISMATCH, true));
        let msg = last_error();
        assert!(msg.contains("ur10e") && msg.contains("ur5e"), "{msg}");

        let allow = TvistShaperOptions {
            allow_other_robot: 1,
            ..TvistShaperOptions::default()
        };
        let (code, h) = new_map("ur10e", map, "zv", Some(&allow));
        assert_eq!((code, h.0.is_null()), (TVIST_OK, false), "{}", last_error());
    }
}

#[test]
fn bad_robots_and_bad_files_have_their_codes_and_name_the_problem() {
    let map = TempMap::of_robot("bad", "ur5e");
    let (code, _) = new_map("ur99", &map, "zv", None);
    assert_eq!(code, TVIST_ERR_UNKNOWN_ROBOT);
    assert!(
        last_error().contains("ur3e, ur5e, ur10e, ur16e, ur20"),
        "{}",
        last_error()
    );

    let missing = TempMap(std::env::temp_dir().join("tvist-ffi-no-such-map.json"));
    let (code, _) = new_map("ur5e", &missing, "zv", None);
    assert_eq!(code, TVIST_ERR_MAP_FILE);
    assert!(
        last_error().contains("no-such-map.json: cannot read"),
        "{}",
        last_error()
    );

    let text = std::fs::read_to_string(&map.0).expect("map text");
    for (tag, bad, field) in [
        (
            "k0",
            text.replacen("\"k_0\": 10000.0", "\"k_0\": \"x\"", 1),
            "modes[0].k_0",
        ),
        (
            "nan",
            text.replacen("\"k_0\": 10000.0", "\"k_0\": NaN", 1),
            "not valid JSON",
        ),
        (
            "version",
            text.replace("\"schema_version\": 1", "\"schema_version\": 2"),
            "schema_version",
        ),
    ] {
        let file = TempMap::new(tag, &bad);
        let (code, h) = new_map("ur5e", &file, "zv", None);
        assert_eq!((code, h.0.is_null()), (TVIST_ERR_MAP_FILE, true), "{tag}");
        let msg = last_error();
        assert!(msg.contains(field) && msg.contains(".json"), "{tag}: {msg}");
    }
}

/// The paper map's file text with its modes repeated to `n` (base, shoulder, base, ...).
fn paper_text_with_modes(n: usize) -> String {
    let meta = serde_json::json!({"robot": "ur5e", "source": "test"});
    let file = MapFile::new(MapForm::Paper10(DynamicMap::paper_ur5e()), &meta).expect("map");
    let mut doc = file.to_value();
    let modes = doc["modes"].as_array().expect("modes").clone();
    doc["modes"] = serde_json::Value::Array(modes.iter().cycle().take(n).cloned().collect());
    serde_json::to_string_pretty(&doc).expect("json")
}

#[test]
fn map_files_the_core_refuses_are_refused_from_c_naming_the_problem() {
    let text = paper_text_with_modes(2);
    let limit = TVIST_MAX_MODES;
    for (tag, bad, problem) in [
        (
            "negative-k0",
            text.replacen("\"k_0\": 10000.0", "\"k_0\": -10000.0", 1),
            "modes[0]: the stiffness",
        ),
        (
            "negative-c0",
            text.replacen("\"c_0\": 0.27", "\"c_0\": -5.0", 1),
            "modes[1]: the damping",
        ),
        (
            "many-modes",
            paper_text_with_modes(limit + 1),
            "modes: the map has 65 modes, more than the limit of 64",
        ),
        (
            "repeated-key",
            text.replacen("\"k_0\": 10000.0", "\"k_0\": 10000.0, \"k_0\": 1.0", 1),
            "the key \"k_0\" appears twice",
        ),
        (
            "too-long",
            format!("{text}{}", " ".repeat(1 << 20)),
            "is more than the 1 MiB a map file may have",
        ),
    ] {
        assert!(bad != text, "{tag}");
        let file = TempMap::new(tag, &bad);
        let (code, h) = new_map("ur5e", &file, "zv", None);
        assert_eq!((code, h.0.is_null()), (TVIST_ERR_MAP_FILE, true), "{tag}");
        let msg = last_error();
        assert!(
            msg.contains(problem) && msg.contains(".json"),
            "{tag}: {msg}"
        );
    }
    // At the limit, and with a byte-order mark: accepted.
    for (tag, good) in [
        ("max-modes", paper_text_with_modes(limit)),
        ("bom", format!("\u{feff}{text}")),
    ] {
        let file = TempMap::new(tag, &good);
        let (code, h) = new_map("ur5e", &file, "zv", None);
        assert_eq!(
            (code, h.0.is_null()),
            (TVIST_OK, false),
            "{tag}: {}",
            last_error()
        );
    }
}

#[test]
fn options_choose_interpolation_and_ei_tolerance_as_in_the_core() {
    let map = TempMap::of_robot("options", "ur5e");
    let options = TvistShaperOptions {
        interpolation: TVIST_INTERP_CUBIC,
        ei_tolerance: 0.1,
        ..TvistShaperOptions::default()
    };
    let (code, mut h) = new_map("ur5e", &map, "ei", Some(&options));
    assert_eq!(code, TVIST_OK, "{}", last_error());
    let ur = ur_e_series("ur5e", RigidBody::point(PAYLOAD_KG, PAYLOAD_COM_M)).expect("robot");
    let mut config =
        TvShaperConfig::new(DT_S, 6, ShaperKind::from_name("ei", Some(0.1)).expect("ei"));
    config.interp = Interpolation::Cubic;
    let dynamics = MapDynamics::new(ur, DynamicMap::paper_ur5e()).expect("provider");
    let mut core = TvShaper::new(dynamics, &config).expect("shaper");
    assert_same_as_core(&mut h, &mut core);

    // The default tolerance differs, so the test above can tell the option was used.
    let (_, mut default) = new_map("ur5e", &map, "ei", None);
    let (mut a, mut b) = ([0.0; 6], [0.0; 6]);
    let mut differs = false;
    for q in a_move(300) {
        h.step(&q, &mut a);
        default.step(&q, &mut b);
        differs |= a != b;
    }
    assert!(differs);

    for (options, what) in [
        (
            TvistShaperOptions {
                interpolation: 7,
                ..TvistShaperOptions::default()
            },
            "interpolation = 7",
        ),
        (
            TvistShaperOptions {
                ei_tolerance: 0.1,
                ..TvistShaperOptions::default()
            },
            "applies to \"ei\" only",
        ),
    ] {
        let (code, _) = new_map("ur5e", &map, "zv", Some(&options));
        assert_eq!(code, TVIST_ERR_INVALID_PARAMETER);
        assert!(last_error().contains(what), "{}", last_error());
    }
}

#[test]
fn a_request_beyond_the_memory_limit_is_refused_not_aborted() {
    // 0.1 rad/s undamped at 100 kHz over 4096 channels: a ZV delay line of 4.7e6 samples per
    // channel, ~154 GB. Every value is within its own documented range.
    let name = c("zv");
    let mut out = ptr::dangling_mut::<TvistShaper>();
    // SAFETY: one-mode arrays, a NUL-terminated name, a writable `out`.
    let code = unsafe {
        tvist_shaper_new_constant(
            [0.1].as_ptr(),
            [0.0].as_ptr(),
            1,
            1e-5,
            4096,
            name.as_ptr(),
            &mut out,
        )
    };
    assert_eq!((code, out.is_null()), (TVIST_ERR_TOO_LARGE, true));
    assert!(last_error().contains("256 MiB"), "{}", last_error());
}

#[test]
fn status_counts_count_each_flag_of_each_step() {
    // Mode 0 above the Nyquist frequency (pi/dt = 1571 rad/s at 2 ms), mode 1 ordinary.
    let name = c("zv");
    let mut out = ptr::null_mut();
    // SAFETY: two-mode arrays, a NUL-terminated name, a writable `out`.
    let code = unsafe {
        tvist_shaper_new_constant_ex(
            [1e4, 40.0].as_ptr(),
            [0.0, 0.05].as_ptr(),
            2,
            DT_S,
            2,
            name.as_ptr(),
            ptr::null(),
            &mut out,
        )
    };
    assert_eq!(code, TVIST_OK, "{}", last_error());
    let mut h = Handle(out);
    assert_eq!(h.counts(), vec![0; TVIST_N_STATUS_FLAGS]);
    let mut y = [0.0; 2];
    for k in 0..10 {
        let x = if k == 3 { [f64::NAN, 0.0] } else { [0.1, 0.2] };
        let status = Status(h.step(&x, &mut y));
        assert!(status.contains(Status::MODE_ABOVE_NYQUIST));
    }
    assert_eq!(h.step(&[0.0; 3], &mut [0.0; 3]), Status::BAD_LENGTH.0);
    let counts = h.counts();
    for (k, &(name, flag)) in Status::FLAGS.iter().enumerate() {
        let expected = match flag {
            Status::MODE_ABOVE_NYQUIST => 10,
            Status::INPUT_HELD | Status::BAD_LENGTH => 1,
            _ => 0,
        };
        assert_eq!(counts[k], expected, "{name}");
    }
    // SAFETY: a null handle returns 0 and writes nothing.
    assert_eq!(
        unsafe { tvist_shaper_status_counts(ptr::null(), ptr::null_mut(), 0) },
        0
    );
    // The same cascade in the core flags the same.
    let modes = ConstantModes::new(vec![Mode::new(1e4, 0.0), Mode::new(40.0, 0.05)]).expect("m");
    let mut core =
        TvShaper::new(modes, &TvShaperConfig::new(DT_S, 2, ShaperKind::Zv)).expect("shaper");
    assert!(core
        .step(&[0.1, 0.2], &mut y)
        .contains(Status::MODE_ABOVE_NYQUIST));
}

impl Handle {
    fn set_map(&mut self, map: &TempMap) -> i32 {
        let path = map.c_path();
        // SAFETY: live handle, NUL-terminated path.
        unsafe { tvist_shaper_set_map(self.0, path.as_ptr()) }
    }
}

/// The pose `a_move` ends at.
fn move_end() -> [f64; 6] {
    *a_move(301).last().expect("a sample")
}

/// A second move, from `move_end()` back towards Q1 over 0.6 s, then rest: `n` samples.
fn a_move_back(n: usize) -> Vec<[f64; 6]> {
    let (from, to) = (move_end(), Q1);
    (0..n)
        .map(|k| {
            let s = (k as f64 * DT_S / 0.6).min(1.0);
            let blend = s * s * s * (10.0 - 15.0 * s + 6.0 * s * s);
            core::array::from_fn(|j| from[j] + (to[j] - from[j]) * blend)
        })
        .collect()
}

/// Steps `h` through `samples`, returning every output.
fn run(h: &mut Handle, samples: &[[f64; 6]]) -> Vec<[f64; 6]> {
    samples
        .iter()
        .map(|q| {
            let mut out = [0.0; 6];
            let status = h.step(q, &mut out);
            assert!(status >= 0, "step status {status}");
            out
        })
        .collect()
}

/// Samples of the rest after `a_move` that bring every delay line to rest: 2 s, ten times
/// what these maps need (the shaper was found at rest 100 samples after the move's end;
/// their lines hold the ZV delay of the slowest mode bound times the 1.5 safety factor).
const SETTLE_SAMPLES: usize = 1000;

#[test]
fn a_map_replaced_between_moves_shapes_the_next_move_as_a_new_shaper_from_that_map() {
    let old_map = TempMap::of_robot("set-old", "ur5e");
    let new_map_file = TempMap::modal_of_robot("set-new", "ur5e");
    let (code, mut h) = new_map("ur5e", &old_map, "zv", None);
    assert_eq!(code, TVIST_OK, "{}", last_error());
    let (code, mut unchanged) = new_map("ur5e", &old_map, "zv", None);
    assert_eq!(code, TVIST_OK, "{}", last_error());
    // First move and the rest after it (the move holds its end pose after 0.6 s).
    let first = a_move(300 + SETTLE_SAMPLES);
    run(&mut h, &first);
    run(&mut unchanged, &first);
    assert_eq!(h.set_map(&new_map_file), TVIST_OK, "{}", last_error());
    // The next move, from rest at the end pose, against a new shaper built from the new file.
    let (code, mut fresh) = new_map("ur5e", &new_map_file, "zv", None);
    assert_eq!(code, TVIST_OK, "{}", last_error());
    let second = a_move_back(600);
    let (swapped, expected, old) = (
        run(&mut h, &second),
        run(&mut fresh, &second),
        run(&mut unchanged, &second),
    );
    // The replaced shaper starts at rest on the held input exactly as the new one starts on
    // its first sample, and both run the same arithmetic: equal to the bit (stricter than
    // any tolerance).
    assert_eq!(swapped, expected);
    // And the replacement took effect: the old map shapes the move differently (the two maps
    // place the modes apart, so outputs differ by far more than rounding).
    let largest_difference = swapped
        .iter()
        .zip(&old)
        .flat_map(|(a, b)| a.iter().zip(b).map(|(x, y)| (x - y).abs()))
        .fold(0.0, f64::max);
    assert!(largest_difference > 1e-6, "{largest_difference}");
}

#[test]
fn set_map_mid_move_is_refused_and_the_output_continues_unchanged() {
    let old_map = TempMap::of_robot("mid-old", "ur5e");
    let new_map_file = TempMap::modal_of_robot("mid-new", "ur5e");
    let (_, mut h) = new_map("ur5e", &old_map, "zv", None);
    let (_, mut twin) = new_map("ur5e", &old_map, "zv", None);
    let samples = a_move(300 + SETTLE_SAMPLES);
    // Mid-move (sample 150), on the first held sample after the move (the input has just
    // stopped, the delay lines still hold the move) and half a delay later: all refused.
    let mut refused_at = Vec::new();
    for (k, q) in samples.iter().enumerate() {
        if [150, 300, 340].contains(&k) {
            assert_eq!(h.set_map(&new_map_file), TVIST_ERR_MID_MOVE, "sample {k}");
            assert!(last_error().contains("mid-move"), "{}", last_error());
            refused_at.push(k);
        }
        let (mut a, mut b) = ([0.0; 6], [0.0; 6]);
        assert_eq!(h.step(q, &mut a), twin.step(q, &mut b));
        assert_eq!(a, b, "sample {k}: the refused call changed the output");
    }
    assert_eq!(refused_at, [150, 300, 340]);
    // At rest it is accepted (the same calls were not refused for another reason).
    assert_eq!(h.set_map(&new_map_file), TVIST_OK, "{}", last_error());
}

#[test]
fn an_invalid_map_file_is_refused_with_the_shaper_unchanged() {
    let old_map = TempMap::of_robot("bad-old", "ur5e");
    let broken = TempMap::new("bad-broken", "{\"kind\": \"paper10\", \"modes\": [");
    let other_robot = TempMap::of_robot("bad-other", "ur10e");
    let missing = TempMap(std::env::temp_dir().join("tvist-ffi-no-such-map.json"));
    let (_, mut h) = new_map("ur5e", &old_map, "zv", None);
    let (_, mut twin) = new_map("ur5e", &old_map, "zv", None);
    let first = a_move(300 + SETTLE_SAMPLES);
    assert_eq!(run(&mut h, &first), run(&mut twin, &first));
    for (bad, code) in [
        (&broken, TVIST_ERR_MAP_FILE),
        (&missing, TVIST_ERR_MAP_FILE),
        (&other_robot, TVIST_ERR_ROBOT_MISMATCH),
    ] {
        assert_eq!(h.set_map(bad), code, "{}", last_error());
    }
    let second = a_move_back(600);
    assert_eq!(run(&mut h, &second), run(&mut twin, &second));
}

#[test]
fn set_map_needs_a_map_driven_shaper_and_valid_pointers() {
    let map = TempMap::of_robot("kind-map", "ur5e");
    let mut constant = constant_zv(&[Mode::new(2.0 * PI * 3.0, 0.05)]);
    assert_eq!(constant.set_map(&map), TVIST_ERR_INVALID_PARAMETER);
    assert!(last_error().contains("constant modes"), "{}", last_error());
    // The paper's built-in map is a map too: replaced before its first step (not started).
    let (robot, zv) = (c("ur5e"), c("zv"));
    let mut out = ptr::null_mut();
    // SAFETY: NUL-terminated strings, a 3-double CoM, a writable `out`.
    let code = unsafe {
        tvist_shaper_new_ur_map(
            robot.as_ptr(),
            PAYLOAD_KG,
            PAYLOAD_COM_M.as_ptr(),
            DT_S,
            zv.as_ptr(),
            &mut out,
        )
    };
    assert_eq!(code, TVIST_OK, "{}", last_error());
    let mut paper = Handle(out);
    let modal = TempMap::modal_of_robot("kind-modal", "ur5e");
    assert_eq!(paper.set_map(&modal), TVIST_OK, "{}", last_error());
    let path = map.c_path();
    // SAFETY: null handle and null path are checked before use.
    unsafe {
        assert_eq!(
            tvist_shaper_set_map(ptr::null_mut(), path.as_ptr()),
            TVIST_ERR_NULL
        );
        assert_eq!(
            tvist_shaper_set_map(constant.0, ptr::null()),
            TVIST_ERR_NULL
        );
    }
}

impl Handle {
    fn set_shaped_modes(&mut self, n_modes: usize) -> i32 {
        // SAFETY: live handle.
        unsafe { tvist_shaper_set_shaped_modes(self.0, n_modes) }
    }
}

/// Base, shoulder and elbow flexible (constant laws), shaping `shaped`.
fn three_joint_map(shaped: ShapedModes) -> ModalMap {
    let flex = |joint: usize, k: f64, c: f64| FlexJoint {
        joint,
        stiffness_nm_per_rad: LoadLaw::constant(k),
        damping_nms_per_rad: LoadLaw::constant(c),
        damping_load_joint: joint,
    };
    let joints = vec![
        flex(0, 22_000.0, 10.0),
        flex(1, 18_000.0, 40.0),
        flex(2, 9_000.0, 15.0),
    ];
    ModalMap::shaping(joints, shaped).expect("modal map")
}

fn three_joint_file(tag: &str, shaped: ShapedModes) -> TempMap {
    let meta = serde_json::json!({"robot": "ur5e", "source": "test"});
    let file = MapFile::new(MapForm::Modal(three_joint_map(shaped)), &meta).expect("modal file");
    TempMap::new(tag, &file.to_json())
}

#[test]
fn set_shaped_modes_between_moves_shapes_as_a_map_of_that_many_lowest_modes() {
    let named = three_joint_file("k-named", ShapedModes::ByJoint(vec![0, 1]));
    let (code, mut h) = new_map("ur5e", &named, "zv", None);
    assert_eq!(code, TVIST_OK, "{}", last_error());
    let first = a_move(300 + SETTLE_SAMPLES);
    run(&mut h, &first);
    let robot = ur_e_series("ur5e", RigidBody::point(PAYLOAD_KG, PAYLOAD_COM_M)).expect("robot");
    for k in [3, 1, 2] {
        assert_eq!(h.set_shaped_modes(k), TVIST_OK, "{}", last_error());
        // The next move exactly as a new shaper from a file with "shaped_modes": k (the same
        // arithmetic from the same rest: equal to the bit).
        let lowest = three_joint_file(&format!("k-{k}"), ShapedModes::Lowest(k));
        let (code, mut fresh) = new_map("ur5e", &lowest, "zv", None);
        assert_eq!(code, TVIST_OK, "{}", last_error());
        let (back, there) = (
            a_move_back(600 + SETTLE_SAMPLES),
            a_move(300 + SETTLE_SAMPLES),
        );
        assert_eq!(run(&mut h, &back), run(&mut fresh, &back), "k = {k}");
        // At rest at Q1 the added delay is that of the k modes shaped: the sum of their ZV
        // durations π / ω_d (the design's last impulse time; rounding only, far below one
        // sample).
        let mut modes = vec![Mode::new(0.0, 0.0); k];
        let mut provider =
            ModalDynamics::new(robot.clone(), three_joint_map(ShapedModes::Lowest(k)))
                .expect("provider");
        assert!(provider.modes(&Q1, &mut modes).is_ok());
        let expected: f64 = modes
            .iter()
            .map(|m| PI / (m.wn_rad_s * (1.0 - m.zeta * m.zeta).sqrt()))
            .sum();
        let delay = h.delay_s();
        assert!(
            (delay - expected).abs() < 1e-9,
            "k = {k}: {delay} vs {expected}"
        );
        run(&mut h, &there);
    }
}

#[test]
fn set_shaped_modes_mid_move_or_out_of_range_is_refused_with_the_shaper_unchanged() {
    let named = three_joint_file("k-mid", ShapedModes::ByJoint(vec![0, 1]));
    let (_, mut h) = new_map("ur5e", &named, "zv", None);
    let (_, mut twin) = new_map("ur5e", &named, "zv", None);
    let samples = a_move(300 + SETTLE_SAMPLES);
    for (k, q) in samples.iter().enumerate() {
        if [150, 300, 340].contains(&k) {
            assert_eq!(h.set_shaped_modes(3), TVIST_ERR_MID_MOVE, "sample {k}");
            assert!(last_error().contains("mid-move"), "{}", last_error());
        }
        let (mut a, mut b) = ([0.0; 6], [0.0; 6]);
        assert_eq!(h.step(q, &mut a), twin.step(q, &mut b));
        assert_eq!(a, b, "sample {k}: the refused call changed the output");
    }
    for bad in [0, 4] {
        assert_eq!(
            h.set_shaped_modes(bad),
            TVIST_ERR_INVALID_PARAMETER,
            "{bad}"
        );
        assert!(last_error().contains("shaped_modes"), "{}", last_error());
    }
    let back = a_move_back(600);
    assert_eq!(run(&mut h, &back), run(&mut twin, &back));
    // A paper10 map, constant modes and null handles are refused.
    let paper = TempMap::of_robot("k-paper", "ur5e");
    let (_, mut p) = new_map("ur5e", &paper, "zv", None);
    assert_eq!(p.set_shaped_modes(1), TVIST_ERR_INVALID_PARAMETER);
    assert!(last_error().contains("modal map"), "{}", last_error());
    // SAFETY: a null handle is checked before use.
    assert_eq!(
        unsafe { tvist_shaper_set_shaped_modes(ptr::null_mut(), 1) },
        TVIST_ERR_NULL
    );
}

/// A ZV shaper of 6 joints on the constant `modes`.
fn constant_zv(modes: &[Mode]) -> Handle {
    let wn: Vec<f64> = modes.iter().map(|m| m.wn_rad_s).collect();
    let zeta: Vec<f64> = modes.iter().map(|m| m.zeta).collect();
    let (zv, mut out) = (c("zv"), ptr::dangling_mut::<TvistShaper>());
    // SAFETY: two readable mode arrays of `modes.len()`, a NUL-terminated name, a writable
    // `out`.
    let code = unsafe {
        tvist_shaper_new_constant(
            wn.as_ptr(),
            zeta.as_ptr(),
            modes.len(),
            DT_S,
            6,
            zv.as_ptr(),
            &mut out,
        )
    };
    assert_eq!(code, TVIST_OK, "{}", last_error());
    Handle(out)
}

impl Handle {
    fn hold_modes_at(&mut self, q: Option<&[f64]>) -> i32 {
        let (ptr, n) = q.map_or((ptr::null(), 6), |q| (q.as_ptr(), q.len()));
        // SAFETY: live handle; `ptr` null or readable for `n` doubles.
        unsafe { tvist::tvist_shaper_hold_modes_at(self.0, ptr, n) }
    }
}

#[test]
fn modes_held_at_the_end_pose_shape_the_next_move_as_those_constant_modes() {
    let named = three_joint_file("hold", ShapedModes::ByJoint(vec![0, 1]));
    let (code, mut h) = new_map("ur5e", &named, "zv", None);
    assert_eq!(code, TVIST_OK, "{}", last_error());
    run(&mut h, &a_move(300 + SETTLE_SAMPLES));
    // The modes the map gives at Q1, where the move back stops.
    let robot = ur_e_series("ur5e", RigidBody::point(PAYLOAD_KG, PAYLOAD_COM_M)).expect("robot");
    let mut provider = ModalDynamics::new(robot, three_joint_map(ShapedModes::ByJoint(vec![0, 1])))
        .expect("provider");
    let mut modes = vec![Mode::new(0.0, 0.0); 2];
    assert!(provider.modes(&Q1, &mut modes).is_ok());
    let mut constant = constant_zv(&modes);
    assert_eq!(h.hold_modes_at(Some(&Q1)), TVIST_OK, "{}", last_error());
    let back = a_move_back(600 + SETTLE_SAMPLES);
    // SAFETY: live handle, 6 readable doubles.
    assert_eq!(
        unsafe { tvist_shaper_reset(constant.0, move_end().as_ptr(), 6) },
        TVIST_OK
    );
    let held = run(&mut h, &back);
    // Held modes are those constant modes: the same filters from the same rest, to the bit.
    assert!(
        held == run(&mut constant, &back),
        "held modes differ from the constant modes"
    );
    // Following the pose again shapes as a new shaper from the file (the call puts the shaper
    // at rest on its input exactly as a new one starts), and not as the held modes did.
    run(&mut h, &a_move(300 + SETTLE_SAMPLES));
    assert_eq!(h.hold_modes_at(None), TVIST_OK, "{}", last_error());
    let (_, mut following) = new_map("ur5e", &named, "zv", None);
    let followed = run(&mut following, &back);
    assert!(
        run(&mut h, &back) == followed,
        "released hold differs from a new shaper"
    );
    assert!(
        held != followed,
        "holding changed nothing on a move whose modes change"
    );
}

#[test]
fn a_hold_mid_move_of_the_wrong_length_or_without_a_map_is_refused() {
    let named = three_joint_file("hold-bad", ShapedModes::ByJoint(vec![0, 1]));
    let (_, mut h) = new_map("ur5e", &named, "zv", None);
    let samples = a_move(300);
    run(&mut h, &samples[..150]);
    assert_eq!(h.hold_modes_at(Some(&Q1)), TVIST_ERR_MID_MOVE);
    assert!(last_error().contains("mid-move"), "{}", last_error());
    run(&mut h, &a_move(300 + SETTLE_SAMPLES)[150..]);
    assert_eq!(
        h.hold_modes_at(Some(&Q1[..4])),
        tvist::TVIST_ERR_DIMENSION_MISMATCH
    );
    let mut constant = constant_zv(&[Mode::new(60.0, 0.05)]);
    assert_eq!(
        constant.hold_modes_at(Some(&Q1)),
        TVIST_ERR_INVALID_PARAMETER
    );
    assert!(
        last_error().contains("not driven by a map"),
        "{}",
        last_error()
    );
    // SAFETY: a null handle is checked before use.
    assert_eq!(
        unsafe { tvist::tvist_shaper_hold_modes_at(ptr::null_mut(), Q1.as_ptr(), 6) },
        TVIST_ERR_NULL
    );
}
