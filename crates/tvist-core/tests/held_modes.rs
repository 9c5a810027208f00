//! Modes held at a pose (`RobotModes::holding_at`, `TvShaper::hold_modes_at`): the held
//! provider gives the modes of that pose whatever the cycle's pose, a shaper holding them
//! shapes exactly as fixed modes do, and the hold is a between-moves setup call.

mod robot_support;

use robot_support::flex_joint;
use tvist_core::{
    ConstantModes, Dynamics, ModalDynamics, ModalMap, Mode, Provider, ShaperKind, TvShaper,
    TvShaperConfig,
};

fn provider() -> ModalDynamics {
    let map = ModalMap::new(
        vec![
            flex_joint(0, 22_000.0, 30.0),
            flex_joint(1, 18_000.0, 60.0),
            flex_joint(2, 9_000.0, 20.0),
        ],
        &[0, 1],
    )
    .expect("valid map");
    ModalDynamics::new(robot_support::ur_robot("ur5e", 5.0), map).expect("valid provider")
}

fn modes_at(p: &mut impl Dynamics, q: &[f64]) -> Vec<Mode> {
    let mut out = vec![Mode::new(0.0, 0.0); p.n_modes()];
    assert!(p.modes(q, &mut out).is_ok());
    out
}

/// A move of every joint from `a` to `b` (smooth cosine ramp over `n` samples), then at rest.
fn ramp(a: &[f64], b: &[f64], n: usize, rest: usize) -> Vec<Vec<f64>> {
    (0..n + rest)
        .map(|i| {
            let s = 0.5 - 0.5 * (std::f64::consts::PI * (i.min(n) as f64) / n as f64).cos();
            a.iter().zip(b).map(|(x, y)| x + s * (y - x)).collect()
        })
        .collect()
}

const Q_START: [f64; 6] = [0.0, -1.2, 1.0, -1.0, -1.5, 0.0];
const Q_END: [f64; 6] = [1.5, -2.0, 2.4, -0.5, -1.5, 0.3];

#[test]
fn a_held_provider_gives_the_held_poses_modes_at_every_pose() {
    let mut free = provider();
    let expected = modes_at(&mut free, &Q_END);
    // Different from the start pose's: the test would see a provider that ignores the hold.
    assert_ne!(modes_at(&mut free, &Q_START), expected);
    let mut held = free.holding_at(Some(&Q_END)).expect("valid pose");
    assert_eq!(held.held_pose(), Some(&Q_END[..]));
    assert!(held.modes_are_constant());
    let mut rng = robot_support::Rng(5);
    for _ in 0..50 {
        assert_eq!(modes_at(&mut held, &rng.pose(6)), expected);
    }
    let mut released = held.holding_at(None).expect("release");
    assert!(!released.modes_are_constant());
    // Both from a fresh start (the modal map follows eigenmode branches from call to call).
    free.restart();
    assert_eq!(
        modes_at(&mut released, &Q_START),
        modes_at(&mut free, &Q_START)
    );
}

#[test]
fn a_hold_is_refused_for_a_pose_of_the_wrong_length() {
    let err = provider()
        .holding_at(Some(&[0.0; 4]))
        .expect_err("4 of 6 joints");
    assert!(err.to_string().contains("pose to hold"), "{err}");
}

#[test]
fn a_shaper_holding_the_end_poses_modes_shapes_as_those_fixed_modes_do() {
    let config = TvShaperConfig::new(0.002, 6, ShaperKind::Zv);
    let end_modes = modes_at(&mut provider(), &Q_END);
    let mut held: TvShaper<Provider> =
        TvShaper::new(Provider::Modal(Box::new(provider())), &config).expect("valid");
    let mut fixed: TvShaper<Provider> = TvShaper::new(
        Provider::Constant(ConstantModes::new(end_modes).expect("valid")),
        &config,
    )
    .expect("valid");
    let mut following: TvShaper<Provider> =
        TvShaper::new(Provider::Modal(Box::new(provider())), &config).expect("valid");
    for s in [&mut held, &mut fixed, &mut following] {
        s.reset(&Q_START);
    }
    held.hold_modes_at(Some(&Q_END)).expect("at rest");
    let (mut a, mut b, mut c) = ([0.0; 6], [0.0; 6], [0.0; 6]);
    let mut largest_difference_from_following = 0.0_f64;
    for q in ramp(&Q_START, &Q_END, 400, 200) {
        assert!(held.step(&q, &mut a).is_ok());
        assert!(fixed.step(&q, &mut b).is_ok());
        following.step(&q, &mut c);
        // Held modes are fixed modes: the same filters, bit for bit.
        assert_eq!(a, b);
        for (x, y) in a.iter().zip(&c) {
            largest_difference_from_following =
                largest_difference_from_following.max((x - y).abs());
        }
    }
    // ...and not the per-cycle shaping (the modes change by tens of per cent over this move).
    assert!(
        largest_difference_from_following > 1e-4,
        "{largest_difference_from_following}"
    );
}

#[test]
fn a_hold_is_a_between_moves_call_and_set_shaped_modes_ends_it() {
    let config = TvShaperConfig::new(0.002, 6, ShaperKind::Zv);
    let mut shaper: TvShaper<Provider> =
        TvShaper::new(Provider::Modal(Box::new(provider())), &config).expect("valid");
    shaper.reset(&Q_START);
    let mut out = [0.0; 6];
    shaper.step(&Q_END, &mut out);
    let err = shaper.hold_modes_at(Some(&Q_END)).expect_err("mid-move");
    assert!(err.to_string().contains("between moves"), "{err}");
    shaper.reset(&Q_END);
    shaper.hold_modes_at(Some(&Q_END)).expect("at rest");
    assert!(shaper.dynamics().modes_are_constant());
    shaper.set_shaped_modes(2).expect("at rest");
    assert!(!shaper.dynamics().modes_are_constant());
    shaper.hold_modes_at(Some(&Q_END)).expect("at rest");
    shaper.hold_modes_at(None).expect("at rest");
    assert!(!shaper.dynamics().modes_are_constant());

    let mut constant: TvShaper<Provider> = TvShaper::new(
        Provider::Constant(ConstantModes::new(vec![Mode::new(60.0, 0.05)]).expect("valid")),
        &config,
    )
    .expect("valid");
    let err = constant.hold_modes_at(Some(&Q_END)).expect_err("no map");
    assert!(err.to_string().contains("driven by a map"), "{err}");
}
