//! The step's shortcuts give exactly what the general path gives.
//!
//! `TvShaper::step` runs channel counts up to 7 with fixed-size rows and any other count with
//! slices; a provider whose modes are constant is asked once per start; a new `ω_n` with the
//! held `ζ` only rescales the delays. Each shortcut must reproduce the general computation
//! bit for bit (the same operations in the same order), outputs and status alike, so the
//! comparisons here are exact.

use tvist_core::{
    ConstantModes, Dynamics, Interpolation, Mode, ModeFilter, ShaperKind, Status, TvShaper,
    TvShaperConfig, SHAPER_NAMES,
};

const DT_S: f64 = 0.002;

/// Modes that change every cycle, independent of `q`: `ω_n` alone most cycles, `ζ` every
/// 7th, an invalid mode every 50th, and delays beyond a short line now and then.
struct Scripted {
    k: usize,
}

impl Dynamics for Scripted {
    fn n_modes(&self) -> usize {
        2
    }
    fn modes(&mut self, _q: &[f64], out: &mut [Mode]) -> Status {
        self.k += 1;
        let s = (self.k % 300) as f64 / 300.0;
        let zeta = 0.05 + 0.02 * (self.k / 7) as f64 % 0.3;
        out[0] = if self.k % 50 == 0 {
            Mode::new(f64::NAN, zeta)
        } else {
            Mode::new(2.0 * std::f64::consts::PI * (4.0 + 12.0 * s), zeta)
        };
        out[1] = Mode::new(70.0 + 30.0 * s, 0.1);
        Status::OK
    }
    fn slowest_mode(&self, _index: usize) -> Option<Mode> {
        None
    }
}

/// Constant modes that do not say so: the shaper asks and compares every cycle.
struct Unannounced(ConstantModes);

impl Dynamics for Unannounced {
    fn n_modes(&self) -> usize {
        self.0.n_modes()
    }
    fn modes(&mut self, q: &[f64], out: &mut [Mode]) -> Status {
        self.0.modes(q, out)
    }
    fn slowest_mode(&self, index: usize) -> Option<Mode> {
        self.0.slowest_mode(index)
    }
}

/// Sample `i` of channel `c`: a smooth move with an occasional non-finite sample.
fn sample(i: usize, c: usize) -> f64 {
    if i % 211 == 13 && c == 1 {
        return f64::INFINITY;
    }
    (0.013 * i as f64 + 0.7 * c as f64).sin() * (1.0 + 0.1 * c as f64)
}

fn config(n_dof: usize, kind: ShaperKind, interp: Interpolation) -> TvShaperConfig {
    let mut cfg = TvShaperConfig::new(DT_S, n_dof, kind);
    cfg.interp = interp;
    cfg.max_delay_s = Some(0.15); // the slowest modes' delays exceed it: clamping runs too
    cfg
}

/// Runs `a` (3 channels: the fixed-size rows) and `b` (9 channels: slices; its first three
/// carry the same signals) side by side, with a reset and a clear on the way, and requires
/// identical outputs and statuses.
fn assert_same_as_slices<D: Dynamics, E: Dynamics>(
    mut a: TvShaper<D>,
    mut b: TvShaper<E>,
    what: &str,
) {
    let (mut ya, mut yb) = ([0.0; 3], [0.0; 9]);
    for i in 0..3000 {
        if i == 1200 {
            a.reset(&[0.2, -0.1, 0.3]);
            b.reset(&[0.2, -0.1, 0.3, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]);
        }
        if i == 2100 {
            a.clear();
            b.clear();
        }
        let x: Vec<f64> = (0..9).map(|c| sample(i, c)).collect();
        let sa = a.step(&x[..3], &mut ya);
        let sb = b.step(&x, &mut yb);
        assert_eq!(sa, sb, "{what}: status of cycle {i}");
        assert_eq!(ya[..], yb[..3], "{what}: cycle {i}");
    }
}

#[test]
fn fixed_size_rows_give_what_slices_give() {
    for name in SHAPER_NAMES {
        let kind = ShaperKind::from_name(name, None).expect("registry name");
        for interp in [Interpolation::Linear, Interpolation::Cubic] {
            let what = format!("{name} {interp:?}");
            let a = TvShaper::new(Scripted { k: 0 }, &config(3, kind, interp)).expect("valid");
            let b = TvShaper::new(Scripted { k: 0 }, &config(9, kind, interp)).expect("valid");
            assert_same_as_slices(a, b, &what);
        }
    }
}

#[test]
fn constant_modes_asked_once_give_what_asking_every_cycle_gives() {
    // The second mode's ZV delay (about 0.16 s at 3 Hz) exceeds the 0.15 s line, so the
    // held design's DELAY_CLAMPED must be reported every cycle on the shortcut as well.
    let modes = vec![
        Mode::new(50.0, 0.15),
        Mode::new(2.0 * 3.0 * std::f64::consts::PI, 0.1),
    ];
    for name in SHAPER_NAMES {
        let kind = ShaperKind::from_name(name, None).expect("registry name");
        for interp in [Interpolation::Linear, Interpolation::Cubic] {
            for n_dof in [3, 9] {
                let constant = ConstantModes::new(modes.clone()).expect("valid");
                assert!(constant.modes_are_constant());
                let cfg = config(n_dof, kind, interp);
                let mut a = TvShaper::new(constant.clone(), &cfg).expect("valid");
                let mut b = TvShaper::new(Unannounced(constant), &cfg).expect("valid");
                let (mut ya, mut yb) = (vec![0.0; n_dof], vec![0.0; n_dof]);
                let mut clamped = 0;
                for i in 0..2000 {
                    if i == 700 {
                        a.reset(&vec![0.5; n_dof]);
                        b.reset(&vec![0.5; n_dof]);
                    }
                    if i == 1400 {
                        // Access to the provider: the next step asks again.
                        let _ = a.dynamics_mut();
                    }
                    let x: Vec<f64> = (0..n_dof).map(|c| sample(i, c)).collect();
                    let (sa, sb) = (a.step(&x, &mut ya), b.step(&x, &mut yb));
                    assert_eq!(sa, sb, "{name} {interp:?} {n_dof}: status of cycle {i}");
                    assert_eq!(ya, yb, "{name} {interp:?} {n_dof}: cycle {i}");
                    clamped += usize::from(sa.contains(Status::DELAY_CLAMPED));
                }
                assert_eq!(
                    clamped, 2000,
                    "{name} {interp:?}: clamping reported every cycle"
                );
            }
        }
    }
}

