//! The modal map against closed forms: two coupled joints (the quadratic characteristic
//! equation), the overdamped fallback, mode assignment through a frequency crossing, and the
//! UR5e provider. (The damped modes against LAPACK: tests/test_modal_map.py.)

mod robot_support;

use tvist_core::{Dynamics, FlexJoint, LoadLaw, ModalDynamics, ModalMap, Mode};

fn joint(j: usize, k: f64, c: f64) -> FlexJoint {
    FlexJoint {
        joint: j,
        stiffness_nm_per_rad: LoadLaw::constant(k),
        damping_nms_per_rad: LoadLaw::constant(c),
        damping_load_joint: j,
    }
}

/// Roots ω² of det(K − ω² M) = 0 for 2 × 2 `M` and diagonal `K`:
/// `det(M) λ² − (k1 m22 + k2 m11) λ + k1 k2 = 0`, ascending.
fn closed_form_w2(m: [f64; 4], k1: f64, k2: f64) -> [f64; 2] {
    let a = m[0] * m[3] - m[1] * m[2];
    let b = -(k1 * m[3] + k2 * m[0]);
    let c = k1 * k2;
    let disc = (b * b - 4.0 * a * c).sqrt();
    // Numerically stable pair of roots.
    let q = -0.5 * (b - disc);
    let (r1, r2) = (q / a, c / q);
    if r1 < r2 {
        [r1, r2]
    } else {
        [r2, r1]
    }
}

#[test]
fn two_coupled_joints_match_the_characteristic_equation() {
    let mut rng = robot_support::Rng(3);
    for _ in 0..500 {
        let (m11, m22) = (0.5 + 10.0 * rng.next_f64(), 0.5 + 10.0 * rng.next_f64());
        // Off-diagonal up to 90 % of the geometric mean: strongly coupled yet positive definite.
        let m12 = 0.9 * (2.0 * rng.next_f64() - 1.0) * (m11 * m22).sqrt();
        let (k1, k2) = (1e3 + 1e5 * rng.next_f64(), 1e3 + 1e5 * rng.next_f64());
        let map =
            ModalMap::new(vec![joint(0, k1, 0.0), joint(1, k2, 0.0)], &[0, 1]).expect("valid");
        let sol = map
            .solve(&[m11, m12, m12, m22], 2, &[])
            .expect("positive definite");
        let mut got = [sol.wn_rad_s[0].powi(2), sol.wn_rad_s[1].powi(2)];
        got.sort_by(f64::total_cmp);
        let want = closed_form_w2([m11, m12, m12, m22], k1, k2);
        for (g, w) in got.iter().zip(&want) {
            // Rounding of Jacobi and of the quadratic formula: far below 1e-10 relative.
            assert!((g / w - 1.0).abs() < 1e-10, "{got:?} vs {want:?}");
        }
        for i in 0..2 {
            let share: f64 = sol.strain_share[i][..2].iter().sum();
            assert!((share - 1.0).abs() < 1e-12);
        }
    }
}

#[test]
fn modal_damping_of_a_single_joint_is_exact() {
    // One flexible joint: ζ = c / (2 √(k J)) exactly, whatever the rest of M.
    let map = ModalMap::new(vec![joint(1, 2.0e4, 300.0)], &[1]).expect("valid");
    let mass = [3.0, 0.4, 0.4, 5.0];
    let mut out = [Mode::new(0.0, 0.0)];
    assert!(map.modes_from_mass_matrix(&mass, 2, &[], &mut out).is_ok());
    assert!((out[0].wn_rad_s - (2.0e4f64 / 5.0).sqrt()).abs() < 1e-12);
    assert!((out[0].zeta - 300.0 / (2.0 * (2.0e4f64 * 5.0).sqrt())).abs() < 1e-15);
}

