//! The C functions, called as C would: error codes for bad input, and results equal to the
//! Rust core's.

mod ffi_support;

use ffi_support::{c, last_error, Handle, DT_S, PAYLOAD_COM_M, PAYLOAD_KG};
use std::ffi::c_char;
use std::ptr;
use tvist::{
    tvist_last_error_message, tvist_shaper_delay_s, tvist_shaper_free, tvist_shaper_n_dof,
    tvist_shaper_new_constant, tvist_shaper_new_ur_map, tvist_shaper_reset, tvist_shaper_step,
    TvistShaper, TVIST_ERR_DIMENSION_MISMATCH, TVIST_ERR_INVALID_MODE, TVIST_ERR_INVALID_PARAMETER,
    TVIST_ERR_NULL, TVIST_ERR_TOO_LARGE, TVIST_ERR_UNKNOWN_ROBOT, TVIST_ERR_UNKNOWN_SHAPER,
    TVIST_MAX_DOF, TVIST_MAX_MODES, TVIST_OK,
};
use tvist_core::files::robot_data::ur_e_series;
use tvist_core::{
    ConstantModes, DynamicMap, MapDynamics, Mode, RigidBody, ShaperKind, Status, TvShaper,
    TvShaperConfig,
};

const PI: f64 = std::f64::consts::PI;
/// The paper's pose Q1 (arm stretched out) and Q3 (folded), SPEC section 3.
const Q1: [f64; 6] = [0.0, -PI, 0.0, -PI / 2.0, 0.0, 0.0];
const Q3: [f64; 6] = [PI / 2.0, -PI / 2.0, 5.0 * PI / 6.0, -PI / 2.0, 0.0, 0.0];
/// `tvist_shaper_new_constant` with Rust arguments: the code and the handle (null on error).
fn new_constant(modes: &[(f64, f64)], dt_s: f64, n_dof: usize, shaper: &str) -> (i32, Handle) {
    let wn: Vec<f64> = modes.iter().map(|m| m.0).collect();
    let zeta: Vec<f64> = modes.iter().map(|m| m.1).collect();
    let name = c(shaper);
    let mut out = ptr::dangling_mut::<TvistShaper>();
    // SAFETY: arrays of `modes.len()` doubles, a NUL-terminated name, a writable `out`.
    let code = unsafe {
        tvist_shaper_new_constant(
            wn.as_ptr(),
            zeta.as_ptr(),
            modes.len(),
            dt_s,
            n_dof,
            name.as_ptr(),
            &mut out,
        )
    };
    (code, Handle(out))
}

fn new_ur_map(robot: &str, payload_kg: f64, shaper: &str) -> (i32, Handle) {
    let (robot, name) = (c(robot), c(shaper));
    let mut out = ptr::dangling_mut::<TvistShaper>();
    // SAFETY: NUL-terminated strings, a 3-vector, a writable `out`.
    let code = unsafe {
        tvist_shaper_new_ur_map(
            robot.as_ptr(),
            payload_kg,
            PAYLOAD_COM_M.as_ptr(),
            DT_S,
            name.as_ptr(),
            &mut out,
        )
    };
    (code, Handle(out))
}

/// Asserts `|a - b| <= 1e-14` elementwise. At rest the output is `Σ A_i x` with `Σ A_i = 1`
/// up to rounding: a few ulp of values below 4 (ulp(4) = 8.9e-16), far below 1e-14.
fn assert_at_rest(a: &[f64], b: &[f64]) {
    assert_eq!(a.len(), b.len());
    for (x, y) in a.iter().zip(b) {
        assert!((x - y).abs() <= 1e-14, "{a:?} != {b:?}");
    }
}

/// A smooth 3-channel test signal with one non-finite sample (exercises `INPUT_HELD`).
fn test_signal(n_samples: usize, n_dof: usize) -> Vec<Vec<f64>> {
    (0..n_samples)
        .map(|k| {
            let t = k as f64 * DT_S;
            (0..n_dof)
                .map(|j| {
                    if k == 40 && j == 1 {
                        f64::NAN
                    } else {
                        (1.0 + j as f64) * (t * (3.0 + j as f64)).sin() + 0.3 * t
                    }
                })
                .collect()
        })
        .collect()
}

