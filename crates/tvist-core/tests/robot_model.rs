//! Robot model, dynamic map and map-driven provider: properties, cross-checks and bad input.
//!
//! The exact comparison against an independent rigid-body library (pinocchio) is in
//! `tests/reference/test_robots.py`; here the model is checked against identities that any
//! correct implementation satisfies, with independent arithmetic.

mod robot_support;

use robot_support::{ur_chain, ur_robot, Rng};
use std::f64::consts::PI;
use tvist_core::{
    DhJoint, DynamicMap, Dynamics, Error, MapCoefficients, MapDynamics, Mode, ModeMap, RigidBody,
    Robot, ShaperKind, Status, TvShaper, TvShaperConfig,
};

const ROBOTS: [&str; 8] = [
    "ur3e", "ur5e", "ur10e", "ur16e", "ur20", "ur3", "ur5", "ur10",
];

fn mass_matrix(robot: &mut Robot, q: &[f64]) -> Vec<f64> {
    let n = robot.n_dof();
    let mut m = vec![0.0; n * n];
    assert!(robot.mass_matrix(q, &mut m).is_ok());
    m
}

fn pose(robot: &mut Robot, q: &[f64]) -> [f64; 16] {
    let mut t = [0.0; 16];
    assert!(robot.flange_pose(q, &mut t).is_ok());
    t
}

/// Cholesky succeeds with positive pivots: `m` (row-major n×n) is positive definite.
fn is_positive_definite(m: &[f64], n: usize) -> bool {
    let mut l = vec![0.0; n * n];
    for i in 0..n {
        for j in 0..=i {
            let s: f64 = (0..j).map(|k| l[i * n + k] * l[j * n + k]).sum();
            if i == j {
                let d = m[i * n + i] - s;
                if d <= 0.0 {
                    return false;
                }
                l[i * n + i] = d.sqrt();
            } else {
                l[i * n + j] = (m[i * n + j] - s) / l[j * n + j];
            }
        }
    }
    true
}

#[test]
fn mass_matrix_is_symmetric_positive_definite_with_diagonal_joint_inertia() {
    let mut rng = Rng(0x1234_5678);
    for name in ROBOTS {
        let mut robot = ur_robot(name, 3.0);
        let n = robot.n_dof();
        for _ in 0..200 {
            let q = rng.pose(n);
            let m = mass_matrix(&mut robot, &q);
            let mut j = vec![0.0; n];
            assert!(robot.joint_inertia(&q, &mut j).is_ok());
            for r in 0..n {
                // Same arithmetic path for the diagonal: equal to round-off (1e-12 relative).
                assert!(
                    (m[r * n + r] - j[r]).abs() <= 1e-12 * j[r].abs().max(1.0),
                    "{name}"
                );
                for c in 0..n {
                    assert_eq!(m[r * n + c], m[c * n + r], "{name}: M symmetric");
                }
            }
            assert!(
                is_positive_definite(&m, n),
                "{name}: M positive definite at {q:?}"
            );
        }
    }
}

#[test]
fn jacobian_matches_finite_differences_of_the_flange_pose() {
    let mut rng = Rng(42);
    let h = 1e-6;
    for name in ROBOTS {
        let mut robot = ur_robot(name, 0.0);
        let n = robot.n_dof();
        for _ in 0..50 {
            let q = rng.pose(n);
            let mut jac = vec![0.0; 6 * n];
            assert!(robot.jacobian(&q, &mut jac).is_ok());
            let t0 = pose(&mut robot, &q);
            for i in 0..n {
                let (mut qp, mut qm) = (q.clone(), q.clone());
                qp[i] += h;
                qm[i] -= h;
                let (tp, tm) = (pose(&mut robot, &qp), pose(&mut robot, &qm));
                // Linear part: d p / d q_i.
                for k in 0..3 {
                    let fd = (tp[4 * k + 3] - tm[4 * k + 3]) / (2.0 * h);
                    // Central difference error ~ h² |p'''| ≈ 1e-12 m plus round-off 1e-16/h.
                    assert!((jac[k * n + i] - fd).abs() < 1e-8, "{name} lin {k},{i}");
                }
                // Angular part: skew(ω) = dR/dq_i · Rᵀ.
                let mut dr = [0.0; 9];
                for r in 0..3 {
                    for c in 0..3 {
                        dr[3 * r + c] = (tp[4 * r + c] - tm[4 * r + c]) / (2.0 * h);
                    }
                }
                let w = |r: usize, c: usize| -> f64 {
                    (0..3).map(|k| dr[3 * r + k] * t0[4 * c + k]).sum::<f64>()
                };
                let omega = [w(2, 1), w(0, 2), w(1, 0)];
                for k in 0..3 {
                    assert!(
                        (jac[(k + 3) * n + i] - omega[k]).abs() < 1e-8,
                        "{name} ang {k},{i}"
                    );
                }
            }
        }
    }
}