#[test]
fn an_overdamped_mode_falls_back_to_the_projected_damping() {
    // Joint 1 at ζ = 1.5 has no oscillating mode, so the damped solve fails; the modes are
    // then the undamped ones with projected damping, exact for uncoupled joints:
    // ω = √(k/J), ζ = c / (2 √(k J)), whatever the (valid) joint 0 does.
    let (k0, j0, c0) = (2.0e4, 4.0, 0.1 * 2.0 * (2.0e4f64 * 4.0).sqrt());
    let (k1, j1, c1) = (1.8e4, 9.0, 1.5 * 2.0 * (1.8e4f64 * 9.0).sqrt());
    let map = ModalMap::new(vec![joint(0, k0, c0), joint(1, k1, c1)], &[0, 1]).expect("valid");
    let mut out = [Mode::new(0.0, 0.0); 2];
    assert!(map
        .modes_from_mass_matrix(&[j0, 0.0, 0.0, j1], 2, &[], &mut out)
        .is_ok());
    assert!((out[0].wn_rad_s / (k0 / j0).sqrt() - 1.0).abs() < 1e-12);
    assert!((out[0].zeta - 0.1).abs() < 1e-12);
    assert!((out[1].wn_rad_s / (k1 / j1).sqrt() - 1.0).abs() < 1e-12);
    assert!((out[1].zeta - 1.5).abs() < 1e-12);
}

#[test]
fn modes_keep_their_joint_through_a_frequency_crossing() {
    // Weakly coupled base (J 4) and shoulder (J 6): sweeping the base stiffness moves the base
    // frequency across the shoulder's. The "base" mode must stay the base-dominated one: its
    // frequency rises with k_0 and ends above the shoulder's, which stays nearly constant
    // (sorting by frequency would swap them). With coupling the two branches veer instead of
    // crossing; the label switches branch where the shares are 50/50, a jump of the veering
    // gap, about |M_01| / √(M_00 M_11) of the frequency: 0.4 % here.
    let mass = [4.0, 0.02, 0.02, 6.0];
    let k_shoulder = 1.8e4;
    let mut previous: Option<[Mode; 2]> = None;
    let mut crossed = false;
    for step in 0..=200 {
        let k_base = 1.0e4 + 2.0e2 * step as f64;
        let map = ModalMap::new(
            vec![joint(0, k_base, 20.0), joint(1, k_shoulder, 80.0)],
            &[0, 1],
        )
        .expect("valid");
        let mut out = [Mode::new(0.0, 0.0); 2];
        map.modes_from_mass_matrix(&mass, 2, &[], &mut out);
        if let Some(prev) = previous {
            let base_change = out[0].wn_rad_s / prev[0].wn_rad_s - 1.0;
            assert!(base_change > 0.0, "base mode fell at step {step}");
            let change = (out[1].wn_rad_s / prev[1].wn_rad_s - 1.0).abs();
            assert!(
                change < 0.006,
                "shoulder mode jumped by {change} at step {step}"
            );
            crossed |= (out[0].wn_rad_s - out[1].wn_rad_s).signum()
                != (prev[0].wn_rad_s - prev[1].wn_rad_s).signum();
        }
        previous = Some(out);
    }
    assert!(
        crossed,
        "the sweep must cross the two frequencies to test anything"
    );
}

#[test]
fn the_ur5e_provider_gives_valid_modes_above_its_delay_bound() {
    let map = ModalMap::new(
        vec![
            joint(0, 22_000.0, 30.0),
            joint(1, 18_000.0, 90.0),
            joint(2, 120_000.0, 40.0),
        ],
        &[0, 1],
    )
    .expect("valid");
    let mut provider =
        ModalDynamics::new(robot_support::ur_robot("ur5e", 5.0), map).expect("valid");
    let slowest = [
        provider.slowest_mode(0).expect("valid"),
        provider.slowest_mode(1).expect("valid"),
    ];
    let mut rng = robot_support::Rng(17);
    let mut out = [Mode::new(0.0, 0.0); 2];
    for _ in 0..2000 {
        let q = rng.pose(6);
        assert!(provider.modes(&q, &mut out).is_ok());
        for (m, s) in out.iter().zip(&slowest) {
            assert!(m.is_valid(), "{q:?}: {m:?}");
            // The Rayleigh bound holds at every pose, not only the sampled ones.
            assert!(m.wn_rad_s >= s.wn_rad_s, "{q:?}: {m:?} below {s:?}");
        }
    }
    let mut short = [Mode::new(0.0, 0.0); 2];
    assert!(!provider.modes(&[0.0; 5], &mut short).is_ok());
    assert!(short[0].wn_rad_s.is_nan());
}