#[test]
fn a_new_natural_frequency_alone_gives_what_a_fresh_design_gives() {
    // Filter `a` sees ω_n change with ζ held (the rescaling shortcut); filter `b` forgets
    // its design before every cycle, so it designs from scratch for the same mode.
    for name in ["zv", "zvd", "zvdd", "mzv", "2hump_ei", "3hump_ei"] {
        let kind = ShaperKind::from_name(name, None).expect("registry name");
        for interp in [Interpolation::Linear, Interpolation::Cubic] {
            let new = || ModeFilter::new(kind, 2, DT_S, 0.2, interp).expect("valid");
            let (mut a, mut b) = (new(), new());
            for i in 0..1500 {
                // 2.4 Hz (delays beyond the 0.2 s line, clamped) up to 40 Hz.
                let wn =
                    2.0 * std::f64::consts::PI * (2.4 + 37.6 * ((i * 37) % 400) as f64 / 400.0);
                let mode = Mode::new(wn, 0.12);
                let x = [sample(i, 0), sample(i, 2)];
                b.forget_mode();
                let (sa, sb) = (a.step(&x, mode), b.step(&x, mode));
                assert_eq!(sa, sb, "{name} {interp:?}: status of cycle {i}");
                assert_eq!(a.output(), b.output(), "{name} {interp:?}: cycle {i}");
                assert_eq!(
                    a.impulses(),
                    kind.design(mode),
                    "{name} {interp:?}: cycle {i}"
                );
            }
        }
    }
}

#[test]
fn drifting_modes_give_what_a_fresh_design_gives() {
    // Filter `a` follows modes that drift slowly (relative steps up to 7e-4 in `ω_n` and 2e-3
    // in `ζ`, as a moving arm's modes do), so most cycles keep every delay's whole sample and
    // only re-split the fractions; the sweep also crosses whole samples, runs into the short
    // line's clamping and back, and holds an invalid mode now and then. Filter `b` forgets
    // its design before every cycle and prepares from scratch. Outputs, statuses and
    // impulses must agree to the bit. (The exact EI shaper's first design is a Newton solve
    // and later ones read its table, so a fresh design differs there by design.)
    for name in ["zv", "zvd", "zvdd", "mzv", "2hump_ei", "3hump_ei"] {
        let kind = ShaperKind::from_name(name, None).expect("registry name");
        for interp in [Interpolation::Linear, Interpolation::Cubic] {
            let new = || ModeFilter::new(kind, 2, DT_S, 0.2, interp).expect("valid");
            let (mut a, mut b) = (new(), new());
            let mut clamped = 0;
            for i in 0..6000 {
                let phase = 2.0 * std::f64::consts::PI * i as f64 / 6000.0;
                // 2.3 Hz (delays beyond the 0.2 s line) to 12.7 Hz and back; ζ 0.05–0.19.
                let wn = 2.0 * std::f64::consts::PI * (7.5 - 5.2 * phase.cos());
                let zeta = 0.12 + 0.07 * (3.0 * phase).sin();
                let mode = if i % 997 == 500 {
                    Mode::new(f64::NAN, zeta)
                } else {
                    Mode::new(wn, zeta)
                };
                let x = [sample(i, 0), sample(i, 2)];
                b.forget_mode();
                if !mode.is_valid() {
                    // `b` holds nothing after forgetting; give it `a`'s held mode instead.
                    let _ = b.step(&x, Mode::new(wn_before(i), zeta_before(i)));
                    let sa = a.step(&x, mode);
                    assert!(sa.contains(Status::MODES_HELD), "{name}: cycle {i}");
                    assert_eq!(a.output(), b.output(), "{name} {interp:?}: cycle {i}");
                    continue;
                }
                let (sa, sb) = (a.step(&x, mode), b.step(&x, mode));
                assert_eq!(sa, sb, "{name} {interp:?}: status of cycle {i}");
                assert_eq!(a.output(), b.output(), "{name} {interp:?}: cycle {i}");
                assert_eq!(a.impulses(), b.impulses(), "{name} {interp:?}: cycle {i}");
                assert_eq!(a.impulses(), kind.design(mode), "{name} {interp:?}: {i}");
                clamped += usize::from(sa.contains(Status::DELAY_CLAMPED));
            }
            assert!(clamped > 100, "{name} {interp:?}: clamping ran ({clamped})");
        }
    }
}

/// The mode [`drifting_modes_give_what_a_fresh_design_gives`] gave in cycle `i − 1`.
fn wn_before(i: usize) -> f64 {
    let phase = 2.0 * std::f64::consts::PI * (i - 1) as f64 / 6000.0;
    2.0 * std::f64::consts::PI * (7.5 - 5.2 * phase.cos())
}

fn zeta_before(i: usize) -> f64 {
    let phase = 2.0 * std::f64::consts::PI * (i - 1) as f64 / 6000.0;
    0.12 + 0.07 * (3.0 * phase).sin()
}
