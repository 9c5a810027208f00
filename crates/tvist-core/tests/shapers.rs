//! The shaper library against its closed forms and its defining residual-vibration properties.

use core::f64::consts::PI;
use proptest::prelude::*;
use tvist_core::shaper::MAX_IMPULSES;
use tvist_core::{prv, Error, Impulses, Mode, ShaperKind, SHAPER_NAMES};

/// Modes used throughout: low and high frequency, undamped to strongly damped.
const MODES: [(f64, f64); 6] = [
    (2.0 * PI * 8.0, 0.0),
    (2.0 * PI * 8.0, 0.05),
    (50.0, 0.1),
    (2.0 * PI * 22.0, 0.26),
    (3.0, 0.37),
    (120.0, 0.6),
];

fn all_kinds() -> Vec<ShaperKind> {
    SHAPER_NAMES
        .iter()
        .map(|n| ShaperKind::from_name(n, None).expect("registry name"))
        .collect()
}

fn prv_of(set: &Impulses, wn: f64, zeta: f64) -> f64 {
    prv(set.amplitudes(), set.times_s(), wn, zeta)
}

#[test]
fn zv_and_zvd_equal_their_closed_forms() {
    for &(wn, zeta) in &MODES {
        let mode = Mode::new(wn, zeta);
        let k = (-zeta * PI / (1.0 - zeta * zeta).sqrt()).exp();
        let wd = wn * (1.0 - zeta * zeta).sqrt();
        let td = 2.0 * PI / wd;
        let zv = ShaperKind::Zv.design(mode);
        let zvd = ShaperKind::Zvd.design(mode);
        let expect_zv = ([1.0 / (1.0 + k), k / (1.0 + k)], [0.0, PI / wd]);
        let d = (1.0 + k) * (1.0 + k);
        let expect_zvd = ([1.0 / d, 2.0 * k / d, k * k / d], [0.0, td / 2.0, td]);
        // 1e-12: the formulas are evaluated in a different order; rounding differs at 1e-16.
        for (got, want) in zv
            .amplitudes()
            .iter()
            .zip(expect_zv.0)
            .chain(zv.times_s().iter().zip(expect_zv.1))
        {
            assert!(
                (got - want).abs() <= 1e-12 * want.abs().max(1.0),
                "ZV {got} vs {want}"
            );
        }
        for (got, want) in zvd
            .amplitudes()
            .iter()
            .zip(expect_zvd.0)
            .chain(zvd.times_s().iter().zip(expect_zvd.1))
        {
            assert!(
                (got - want).abs() <= 1e-12 * want.abs().max(1.0),
                "ZVD {got} vs {want}"
            );
        }
        assert_eq!(zv.len(), 2);
        assert_eq!(zvd.len(), 3);
    }
}

#[test]
fn zero_vibration_shapers_cancel_their_design_mode() {
    for kind in [
        ShaperKind::Zv,
        ShaperKind::Zvd,
        ShaperKind::Zvdd,
        ShaperKind::Mzv,
    ] {
        for &(wn, zeta) in &MODES {
            let set = Impulses::design(kind, Mode::new(wn, zeta)).expect("valid");
            let r = prv_of(&set, wn, zeta);
            // Exact cancellation in theory; 1e-9 leaves room for rounding only.
            assert!(r <= 1e-9, "{} at ({wn}, {zeta}): PRV {r}", kind.name());
            // ...and the check can fail: 60 % off-design it leaves vibration (for the lightly
            // damped modes; ZVDD at ζ = 0.6 is robust enough to stay below 1e-3 there).
            if zeta <= 0.3 {
                assert!(
                    prv_of(&set, 1.6 * wn, zeta) > 1e-3,
                    "{} off-design",
                    kind.name()
                );
            }
        }
    }
}

#[test]
fn every_registry_shaper_is_normalized_sorted_and_starts_at_zero() {
    for kind in all_kinds() {
        for &(wn, zeta) in &MODES {
            if zeta > kind.max_zeta() {
                continue;
            }
            let a = kind.design(Mode::new(wn, zeta));
            assert!(a.len() <= MAX_IMPULSES);
            let sum: f64 = a.amplitudes().iter().sum();
            assert!((sum - 1.0).abs() <= 1e-14, "{}: sum {sum}", kind.name());
            assert_eq!(a.times_s()[0], 0.0);
            assert!(
                a.times_s().windows(2).all(|w| w[1] >= w[0]),
                "{} unsorted",
                kind.name()
            );
            assert!(
                a.amplitudes().iter().all(|&x| x > 0.0),
                "{}: {:?}",
                kind.name(),
                a.amplitudes()
            );
        }
    }
}

