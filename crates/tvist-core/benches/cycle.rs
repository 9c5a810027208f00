//! Per-cycle cost of the streaming shaper, every case interleaved in one process:
//! `cargo bench -p tvist-core --bench cycle` (or `make bench`).
//!
//! Each round runs every case once (in a rotated order) for [`STEPS`] cycles and records
//! ns/cycle; the table gives the minimum and the median over [`ROUNDS`] rounds and each case's
//! ratio to its reference as the median of the per-round ratios (both measured in the same
//! round, so machine load that changes between rounds cancels). Nothing here asserts on time.
//!
//! The shaper reference is a plain fixed convolution (ring buffer, two linear fractional reads
//! per impulse) of the same impulses, checked to give the same output.

use std::f64::consts::PI;
use std::hint::black_box;
use std::time::Instant;
use tvist_core::{
    ConstantModes, DynamicMap, Dynamics, ImpulseArray, Interpolation, MapDynamics, Mode,
    ShaperKind, Status, TvShaper, TvShaperConfig,
};

#[path = "../tests/robot_support/mod.rs"]
mod robot_support;

#[path = "support/hand_ur5e.rs"]
mod hand_ur5e;

/// Rounds per case (min and median are taken over these).
const ROUNDS: usize = 41;
/// Cycles per case and round (20 s at 500 Hz).
const STEPS: usize = 10_000;
const DT_S: f64 = 0.002;

/// The two UR5e modes of pose Q1 (Table 3): damped 8.018 Hz at ζ = 0.2645, 6.909 Hz at 0.373.
fn q1_modes() -> [Mode; 2] {
    [
        Mode::new(2.0 * PI * 8.018 / (1.0f64 - 0.2645 * 0.2645).sqrt(), 0.2645),
        Mode::new(2.0 * PI * 6.909 / (1.0f64 - 0.373 * 0.373).sqrt(), 0.373),
    ]
}

/// One 10 Hz mode for the single-channel cases.
const ONE_MODE: Mode = Mode::new(2.0 * PI * 10.0, 0.1);

/// A plain fixed convolution of `N` channels (the channel count known at compile time, as in
/// a hand-written filter): ring buffer, two linear reads per impulse.
struct FixedConvolution<const N: usize> {
    head: usize,
    buf: Vec<[f64; N]>,
    /// Per impulse: whole-sample delay `k` and the weights of ages `k` and `k + 1`.
    taps: Vec<(usize, f64, f64)>,
}

impl<const N: usize> FixedConvolution<N> {
    fn new(impulses: &ImpulseArray) -> Self {
        let taps: Vec<(usize, f64, f64)> = impulses
            .amplitudes()
            .iter()
            .zip(impulses.times_s())
            .map(|(&a, &t)| {
                let d = t / DT_S;
                let k = d.floor();
                let mu = d - k;
                (k as usize, a * (1.0 - mu), a * mu)
            })
            .collect();
        let capacity = taps.iter().map(|t| t.0).max().unwrap_or(0) + 2;
        FixedConvolution {
            head: 0,
            buf: vec![[0.0; N]; capacity],
            taps,
        }
    }

    #[inline]
    fn step(&mut self, x: &[f64; N]) -> [f64; N] {
        let cap = self.buf.len();
        self.head = if self.head + 1 == cap {
            0
        } else {
            self.head + 1
        };
        self.buf[self.head] = *x;
        let mut out = [0.0; N];
        for &(k, w0, w1) in &self.taps {
            let i0 = if self.head >= k {
                self.head - k
            } else {
                self.head + cap - k
            };
            let i1 = if i0 == 0 { cap - 1 } else { i0 - 1 };
            let (r0, r1) = (&self.buf[i0], &self.buf[i1]);
            for c in 0..N {
                out[c] += w0 * r0[c] + w1 * r1[c];
            }
        }
        out
    }
}

/// A cascade of fixed convolutions, one per mode (the fixed-mode equivalent of `TvShaper`).
struct FixedCascade<const N: usize>(Vec<FixedConvolution<N>>);

impl<const N: usize> FixedCascade<N> {
    fn new(kind: ShaperKind, modes: &[Mode]) -> Self {
        FixedCascade(
            modes
                .iter()
                .map(|m| FixedConvolution::new(&kind.design(*m)))
                .collect(),
        )
    }