#[test]
fn null_and_misaligned_pointers_return_err_null() {
    let (wn, zeta, name) = ([20.0], [0.05], c("zv"));
    let mut out = ptr::null_mut::<TvistShaper>();
    // SAFETY (all calls below): every non-null pointer is valid for its stated length; the
    // functions must reject the null or misaligned one before touching anything.
    unsafe {
        // A fresh non-null `out` per call: a rejected call must overwrite it with NULL.
        let raw = |wn: *const f64, zeta: *const f64, name: *const c_char| {
            let mut out = ptr::dangling_mut::<TvistShaper>();
            let code = tvist_shaper_new_constant(wn, zeta, 1, DT_S, 1, name, &mut out);
            (code, out)
        };
        let bytes = [0u64; 2];
        let misaligned = bytes.as_ptr().cast::<u8>().wrapping_add(1).cast::<f64>();
        for (code, out) in [
            raw(ptr::null(), zeta.as_ptr(), name.as_ptr()),
            raw(wn.as_ptr(), ptr::null(), name.as_ptr()),
            raw(wn.as_ptr(), zeta.as_ptr(), ptr::null()),
            raw(misaligned, zeta.as_ptr(), name.as_ptr()),
        ] {
            assert_eq!(code, TVIST_ERR_NULL);
            assert!(out.is_null(), "*out is set to NULL on failure");
        }
        let (w, z, n) = (wn.as_ptr(), zeta.as_ptr(), name.as_ptr());
        let no_out = tvist_shaper_new_constant(w, z, 1, DT_S, 1, n, ptr::null_mut());
        assert_eq!(no_out, TVIST_ERR_NULL);
        let robot = c("ur5e");
        assert_eq!(
            tvist_shaper_new_ur_map(
                robot.as_ptr(),
                0.0,
                ptr::null(),
                DT_S,
                name.as_ptr(),
                &mut out
            ),
            TVIST_ERR_NULL
        );
        assert_eq!(
            tvist_shaper_new_ur_map(
                ptr::null(),
                0.0,
                PAYLOAD_COM_M.as_ptr(),
                DT_S,
                name.as_ptr(),
                &mut out
            ),
            TVIST_ERR_NULL
        );
        assert!(last_error().contains("non-null"), "{}", last_error());

        let (code, mut h) = new_constant(&[(20.0, 0.05)], DT_S, 2, "zv");
        assert_eq!(code, TVIST_OK);
        let mut q = [1.0, 2.0];
        assert_eq!(
            tvist_shaper_step(ptr::null_mut(), q.as_ptr(), q.as_mut_ptr(), 2),
            TVIST_ERR_NULL
        );
        assert_eq!(
            tvist_shaper_step(h.0, ptr::null(), q.as_mut_ptr(), 2),
            TVIST_ERR_NULL
        );
        assert_eq!(
            tvist_shaper_step(h.0, q.as_ptr(), ptr::null_mut(), 2),
            TVIST_ERR_NULL
        );
        assert_eq!(
            tvist_shaper_reset(ptr::null_mut(), q.as_ptr(), 2),
            TVIST_ERR_NULL
        );
        assert_eq!(tvist_shaper_reset(h.0, ptr::null(), 2), TVIST_ERR_NULL);
        assert!(tvist_shaper_delay_s(ptr::null()).is_nan());
        assert_eq!(tvist_shaper_n_dof(ptr::null()), 0);
        tvist_shaper_free(ptr::null_mut());
        // The handle still works after the rejected calls.
        assert_eq!(h.step(&[1.0, 2.0], &mut q), Status::OK.0);
        assert_at_rest(&q, &[1.0, 2.0]);
    }
}