/// Massless links and a point payload at the flange origin: `M = m J_vᵀ J_v` and
/// `τ_g = m g J_v[z, :]`, an identity independent of the composite-body algebra.
#[test]
fn leading_joint_inertias_and_gravity_equal_the_full_evaluation() {
    let mut rng = Rng(0xBEEF);
    for name in ROBOTS {
        let mut robot = ur_robot(name, 4.0);
        let n = robot.n_dof();
        for _ in 0..100 {
            let q = rng.pose(n);
            let (mut j_all, mut tau_all) = (vec![0.0; n], vec![0.0; n]);
            assert!(robot.gravity_torque(&q, &mut tau_all).is_ok());
            assert!(robot.joint_inertia(&q, &mut j_all).is_ok());
            for joints in 0..=n {
                let (mut j, mut tau) = (vec![f64::NAN; n], vec![f64::NAN; n]);
                let status =
                    robot.leading_joint_inertia_and_gravity(&q, joints, &mut j, Some(&mut tau));
                assert!(status.is_ok());
                for i in 0..n {
                    if i < joints {
                        // Per-body sums (joint 0 at angle 0: both quantities are independent
                        // of it) against the composite-body algorithm: independent arithmetic,
                        // equal to round-off. The composite algorithm sums inertias about the
                        // base origin, so its rounding is relative to the largest, J_0.
                        let tol = 1e-12 * j_all[0];
                        assert!((j[i] - j_all[i]).abs() <= tol, "{name} J{i}");
                        let scale = tau_all[i].abs().max(1.0);
                        assert!((tau[i] - tau_all[i]).abs() <= 1e-12 * scale, "{name} τ{i}");
                    } else {
                        assert!(j[i].is_nan() && tau[i].is_nan(), "{name}: {i} was written");
                    }
                }
            }
        }
        let mut j = vec![0.0; n];
        let status = robot.leading_joint_inertia_and_gravity(&vec![0.0; n], n + 1, &mut j, None);
        assert_eq!(status, Status::BAD_LENGTH);
    }
}

#[test]
fn point_payload_mass_matrix_and_gravity_follow_from_the_jacobian() {
    let mut rng = Rng(7);
    let m_kg = 2.5;
    for name in ROBOTS {
        let (joints, links) = ur_chain(name);
        let massless = vec![RigidBody::NONE; links.len()];
        let mut robot =
            Robot::new(joints, massless, RigidBody::point(m_kg, [0.0; 3])).expect("valid robot");
        let n = robot.n_dof();
        for _ in 0..50 {
            let q = rng.pose(n);
            let m = mass_matrix(&mut robot, &q);
            let mut jac = vec![0.0; 6 * n];
            assert!(robot.jacobian(&q, &mut jac).is_ok());
            let mut tau = vec![0.0; n];
            assert!(robot.gravity_torque(&q, &mut tau).is_ok());
            for r in 0..n {
                for c in 0..n {
                    let want: f64 =
                        m_kg * (0..3).map(|k| jac[k * n + r] * jac[k * n + c]).sum::<f64>();
                    assert!((m[r * n + c] - want).abs() < 1e-12, "{name} M[{r},{c}]");
                }
                let want = m_kg * tvist_core::robot::model::GRAVITY_M_S2 * jac[2 * n + r];
                assert!((tau[r] - want).abs() < 1e-11, "{name} tau[{r}]");
            }
        }
    }
}