/// Residual vibration of `set` on `(r·wn, zeta)` for r on a fine grid.
fn sweep(set: &Impulses, wn: f64, zeta: f64, lo: f64, hi: f64, n: usize) -> Vec<(f64, f64)> {
    (0..=n)
        .map(|i| {
            let r = lo + (hi - lo) * i as f64 / n as f64;
            (r, prv_of(set, r * wn, zeta))
        })
        .collect()
}

/// The contiguous interval of frequency ratios around 1 where `prv <= limit`.
fn band(curve: &[(f64, f64)], limit: f64) -> (f64, f64) {
    let centre = curve
        .iter()
        .position(|&(r, _)| r >= 1.0)
        .expect("grid covers 1");
    assert!(curve[centre].1 <= limit, "design point above the limit");
    let mut lo = centre;
    while lo > 0 && curve[lo - 1].1 <= limit {
        lo -= 1;
    }
    let mut hi = centre;
    while hi + 1 < curve.len() && curve[hi + 1].1 <= limit {
        hi += 1;
    }
    assert!(
        lo > 0 && hi + 1 < curve.len(),
        "band reaches the sweep edge"
    );
    (curve[lo].0, curve[hi].0)
}

/// Accuracy of the published EI polynomial fit for the design-point vibration, per tolerance:
/// the fit's worst deviation from `V` over ζ ∈ [0, 0.2] is 3.5e-4 (V = 3 %), 1.22e-3 (5 %, at
/// ζ = 0) and 4.8e-3 (10 %, at ζ = 0), measured independently in tests/test_shapers.py.
fn ei_fit_accuracy(v_tol: f64) -> f64 {
    if v_tol <= 0.03 {
        1e-3
    } else if v_tol <= 0.05 {
        1.5e-3
    } else {
        5e-3
    }
}

#[test]
fn ei_meets_its_tolerance_at_the_design_point_and_over_its_band() {
    for v_tol in [0.03, 0.05, 0.1] {
        let kind = ShaperKind::from_name("ei", Some(v_tol)).expect("valid tolerance");
        for zeta in [0.0, 0.05, 0.1, 0.2] {
            let wn = 2.0 * PI * 10.0;
            let set = Impulses::design(kind, Mode::new(wn, zeta)).expect("valid");
            let acc = ei_fit_accuracy(v_tol);
            let at_design = prv_of(&set, wn, zeta);
            assert!(
                (at_design - v_tol).abs() <= acc,
                "V={v_tol} ζ={zeta}: PRV {at_design}"
            );
            let curve = sweep(&set, wn, zeta, 0.5, 1.6, 11_000);
            let (lo, hi) = band(&curve, v_tol + acc);
            // The EI band is ±20 % at V = 5 % undamped; require at least ±10 % for all V.
            assert!(
                lo < 0.9 && hi > 1.1,
                "V={v_tol} ζ={zeta}: band [{lo}, {hi}] too narrow"
            );
            // Inside the band it never exceeds the tolerance (by construction of `band`), and
            // just outside it does: the band is where the insensitivity ends.
            assert!(prv_of(&set, 0.97 * lo * wn, zeta) > v_tol + acc);
            assert!(prv_of(&set, 1.03 * hi * wn, zeta) > v_tol + acc);
            // A ZV shaper is far more sensitive: at the band edges it leaves several times more.
            let zv = Impulses::design(ShaperKind::Zv, Mode::new(wn, zeta)).expect("valid");
            assert!(prv_of(&zv, lo * wn, zeta) > 1.5 * v_tol);
        }
    }
}

/// Local maxima and minima of a sampled curve.
/// Sampled `(frequency ratio, PRV)` points.
type Points = Vec<(f64, f64)>;

fn extrema(curve: &[(f64, f64)]) -> (Points, Points) {
    let mut max = Vec::new();
    let mut min = Vec::new();
    for w in curve.windows(3) {
        if w[1].1 > w[0].1 && w[1].1 > w[2].1 {
            max.push(w[1]);
        }
        if w[1].1 < w[0].1 && w[1].1 < w[2].1 {
            min.push(w[1]);
        }
    }
    (max, min)
}

