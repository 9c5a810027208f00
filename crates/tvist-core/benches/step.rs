//! Criterion benchmarks of the per-cycle cost: `cargo bench -p tvist-core --bench step`.
//! Reported as absolute times; the README lists them with the ratios between cases.

use criterion::{criterion_group, criterion_main, Criterion};
use std::hint::black_box;
use tvist_core::{ConstantModes, Mode, ShaperKind, TvShaper, TvShaperConfig};

fn bench_step(c: &mut Criterion) {
    let modes = ConstantModes::new(vec![Mode::new(2.0 * 3.14159 * 8.0, 0.26), Mode::new(2.0 * 3.14159 * 6.9, 0.37)])
        .expect("valid modes");
    let config = TvShaperConfig::new(0.002, 6, ShaperKind::Zv);
    let mut shaper = TvShaper::new(modes, &config).expect("valid config");
    let mut q = [0.0f64; 6];
    let mut out = [0.0f64; 6];
    let mut k = 0u64;
    c.bench_function("step 6dof 2 modes zv (constant modes)", |b| {
        b.iter(|| {
            k += 1;
            let x = (k % 1000) as f64 * 1e-3;
            q.iter_mut().for_each(|v| *v = x);
            black_box(shaper.step(black_box(&q), &mut out));
        })
    });
}

criterion_group!(benches, bench_step);
criterion_main!(benches);
