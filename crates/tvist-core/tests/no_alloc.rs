//! The real-time path never allocates after construction.
//!
//! This file is its own test binary with a counting global allocator. Only allocations made
//! by the measuring thread inside a measured window are counted (a const thread-local flag,
//! which itself never allocates), so the harness' other threads cannot disturb the count.

mod alloc_support;

use alloc_support::{allocations_in, the_counter_sees_this_thread_only};
use tvist_core::{
    ConstantModes, DelayLine, Dynamics, Interpolation, Mode, ModeFilter, ShaperKind, Status,
    TvShaper, TvShaperConfig, SHAPER_NAMES,
};

#[test]
fn the_real_time_path_never_allocates() {
    the_counter_sees_this_thread_only();
    tv_shaper_step_never_allocates();
    mode_filter_delay_line_and_design_never_allocate();
}

/// A provider whose modes change every cycle (frequency sweep, damping wobble, the odd
/// invalid mode): every code path of the time-varying step runs.
struct Sweep {
    k: u64,
}

impl Dynamics for Sweep {
    fn n_modes(&self) -> usize {
        2
    }
    fn modes(&mut self, q: &[f64], out: &mut [Mode]) -> Status {
        self.k += 1;
        let s = (self.k % 400) as f64 / 400.0 + q.first().copied().unwrap_or(0.0).abs() * 1e-3;
        out[0] = Mode::new(
            2.0 * core::f64::consts::PI * (6.0 + 16.0 * s),
            0.05 + 0.3 * s,
        );
        out[1] = if self.k % 97 == 0 {
            Mode::new(f64::NAN, 0.1)
        } else {
            Mode::new(60.0 + 40.0 * s, 0.45 * s)
        };
        Status::OK
    }
    fn slowest_mode(&self, _index: usize) -> Option<Mode> {
        None
    }
}

fn tv_shaper_step_never_allocates() {
    // 1 and 6 channels run with fixed-size rows, 9 with slices.
    for n_dof in [1, 6, 9] {
        for name in SHAPER_NAMES {
            for interp in [Interpolation::Linear, Interpolation::Cubic] {
                tv_shaper_never_allocates(n_dof, name, interp);
            }
        }
    }
}

fn tv_shaper_never_allocates(n_dof: usize, name: &str, interp: Interpolation) {
    let kind = ShaperKind::from_name(name, None).expect("registry");
    // Time-varying provider, with delays that sometimes exceed the buffer.
    let mut cfg = TvShaperConfig::new(0.002, n_dof, kind);
    cfg.interp = interp;
    cfg.max_delay_s = Some(0.12);
    let mut shaper = TvShaper::new(Sweep { k: 0 }, &cfg).expect("valid");
    let mut y = vec![0.0; n_dof];
    let (bad_in, reset, next, cleared) = (
        vec![0.0; n_dof + 1],
        vec![0.1; n_dof],
        vec![0.2; n_dof],
        vec![0.3; n_dof],
    );
    let n = allocations_in(|| {
        for i in 0..2000 {
            let v = (i as f64 * 0.01).sin();
            let x = if i % 333 == 7 { [f64::NAN; 9] } else { [v; 9] };
            let _ = shaper.step(&x[..n_dof], &mut y);
        }
        let _ = shaper.step(&bad_in, &mut y); // BAD_LENGTH path
        shaper.reset(&reset);
        let _ = shaper.step(&next, &mut y);
        shaper.clear();
        let _ = shaper.step(&cleared, &mut y);
    });
    assert_eq!(n, 0, "{name} {interp:?} {n_dof}: {n} allocations");

    // Constant modes (asked once per start), stepping and the block API.
    let modes =
        ConstantModes::new(vec![Mode::new(50.0, 0.15), Mode::new(43.0, 0.1)]).expect("valid");
    let mut cfg = TvShaperConfig::new(0.002, n_dof, kind);
    cfg.interp = interp;
    let mut shaper = TvShaper::new(modes, &cfg).expect("valid");
    let x: Vec<f64> = (0..1000 * n_dof).map(|i| (i as f64 * 1e-3).cos()).collect();
    let mut out = vec![0.0; x.len()];
    let n = allocations_in(|| {
        let _ = shaper.shape_into(&x, &mut out);
        shaper.reset(&reset);
        for row in x.chunks_exact(n_dof) {
            let _ = shaper.step(row, &mut y);
        }
        let _ = shaper.dynamics_mut();
        let _ = shaper.shape_into(&x, &mut out);
    });
    assert_eq!(
        n, 0,
        "{name} {interp:?} {n_dof} constant modes: {n} allocations"
    );
}

fn mode_filter_delay_line_and_design_never_allocate() {
    for interp in [Interpolation::Linear, Interpolation::Cubic] {
        let mut filter = ModeFilter::new(ShaperKind::Zvd, 3, 0.002, 0.3, interp).expect("valid");
        let mut line = DelayLine::new(3, 40.0, interp).expect("valid");
        let mut acc = [0.0; 3];
        let n = allocations_in(|| {
            filter.reset(&[1.0, 2.0, 3.0]);
            for i in 0..1000 {
                let x = [i as f64, -(i as f64), 0.5];
                let _ = filter.step(&x, Mode::new(20.0 + (i % 50) as f64, 0.1));
                line.push(&x);
                for d in [0.0, 0.5, 3.25, 39.9, 1e9, f64::NAN, -2.0] {
                    let _ = line.accumulate(d, 0.3, &mut acc);
                }
            }
            line.fill(&[0.0; 3]);
            filter.forget_mode();
        });
        assert_eq!(n, 0, "{interp:?}: {n} allocations");
    }
    let n = allocations_in(|| {
        for name in SHAPER_NAMES {
            let kind = ShaperKind::from_name(name, None).expect("registry");
            for z in [0.0, 0.1, 0.2] {
                std::hint::black_box(kind.design(Mode::new(30.0, z)));
            }
        }
    });
    assert_eq!(n, 0);
}