#[test]
fn payload_equals_merging_it_into_the_last_link() {
    let (joints, mut links) = ur_chain("ur5e");
    let payload = RigidBody {
        mass_kg: 2.0,
        com_m: [0.01, -0.02, 0.07],
        inertia_kg_m2: [0.004, 0.005, 0.003, 0.0002, -0.0001, 0.0003],
    };
    let mut with_payload = Robot::new(joints.clone(), links.clone(), payload).expect("valid");
    let last = links.len() - 1;
    links[last] = links[last].combined(&payload);
    let mut merged = Robot::new(joints, links, RigidBody::NONE).expect("valid");
    let q = [0.3, -1.2, 0.7, -0.4, 1.1, 0.2];
    let (a, b) = (
        mass_matrix(&mut with_payload, &q),
        mass_matrix(&mut merged, &q),
    );
    assert_eq!(a, b);
}

#[test]
fn heavier_payload_raises_every_joint_inertia() {
    let q = [0.0, -PI, 0.0, -PI / 2.0, 0.0, 0.0];
    let (mut light, mut heavy) = (ur_robot("ur5e", 0.0), ur_robot("ur5e", 5.0));
    let (mut jl, mut jh) = ([0.0; 6], [0.0; 6]);
    light.joint_inertia(&q, &mut jl);
    heavy.joint_inertia(&q, &mut jh);
    // Joint 5 turns about the flange z axis, on which the point payload lies: no change.
    for i in 0..5 {
        assert!(jh[i] > jl[i], "J_{i}: {} vs {}", jh[i], jl[i]);
    }
    // Exact answer is zero; the CRBA sums payload terms of ~3.6 kg m² through the chain, so a
    // few roundings (~1e-15 each) remain. A real payload effect would be above 1e-6.
    assert!((jh[5] - jl[5]).abs() < 1e-13, "J_5: {} vs {}", jh[5], jl[5]);
}

#[test]
fn inertia_bounds_hold_over_random_poses() {
    let mut rng = Rng(99);
    for name in ROBOTS {
        let mut robot = ur_robot(name, 5.0);
        let bound = robot.joint_inertia_upper_bound();
        let tau_bound = robot.gravity_torque_upper_bound();
        let n = robot.n_dof();
        let (mut j, mut tau) = (vec![0.0; n], vec![0.0; n]);
        for _ in 0..500 {
            let q = rng.pose(n);
            robot.joint_inertia_and_gravity(&q, &mut j, Some(&mut tau));
            for i in 0..n {
                assert!(j[i] <= bound[i], "{name} J_{i}");
                assert!(tau[i].abs() <= tau_bound[i], "{name} tau_{i}");
            }
        }
    }
}

#[test]
fn wrong_lengths_report_bad_length_and_leave_outputs_alone() {
    let mut robot = ur_robot("ur5e", 0.0);
    let mut out = [7.0; 6];
    assert_eq!(robot.joint_inertia(&[0.0; 5], &mut out), Status::BAD_LENGTH);
    assert_eq!(
        robot.joint_inertia(&[0.0; 6], &mut out[..5]),
        Status::BAD_LENGTH
    );
    assert_eq!(
        robot.gravity_torque(&[0.0; 7], &mut out),
        Status::BAD_LENGTH
    );
    assert_eq!(
        robot.mass_matrix(&[0.0; 6], &mut [0.0; 35]),
        Status::BAD_LENGTH
    );
    assert_eq!(
        robot.jacobian(&[0.0; 6], &mut [0.0; 35]),
        Status::BAD_LENGTH
    );
    assert_eq!(
        robot.flange_pose(&[0.0; 3], &mut [0.0; 16]),
        Status::BAD_LENGTH
    );
    let mut tau = [0.0; 4];
    assert_eq!(
        robot.joint_inertia_and_gravity(&[0.0; 6], &mut out, Some(&mut tau)),
        Status::BAD_LENGTH
    );
    assert_eq!(out, [7.0; 6]);
}

fn expect_invalid(result: Result<Robot, Error>, needle: &str) {
    let err = result.expect_err("an invalid robot must be rejected");
    assert!(
        err.to_string().contains(needle),
        "{err} does not mention {needle:?}"
    );
}