    fn fill(&mut self, x: &[f64; N]) {
        for f in &mut self.0 {
            f.buf.iter_mut().for_each(|row| *row = *x);
        }
    }

    #[inline]
    fn step(&mut self, x: &[f64; N]) -> [f64; N] {
        let mut y = *x;
        for f in &mut self.0 {
            y = f.step(&y);
        }
        y
    }
}

/// Modes that change every cycle: `ω_n` (and `ζ` if `zeta_too`) sweep ±20 % around Q1 over
/// 1000 cycles. The sweep is tabulated at setup, so the provider's own cost per cycle is a
/// table read (as cheap as [`ConstantModes`]) and the case measures the shaper.
struct Sweeping {
    k: usize,
    table: Vec<[Mode; 2]>,
}

impl Sweeping {
    fn new(zeta_too: bool) -> Sweeping {
        let table = (0..1000)
            .map(|k| {
                let s = 0.8 + 0.4 * k as f64 / 1000.0;
                let z = if zeta_too { 0.9 + 0.1 * s } else { 1.0 };
                q1_modes().map(|m| Mode::new(m.wn_rad_s * s, m.zeta * z))
            })
            .collect();
        Sweeping { k: 0, table }
    }
}

impl Dynamics for Sweeping {
    fn n_modes(&self) -> usize {
        2
    }
    fn modes(&mut self, _q: &[f64], out: &mut [Mode]) -> Status {
        self.k = if self.k + 1 < self.table.len() {
            self.k + 1
        } else {
            0
        };
        if let Some(modes) = self.table.get(self.k) {
            for (o, m) in out.iter_mut().zip(modes) {
                *o = *m;
            }
        }
        Status::OK
    }
    fn slowest_mode(&self, index: usize) -> Option<Mode> {
        q1_modes()
            .get(index)
            .map(|m| Mode::new(0.8 * m.wn_rad_s, m.zeta))
    }
}

/// Slowly drifting modes: `ω_n` ±10 % and `ζ` ±5 % around Q1 over a 10 s sine (a relative
/// change of at most 1.3e-4 per cycle), as a moving arm's modes drift.
struct Drifting {
    k: u32,
}

impl Dynamics for Drifting {
    fn n_modes(&self) -> usize {
        2
    }
    fn modes(&mut self, _q: &[f64], out: &mut [Mode]) -> Status {
        self.k = self.k.wrapping_add(1);
        let phase = 2.0 * PI * (self.k % 5000) as f64 / 5000.0;
        let (s, c) = phase.sin_cos();
        for (o, m) in out.iter_mut().zip(q1_modes()) {
            *o = Mode::new(m.wn_rad_s * (1.0 + 0.1 * s), m.zeta * (1.0 + 0.05 * c));
        }
        Status::OK
    }
    fn slowest_mode(&self, index: usize) -> Option<Mode> {
        q1_modes()
            .get(index)
            .map(|m| Mode::new(0.9 * m.wn_rad_s, 1.05 * m.zeta))
    }
}

/// Joint positions `(STEPS, n)`: a smooth multi-joint move (rad).
fn signal(n: usize) -> Vec<f64> {
    (0..STEPS)
        .flat_map(|i| {
            let t = i as f64 * DT_S;
            (0..n).map(move |j| 0.8 * (2.0 * PI * 0.3 * t + 0.4 * j as f64).sin() - 1.5)
        })
        .collect()
}

type Run = Box<dyn FnMut() -> f64>;

struct Case {
    /// Row number in the full table.
    number: usize,
    name: &'static str,
    /// Index of the case this one is compared with (same round), and the target ratio.
    reference: Option<(usize, Option<f64>)>,
    run: Run,
    ns: Vec<f64>,
    ratios: Vec<f64>,
}

/// Runs a shaper over the whole signal; returns a checksum so nothing is optimized away.
fn shaper_run<D: Dynamics + 'static>(mut shaper: TvShaper<D>, n: usize) -> Run {
    let x = signal(n);
    let mut y = vec![0.0; n];
    Box::new(move || {
        let mut sum = 0.0;
        for row in x.chunks_exact(n) {
            black_box(shaper.step(black_box(row), &mut y));
            sum += y[0];
        }
        sum
    })
}

fn fixed_run<const N: usize>(mut fixed: FixedCascade<N>) -> Run {
    let x: Vec<[f64; N]> = rows(&signal(N));
    fixed.fill(&x[0]);
    Box::new(move || {
        let mut sum = 0.0;
        for row in &x {
            sum += fixed.step(black_box(row))[0];
        }
        sum
    })
}

