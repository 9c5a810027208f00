//! Per-cycle cost of map-driven shaping: `cargo bench -p tvist-core --bench map_step`.
//!
//! A full 6-DOF, two-mode ZV step with the UR5e (5 kg payload) inertia evaluated at the
//! previous output and the paper's map, next to the same step with constant modes (the
//! reference case of `benches/step.rs`) in the same process, so their ratio is meaningful.

use criterion::{criterion_group, criterion_main, Criterion};
use std::hint::black_box;
use tvist_core::{
    ConstantModes, DynamicMap, Dynamics, MapDynamics, Mode, ShaperKind, TvShaper, TvShaperConfig,
};

#[path = "../tests/robot_support/mod.rs"]
mod robot_support;

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

fn bench_map_step(c: &mut Criterion) {
    let config = TvShaperConfig::new(0.002, 6, ShaperKind::Zv);
    let (mut q, mut out) = ([0.0f64; 6], [0.0f64; 6]);

    let constant = ConstantModes::new(vec![Mode::new(50.4, 0.26), Mode::new(43.4, 0.37)])
        .expect("valid modes");
    let mut shaper = TvShaper::new(constant, &config).expect("valid config");
    let mut k = 0u64;
    c.bench_function("step 6dof 2 modes zv (constant modes)", |b| {
        b.iter(|| {
            k += 1;
            pose(k, &mut q);
            black_box(shaper.step(black_box(&q), &mut out));
        })
    });

    let provider = MapDynamics::new(
        robot_support::ur_robot("ur5e", 5.0),
        DynamicMap::paper_ur5e(),
    )
    .expect("valid map");
    let mut shaper = TvShaper::new(provider, &config).expect("valid config");
    let mut k = 0u64;
    c.bench_function("step 6dof 2 modes zv (ur5e inertia + paper map)", |b| {
        b.iter(|| {
            k += 1;
            pose(k, &mut q);
            black_box(shaper.step(black_box(&q), &mut out));
        })
    });

    let mut provider = MapDynamics::new(
        robot_support::ur_robot("ur5e", 5.0),
        DynamicMap::paper_ur5e(),
    )
    .expect("valid map");
    let mut modes = [Mode::new(0.0, 0.0); 2];
    let mut k = 0u64;
    c.bench_function("ur5e inertia + paper map only (MapDynamics::modes)", |b| {
        b.iter(|| {
            k += 1;
            pose(k, &mut q);
            black_box(provider.modes(black_box(&q), &mut modes));
        })
    });
}

criterion_group!(benches, bench_map_step);
criterion_main!(benches);