#[test]
fn robot_construction_rejects_bad_input() {
    let (joints, links) = ur_chain("ur5e");
    let ok_payload = RigidBody::NONE;
    expect_invalid(Robot::new(vec![], vec![], ok_payload), "at least one joint");
    expect_invalid(
        Robot::new(joints.clone(), links[..5].to_vec(), ok_payload),
        "number of links",
    );

    let mut bad = joints.clone();
    bad[2] = DhJoint::new(f64::NAN, 0.0, 0.0);
    expect_invalid(Robot::new(bad, links.clone(), ok_payload), "joint 2");

    let with_link = |i: usize, body: RigidBody| {
        let mut l = links.clone();
        l[i] = body;
        Robot::new(joints.clone(), l, ok_payload)
    };
    expect_invalid(
        with_link(1, RigidBody::point(-1.0, [0.0; 3])),
        "mass_kg = -1",
    );
    expect_invalid(
        with_link(3, RigidBody::point(1.0, [0.0, f64::NAN, 0.0])),
        "finite",
    );
    let not_psd = RigidBody {
        mass_kg: 1.0,
        com_m: [0.0; 3],
        inertia_kg_m2: [1.0, 1.0, 1.0, 2.0, 0.0, 0.0],
    };
    expect_invalid(with_link(0, not_psd), "positive semi-definite");
    let triangle = RigidBody {
        mass_kg: 1.0,
        com_m: [0.0; 3],
        inertia_kg_m2: [0.1, 0.1, 0.5, 0.0, 0.0, 0.0],
    };
    expect_invalid(with_link(0, triangle), "triangle inequality");
    let massless = RigidBody {
        mass_kg: 0.0,
        com_m: [0.0; 3],
        inertia_kg_m2: [0.1, 0.1, 0.1, 0.0, 0.0, 0.0],
    };
    expect_invalid(with_link(4, massless), "massless");
    expect_invalid(
        Robot::new(
            joints.clone(),
            links.clone(),
            RigidBody::point(-5.0, [0.0; 3]),
        ),
        "payload",
    );
    let mut robot = Robot::new(joints, links, ok_payload).expect("valid");
    assert!(robot
        .set_payload(RigidBody::point(f64::INFINITY, [0.0; 3]))
        .is_err());
    // A failed set_payload keeps the old payload.
    assert_eq!(robot.payload().mass_kg, 0.0);
}

#[test]
fn paper_map_reproduces_table_3_at_q3() {
    // SPEC section 3: Q3 (J0, J1) = (1.12, 1.58) -> 22.026 Hz / 0.0772, 19.220 Hz / 0.1357.
    let map = DynamicMap::paper_ur5e();
    let mut out = [Mode::new(0.0, 0.0); 2];
    assert!(map.modes_from_inertia(&[1.12, 1.58], &[], &mut out).is_ok());
    let fd = |m: Mode| m.wd_rad_s() / (2.0 * PI);
    // 1e-3 relative: the reference values are given to 4-5 significant digits.
    for (got, want) in [
        (fd(out[0]), 22.026),
        (out[0].zeta, 0.0772),
        (fd(out[1]), 19.220),
        (out[1].zeta, 0.1357),
    ] {
        assert!((got / want - 1.0).abs() < 1e-3, "{got} vs {want}");
    }
}

#[test]
fn base_frequency_from_j0_is_expressible() {
    // Eq. 46: the general form with J = J_0 depends on J_0 only.
    let c = MapCoefficients::reduced(10_000.0, 1060.0, 2.54, 1.53, 0.39, 3.81);
    let map = DynamicMap::new(vec![ModeMap::general(c, 0)]).expect("valid");
    let mut a = [Mode::new(0.0, 0.0)];
    let mut b = [Mode::new(0.0, 0.0)];
    map.modes_from_inertia(&[2.0, 5.0], &[], &mut a);
    map.modes_from_inertia(&[2.0, 9.0], &[], &mut b);
    assert_eq!(a, b);
    let j: f64 = 2.0;
    let wn = ((1.0 + 2.54 / j) * (10_000.0 + 1060.0 * j) / j).sqrt();
    assert!((a[0].wn_rad_s - wn).abs() < 1e-12 * wn);
}

