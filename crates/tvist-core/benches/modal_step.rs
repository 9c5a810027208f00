//! Per-cycle cost of modal-map shaping against the published-map step:
//! `cargo bench -p tvist-core --bench modal_step`.
//!
//! A full 6-DOF, two-mode ZV step of the UR5e (5 kg payload): the published 10-coefficient map
//! (joint inertias + map) next to the modal map (mass matrix + gravity torques + 3 × 3
//! eigenproblem of base, shoulder and elbow; 5 × 5 with wrists 1-2; 9 × 9 with wrists 1-2 and
//! bending upper arm and forearm, on the hinged arm's 10 × 10 mass matrix), and each provider's
//! evaluation alone. The cases
//! are interleaved in rounds (order alternating) in one process, each with the same number
//! of steps per round, and reported as min and median over the rounds, so that the load of a
//! shared machine hits both sides alike.

use std::hint::black_box;
use std::time::Instant;
use tvist_core::{
    DynamicMap, Dynamics, FlexJoint, LinkHinge, LoadLaw, MapDynamics, ModalDynamics, ModalMap,
    Mode, ShaperKind, TvShaper, TvShaperConfig,
};

#[path = "../tests/robot_support/mod.rs"]
mod robot_support;

#[path = "support/ur5e_twin.rs"]
mod ur5e_twin;

const ROUNDS: usize = 400;
const STEPS_PER_ROUND: u64 = 2_000;

/// A slow base-and-shoulder sweep so the inertia and the modes change every cycle.
fn pose(k: u64, q: &mut [f64; 6]) {
    let s = (k % 5000) as f64 * 2e-4;
    *q = [
        s,
        -3.0 + 1.2 * s,
        0.5 * s,
        -std::f64::consts::FRAC_PI_2,
        0.3,
        0.0,
    ];
}

/// The UR5e twin's gear laws (load-dependent stiffness and damping: gravity torques needed):
/// base, shoulder and elbow, plus wrists 1-2 if `wrists`.
fn modal_map(wrists: bool) -> ModalMap {
    let mut joints = ur5e_twin::base_shoulder_elbow();
    if wrists {
        for joint in [3, 4] {
            joints.push(FlexJoint {
                joint,
                stiffness_nm_per_rad: LoadLaw::constant(15_000.0),
                damping_nms_per_rad: LoadLaw::constant(5.0),
                damping_load_joint: joint,
            });
        }
    }
    ModalMap::new(joints, &[0, 1]).expect("valid map")
}

/// Nanoseconds per call of `f` over one round.
fn time_round(mut f: impl FnMut(u64)) -> f64 {
    let start = Instant::now();
    for k in 0..STEPS_PER_ROUND {
        f(k);
    }
    start.elapsed().as_nanos() as f64 / STEPS_PER_ROUND as f64
}

fn min_median(mut v: Vec<f64>) -> (f64, f64) {
    v.sort_by(f64::total_cmp);
    (v[0], v[v.len() / 2])
}

fn main() {
    let config = TvShaperConfig::new(0.002, 6, ShaperKind::Zv);
    let robot = || robot_support::ur_robot("ur5e", 5.0);
    let mut paper_shaper = TvShaper::new(
        MapDynamics::new(robot(), DynamicMap::paper_ur5e()).expect("valid map"),
        &config,
    )
    .expect("valid config");
    let mut modal_shaper = TvShaper::new(
        ModalDynamics::new(robot(), modal_map(false)).expect("valid map"),
        &config,
    )
    .expect("valid config");
    let mut modal5_shaper = TvShaper::new(
        ModalDynamics::new(robot(), modal_map(true)).expect("valid map"),
        &config,
    )
    .expect("valid config");
    // Bending upper arm and forearm: hinge pairs at their middles (about 40-50 Hz bending).
    let hinge = |link| LinkHinge {
        link,
        at_fraction: 0.5,
        stiffness_nm_per_rad: 140_000.0,
        damping_nms_per_rad: 13.0,
    };
    let hinged = modal_map(true)
        .with_link_hinges(vec![hinge(1), hinge(2)])
        .expect("valid hinges");
    let mut modal9_shaper = TvShaper::new(
        ModalDynamics::new(robot(), hinged).expect("valid map"),
        &config,
    )
    .expect("valid config");
    let mut paper = MapDynamics::new(robot(), DynamicMap::paper_ur5e()).expect("valid map");
    let mut modal = ModalDynamics::new(robot(), modal_map(false)).expect("valid map");
    let (mut q, mut out) = ([0.0f64; 6], [0.0f64; 6]);
    let (mut rigid, mut mass, mut tau) = (robot(), [0.0f64; 36], [0.0f64; 6]);
    let mut modes = [Mode::new(0.0, 0.0); 2];

    let names = [
        "full step, published map (inertia + map + shaping)",
        "full step, modal map (mass matrix + gravity + 3x3 eigen + shaping)",
        "published map provider alone",
        "modal map provider alone",
        "full step, modal map with 5 flexible joints (5x5 eigen)",
        "of the modal provider: 3x3 mass block + gravity torques (one pass)",
        "full step, modal map, 5 joints + 2 bending links (9x9 eigen)",
    ];
    let mut times: Vec<Vec<f64>> = vec![Vec::with_capacity(ROUNDS); names.len()];
    for round in 0..ROUNDS {
        let mut order = [0usize, 1, 2, 3, 4, 5, 6];
        if round % 2 == 1 {
            order.reverse();
        }
        for case in order {
            let t = match case {
                0 => time_round(|k| {
                    pose(k, &mut q);
                    black_box(paper_shaper.step(black_box(&q), &mut out));
                }),
                1 => time_round(|k| {
                    pose(k, &mut q);
                    black_box(modal_shaper.step(black_box(&q), &mut out));
                }),
                2 => time_round(|k| {
                    pose(k, &mut q);
                    black_box(paper.modes(black_box(&q), &mut modes));
                }),
                3 => time_round(|k| {
                    pose(k, &mut q);
                    black_box(modal.modes(black_box(&q), &mut modes));
                }),
                4 => time_round(|k| {
                    pose(k, &mut q);
                    black_box(modal5_shaper.step(black_box(&q), &mut out));
                }),
                6 => time_round(|k| {
                    pose(k, &mut q);
                    black_box(modal9_shaper.step(black_box(&q), &mut out));
                }),
                _ => time_round(|k| {
                    pose(k, &mut q);
                    // What the 3-joint modal provider evaluates: the leading 3 x 3 block.
                    black_box(rigid.leading_mass_matrix_and_gravity(
                        black_box(&q),
                        3,
                        &mut mass,
                        Some(&mut tau),
                    ));
                }),
            };
            times[case].push(t);
        }
    }
    let (_, reference) = min_median(times[0].clone());
    println!(
        "{ROUNDS} interleaved rounds x {STEPS_PER_ROUND} steps (UR5e, 5 kg, 6 DOF, 2 modes, ZV)"
    );
    println!(
        "{:<70} {:>9} {:>9} {:>7}",
        "case", "min ns", "median ns", "ratio"
    );
    for (name, t) in names.iter().zip(times) {
        let (min, median) = min_median(t);
        println!(
            "{name:<70} {min:>9.0} {median:>9.0} {:>7.2}",
            median / reference
        );
    }
}