#[test]
fn wrong_lengths_are_rejected_without_touching_the_arrays() {
    let (code, mut h) = new_constant(&[(20.0, 0.05)], DT_S, 3, "zv");
    assert_eq!(code, TVIST_OK);
    // SAFETY: live handle.
    assert_eq!(unsafe { tvist_shaper_n_dof(h.0) }, 3);
    let mut out = [7.0; 2];
    assert_eq!(h.step(&[1.0, 2.0], &mut out), Status::BAD_LENGTH.0);
    assert_eq!(out, [7.0; 2], "nothing written on a length mismatch");
    // SAFETY: the array holds 2 doubles; the call must not read it (n_dof 5 is wrong).
    let code = unsafe { tvist_shaper_reset(h.0, [0.0; 2].as_ptr(), 5) };
    assert_eq!(code, TVIST_ERR_DIMENSION_MISMATCH);

    for (n_dof, code_expected, what) in [
        (0, TVIST_ERR_INVALID_PARAMETER, "n_dof must be at least 1"),
        (TVIST_MAX_DOF + 1, TVIST_ERR_TOO_LARGE, "exceeds"),
    ] {
        let (code, h) = new_constant(&[(20.0, 0.05)], DT_S, n_dof, "zv");
        assert_eq!((code, h.0.is_null()), (code_expected, true));
        assert!(last_error().contains(what), "{}", last_error());
    }
    let (code, _) = new_constant(&[], DT_S, 1, "zv");
    assert_eq!(code, TVIST_ERR_INVALID_PARAMETER);
    assert!(
        last_error().contains("at least one mode"),
        "{}",
        last_error()
    );
    let too_many = vec![(20.0, 0.05); TVIST_MAX_MODES + 1];
    assert_eq!(
        new_constant(&too_many, DT_S, 1, "zv").0,
        TVIST_ERR_TOO_LARGE
    );
    assert!(
        last_error().contains("65 modes, more than the limit of 64"),
        "{}",
        last_error()
    );
    let (code, _) = new_constant(&too_many[1..], DT_S, 1, "zv");
    assert_eq!(code, TVIST_OK, "{}", last_error());
}

#[test]
fn setup_errors_have_their_codes_and_messages() {
    let (code, h) = new_constant(&[(20.0, 0.05)], DT_S, 1, "zvv");
    assert_eq!((code, h.0.is_null()), (TVIST_ERR_UNKNOWN_SHAPER, true));
    assert!(last_error().contains("\"zvv\""), "{}", last_error());

    let bad_utf8 = [0xffu8, 0xfe, 0].as_ptr().cast::<c_char>();
    let mut out = ptr::null_mut();
    // SAFETY: valid arrays, a NUL-terminated (non-UTF-8) name, a writable `out`.
    let code = unsafe {
        tvist_shaper_new_constant(
            [20.0].as_ptr(),
            [0.0].as_ptr(),
            1,
            DT_S,
            1,
            bad_utf8,
            &mut out,
        )
    };
    assert_eq!(code, TVIST_ERR_UNKNOWN_SHAPER);

    let (code, _) = new_constant(&[(20.0, 0.05), (30.0, 1.0)], DT_S, 1, "zv");
    assert_eq!(code, TVIST_ERR_INVALID_MODE);
    assert!(last_error().contains("invalid mode 1"), "{}", last_error());
    assert_eq!(
        new_constant(&[(-1.0, 0.0)], DT_S, 1, "zv").0,
        TVIST_ERR_INVALID_MODE
    );
    assert_eq!(
        new_constant(&[(20.0, 0.0)], 0.0, 1, "zv").0,
        TVIST_ERR_INVALID_PARAMETER
    );
    assert!(last_error().contains("dt_s"), "{}", last_error());

    let (code, h) = new_ur_map("ur10e", 0.0, "zv");
    assert_eq!((code, h.0.is_null()), (TVIST_ERR_UNKNOWN_ROBOT, true));
    assert!(last_error().contains("ur10e"), "{}", last_error());
    assert_eq!(
        new_ur_map("ur5e", -1.0, "zv").0,
        TVIST_ERR_INVALID_PARAMETER
    );
    assert!(last_error().contains("payload"), "{}", last_error());

    // The snprintf contract: the full length is returned whatever the buffer.
    let full = last_error().len();
    // SAFETY: a null buffer with length 0 is allowed.
    assert_eq!(
        unsafe { tvist_last_error_message(ptr::null_mut(), 0) },
        full
    );
    let mut small = [1 as c_char; 4];
    // SAFETY: `small` is writable for 4 bytes.
    assert_eq!(
        unsafe { tvist_last_error_message(small.as_mut_ptr(), 4) },
        full
    );
    assert_eq!(small[3], 0, "truncated text is NUL-terminated");
}