#[test]
fn gravity_term_uses_the_frequency_joints_torque() {
    let c = MapCoefficients {
        k_g: 50.0,
        c_1: 0.2,
        ..MapCoefficients::reduced(1e4, 800.0, 2.0, 1.0, 0.1, 3.0)
    };
    let map = DynamicMap::new(vec![ModeMap::general(c, 1)]).expect("valid");
    assert!(map.uses_gravity());
    let mut out = [Mode::new(0.0, 0.0)];
    // Gravity torques missing: bad length, not a silent zero.
    assert_eq!(
        map.modes_from_inertia(&[3.0, 4.0], &[], &mut out),
        Status::BAD_LENGTH
    );
    assert!(map
        .modes_from_inertia(&[3.0, 4.0], &[0.0, -20.0], &mut out)
        .is_ok());
    let (j, tau) = (4.0f64, 20.0f64);
    // |τ| smoothed with τ_s = 1 N m (modes::paper10::dynamic_map module docs, "Gravity term").
    let k = 1e4 + 800.0 * j + 50.0 * ((tau * tau + 1.0).sqrt() - 1.0);
    let wn = ((1.0 + 2.0 / j) * k / j).sqrt();
    let zeta = (1.0 + 2.0 / j).sqrt() * (1.0 + 0.2 * j.sqrt() + 0.1 * j) * (1.0 + 3.0 * j)
        / (2.0 * (k * j).sqrt());
    assert!((out[0].wn_rad_s - wn).abs() < 1e-12 * wn);
    assert!((out[0].zeta - zeta).abs() < 1e-12 * zeta);
}

#[test]
fn dynamic_map_rejects_bad_coefficients() {
    assert!(DynamicMap::new(vec![]).is_err());
    let mut c = MapCoefficients::reduced(1e4, 800.0, 2.0, 1.0, 0.1, 3.0);
    c.c_tau = f64::NAN;
    let err = DynamicMap::new(vec![ModeMap::general(c, 1)]).expect_err("NaN coefficient");
    assert!(err.to_string().contains("c_tau"), "{err}");
    let mut m = ModeMap::general(MapCoefficients::reduced(1e4, 800.0, 2.0, 1.0, 0.1, 3.0), 1);
    m.damping_gain_exponent = f64::INFINITY;
    assert!(DynamicMap::new(vec![m]).is_err());
}

#[test]
fn map_dynamics_rejects_maps_invalid_in_the_workspace() {
    let robot = ur_robot("ur5e", 5.0);
    // Non-positive stiffness everywhere: no such map exists (the map's own sign rules).
    let soft = MapCoefficients::reduced(-1e6, 0.0, 2.0, 1.0, 0.1, 3.0);
    let err = DynamicMap::new(vec![ModeMap::general(soft, 1)]).expect_err("negative stiffness");
    assert!(err.to_string().contains("the stiffness"), "{err}");
    // Overdamped (zeta >= 1) somewhere: huge damping coefficient.
    let damped = MapCoefficients::reduced(1e4, 800.0, 2.0, 1e4, 0.1, 3.0);
    assert!(MapDynamics::new(
        robot.clone(),
        DynamicMap::new(vec![ModeMap::general(damped, 1)]).expect("finite")
    )
    .is_err());
    // The shoulder's coefficients on joint 5 (J_5 ~ 3e-4 kg m²): (1 + k_p/J) ~ 7000 drives
    // zeta far above 1, so that map is rejected too.
    let shoulder = MapCoefficients::reduced(1e4, 763.0, 1.73, 0.27, 0.038, 47.2);
    assert!(MapDynamics::new(
        robot.clone(),
        DynamicMap::new(vec![ModeMap::general(shoulder, 5)]).expect("finite")
    )
    .is_err());
    // A joint the robot does not have.
    let err = MapDynamics::new(
        robot,
        DynamicMap::new(vec![ModeMap::general(shoulder, 6)]).expect("finite"),
    )
    .expect_err("joint 6 of 6");
    assert!(
        err.to_string().contains("joints read by the dynamic map"),
        "{err}"
    );
}

#[test]
fn slowest_mode_bounds_the_frequency_at_random_poses() {
    let mut rng = Rng(2024);
    let mut provider =
        MapDynamics::new(ur_robot("ur5e", 5.0), DynamicMap::paper_ur5e()).expect("valid");
    let slowest: Vec<Mode> = (0..2)
        .map(|m| provider.slowest_mode(m).expect("bounded"))
        .collect();
    let mut modes = [Mode::new(0.0, 0.0); 2];
    for _ in 0..2000 {
        let q = rng.pose(6);
        assert!(provider.modes(&q, &mut modes).is_ok());
        for m in 0..2 {
            assert!(modes[m].is_valid());
            assert!(
                modes[m].wn_rad_s >= slowest[m].wn_rad_s,
                "mode {m} at {q:?}"
            );
        }
    }
}

