//! Criterion benchmarks of the per-cycle cost: `cargo bench -p tvist-core --bench step`.
//!
//! Cases (6 DOF, the two UR5e modes of pose Q1, 500 Hz):
//! - constant modes, ZV, linear reads: the sequence is designed once and reused;
//! - modes that change every cycle (a frequency sweep), ZV, linear: redesign each cycle;
//! - the same sweep with cubic reads;
//! - the same sweep with the (exact, Newton-refined) 5 % EI shaper, linear reads.

use criterion::{criterion_group, criterion_main, Criterion};
use std::f64::consts::PI;
use std::hint::black_box;
use tvist_core::{
    ConstantModes, Dynamics, Interpolation, Mode, ShaperKind, Status, TvShaper, TvShaperConfig,
};

const Q1_MODES: [Mode; 2] = [
    Mode::new(2.0 * PI * 8.3, 0.2645),
    Mode::new(2.0 * PI * 7.45, 0.373),
];

/// Modes sweeping ±20 % around the Q1 modes, a new value every cycle.
struct Sweeping {
    k: u32,
}

impl Dynamics for Sweeping {
    fn n_modes(&self) -> usize {
        2
    }
    fn modes(&mut self, _q: &[f64], out: &mut [Mode]) -> Status {
        self.k = self.k.wrapping_add(1);
        let s = 0.8 + 0.4 * (self.k % 1000) as f64 / 1000.0;
        for (o, m) in out.iter_mut().zip(Q1_MODES) {
            *o = Mode::new(m.wn_rad_s * s, m.zeta);
        }
        Status::OK
    }
    fn slowest_mode(&self, index: usize) -> Option<Mode> {
        Q1_MODES
            .get(index)
            .map(|m| Mode::new(0.8 * m.wn_rad_s, m.zeta))
    }
}

fn run<D: Dynamics>(c: &mut Criterion, name: &str, mut shaper: TvShaper<D>) {
    let mut q = [0.0f64; 6];
    let mut out = [0.0f64; 6];
    let mut k = 0u64;
    c.bench_function(name, |b| {
        b.iter(|| {
            k += 1;
            let x = (k % 1000) as f64 * 1e-3;
            q.iter_mut().for_each(|v| *v = x);
            black_box(shaper.step(black_box(&q), &mut out));
        })
    });
}

fn bench_step(c: &mut Criterion) {
    let config = TvShaperConfig::new(0.002, 6, ShaperKind::Zv);
    let constant = ConstantModes::new(Q1_MODES.to_vec()).expect("valid modes");
    run(
        c,
        "step 6dof 2 modes zv linear (constant modes)",
        TvShaper::new(constant, &config).expect("valid"),
    );
    run(
        c,
        "step 6dof 2 modes zv linear (modes change every cycle)",
        TvShaper::new(Sweeping { k: 0 }, &config).expect("valid"),
    );
    let mut cubic = config.clone();
    cubic.interp = Interpolation::Cubic;
    run(
        c,
        "step 6dof 2 modes zv cubic (modes change every cycle)",
        TvShaper::new(Sweeping { k: 0 }, &cubic).expect("valid"),
    );
    let ei = TvShaperConfig::new(
        0.002,
        6,
        ShaperKind::from_name("ei", None).expect("registry name"),
    );
    run(
        c,
        "step 6dof 2 modes ei linear (modes change every cycle)",
        TvShaper::new(Sweeping { k: 0 }, &ei).expect("valid"),
    );
}

criterion_group!(benches, bench_step);
criterion_main!(benches);
