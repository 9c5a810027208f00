//! `tvist_shaper_step`, `_reset`, `_delay_s` and `_status_counts` never allocate, for every
//! constructor (constant modes, the paper's map, a paper10 map file, a modal map file).
//!
//! Its own test binary: the counting global allocator sees only this file's allocations, and
//! a single `#[test]` keeps other test threads out of the measured windows.

#[path = "../../tvist-core/tests/alloc_support/mod.rs"]
mod alloc_support;

use alloc_support::{allocations_in, the_counter_sees_this_thread_only};
use std::ffi::CString;
use std::ptr;
use tvist::{
    tvist_shaper_delay_s, tvist_shaper_free, tvist_shaper_new_constant, tvist_shaper_new_map,
    tvist_shaper_new_ur_map, tvist_shaper_reset, tvist_shaper_status_counts, tvist_shaper_step,
    TvistShaper, TVIST_N_STATUS_FLAGS, TVIST_OK,
};
use tvist_core::files::map_file::{MapFile, MapForm};
use tvist_core::{DynamicMap, FlexJoint, LoadLaw, ModalMap};

/// Runs 500 cycles of a moving 6-joint input, a reset and delay queries on `shaper`.
fn cycle(shaper: *mut TvistShaper) -> usize {
    let q0 = [0.0, -std::f64::consts::PI, 0.0, -1.5, 0.0, 0.0];
    let (mut x, mut y) = (q0, [0.0; 6]);
    let mut delay_sum = 0.0;
    let n = allocations_in(|| {
        // SAFETY: a live handle of 6 channels; every array holds 6 doubles.
        unsafe {
            assert_eq!(tvist_shaper_reset(shaper, q0.as_ptr(), 6), TVIST_OK);
            for k in 0..500 {
                x[0] = q0[0] + 0.5 * (k as f64 * 0.01).sin();
                x[1] = q0[1] + 0.3 * (k as f64 * 0.007).sin();
                if k == 100 {
                    x[2] = f64::NAN;
                } else {
                    x[2] = 0.0;
                }
                assert!(tvist_shaper_step(shaper, x.as_ptr(), y.as_mut_ptr(), 6) >= 0);
                delay_sum += tvist_shaper_delay_s(shaper);
                let mut counts = [0u64; TVIST_N_STATUS_FLAGS];
                let n = tvist_shaper_status_counts(shaper, counts.as_mut_ptr(), counts.len());
                assert_eq!(n, TVIST_N_STATUS_FLAGS);
            }
        }
    });
    assert!(delay_sum > 0.0 && y.iter().all(|v| v.is_finite()));
    n
}

#[test]
fn per_cycle_calls_never_allocate() {
    the_counter_sees_this_thread_only();

    let (zv, ur5e) = (
        CString::new("zv").expect("name"),
        CString::new("ur5e").expect("name"),
    );
    let (mut constant, mut map, mut from_file) =
        (ptr::null_mut(), ptr::null_mut(), ptr::null_mut());
    let path = std::env::temp_dir().join(format!("tvist-no-alloc-{}.json", std::process::id()));
    let meta = serde_json::json!({"robot": "ur10e"});
    let file = MapFile::new(MapForm::Paper10(DynamicMap::paper_ur5e()), &meta).expect("map");
    std::fs::write(&path, file.to_json()).expect("write map");
    let c_path = CString::new(path.to_str().expect("UTF-8 path")).expect("path");
    // A modal map whose base stiffness and damping read gravity torques (both per-cycle
    // evaluations: mass matrix and gravity).
    let flex = |joint: usize, k: f64, c: f64| FlexJoint {
        joint,
        stiffness_nm_per_rad: LoadLaw {
            at_zero: k,
            per_nm: 0.0,
            per_nm2: 0.01,
        },
        damping_nms_per_rad: LoadLaw {
            at_zero: c,
            per_nm: 0.2,
            per_nm2: 0.0,
        },
        damping_load_joint: 1,
    };
    let modal = ModalMap::new(vec![flex(0, 2.6e4, 14.0), flex(1, 2.2e4, 21.0)], &[0, 1])
        .expect("modal map");
    let modal_path =
        std::env::temp_dir().join(format!("tvist-no-alloc-modal-{}.json", std::process::id()));
    let modal_file = MapFile::new(MapForm::Modal(modal), &meta).expect("modal file");
    std::fs::write(&modal_path, modal_file.to_json()).expect("write modal map");
    let c_modal_path = CString::new(modal_path.to_str().expect("UTF-8 path")).expect("path");
    let mut from_modal_file = ptr::null_mut();
    let ur10e = CString::new("ur10e").expect("name");
    // SAFETY: arrays of the stated lengths, NUL-terminated names, writable outputs.
    unsafe {
        let (wn, zeta) = ([40.0, 110.0], [0.05, 0.1]);
        let code = tvist_shaper_new_constant(
            wn.as_ptr(),
            zeta.as_ptr(),
            2,
            0.002,
            6,
            zv.as_ptr(),
            &mut constant,
        );
        assert_eq!(code, TVIST_OK);
        let com = [0.0, 0.0, 0.05];
        let code = tvist_shaper_new_ur_map(
            ur5e.as_ptr(),
            5.0,
            com.as_ptr(),
            0.002,
            zv.as_ptr(),
            &mut map,
        );
        assert_eq!(code, TVIST_OK);
        let code = tvist_shaper_new_map(
            ur10e.as_ptr(),
            5.0,
            com.as_ptr(),
            c_path.as_ptr(),
            0.002,
            zv.as_ptr(),
            &mut from_file,
        );
        assert_eq!(code, TVIST_OK);
        let code = tvist_shaper_new_map(
            ur10e.as_ptr(),
            5.0,
            com.as_ptr(),
            c_modal_path.as_ptr(),
            0.002,
            zv.as_ptr(),
            &mut from_modal_file,
        );
        assert_eq!(code, TVIST_OK);
    }
    let _ = std::fs::remove_file(&path);
    let _ = std::fs::remove_file(&modal_path);
    assert_eq!(cycle(constant), 0, "constant-mode shaper allocated");
    assert_eq!(cycle(map), 0, "map-driven shaper allocated");
    assert_eq!(cycle(from_file), 0, "map-file shaper allocated");
    assert_eq!(cycle(from_modal_file), 0, "modal map-file shaper allocated");
    // SAFETY: handles from the constructors, freed once.
    unsafe {
        tvist_shaper_free(constant);
        tvist_shaper_free(map);
        tvist_shaper_free(from_file);
        tvist_shaper_free(from_modal_file);
    }
}