#[test]
fn steps_equal_the_rust_core() {
    let modes = [(2.0 * PI * 3.0, 0.05), (2.0 * PI * 7.5, 0.12)];
    let n_dof = 3;
    let (code, mut h) = new_constant(&modes, DT_S, n_dof, "zvd");
    assert_eq!(code, TVIST_OK);
    let provider =
        ConstantModes::new(modes.iter().map(|&(w, z)| Mode::new(w, z)).collect()).expect("modes");
    let config = TvShaperConfig::new(DT_S, n_dof, ShaperKind::Zvd);
    let mut direct = TvShaper::new(provider, &config).expect("shaper");

    let (mut via_c, mut via_rust) = (vec![0.0; n_dof], vec![0.0; n_dof]);
    let mut held = false;
    for x in test_signal(400, n_dof) {
        let code = h.step(&x, &mut via_c);
        let status = direct.step(&x, &mut via_rust);
        assert_eq!(code, status.0);
        held |= status.contains(Status::INPUT_HELD);
        // Same code on the same data in the same binary: bitwise equal, stricter than 1e-15.
        assert_eq!(via_c, via_rust);
        assert_eq!(h.delay_s().to_bits(), direct.delay_s().to_bits());
    }
    assert!(held, "the NaN sample was reported through the C API");
    // ZVD of two modes: the delay is one damped period of each, 1/f_d.
    let expected: f64 = modes
        .iter()
        .map(|&(w, z)| 2.0 * PI / (w * (1.0 - z * z).sqrt()))
        .sum();
    // Relative 1e-12: the same formula in a different operation order (rounding only).
    assert!((h.delay_s() - expected).abs() <= 1e-12 * expected);

    // Reset: at rest at q0 in both; a constant q0 then passes unchanged.
    let q0 = [0.5, -1.0, 2.0];
    // SAFETY: live handle, 3 doubles.
    assert_eq!(
        unsafe { tvist_shaper_reset(h.0, q0.as_ptr(), n_dof) },
        TVIST_OK
    );
    direct.reset(&q0);
    for _ in 0..10 {
        assert_eq!(h.step(&q0, &mut via_c), direct.step(&q0, &mut via_rust).0);
        assert_eq!(via_c, via_rust);
        assert_at_rest(&via_c, &q0);
    }
}

#[test]
fn input_and_output_may_share_one_array() {
    let modes = [(2.0 * PI * 4.0, 0.1)];
    let (_, mut separate) = new_constant(&modes, DT_S, 2, "zv");
    let (_, in_place) = new_constant(&modes, DT_S, 2, "zv");
    let mut out = [0.0; 2];
    for x in test_signal(100, 2) {
        separate.step(&x, &mut out);
        let mut buf = [x[0], x[1]];
        // SAFETY: live handle; `buf` is both the input and the output, as the header allows.
        unsafe { tvist_shaper_step(in_place.0, buf.as_ptr(), buf.as_mut_ptr(), 2) };
        assert_eq!(buf, out);
    }
}