fn rows<const N: usize>(x: &[f64]) -> Vec<[f64; N]> {
    x.chunks_exact(N)
        .map(|r| r.try_into().expect("N values"))
        .collect()
}

/// Largest difference between the fixed reference and `TvShaper` with constant modes.
fn reference_agreement<const N: usize>(kind: ShaperKind, modes: &[Mode]) -> f64 {
    let x: Vec<[f64; N]> = rows(&signal(N));
    let mut fixed = FixedCascade::<N>::new(kind, modes);
    fixed.fill(&x[0]);
    let cfg = TvShaperConfig::new(DT_S, N, kind);
    let mut shaper =
        TvShaper::new(ConstantModes::new(modes.to_vec()).expect("valid"), &cfg).expect("valid");
    let mut b = [0.0; N];
    let mut worst = 0.0f64;
    for row in &x {
        let a = fixed.step(row);
        let _ = shaper.step(row, &mut b);
        for (p, q) in a.iter().zip(&b) {
            worst = worst.max((p - q).abs());
        }
    }
    worst
}

fn constant(n: usize, kind: ShaperKind, modes: &[Mode]) -> Run {
    let cfg = TvShaperConfig::new(DT_S, n, kind);
    shaper_run(
        TvShaper::new(ConstantModes::new(modes.to_vec()).expect("valid"), &cfg).expect("valid"),
        n,
    )
}

fn with<D: Dynamics + 'static>(dynamics: D, kind: ShaperKind, interp: Interpolation) -> Run {
    let mut cfg = TvShaperConfig::new(DT_S, 6, kind);
    cfg.interp = interp;
    shaper_run(TvShaper::new(dynamics, &cfg).expect("valid"), 6)
}

fn ur5e_map() -> MapDynamics {
    MapDynamics::new(
        robot_support::ur_robot("ur5e", 5.0),
        DynamicMap::paper_ur5e(),
    )
    .expect("valid map")
}

/// Bench row #10 written out by hand for its one case ([`hand_ur5e`]).
fn hand_ur5e() -> hand_ur5e::HandUr5eZv {
    let map = DynamicMap::paper_ur5e();
    let [base, shoulder] = [0, 1].map(|m| map.mode_maps()[m].coefficients);
    hand_ur5e::HandUr5eZv::new(&robot_support::ur_robot("ur5e", 5.0), base, shoulder, DT_S)
}

/// Largest difference between row #10 (`TvShaper` with [`MapDynamics`]) and its hand-written
/// form over the whole signal.
fn hand_agreement() -> f64 {
    let x: Vec<[f64; 6]> = rows(&signal(6));
    let mut hand = hand_ur5e();
    hand.fill(&x[0]);
    let cfg = TvShaperConfig::new(DT_S, 6, ShaperKind::Zv);
    let mut shaper = TvShaper::new(ur5e_map(), &cfg).expect("valid");
    let mut b = [0.0; 6];
    let mut worst = 0.0f64;
    for row in &x {
        let a = hand.step(row);
        let _ = shaper.step(row, &mut b);
        for (p, q) in a.iter().zip(&b) {
            worst = worst.max((p - q).abs());
        }
    }
    worst
}

