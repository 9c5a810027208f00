//! Per-cycle cost of the rigid-body passes a map reads every cycle, for the UR arms:
//! `cargo bench -p tvist-core --bench robot_pass`.
//!
//! Rows: the inertia-only pass of the leading two joints (what the published map reads), the
//! published map provider, the modal map provider (mass-matrix block, gravity torques and the
//! 3 × 3 eigenproblem), and the full mass matrix with gravity torques. Every case runs
//! [`STEPS`] cycles on a slow sweep of poses per round; the rounds interleave every case (the
//! order rotates) and the table gives the min and median ns per cycle over [`ROUNDS`] rounds
//! and each case's ratio to the reference as the median of the per-round ratios (both
//! measured in the same round, so load that changes between rounds cancels).
//!
//! The reference is code that does not depend on the robot model's implementation: the
//! UR5e two-mode ZV cycle written out by hand (`support/hand_ur5e.rs`). Its ratios are
//! therefore comparable between two versions of the library measured on the same machine.
//! Nothing here asserts on time.

use std::hint::black_box;
use std::time::Instant;
use tvist_core::{DynamicMap, Dynamics, MapDynamics, ModalDynamics, ModalMap, Mode, Robot};

#[path = "../tests/robot_support/mod.rs"]
mod robot_support;

#[path = "support/ur5e_twin.rs"]
mod ur5e_twin;

#[path = "support/hand_ur5e.rs"]
mod hand_ur5e;

/// Rounds per case (min and median are taken over these).
const ROUNDS: usize = 61;
/// Cycles per case and round.
const STEPS: usize = 4_000;
const DT_S: f64 = 0.002;

/// A slow sweep of every joint so the inertias and modes change every cycle.
fn poses(n: usize) -> Vec<f64> {
    (0..STEPS)
        .flat_map(|i| {
            let t = i as f64 * DT_S;
            (0..n).map(move |j| {
                0.8 * (2.0 * std::f64::consts::PI * 0.3 * t + 0.4 * j as f64).sin() - 1.5
            })
        })
        .collect()
}

/// Base, shoulder and elbow flexible with load-dependent laws (gravity torques needed).
fn modal_map() -> ModalMap {
    ModalMap::new(ur5e_twin::base_shoulder_elbow(), &[0, 1]).expect("valid map")
}

type Run = Box<dyn FnMut() -> f64>;

/// Runs `f` on every pose of the sweep; returns a checksum so nothing is optimized away.
fn over_poses(n: usize, mut f: impl FnMut(&[f64]) -> f64 + 'static) -> Run {
    let x = poses(n);
    Box::new(move || x.chunks_exact(n).map(|q| f(black_box(q))).sum())
}

/// The cases of one robot, named after it.
fn robot_cases(label: &str, robot: impl Fn() -> Robot) -> Vec<(String, Run)> {
    let n = robot().n_dof();
    let mut cases: Vec<(String, Run)> = Vec::new();
    let mut rigid = robot();
    let mut inertia = vec![0.0; n];
    cases.push((
        format!("{label}: inertia-only pass, joints 0-1"),
        over_poses(n, move |q| {
            rigid.leading_joint_inertia_and_gravity(q, 2, &mut inertia, None);
            inertia[0] + inertia[1]
        }),
    ));
    let mut paper = MapDynamics::new_allowing_other_robot(robot(), DynamicMap::paper_ur5e())
        .expect("valid map");
    let mut modes = [Mode::new(0.0, 0.0); 2];
    cases.push((
        format!("{label}: published map provider (inertias + map)"),
        over_poses(n, move |q| {
            paper.modes(q, &mut modes);
            modes[0].wn_rad_s
        }),
    ));
    let mut modal = ModalDynamics::new_allowing_other_robot(robot(), modal_map()).expect("valid");
    let mut modal_modes = [Mode::new(0.0, 0.0); 2];
    cases.push((
        format!("{label}: modal map provider (3x3 mass block + gravity + eigen)"),
        over_poses(n, move |q| {
            modal.modes(q, &mut modal_modes);
            modal_modes[0].wn_rad_s
        }),
    ));
    let mut full = robot();
    let (mut mass, mut tau) = (vec![0.0; n * n], vec![0.0; n]);
    cases.push((
        format!("{label}: full mass matrix + gravity torques"),
        over_poses(n, move |q| {
            full.leading_mass_matrix_and_gravity(q, n, &mut mass, Some(&mut tau));
            mass[0] + tau[1]
        }),
    ));
    cases
}

fn main() {
    let mut cases: Vec<(String, Run)> = Vec::new();
    {
        let map = DynamicMap::paper_ur5e();
        let [base, shoulder] = [0, 1].map(|m| map.mode_maps()[m].coefficients);
        let mut hand =
            hand_ur5e::HandUr5eZv::new(&robot_support::ur_robot("ur5e", 5.0), base, shoulder, DT_S);
        let x: Vec<[f64; 6]> = poses(6)
            .chunks_exact(6)
            .map(|r| r.try_into().expect("6 values"))
            .collect();
        hand.fill(&x[0]);
        cases.push((
            "reference: the UR5e two-mode ZV cycle written out by hand".into(),
            Box::new(move || x.iter().map(|row| hand.step(black_box(row))[0]).sum()),
        ));
    }
    cases.extend(robot_cases("UR5e (DH)", || {
        robot_support::ur_robot("ur5e", 5.0)
    }));
    cases.extend(robot_cases("UR10e (DH)", || {
        robot_support::ur_robot("ur10e", 5.0)
    }));
    // The same UR5e placed as a URDF places it: link frames along the DH frames (every step
    // a DH step) and turned (every step general).
    cases.extend(robot_cases("UR5e (URDF, DH steps)", || {
        robot_support::ur_robot_placed("ur5e", 5.0, &[])
    }));
    cases.extend(robot_cases("UR5e (URDF, general steps)", || {
        robot_support::ur_robot_placed("ur5e", 5.0, &robot_support::GENERAL_TURNS)
    }));

    let mut ns: Vec<Vec<f64>> = vec![Vec::with_capacity(ROUNDS); cases.len()];
    let mut ratios: Vec<Vec<f64>> = vec![Vec::with_capacity(ROUNDS); cases.len()];
    let mut checksum = 0.0;
    for round in 0..ROUNDS {
        let mut round_ns = vec![0.0; cases.len()];
        for k in 0..cases.len() {
            let i = (k + round) % cases.len();
            let start = Instant::now();
            checksum += black_box((cases[i].1)());
            round_ns[i] = start.elapsed().as_nanos() as f64 / STEPS as f64;
        }
        for (i, t) in round_ns.iter().enumerate() {
            ns[i].push(*t);
            ratios[i].push(t / round_ns[0]);
        }
    }
    println!("{ROUNDS} interleaved rounds x {STEPS} cycles (5 kg 5 cm beyond the flange); checksum {checksum:.3e}\n");
    println!("| # | case | min ns | median ns | ratio to #1 |");
    println!("|---|---|---|---|---|");
    for (i, (name, _)) in cases.iter().enumerate() {
        println!(
            "| {} | {name} | {:.1} | {:.1} | {:.3} |",
            i + 1,
            min(&ns[i]),
            median(&ns[i]),
            median(&ratios[i])
        );
    }
}

fn min(v: &[f64]) -> f64 {
    v.iter().copied().fold(f64::INFINITY, f64::min)
}

fn median(v: &[f64]) -> f64 {
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    s[s.len() / 2]
}
