//! Shaped modes stay continuous along a motion: each slot of a modal map follows its eigenmode
//! branch (through a far dominance swap, and where the K-th and the next mode cross), and the
//! shaper limits and reports any faster change of a provider's mode.

mod robot_support;

use core::f64::consts::PI;
use robot_support::flex_joint;
use tvist_core::modes::modal::modal_map::HANDOVER_STEP;
use tvist_core::tv_shaper::MAX_LN_WN_RATE_PER_S;
use tvist_core::{
    Dynamics, ModalMap, Mode, ModeTrack, ShapedModes, ShaperKind, Status, TvShaper, TvShaperConfig,
};

const DT_S: f64 = 0.002;

fn unit(v: [f64; 3]) -> [f64; 3] {
    let n = v.iter().map(|x| x * x).sum::<f64>().sqrt();
    v.map(|x| x / n)
}

/// The mass matrix whose undamped modes with `K = diag(k)` have the frequencies `freq_hz` and
/// the orthonormal shapes `y` (in `K^{1/2}`-scaled coordinates): `M = K^{1/2} (Σ y yᵀ/ω²)
/// K^{1/2}`, built forward from the modes (the inverse of what the map solves).
fn mass_with_shapes(k: [f64; 3], freq_hz: [f64; 3], y: [[f64; 3]; 3]) -> [f64; 9] {
    let mut m = [0.0; 9];
    for r in 0..3 {
        for c in 0..3 {
            let b: f64 = (0..3)
                .map(|i| y[i][r] * y[i][c] / (2.0 * PI * freq_hz[i]).powi(2))
                .sum();
            m[3 * r + c] = (k[r] * k[c]).sqrt() * b;
        }
    }
    m
}

/// Largest relative change of any slot's ω_n and largest change of its ζ from one pose of
/// `path` to the next, evaluated per pose (`track` None) or tracked along the path.
fn largest_steps(map: &ModalMap, path: &[[f64; 9]], tracked: bool) -> (f64, f64) {
    let n = map.n_modes();
    let mut track = ModeTrack::default();
    let mut previous: Option<Vec<Mode>> = None;
    let (mut wn_step, mut zeta_step) = (0.0f64, 0.0f64);
    for mass in path {
        let mut out = vec![Mode::new(0.0, 0.0); n];
        let status = if tracked {
            map.modes_tracked(mass, 3, &[], &mut track, &mut out)
        } else {
            map.modes_from_mass_matrix(mass, 3, &[], &mut out)
        };
        assert!(status.is_ok() && out.iter().all(Mode::is_valid), "{out:?}");
        if let Some(prev) = &previous {
            for (a, b) in out.iter().zip(prev) {
                wn_step = wn_step.max((a.wn_rad_s / b.wn_rad_s).ln().abs());
                zeta_step = zeta_step.max((a.zeta - b.zeta).abs());
            }
        }
        previous = Some(out);
    }
    (wn_step, zeta_step)
}

#[test]
fn slots_follow_their_branch_through_a_far_dominance_swap() {
    // Three flexible joints; the modes at 15 and 31 Hz turn their shapes into each other along
    // the path (a rotation by 90° over 2000 poses, 0.045° a pose) while the 45 Hz one stays:
    // the shoulder's largest share passes from the 15 Hz mode to the 31 Hz one, and the two
    // lowest swap which joint they strain most. Chosen per pose, the shoulder slot (and a
    // slot of the two lowest) jumps between the two, 15 to 31 Hz. Tracked, a slot of the two
    // lowest keeps its mode (the set does not change); the shoulder slot hands over from the
    // 15 Hz mode to the 31 Hz one by HANDOVER_STEP a step. Light damping (ζ about 0.02)
    // keeps the modes nearly those built.
    let k = [26_000.0, 22_000.0, 90_000.0];
    let freq_hz = [15.0, 31.0, 45.0];
    let u = unit([0.6, 1.0, 0.1]);
    let w0 = unit([0.1, 0.4, 1.0]);
    let uw: f64 = (0..3).map(|f| u[f] * w0[f]).sum();
    let w = unit([w0[0] - uw * u[0], w0[1] - uw * u[1], w0[2] - uw * u[2]]);
    let c = [
        u[1] * w[2] - u[2] * w[1],
        u[2] * w[0] - u[0] * w[2],
        u[0] * w[1] - u[1] * w[0],
    ];
    let path: Vec<[f64; 9]> = (0..=2000)
        .map(|s| {
            let theta = 0.5 * PI * s as f64 / 2000.0;
            let (sn, cs) = theta.sin_cos();
            let a = [0, 1, 2].map(|f| cs * u[f] + sn * w[f]);
            let b = [0, 1, 2].map(|f| -sn * u[f] + cs * w[f]);
            mass_with_shapes(k, freq_hz, [a, b, c])
        })
        .collect();
    let flex = vec![
        flex_joint(0, k[0], 8.0),
        flex_joint(1, k[1], 8.0),
        flex_joint(2, k[2], 8.0),
    ];
    for shaped in [ShapedModes::ByJoint(vec![1]), ShapedModes::Lowest(2)] {
        let map = ModalMap::shaping(flex.clone(), shaped.clone()).expect("valid");
        // The path does take the per-pose rule through the swap: 15 -> 31 Hz is 0.73 in ln ω.
        let (jump, _) = largest_steps(&map, &path, false);
        assert!(
            jump > 0.5,
            "{shaped:?}: the per-pose rule jumps by only {jump}"
        );
        // Tracked: the shapes turn by 0.045° a pose, the frequencies move only through the
        // damping coupling (below 1e-4 a pose), plus a handover's HANDOVER_STEP: below one
        // cycle's slew limit (1 % at 2 ms), which never binds.
        let (step, _) = largest_steps(&map, &path, true);
        let bound = match shaped {
            ShapedModes::Lowest(_) => 1e-4,
            ShapedModes::ByJoint(_) => HANDOVER_STEP + 1e-4,
        };
        assert!(
            step < bound && step < MAX_LN_WN_RATE_PER_S * DT_S,
            "{shaped:?}: a tracked slot changes by {step} in ln ω in one step"
        );
    }
}