#[test]
fn map_dynamics_reports_bad_q_and_the_shaper_holds_the_mode() {
    let provider =
        MapDynamics::new(ur_robot("ur5e", 5.0), DynamicMap::paper_ur5e()).expect("valid");
    let mut modes = [Mode::new(0.0, 0.0); 2];
    let mut p = provider.clone();
    assert_eq!(p.modes(&[0.0; 5], &mut modes), Status::BAD_LENGTH);
    assert!(!modes[0].is_valid() && !modes[1].is_valid());

    let config = TvShaperConfig::new(0.002, 6, ShaperKind::Zv);
    let mut shaper = TvShaper::new(provider, &config).expect("valid");
    let q1 = [0.0, -PI, 0.0, -PI / 2.0, 0.0, 0.0];
    let mut out = [0.0; 6];
    assert!(shaper.step(&q1, &mut out).is_ok());
    let held = shaper.current_modes().to_vec();
    assert!(held.iter().all(Mode::is_valid));
    let delay = shaper.delay_s();
    // A NaN input is held by the shaper itself; the modes stay valid.
    let mut bad = q1;
    bad[1] = f64::NAN;
    let status = shaper.step(&bad, &mut out);
    assert!(status.contains(Status::INPUT_HELD));
    assert!(out.iter().all(|v| v.is_finite()));
    assert_eq!(shaper.delay_s(), delay);
}

#[test]
fn shaper_with_map_has_the_map_delay_at_rest() {
    let provider =
        MapDynamics::new(ur_robot("ur5e", 5.0), DynamicMap::paper_ur5e()).expect("valid");
    let mut expected = [Mode::new(0.0, 0.0); 2];
    let mut probe = provider.clone();
    let q = [0.4, -2.0, 1.0, -1.0, 0.5, 0.0];
    probe.modes(&q, &mut expected);
    let config = TvShaperConfig::new(0.002, 6, ShaperKind::Zv);
    let mut shaper = TvShaper::new(provider, &config).expect("valid");
    let mut out = [0.0; 6];
    for _ in 0..10 {
        assert!(shaper.step(&q, &mut out).is_ok());
    }
    // ZV delay pi / w_d per mode, summed over the cascade.
    let want: f64 = expected.iter().map(|m| PI / m.wd_rad_s()).sum();
    assert!(
        (shaper.delay_s() - want).abs() < 1e-12,
        "{} vs {want}",
        shaper.delay_s()
    );
    // At rest the output is the input times the sum of the impulse weights, 1 up to the
    // rounding of the weights designed from these modes: within 2 ulp of each joint value.
    for (o, x) in out.iter().zip(&q) {
        assert!(
            (o - x).abs() <= 2.0 * f64::EPSILON * x.abs(),
            "{out:?} vs {q:?}"
        );
    }
}

/// A pose bit-identical to the previous one returns the stored modes: the same modes and
/// status as a fresh evaluation; any other pose (one ulp away, or a NaN) is evaluated.
#[test]
fn a_repeated_pose_gives_the_modes_of_a_fresh_evaluation() {
    let make = || MapDynamics::new(ur_robot("ur5e", 5.0), DynamicMap::paper_ur5e()).expect("valid");
    let mut provider = make();
    let mut rng = Rng(99);
    let (mut got, mut again, mut fresh) = (
        [Mode::new(0.0, 0.0); 2],
        [Mode::new(0.0, 0.0); 2],
        [Mode::new(0.0, 0.0); 2],
    );
    for _ in 0..50 {
        let q = rng.pose(6);
        let status = provider.modes(&q, &mut got);
        assert_eq!(provider.modes(&q, &mut again), status);
        assert_eq!(again, got);
        assert_eq!(make().modes(&q, &mut fresh), status);
        assert_eq!(fresh, got);
        // One ulp away in the last joint: evaluated anew, equal to a fresh evaluation.
        let mut near = q.clone();
        near[5] = f64::from_bits(near[5].to_bits() + 1);
        provider.modes(&near, &mut again);
        make().modes(&near, &mut fresh);
        assert_eq!(again, fresh);
    }
    let mut bad = vec![0.3; 6];
    bad[2] = f64::NAN;
    provider.modes(&bad, &mut got);
    assert!(got.iter().all(|m| !m.is_valid()));
    provider.modes(&bad, &mut again);
    assert!(again.iter().all(|m| !m.is_valid()));
}