#[test]
fn multi_hump_ei_shapers_have_their_humps() {
    // The 2- and 3-hump tables are fitted for V = 5 %; the fit's humps reach at most 5.55 %
    // for ζ <= 0.2 (measured), hence the 0.6 % allowance.
    let limit = 0.05 + 0.006;
    for (kind, humps) in [(ShaperKind::Ei2Hump, 2), (ShaperKind::Ei3Hump, 3)] {
        for zeta in [0.0, 0.05, 0.1, 0.2] {
            let wn = 40.0;
            let set = Impulses::design(kind, Mode::new(wn, zeta)).expect("valid");
            let curve = sweep(&set, wn, zeta, 0.35, 1.9, 15_500);
            let (lo, hi) = band(&curve, limit);
            let inside: Vec<_> = curve
                .iter()
                .copied()
                .filter(|&(r, _)| r >= lo && r <= hi)
                .collect();
            let (max, min) = extrema(&inside);
            assert_eq!(max.len(), humps, "{} ζ={zeta}: maxima {max:?}", kind.name());
            assert_eq!(
                min.len(),
                humps + 1,
                "{} ζ={zeta}: minima {min:?}",
                kind.name()
            );
            for &(_, p) in &max {
                assert!(p > 0.03 && p <= limit, "{} ζ={zeta}: hump {p}", kind.name());
            }
            for &(_, p) in &min {
                assert!(p < 0.02, "{} ζ={zeta}: zero {p}", kind.name());
            }
            // 2-hump: a zero at the design point; 3-hump: its middle hump there.
            let design = prv_of(&set, wn, zeta);
            match humps {
                2 => assert!(design < 0.004, "2-hump design PRV {design}"),
                _ => assert!((design - 0.05).abs() < 0.006, "3-hump design PRV {design}"),
            }
            // Wider than the one-hump EI: at least ±25 %.
            assert!(
                lo < 0.75 && hi > 1.25,
                "{} ζ={zeta}: band [{lo}, {hi}]",
                kind.name()
            );
            assert!(prv_of(&set, 0.97 * lo * wn, zeta) > limit);
            assert!(prv_of(&set, 1.03 * hi * wn, zeta) > limit);
        }
    }
}

#[test]
fn zeta_beyond_a_fit_range_is_rejected_at_design() {
    for kind in [
        ShaperKind::Ei { v_tol: 0.05 },
        ShaperKind::Ei2Hump,
        ShaperKind::Ei3Hump,
    ] {
        let err = Impulses::design(kind, Mode::new(10.0, kind.max_zeta() + 0.01))
            .expect_err("beyond the fit");
        assert!(err.to_string().contains(kind.name()), "{err}");
        assert!(Impulses::design(kind, Mode::new(10.0, kind.max_zeta())).is_ok());
    }
    // The closed forms cover every underdamped mode.
    assert!(Impulses::design(ShaperKind::Zvd, Mode::new(10.0, 0.999)).is_ok());
}

#[test]
fn invalid_modes_and_names_are_rejected() {
    for (wn, zeta) in [
        (0.0, 0.1),
        (-1.0, 0.1),
        (f64::NAN, 0.1),
        (f64::INFINITY, 0.1),
        (1e-320, 0.1),
        (10.0, -0.01),
        (10.0, 1.0),
        (10.0, f64::NAN),
    ] {
        assert!(matches!(
            Impulses::design(ShaperKind::Zv, Mode::new(wn, zeta)),
            Err(Error::InvalidMode { .. })
        ));
    }
    assert!(matches!(
        ShaperKind::from_name("zvx", None),
        Err(Error::UnknownShaper(_))
    ));
    for bad in [0.0, -0.1, 0.21, f64::NAN] {
        assert!(matches!(
            ShaperKind::from_name("ei", Some(bad)),
            Err(Error::InvalidParameter(_))
        ));
    }
    assert!(matches!(
        ShaperKind::from_name("zv", Some(0.05)),
        Err(Error::InvalidParameter(_))
    ));
    for name in SHAPER_NAMES {
        assert_eq!(
            ShaperKind::from_name(name, None).expect("registry").name(),
            name
        );
    }
}

