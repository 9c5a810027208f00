//! Joints placed as URDF places them (origin, then a turn about an axis) give the same model
//! as the DH chain they describe: mass matrix, joint inertias (general and inertia-only
//! passes), gravity torques, flange pose and Jacobian, whatever link frames the description
//! chooses. (A first joint off the gravity axis is checked against pinocchio in the Python
//! tests, on a shipped arm whose description tilts it.)

mod robot_support;

use robot_support::{ur_robot, ur_robot_placed, Rng, GENERAL_TURNS};
use tvist_core::{RigidBody, Robot};

/// Largest difference of every quantity of `a` and `b` over `poses`, each relative to the
/// largest magnitude of that quantity over the poses.
fn largest_relative_difference(a: &mut Robot, b: &mut Robot, poses: &[Vec<f64>]) -> f64 {
    let n = a.n_dof();
    let mut worst: f64 = 0.0;
    type Eval = fn(&mut Robot, &[f64], &mut [f64]);
    let evals: [(usize, Eval); 6] = [
        (n * n, |r, q, o| {
            r.mass_matrix(q, o);
        }),
        (n, |r, q, o| {
            r.joint_inertia(q, o);
        }),
        (n, |r, q, o| {
            r.gravity_torque(q, o);
        }),
        (n, |r, q, o| {
            // The inertia-only pass of the leading three joints (what maps read).
            r.leading_joint_inertia_and_gravity(q, 3, o, None);
        }),
        (6 * n, |r, q, o| {
            r.jacobian(q, o);
        }),
        (16, |r, q, o| {
            let mut pose = [0.0; 16];
            r.flange_pose(q, &mut pose);
            o.copy_from_slice(&pose);
        }),
    ];
    for (width, eval) in evals {
        let (mut x, mut y) = (vec![0.0; width], vec![0.0; width]);
        let (mut scale, mut diff): (f64, f64) = (0.0, 0.0);
        for q in poses {
            eval(a, q, &mut x);
            eval(b, q, &mut y);
            for (u, v) in x.iter().zip(&y) {
                scale = scale.max(u.abs());
                diff = diff.max((u - v).abs());
            }
        }
        worst = worst.max(diff / scale);
    }
    worst
}

#[test]
fn ur_arms_placed_as_urdf_equal_their_dh_chains() {
    let mut rng = Rng(11);
    let poses: Vec<Vec<f64>> = (0..500).map(|_| rng.pose(6)).collect();
    for name in ["ur3e", "ur5e", "ur10e", "ur16e", "ur20", "ur5"] {
        let mut dh = ur_robot(name, 3.0);
        // Link frames along the DH frames (DH steps) and turned every which way (general).
        for turns in [&[][..], &GENERAL_TURNS[..]] {
            let mut placed = ur_robot_placed(name, 3.0, turns);
            let d = largest_relative_difference(&mut dh, &mut placed, &poses);
            // Tolerance: the two forms associate the same sums differently and the placed one
            // goes through rpy angles and back; 1e-13 of each quantity's scale is a few
            // hundred ulp, far below any modelling error (a wrong sign or frame gives O(1)).
            assert!(d <= 1e-13, "{name} with turns {turns:?}: {d:e}");
        }
    }
}

#[test]
fn a_payload_replaced_later_matches_one_given_at_setup() {
    let mut placed = ur_robot_placed("ur5e", 0.0, &GENERAL_TURNS);
    placed
        .set_payload(RigidBody::point(3.0, [0.0, 0.0, 0.05]))
        .expect("valid payload");
    let mut dh = ur_robot("ur5e", 3.0);
    let poses: Vec<Vec<f64>> = (0..50).map(|_| Rng(3).pose(6)).collect();
    let d = largest_relative_difference(&mut dh, &mut placed, &poses);
    assert!(d <= 1e-13, "{d:e}");
}