#[test]
fn slot_damping_stays_continuous_where_the_kth_and_the_next_mode_cross() {
    // Three uncoupled joints (diagonal M); the two lowest are shaped. Joint 0 stays at 10 Hz;
    // joint 1's inertia grows so that its mode (ζ 0.28) falls through joint 2's (ζ 0.14,
    // 20 Hz), exactly crossing it. Chosen per pose, the second slot goes from joint 2's mode
    // to joint 1's at the crossing: its ζ jumps by 0.14. Tracked, the slot hands over: ζ
    // moves by HANDOVER_STEP a pose at most (rounding 1e-12), and ω by no more than the swept
    // mode's 0.1 % per pose plus the gap the handover closes, below that 0.1 % (the two
    // frequencies meet at the crossing): 2.1e-3.
    let k = 2.0e4_f64;
    let damping = |zeta: f64, inertia: f64| 2.0 * zeta * (k * inertia).sqrt();
    let inertia_at = |hz: f64| k / (2.0 * PI * hz).powi(2);
    let (j0, j2) = (inertia_at(10.0), inertia_at(20.0));
    let j1_start = inertia_at(24.0);
    let path: Vec<f64> = (0..=400)
        .map(|s| j1_start * 1.002f64.powi(s)) // 24 Hz down to 24/e^0.4 = 16 Hz
        .collect();
    let mut previous: Option<[Mode; 2]> = None;
    let (mut static_zeta_jump, mut tracked_zeta_step, mut tracked_wn_step) =
        (0.0f64, 0.0f64, 0.0f64);
    let mut track = ModeTrack::default();
    let mut previous_tracked: Option<[Mode; 2]> = None;
    for &j1 in &path {
        // ζ 0.28 on joint 1 at every inertia: its damper follows its inertia.
        let map = ModalMap::shaping(
            vec![
                flex_joint(0, k, damping(0.1, j0)),
                flex_joint(1, k, damping(0.28, j1)),
                flex_joint(2, k, damping(0.14, j2)),
            ],
            ShapedModes::Lowest(2),
        )
        .expect("valid");
        let mass = [j0, 0.0, 0.0, 0.0, j1, 0.0, 0.0, 0.0, j2];
        let mut per_pose = [Mode::new(0.0, 0.0); 2];
        let mut tracked = [Mode::new(0.0, 0.0); 2];
        assert!(map
            .modes_from_mass_matrix(&mass, 3, &[], &mut per_pose)
            .is_ok());
        assert!(map
            .modes_tracked(&mass, 3, &[], &mut track, &mut tracked)
            .is_ok());
        if let (Some(p), Some(t)) = (previous, previous_tracked) {
            for r in 0..2 {
                static_zeta_jump = static_zeta_jump.max((per_pose[r].zeta - p[r].zeta).abs());
                tracked_zeta_step = tracked_zeta_step.max((tracked[r].zeta - t[r].zeta).abs());
                tracked_wn_step =
                    tracked_wn_step.max((tracked[r].wn_rad_s / t[r].wn_rad_s).ln().abs());
            }
        }
        previous = Some(per_pose);
        previous_tracked = Some(tracked);
    }
    assert!(
        static_zeta_jump > 0.1,
        "the per-pose rule must swap: {static_zeta_jump}"
    );
    assert!(
        tracked_zeta_step < HANDOVER_STEP + 1e-12,
        "a tracked slot's ζ changes by {tracked_zeta_step}"
    );
    assert!(
        tracked_wn_step < 2.1e-3,
        "a tracked slot's ω changes by {tracked_wn_step}"
    );
    // At the end the slots hold the two lowest, joint 0's and joint 1's modes.
    let end = previous_tracked.expect("evaluated");
    assert!(
        (end[0].zeta - 0.1).abs() < 1e-12 && (end[1].zeta - 0.28).abs() < 1e-12,
        "{end:?}"
    );
}

