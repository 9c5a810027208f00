//! The modal map against closed forms: two coupled joints (the quadratic characteristic
//! equation), the overdamped fallback, mode assignment through a frequency crossing, and the
//! UR5e provider. (The damped modes against LAPACK: tests/reference/test_modal_map.py.)

mod robot_support;

use robot_support::flex_joint;
use tvist_core::{Dynamics, ModalDynamics, ModalMap, Mode, ModeTrack, ShapedModes};

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
        let map = ModalMap::new(
            vec![flex_joint(0, k1, 0.0), flex_joint(1, k2, 0.0)],
            &[0, 1],
        )
        .expect("valid");
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
    let map = ModalMap::new(vec![flex_joint(1, 2.0e4, 300.0)], &[1]).expect("valid");
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
    let map =
        ModalMap::new(vec![flex_joint(0, k0, c0), flex_joint(1, k1, c1)], &[0, 1]).expect("valid");
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
            vec![flex_joint(0, k_base, 20.0), flex_joint(1, k_shoulder, 80.0)],
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
            flex_joint(0, 22_000.0, 30.0),
            flex_joint(1, 18_000.0, 90.0),
            flex_joint(2, 120_000.0, 40.0),
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
        // Unrelated poses, each a fresh start (no branch to follow between them).
        provider.restart();
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

/// The mass matrix whose undamped modes with `K = diag(k)` are `freq_hz` with strain shares
/// `v_fi²`, for the orthogonal `v` the Householder reflection that maps the first unit vector
/// to `first_row` (unit norm): `K^{-1/2} M K^{-1/2} = V diag(1/ω²) Vᵀ` (module docs of
/// `modal_map`), so `M = K^{1/2} V diag(1/ω²) Vᵀ K^{1/2}`. Built forward from the modes, the
/// inverse of what the map solves.
fn mass_with_modes(k: [f64; 3], freq_hz: [f64; 3], first_row: [f64; 3]) -> [f64; 9] {
    let u = [1.0 - first_row[0], -first_row[1], -first_row[2]];
    let uu: f64 = u.iter().map(|x| x * x).sum();
    let v = |r: usize, c: usize| f64::from(u8::from(r == c)) - 2.0 * u[r] * u[c] / uu;
    let inv_w2 = freq_hz.map(|f| (2.0 * std::f64::consts::PI * f).powi(-2));
    let mut m = [0.0; 9];
    for r in 0..3 {
        for c in 0..3 {
            let b: f64 = (0..3).map(|i| v(r, i) * inv_w2[i] * v(c, i)).sum();
            m[3 * r + c] = (k[r] * k[c]).sqrt() * b;
        }
    }
    m
}

#[test]
fn far_apart_modes_sharing_the_base_are_not_blended() {
    // A pose of an arm whose base strains two modes far apart: 17.02 Hz with base share 0.49
    // and 34.96 Hz with base share 0.37 (the rest, 0.14, in a 52 Hz mode). Weighting every
    // eigenmode by share⁴ reported a 21.41 Hz "base mode", which is neither; the base mode
    // is the dominant eigenmode, 17.02 Hz. Undamped, so the solved frequencies are the
    // undamped ones: exact to rounding (1e-9 relative is far above it).
    let shares: [f64; 3] = [0.49, 0.37, 0.14];
    let k = [26_000.0, 22_000.0, 15_000.0];
    let freq_hz = [17.02, 34.96, 52.0];
    let mass = mass_with_modes(k, freq_hz, shares.map(f64::sqrt));
    let map = ModalMap::new(
        vec![
            flex_joint(0, k[0], 0.0),
            flex_joint(1, k[1], 0.0),
            flex_joint(2, k[2], 0.0),
        ],
        &[0],
    )
    .expect("valid");
    let sol = map.solve(&mass, 3, &[]).expect("positive definite");
    // The data are what they claim: the solver finds the three modes and the base shares.
    for (f, s) in freq_hz.iter().zip(shares) {
        let i = (0..3)
            .find(|&i| (sol.wn_rad_s[i] / (2.0 * std::f64::consts::PI) / f - 1.0).abs() < 1e-9)
            .expect("the mode is found");
        assert!((sol.strain_share[i][0] - s).abs() < 1e-9, "{sol:?}");
    }
    let mut out = [Mode::new(0.0, 0.0)];
    assert!(map.modes_from_mass_matrix(&mass, 3, &[], &mut out).is_ok());
    let base_hz = out[0].wn_rad_s / (2.0 * std::f64::consts::PI);
    assert!(
        (base_hz / 17.02 - 1.0).abs() < 1e-9,
        "base mode {base_hz} Hz"
    );
}