fn main() {
    let q1 = q1_modes();
    let ei = ShaperKind::from_name("ei", None).expect("registry name");
    let linear = Interpolation::Linear;
    let mut cases: Vec<Case> = Vec::new();
    let mut add = |name, reference, run| {
        cases.push(Case {
            number: cases.len() + 1,
            name,
            reference,
            run,
            ns: Vec::new(),
            ratios: Vec::new(),
        });
        cases.len() - 1
    };
    let fixed_zv1 = add(
        "1 DOF, 1 mode ZV: plain fixed convolution",
        None,
        fixed_run(FixedCascade::<1>::new(ShaperKind::Zv, &[ONE_MODE])),
    );
    add(
        "1 DOF, 1 mode ZV: TvShaper, constant mode",
        Some((fixed_zv1, Some(3.0))),
        constant(1, ShaperKind::Zv, &[ONE_MODE]),
    );
    let fixed_zvd1 = add(
        "1 DOF, 1 mode ZVD: plain fixed convolution",
        None,
        fixed_run(FixedCascade::<1>::new(ShaperKind::Zvd, &[ONE_MODE])),
    );
    add(
        "1 DOF, 1 mode ZVD: TvShaper, constant mode",
        Some((fixed_zvd1, Some(3.0))),
        constant(1, ShaperKind::Zvd, &[ONE_MODE]),
    );
    let fixed6 = add(
        "6 DOF, 2 modes ZV: plain fixed convolution",
        None,
        fixed_run(FixedCascade::<6>::new(ShaperKind::Zv, &q1)),
    );
    let constant6 = add(
        "6 DOF, 2 modes ZV: TvShaper, constant modes",
        Some((fixed6, Some(1.5))),
        constant(6, ShaperKind::Zv, &q1),
    );
    add(
        "6 DOF, 2 modes ZV: ω_n changes every cycle",
        Some((constant6, Some(1.5))),
        with(Sweeping::new(false), ShaperKind::Zv, linear),
    );
    add(
        "6 DOF, 2 modes ZV: ω_n and ζ change every cycle",
        Some((constant6, None)),
        with(Sweeping::new(true), ShaperKind::Zv, linear),
    );
    add(
        "6 DOF, 2 modes ZV, cubic reads: ω_n changes every cycle",
        Some((constant6, None)),
        with(Sweeping::new(false), ShaperKind::Zv, Interpolation::Cubic),
    );
    add(
        "6 DOF, 2 modes ZV: UR5e inertia + paper map + shaping",
        Some((constant6, Some(4.0))),
        with(ur5e_map(), ShaperKind::Zv, linear),
    );
    add(
        "UR5e inertia + paper map alone (MapDynamics::modes)",
        Some((constant6, None)),
        {
            let mut provider = ur5e_map();
            let x = signal(6);
            let mut modes = [Mode::new(0.0, 0.0); 2];
            Box::new(move || {
                let mut sum = 0.0;
                for q in x.chunks_exact(6) {
                    black_box(provider.modes(black_box(q), &mut modes));
                    sum += modes[0].wn_rad_s;
                }
                sum
            })
        },
    );
    let zvd_drift = add(
        "6 DOF, 2 modes ZVD: modes drift slowly",
        Some((constant6, None)),
        with(Drifting { k: 0 }, ShaperKind::Zvd, linear),
    );
    add(
        "6 DOF, 2 modes EI (exact, V = 5 %): modes drift slowly",
        Some((zvd_drift, Some(3.0))),
        with(Drifting { k: 0 }, ei, linear),
    );

    add(
        "6 DOF, 2 modes ZV: #10 written out by hand for the UR5e (the floor)",
        Some((constant6, None)),
        {
            let x: Vec<[f64; 6]> = rows(&signal(6));
            let mut hand = hand_ur5e();
            hand.fill(&x[0]);
            Box::new(move || {
                let mut sum = 0.0;
                for row in &x {
                    sum += hand.step(black_box(row))[0];
                }
                sum
            })
        },
    );

    // Same impulses, the same two-point reads in another order: rounding only.
    for d in [
        reference_agreement::<1>(ShaperKind::Zv, &[ONE_MODE]),
        reference_agreement::<1>(ShaperKind::Zvd, &[ONE_MODE]),
        reference_agreement::<6>(ShaperKind::Zv, &q1),
    ] {
        assert!(d <= 1e-12, "the fixed reference disagrees by {d}");
    }
    // The same modes up to rounding in a loop that feeds the output back into the modes: a
    // 1e-16 relative difference of a delay moves a read by 1e-16 of a sample.
    let d = hand_agreement();
    assert!(d <= 1e-12, "the hand-written row #10 disagrees by {d} rad");

    // Instruction counts (load-independent): `TVIST_BENCH_CASE=<#>` runs that case's cycles
    // once inside `measured`, for `valgrind --tool=callgrind --toggle-collect=*measured*`.
    if let Ok(k) = std::env::var("TVIST_BENCH_CASE") {
        let k: usize = k.parse().expect("TVIST_BENCH_CASE is a case number");
        let case = cases
            .get_mut(k - 1)
            .expect("TVIST_BENCH_CASE is a case number");
        black_box((case.run)());
        println!("{}: {}", k, case.name);
        black_box(measured(&mut case.run));
        return;
    }

    // `TVIST_BENCH_CASES=6,10,11` times only these cases and the ones they are compared with.
    if let Ok(list) = std::env::var("TVIST_BENCH_CASES") {
        let mut keep = vec![false; cases.len()];
        for k in list.split(',') {
            let k: usize = k
                .trim()
                .parse()
                .expect("TVIST_BENCH_CASES lists case numbers");
            keep[k - 1] = true;
            if let Some((r, _)) = cases[k - 1].reference {
                keep[r] = true;
            }
        }
        let mut index = 0;
        let mut renumber = vec![0; cases.len()];
        for (i, &kept) in keep.iter().enumerate() {
            renumber[i] = index;
            index += usize::from(kept);
        }
        let mut i = 0;
        cases.retain(|_| {
            i += 1;
            keep[i - 1]
        });
        for case in &mut cases {
            case.reference = case
                .reference
                .filter(|&(r, _)| keep[r])
                .map(|(r, target)| (renumber[r], target));
        }
    }

    // Warm-up round, then interleaved measured rounds in a rotated order.
    for case in &mut cases {
        black_box((case.run)());
    }
    let n_cases = cases.len();
    let load_before = load_average();
    for round in 0..ROUNDS {
        for k in 0..n_cases {
            let case = &mut cases[(k + round) % n_cases];
            let start = Instant::now();
            black_box(measured(&mut case.run));
            case.ns
                .push(start.elapsed().as_secs_f64() * 1e9 / STEPS as f64);
        }
        for i in 0..n_cases {
            if let Some((r, _)) = cases[i].reference {
                let ratio = cases[i].ns[round] / cases[r].ns[round];
                cases[i].ratios.push(ratio);
            }
        }
    }
    print_table(&cases, load_before, load_average());
    // How far the general path of row #10 is from its hand-written floor (row #14).
    let row = |number| cases.iter().find(|c| c.number == number);
    if let (Some(general), Some(floor)) = (row(10), row(14)) {
        let ratios: Vec<f64> = general
            .ns
            .iter()
            .zip(&floor.ns)
            .map(|(g, f)| g / f)
            .collect();
        println!(
            "\n#10 / #14 (the general path against its hand-written floor): {:.2}",
            median(&ratios)
        );
    }
}