/// One mode whose frequency follows a script of the cycle count.
struct Scripted {
    k: usize,
    wn_at: fn(usize) -> f64,
}

impl Dynamics for Scripted {
    fn n_modes(&self) -> usize {
        1
    }
    fn modes(&mut self, _q: &[f64], out: &mut [Mode]) -> Status {
        out[0] = Mode::new((self.wn_at)(self.k), 0.1);
        self.k += 1;
        Status::OK
    }
    fn slowest_mode(&self, _index: usize) -> Option<Mode> {
        Some(Mode::new(2.0 * PI * 10.0, 0.2))
    }
}

/// Shapes a ramp (the input moves every cycle) for `cycles`, then holds it; returns per cycle
/// the filter's mode and status.
fn run(wn_at: fn(usize) -> f64, moving: usize, held: usize) -> Vec<(Mode, Status)> {
    let cfg = TvShaperConfig::new(DT_S, 1, ShaperKind::Zv);
    let mut shaper = TvShaper::new(Scripted { k: 0, wn_at }, &cfg).expect("valid");
    let mut y = [0.0];
    (0..moving + held)
        .map(|i| {
            let x = 1e-3 * i.min(moving) as f64;
            let status = shaper.step(&[x], &mut y);
            let mode = shaper.filters()[0].held_mode().expect("shaping");
            (mode, status)
        })
        .collect()
}

#[test]
fn a_jumping_mode_is_slew_limited_and_reported() {
    // The provider's mode jumps from 14.9 to 30.9 Hz at cycle 100 of a move: the filter
    // approaches it by the per-cycle limit (exp(MAX_LN_WN_RATE_PER_S dt) exactly, rounding
    // 1e-12) and reports it every cycle it binds, then follows it unlimited.
    let limit = MAX_LN_WN_RATE_PER_S * DT_S;
    let cycles = run(|k| 2.0 * PI * if k < 100 { 14.9 } else { 30.9 }, 400, 0);
    let needed = ((30.9f64 / 14.9).ln() / limit).ceil() as usize;
    let mut flagged = 0;
    for (i, pair) in cycles.windows(2).enumerate() {
        let ((a, _), (b, status)) = (pair[0], pair[1]);
        let step = (b.wn_rad_s / a.wn_rad_s).ln();
        assert!(
            step <= limit * (1.0 + 1e-12),
            "cycle {}: ln ω step {step}",
            i + 1
        );
        if status.contains(Status::MODE_SLEW_LIMITED) {
            flagged += 1;
            assert!(
                (step / limit - 1.0).abs() < 1e-9,
                "cycle {}: step {step}",
                i + 1
            );
        }
    }
    // The cycles that bind: all but the last of the approach (which lands on the mode).
    assert_eq!(flagged, needed - 1);
    assert!((cycles[399].0.wn_rad_s / (2.0 * PI * 30.9) - 1.0).abs() < 1e-12);
}

#[test]
fn pose_driven_changes_and_changes_at_rest_are_not_limited() {
    // A mode that drifts by 30 % over 0.5 s (0.1 % a cycle, the pace of a pose-driven change)
    // never binds; a jump while the input rests (longer than every delay line) is taken at
    // once: it cannot change the output.
    let drifting = run(
        |k| 2.0 * PI * 15.0 * (1.0 + 0.3 * (k.min(250) as f64 / 250.0)),
        400,
        0,
    );
    assert!(drifting
        .iter()
        .all(|(_, s)| !s.contains(Status::MODE_SLEW_LIMITED)));
    let resting = run(|k| 2.0 * PI * if k < 300 { 14.9 } else { 30.9 }, 10, 400);
    let (after, status) = resting[300];
    assert_eq!(after.wn_rad_s, 2.0 * PI * 30.9);
    assert!(!status.contains(Status::MODE_SLEW_LIMITED));
}
