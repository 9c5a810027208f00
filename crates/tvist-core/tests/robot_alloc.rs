//! The robot model, the dynamic map and the map-driven shaper never allocate per call.
//!
//! Its own test binary with a counting global allocator. Only allocations made by the
//! measuring thread inside a measured window are counted (a const thread-local flag), so the
//! test harness's own threads cannot disturb the count.

mod robot_support;

mod alloc_support;

use alloc_support::{allocations_in, the_counter_sees_this_thread_only};
use tvist_core::{DynamicMap, MapDynamics, Mode, ShaperKind};

#[test]
fn robot_map_and_map_shaper_never_allocate() {
    the_counter_sees_this_thread_only();

    // The DH chain, and the same arm placed as URDF places it: along the DH frames (DH
    // steps), in turned link frames (general steps) and with its first joint tilted.
    let robots = [
        robot_support::ur_robot("ur5e", 5.0),
        robot_support::ur_robot_placed("ur5e", 5.0, &[]),
        robot_support::ur_robot_placed("ur5e", 5.0, &robot_support::GENERAL_TURNS),
        robot_support::ur_robot_tilted("ur5e", 5.0),
    ];
    let mut rng = robot_support::Rng(5);
    let poses: Vec<Vec<f64>> = (0..200).map(|_| rng.pose(6)).collect();
    for mut robot in robots.clone() {
        let (mut m, mut jac, mut j, mut tau, mut pose) =
            ([0.0; 36], [0.0; 36], [0.0; 6], [0.0; 6], [0.0; 16]);
        let n = allocations_in(|| {
            for q in &poses {
                robot.mass_matrix(q, &mut m);
                robot.jacobian(q, &mut jac);
                robot.joint_inertia(q, &mut j);
                robot.gravity_torque(q, &mut tau);
                robot.flange_pose(q, &mut pose);
                robot.joint_inertia_and_gravity(q, &mut j, Some(&mut tau));
                robot.leading_joint_inertia_and_gravity(q, 2, &mut j, Some(&mut tau));
                robot.leading_mass_matrix_and_gravity(q, 3, &mut m, Some(&mut tau));
                // The inertia-only pass, for every number of joints read.
                for joints in 0..=6 {
                    robot.leading_joint_inertia_and_gravity(q, joints, &mut j, None);
                }
            }
            // An angle beyond the inline sine's range takes the general pass.
            robot.leading_joint_inertia_and_gravity(
                &[0.0, 0.0, 2.0e5, 0.0, 0.0, 0.0],
                2,
                &mut j,
                None,
            );
            // Wrong lengths and NaN poses take the same allocation-free path.
            robot.mass_matrix(&[0.0; 5], &mut m);
            robot.joint_inertia(&[f64::NAN; 6], &mut j);
        });
        assert_eq!(n, 0, "robot model allocated {n} times");
    }

    let map = DynamicMap::paper_ur5e();
    let mut modes = [Mode::new(0.0, 0.0); 2];
    let n = allocations_in(|| {
        map.modes_from_inertia(&[9.73, 9.25], &[], &mut modes);
        map.modes_from_inertia(&[-1.0, f64::NAN], &[], &mut modes);
        map.modes_from_inertia(&[1.0], &[], &mut modes);
    });
    assert_eq!(n, 0, "dynamic map allocated {n} times");

    for robot in robots {
        let provider = MapDynamics::new_allowing_other_robot(robot, DynamicMap::paper_ur5e())
            .expect("valid map");
        alloc_support::assert_robot_provider_never_allocates(
            provider,
            ShaperKind::Zvd,
            &poses,
            "MapDynamics",
        );
    }
}
