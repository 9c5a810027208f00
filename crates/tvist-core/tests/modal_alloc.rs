//! The modal map, its provider and the shaper driven by it never allocate per call.
//!
//! Its own test binary with a counting global allocator (see `alloc_support`).

mod robot_support;

mod alloc_support;

use alloc_support::{allocations_in, the_counter_sees_this_thread_only};
use tvist_core::{
    Dynamics, FlexJoint, LinkHinge, LoadLaw, ModalDynamics, ModalMap, Mode, ModeTrack, ShapedModes,
    ShaperKind, Status, TvShaper, TvShaperConfig,
};

fn ur5e_like_map() -> ModalMap {
    let law = |v0: f64, v1: f64, v2: f64| LoadLaw {
        at_zero: v0,
        per_nm: v1,
        per_nm2: v2,
    };
    ModalMap::new(
        vec![
            FlexJoint {
                joint: 0,
                stiffness_nm_per_rad: LoadLaw::constant(22_000.0),
                damping_nms_per_rad: law(5.0, 0.56, 0.0157),
                damping_load_joint: 1,
            },
            FlexJoint {
                joint: 1,
                stiffness_nm_per_rad: law(18_000.0, 0.0, 0.23),
                damping_nms_per_rad: law(60.0, 0.6, 0.0),
                damping_load_joint: 1,
            },
            FlexJoint {
                joint: 2,
                stiffness_nm_per_rad: LoadLaw::constant(120_000.0),
                damping_nms_per_rad: LoadLaw::constant(40.0),
                damping_load_joint: 2,
            },
        ],
        &[0, 1],
    )
    .expect("valid map")
}

#[test]
fn modal_map_provider_and_shaper_never_allocate() {
    the_counter_sees_this_thread_only();

    let map = ur5e_like_map();
    let mut modes = [Mode::new(0.0, 0.0); 2];
    let mass = [
        9.0, 0.1, 0.05, 0.0, 0.0, 0.0, //
        0.1, 8.0, 2.0, 0.0, 0.0, 0.0, //
        0.05, 2.0, 1.5, 0.0, 0.0, 0.0, //
        0.0, 0.0, 0.0, 0.1, 0.0, 0.0, //
        0.0, 0.0, 0.0, 0.0, 0.1, 0.0, //
        0.0, 0.0, 0.0, 0.0, 0.0, 0.01,
    ];
    let tau = [0.0, 40.0, 10.0, 1.0, 0.5, 0.0];
    let n = allocations_in(|| {
        map.modes_from_mass_matrix(&mass, 6, &tau, &mut modes);
        let _ = map.solve(&mass, 6, &tau);
        // Wrong lengths and non-finite input take the same allocation-free path.
        map.modes_from_mass_matrix(&mass[..30], 6, &tau, &mut modes);
        map.modes_from_mass_matrix(&[f64::NAN; 36], 6, &tau, &mut modes);
    });
    assert_eq!(n, 0, "ModalMap evaluation allocated {n} times");

    // The frequency-ranked selection (a sort of the eigenmodes) takes the same path.
    for k in 1..=3 {
        let lowest = map.shaping_lowest(k).expect("valid");
        assert_eq!(lowest.shaped_modes(), &ShapedModes::Lowest(k));
        let mut modes = vec![Mode::new(0.0, 0.0); k];
        let mut track = ModeTrack::default();
        let n = allocations_in(|| {
            lowest.modes_from_mass_matrix(&mass, 6, &tau, &mut modes);
            // Tracked: the first call picks by the rule, the next ones follow the branches.
            for _ in 0..3 {
                lowest.modes_tracked(&mass, 6, &tau, &mut track, &mut modes);
            }
            lowest.modes_tracked(&mass[..30], 6, &tau, &mut track, &mut modes);
            lowest.modes_tracked(&[f64::NAN; 36], 6, &tau, &mut track, &mut modes);
            lowest.modes_from_mass_matrix(&mass[..30], 6, &tau, &mut modes);
            lowest.modes_from_mass_matrix(&[f64::NAN; 36], 6, &tau, &mut modes);
        });
        assert_eq!(n, 0, "ModalMap (lowest {k}) evaluation allocated {n} times");
    }

    let mut rng = robot_support::Rng(11);
    let poses: Vec<Vec<f64>> = (0..200).map(|_| rng.pose(6)).collect();
    // The DH chain and the same arm placed as URDF places it (DH steps, general steps), each
    // with the joint-named modes and with the three lowest.
    // With bending upper arm and forearm: a 7-coordinate eigenproblem on the hinged arm.
    let hinge = |link| LinkHinge {
        link,
        at_fraction: 0.5,
        stiffness_nm_per_rad: 150_000.0,
        damping_nms_per_rad: 15.0,
    };
    let hinged = map
        .clone()
        .with_link_hinges(vec![hinge(1), hinge(2)])
        .expect("valid hinges");
    for (robot, map) in [
        (robot_support::ur_robot("ur5e", 5.0), &map),
        (robot_support::ur_robot_placed("ur5e", 5.0, &[]), &map),
        (
            robot_support::ur_robot_placed("ur5e", 5.0, &robot_support::GENERAL_TURNS),
            &map,
        ),
        (robot_support::ur_robot_tilted("ur5e", 5.0), &map),
        (robot_support::ur_robot("ur5e", 5.0), &hinged),
        (
            robot_support::ur_robot_placed("ur5e", 5.0, &robot_support::GENERAL_TURNS),
            &hinged,
        ),
    ] {
        let provider = ModalDynamics::new(robot, map.clone()).expect("valid map");
        let lowest = provider.shaping_lowest(3).expect("valid");
        let held = provider.holding_at(Some(&poses[0])).expect("valid pose");
        alloc_support::assert_robot_provider_never_allocates(
            provider,
            ShaperKind::Zv,
            &poses,
            "ModalDynamics",
        );
        alloc_support::assert_robot_provider_never_allocates(
            lowest,
            ShaperKind::Zv,
            &poses,
            "ModalDynamics (3 lowest modes)",
        );
        assert_held_provider_and_shaper_never_allocate(held, &poses);
    }
}

/// Held at a pose: the pose is taken out and put back every call, never copied; the shaper
/// designs its filters once and runs them held.
fn assert_held_provider_and_shaper_never_allocate(mut held: ModalDynamics, poses: &[Vec<f64>]) {
    let mut modes = vec![Mode::new(0.0, 0.0); held.n_modes()];
    let n = allocations_in(|| {
        for q in poses {
            held.modes(q, &mut modes);
        }
        held.restart();
        held.modes(&poses[1], &mut modes);
    });
    assert_eq!(n, 0, "held ModalDynamics::modes allocated {n} times");
    let config = TvShaperConfig::new(0.002, 6, ShaperKind::Zv);
    let mut shaper = TvShaper::new(held, &config).expect("valid config");
    let mut out = [0.0; 6];
    let mut statuses = Status::OK;
    let n = allocations_in(|| {
        for q in poses {
            statuses |= shaper.step(q, &mut out);
        }
    });
    assert_eq!(
        n, 0,
        "TvShaper<held ModalDynamics>::step allocated {n} times"
    );
    // The random poses jump, the held modes do not: no slew limit binds.
    assert!(!statuses.contains(Status::MODE_SLEW_LIMITED));
}