#[test]
fn the_tracked_mode_is_continuous_through_a_veering_swap() {
    // Base (J 4) and shoulder (J 6) coupled at 2 % (|M_01| / √(M_00 M_11)): sweeping the base
    // stiffness takes the two branches through a veering, where the base-dominated
    // eigenmode swaps branch. The tracked slot hands over from one branch to the other by
    // HANDOVER_STEP (0.4 %) per step, on top of what the sweep moves the frequencies (0.125 %
    // in k is 0.06 % in ω), instead of the ~2 % jump between the branches. Bound: 0.5 %.
    let m01 = 0.02 * 24f64.sqrt();
    let mass = [4.0, m01, m01, 6.0];
    let mut previous: Option<Mode> = None;
    let mut swapped = false;
    let mut previous_dominant: Option<usize> = None;
    let mut track = ModeTrack::default();
    for step in 0..=400 {
        let k_base = 1.0e4 + 12.5 * step as f64;
        let map = ModalMap::new(
            vec![flex_joint(0, k_base, 0.0), flex_joint(1, 1.8e4, 0.0)],
            &[0],
        )
        .expect("valid");
        let mut out = [Mode::new(0.0, 0.0)];
        map.modes_tracked(&mass, 2, &[], &mut track, &mut out);
        let sol = map.solve(&mass, 2, &[]).expect("valid");
        let dominant = usize::from(sol.strain_share[1][0] > sol.strain_share[0][0]);
        // The solver's order may follow the branches or not: compare frequencies.
        let branch = usize::from(sol.wn_rad_s[dominant] > sol.wn_rad_s[1 - dominant]);
        swapped |= previous_dominant.is_some_and(|p| p != branch);
        previous_dominant = Some(branch);
        if let Some(prev) = previous {
            let change = (out[0].wn_rad_s / prev.wn_rad_s - 1.0).abs();
            assert!(
                change < 0.005,
                "base mode jumped by {change} at step {step}"
            );
        }
        previous = Some(out[0]);
    }
    assert!(swapped, "the sweep must take the base through the swap");
}

#[test]
fn shaped_modes_are_the_lowest_frequencies_in_order() {
    // Frequency-ranked selection: the K lowest eigenmodes of the closed-form 2 × 2 problem,
    // whatever joint dominates them (in slots by joint, so compared as a set), each an
    // eigenmode as it is. Tolerance as in the characteristic-equation test.
    let mut rng = robot_support::Rng(5);
    for _ in 0..200 {
        let (m11, m22) = (0.5 + 10.0 * rng.next_f64(), 0.5 + 10.0 * rng.next_f64());
        let m12 = 0.9 * (2.0 * rng.next_f64() - 1.0) * (m11 * m22).sqrt();
        let (k1, k2) = (1e3 + 1e5 * rng.next_f64(), 1e3 + 1e5 * rng.next_f64());
        let flex = vec![flex_joint(0, k1, 0.0), flex_joint(1, k2, 0.0)];
        let want = closed_form_w2([m11, m12, m12, m22], k1, k2);
        for k in 1..=2 {
            let map = ModalMap::shaping(flex.clone(), ShapedModes::Lowest(k)).expect("valid");
            assert_eq!(map.n_modes(), k);
            let mut out = vec![Mode::new(0.0, 0.0); k];
            assert!(map
                .modes_from_mass_matrix(&[m11, m12, m12, m22], 2, &[], &mut out)
                .is_ok());
            let mut got: Vec<f64> = out.iter().map(|o| o.wn_rad_s.powi(2)).collect();
            got.sort_by(f64::total_cmp);
            for (g, w) in got.iter().zip(&want) {
                assert!((g / w - 1.0).abs() < 1e-10, "{out:?} vs {want:?}");
            }
        }
    }
    // 0 and more modes than flexible joints are refused.
    let flex = vec![flex_joint(0, 1.0, 0.0), flex_joint(1, 1.0, 0.0)];
    assert!(ModalMap::shaping(flex.clone(), ShapedModes::Lowest(0)).is_err());
    assert!(ModalMap::shaping(flex.clone(), ShapedModes::Lowest(3)).is_err());
    let two = ModalMap::new(flex, &[0]).expect("valid");
    assert_eq!(two.shaping_lowest(2).expect("valid").n_modes(), 2);
    assert!(two.shaping_lowest(3).is_err());
}