/// One pass of a case: [`STEPS`] cycles.
#[inline(never)]
fn measured(run: &mut Run) -> f64 {
    run()
}

/// The machine's 1-minute load average (`/proc/loadavg`; `None` where there is none): the
/// table states the load it was measured under, since other processes slow every case.
fn load_average() -> Option<f64> {
    std::fs::read_to_string("/proc/loadavg")
        .ok()?
        .split_whitespace()
        .next()?
        .parse()
        .ok()
}

fn print_table(cases: &[Case], load_before: Option<f64>, load_after: Option<f64>) {
    let load = |l: Option<f64>| l.map_or("unknown".to_string(), |v| format!("{v:.2}"));
    println!(
        "{ROUNDS} interleaved rounds of {STEPS} cycles per case (500 Hz, linear reads unless \
         noted); ns per cycle; ratio: median over the rounds of case / reference (same round); \
         1-minute load average {} before the rounds, {} after\n",
        load(load_before),
        load(load_after)
    );
    println!("| # | case | min ns | median ns | ratio to | ratio | target |");
    println!("|---|---|---|---|---|---|---|");
    for c in cases {
        let (reference, ratio, target) = match c.reference {
            Some((r, target)) => {
                let ratio = median(&c.ratios);
                let verdict = |t: f64| {
                    let met = if ratio <= t { "met" } else { "not met" };
                    format!("≤ {t} ({met})")
                };
                (
                    format!("#{}", cases[r].number),
                    format!("{ratio:.2}"),
                    target.map(verdict).unwrap_or_default(),
                )
            }
            None => ("".into(), "".into(), "".into()),
        };
        println!(
            "| {} | {} | {:.1} | {:.1} | {reference} | {ratio} | {target} |",
            c.number,
            c.name,
            min(&c.ns),
            median(&c.ns),
        );
    }
}

fn min(v: &[f64]) -> f64 {
    v.iter().copied().fold(f64::INFINITY, f64::min)
}

fn median(v: &[f64]) -> f64 {
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    match s.len() {
        0 => f64::NAN,
        n if n % 2 == 1 => s[n / 2],
        n => 0.5 * (s[n / 2 - 1] + s[n / 2]),
    }
}