/// ZV delay of the two-mode map at rest at `q`, from the paper's equations 47–51 with the
/// published coefficients (SPEC section 3), written out independently of the core's map.
fn paper_zv_delay_s(q: &[f64; 6]) -> f64 {
    let mut robot = ur_e_series("ur5e", RigidBody::point(PAYLOAD_KG, PAYLOAD_COM_M)).expect("ur5e");
    let mut j = [0.0; 6];
    assert!(robot.joint_inertia(q, &mut j).is_ok());
    let (j0, j1) = (j[0], j[1]);
    // Table 1 (base) and Table 2 (shoulder): k_0, k_J, k_p, c_0, c_2, c_tau.
    let (k0, kj, kp, c0, c2, ct) = (10_000.0, 1060.0, 2.54, 1.53, 0.39, 3.81);
    let stiffness = k0 + kj * j1;
    let wn0 = (1.0 + kp / j1).sqrt() * (stiffness / j1).sqrt();
    let zeta0 = (1.0 + kp / j0) * (c0 + c2 * j0) * (1.0 + ct * j0)
        / (2.0 * (stiffness * j1).sqrt() * (1.0 + kp / j1).sqrt());
    let (k0, kj, kp, c0, c2, ct) = (10_000.0, 763.0, 1.73, 0.27, 0.038, 47.2);
    let stiffness = k0 + kj * j1;
    let wn1 = (1.0 + kp / j1).sqrt() * (stiffness / j1).sqrt();
    let zeta1 =
        (1.0 + kp / j1).sqrt() * (c0 + c2 * j1) * (1.0 + ct * j1) / (2.0 * (stiffness * j1).sqrt());
    // ZV: the second impulse at half a damped period.
    [(wn0, zeta0), (wn1, zeta1)]
        .iter()
        .map(|&(w, z)| PI / (w * (1.0 - z * z).sqrt()))
        .sum()
}

#[test]
fn the_ur5e_map_shaper_follows_the_paper_map_and_equals_the_core() {
    let (code, mut h) = new_ur_map("ur5e", PAYLOAD_KG, "zv");
    assert_eq!(code, TVIST_OK, "{}", last_error());
    // SAFETY: live handle.
    assert_eq!(unsafe { tvist_shaper_n_dof(h.0) }, 6);
    let robot = ur_e_series("ur5e", RigidBody::point(PAYLOAD_KG, PAYLOAD_COM_M)).expect("ur5e");
    let provider = MapDynamics::new(robot, DynamicMap::paper_ur5e()).expect("map");
    let mut direct =
        TvShaper::new(provider, &TvShaperConfig::new(DT_S, 6, ShaperKind::Zv)).expect("shaper");

    // At rest in each of the paper's poses the delay is the two-mode ZV delay of the map there
    // (relative 1e-12: the same equations evaluated in another operation order).
    let mut out = [0.0; 6];
    for q in [Q1, Q3] {
        // SAFETY: live handle, 6 doubles.
        assert_eq!(unsafe { tvist_shaper_reset(h.0, q.as_ptr(), 6) }, TVIST_OK);
        assert_eq!(h.step(&q, &mut out), Status::OK.0);
        assert_at_rest(&out, &q);
        let expected = paper_zv_delay_s(&q);
        assert!(
            (h.delay_s() - expected).abs() <= 1e-12 * expected,
            "delay {} s, paper map {expected} s",
            h.delay_s()
        );
    }
    // The folded pose has stiffer, faster modes: a shorter delay (Table 4: 135 vs 49 ms).
    assert!(paper_zv_delay_s(&Q3) < 0.5 * paper_zv_delay_s(&Q1));

    // A move from Q1 towards Q3 shaped through C equals the core, step by step.
    // SAFETY: live handle, 6 doubles.
    assert_eq!(unsafe { tvist_shaper_reset(h.0, Q1.as_ptr(), 6) }, TVIST_OK);
    direct.reset(&Q1);
    let mut via_rust = [0.0; 6];
    let mut delays = Vec::new();
    for k in 0..=800 {
        let s = (k as f64 / 600.0).min(1.0);
        let x: Vec<f64> = (0..6).map(|j| Q1[j] + s * (Q3[j] - Q1[j])).collect();
        assert_eq!(h.step(&x, &mut out), direct.step(&x, &mut via_rust).0);
        assert_eq!(out, via_rust, "bitwise equal at sample {k}");
        delays.push(h.delay_s());
    }
    assert_at_rest(&out, &Q3);
    let (lo, hi) = delays.iter().fold((f64::INFINITY, 0.0f64), |(lo, hi), &d| {
        (lo.min(d), hi.max(d))
    });
    assert!(
        hi > 2.0 * lo,
        "the delay varies along the move: {lo} .. {hi} s"
    );
}