#[test]
fn custom_sets_are_validated_and_normalized() {
    let cases: [(Vec<f64>, Vec<f64>, &str); 7] = [
        (vec![], vec![], "empty"),
        (vec![1.0, 1.0], vec![0.0], "2 amplitudes but 1 times"),
        (
            vec![1.0, f64::NAN],
            vec![0.0, 0.1],
            "amplitude 1 is not finite",
        ),
        (
            vec![1.0, 1.0],
            vec![0.0, f64::INFINITY],
            "time 1 is not finite",
        ),
        (vec![1.0, 1.0], vec![0.2, 0.1], "non-decreasing"),
        (vec![1.0, -1.0], vec![0.0, 0.1], "sum to zero"),
        (vec![1.0], vec![-0.1], "negative"),
    ];
    for (a, t, what) in cases {
        let err = Impulses::new(a, t).expect_err(what).to_string();
        assert!(err.contains(what), "expected {what:?} in {err:?}");
    }
    let set = Impulses::new(vec![2.0, 2.0], vec![0.0, 0.05]).expect("valid");
    assert_eq!(set.amplitudes(), &[0.5, 0.5]);
    assert_eq!(set.duration_s(), 0.05);
}

#[test]
fn prv_matches_a_direct_evaluation_and_is_one_for_a_single_impulse() {
    // One impulse leaves the full vibration.
    assert!((prv(&[1.0], &[0.0], 10.0, 0.1) - 1.0).abs() < 1e-15);
    assert!((prv(&[1.0], &[0.3], 10.0, 0.1) - 1.0).abs() < 1e-15);
    // Direct formula (eqs. 52-55) with the exponent applied as written.
    let (a, t): ([f64; 3], [f64; 3]) = ([0.3, 0.5, 0.2], [0.0, 0.04, 0.11]);
    let (wn, z): (f64, f64) = (37.0, 0.12);
    let wd = wn * (1.0 - z * z).sqrt();
    let c: f64 = a
        .iter()
        .zip(&t)
        .map(|(a, t)| a * (z * wn * t).exp() * (wd * t).cos())
        .sum();
    let s: f64 = a
        .iter()
        .zip(&t)
        .map(|(a, t)| a * (z * wn * t).exp() * (wd * t).sin())
        .sum();
    let direct = (-z * wn * t[2]).exp() * (c * c + s * s).sqrt();
    assert!((prv(&a, &t, wn, z) - direct).abs() < 1e-14);
    // Extra entries of the longer slice are ignored (also for the final time).
    assert!((prv(&[1.0], &[0.0, 5.0], 10.0, 0.1) - 1.0).abs() < 1e-15);
    assert!(prv(&a, &t, -1.0, z).is_nan());
    assert!(prv(&a, &t, wn, 1.0).is_nan());
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(200))]

    /// Eq. 53: the residual vibration of a convolution is the product of the factors'.
    #[test]
    fn convolution_multiplies_residual_vibration(
        k1 in 0usize..7, k2 in 0usize..7,
        f1 in 2.0f64..30.0, f2 in 2.0f64..30.0,
        z1 in 0.0f64..0.2, z2 in 0.0f64..0.2,
        fe in 1.0f64..40.0, ze in 0.0f64..0.5,
    ) {
        let kinds = all_kinds();
        let s1 = Impulses::design(kinds[k1], Mode::new(2.0 * PI * f1, z1)).expect("valid");
        let s2 = Impulses::design(kinds[k2], Mode::new(2.0 * PI * f2, z2)).expect("valid");
        let c = Impulses::convolve(&[&s1, &s2]).expect("valid");
        let sum: f64 = c.amplitudes().iter().sum();
        prop_assert!((sum - 1.0).abs() < 1e-12);
        prop_assert!(c.times_s().windows(2).all(|w| w[1] > w[0]));
        prop_assert!((c.duration_s() - s1.duration_s() - s2.duration_s()).abs() < 1e-12);
        let we = 2.0 * PI * fe;
        let product = prv_of(&s1, we, ze) * prv_of(&s2, we, ze);
        prop_assert!((prv_of(&c, we, ze) - product).abs() < 1e-12, "{} vs {}", prv_of(&c, we, ze), product);
        // At each design mode the convolution inherits that factor's cancellation.
        prop_assert!(prv_of(&c, 2.0 * PI * f1, z1) <= prv_of(&s1, 2.0 * PI * f1, z1) + 1e-12);
    }
}
