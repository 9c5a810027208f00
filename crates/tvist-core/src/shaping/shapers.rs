//! The shaper library: impulse sequences as data.
//!
//! Every sequence is normalized to `Σ A_i = 1` (so the final position is kept) with
//! non-decreasing times in seconds starting at `t_0 = 0`. Formulas:
//! - ZV / ZVD / ZVDD: closed forms, e.g. ZV `A = [1, K]/(1+K)`, `t = [0, π/ω_d]`,
//!   `K = exp(−ζπ/√(1−ζ²))`.
//! - MZV: three impulses at `[0, 3/8, 3/4]·T_d` with the damped amplitudes of the standard
//!   modified-ZV form.
//!
//!   These four are defined once (`ClosedForm`); the general shape and the time-varying
//!   filter's direct path both evaluate that definition.
//! - EI: designed exactly for the damped mode ([`crate::shaping::ei`]: residual vibration `V` at the
//!   design point, its local maximum, and zero vibration at one frequency either side), starting
//!   from the published polynomial-in-ζ fit; the vibration tolerance `V` is a parameter
//!   (default 5 %).
//! - 2-hump and 3-hump EI: the standard polynomial-in-ζ approximations (the same ones
//!   3D-printer firmware uses), tabulated for 5 %.
//!
//! [`ShaperKind::design`] is allocation-free and used every control cycle; [`Impulses`] is the
//! heap-backed set used offline (custom sets, convolution, analysis).

use crate::error::Error;
use crate::shaping::ei;
use core::f64::consts::PI;

/// The largest impulse count of a registry shaper (3-hump EI has five).
pub const MAX_IMPULSES: usize = 5;

/// Default vibration tolerance of the EI shaper (5 %).
pub const DEFAULT_EI_TOLERANCE: f64 = 0.05;

/// A named shaper family; `design` turns it into impulses for one mode.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ShaperKind {
    Zv,
    Zvd,
    Zvdd,
    Mzv,
    /// Extra-insensitive shaper with vibration tolerance `v_tol` (fraction, e.g. 0.05).
    Ei {
        v_tol: f64,
    },
    Ei2Hump,
    Ei3Hump,
}

/// A mode of vibration: undamped natural frequency (rad/s) and damping ratio.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Mode {
    pub wn_rad_s: f64,
    pub zeta: f64,
}

impl Mode {
    pub const fn new(wn_rad_s: f64, zeta: f64) -> Self {
        Self { wn_rad_s, zeta }
    }

    /// True if `wn` is a positive normal float (finite, not subnormal, so `2π/ω_n` is finite)
    /// and `0 <= zeta < 1` (an underdamped mode).
    #[inline]
    pub fn is_valid(&self) -> bool {
        self.wn_rad_s.is_normal() && self.wn_rad_s > 0.0 && self.zeta >= 0.0 && self.zeta < 1.0
    }

    /// Damped natural frequency `ω_d = ω_n √(1−ζ²)` in rad/s.
    #[inline]
    pub fn wd_rad_s(&self) -> f64 {
        self.wn_rad_s * (1.0 - self.zeta * self.zeta).sqrt()
    }

    /// Checks validity, naming the mode by `index` in the error.
    pub fn validate(&self, index: usize) -> Result<(), Error> {
        if self.is_valid() {
            Ok(())
        } else {
            Err(Error::InvalidMode {
                index,
                wn_rad_s: self.wn_rad_s,
                zeta: self.zeta,
            })
        }
    }
}

/// A fixed-capacity impulse sequence (no heap), as produced each cycle by [`ShaperKind::design`].
///
/// Invariant: `len <= MAX_IMPULSES`; entries past `len` are zero.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ImpulseArray {
    len: usize,
    amplitudes: [f64; MAX_IMPULSES],
    times_s: [f64; MAX_IMPULSES],
}

impl ImpulseArray {
    /// The identity sequence: one unit impulse at `t = 0` (no shaping).
    pub const IDENTITY: ImpulseArray = ImpulseArray {
        len: 1,
        amplitudes: [1.0, 0.0, 0.0, 0.0, 0.0],
        times_s: [0.0; MAX_IMPULSES],
    };

    #[inline]
    pub fn len(&self) -> usize {
        self.len
    }

    #[inline]
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    #[inline]
    pub fn amplitudes(&self) -> &[f64] {
        &self.amplitudes[..self.len]
    }

    #[inline]
    pub fn times_s(&self) -> &[f64] {
        &self.times_s[..self.len]
    }

    /// Sets the times to those of `shape` at natural frequency `wn_rad_s` (`t_i = phase_i /
    /// ω_n`); `shape` is the one the sequence was made from ([`DampedShape::at`]), so only
    /// `ω_n` changes.
    #[inline]
    pub(crate) fn retime(&mut self, shape: &DampedShape, wn_rad_s: f64) {
        let period = 1.0 / wn_rad_s; // s per rad of ω_n t
        for (t, p) in self.times_s.iter_mut().zip(shape.phases_rad()) {
            *t = p * period;
        }
    }

    /// Time of the last impulse: the delay this sequence adds, in seconds.
    #[inline]
    pub fn duration_s(&self) -> f64 {
        self.times_s().last().copied().unwrap_or(0.0)
    }
}

/// Evaluates `Σ_k c[k] ζ^k` (Horner) for the tabulated EI expansions.
#[inline]
fn poly(c: &[f64; 4], zeta: f64) -> f64 {
    ((c[3] * zeta + c[2]) * zeta + c[1]) * zeta + c[0]
}

// Expansion coefficients (times in undamped periods, amplitudes unnormalized) of the 5 %
// 2-hump and 3-hump EI shapers, as polynomials in ζ up to ζ³.
const EI2_T: [[f64; 4]; 4] = [
    [0.0, 0.0, 0.0, 0.0],
    [0.49890, 0.16270, -0.54262, 6.16180],
    [0.99748, 0.18382, -1.58270, 8.17120],
    [1.49920, -0.09297, -0.28338, 1.85710],
];
const EI2_A: [[f64; 4]; 4] = [
    [0.16054, 0.76699, 2.26560, -1.22750],
    [0.33911, 0.45081, -2.58080, 1.73650],
    [0.34089, -0.61533, -0.68765, 0.42261],
    [0.15997, -0.60246, 1.00280, -0.93145],
];
const EI3_T: [[f64; 4]; 5] = [
    [0.0, 0.0, 0.0, 0.0],
    [0.49974, 0.23834, 0.44559, 12.4720],
    [0.99849, 0.29808, -2.36460, 23.3990],
    [1.49870, 0.10306, -2.01390, 17.0320],
    [1.99960, -0.28231, 0.61536, 5.40450],
];
const EI3_A: [[f64; 4]; 5] = [
    [0.11275, 0.76632, 3.29160, -1.44380],
    [0.23698, 0.61164, -2.57850, 4.85220],
    [0.30008, -0.19062, -2.14560, 0.13744],
    [0.23775, -0.73297, 0.46885, -2.08650],
    [0.11244, -0.45439, 0.96382, -1.46000],
];

impl ShaperKind {
    /// Looks a shaper up by registry name. `ei_tolerance` applies to `"ei"` only
    /// (`None` = 5 %); it must lie in `[0.005, 0.2]` ([`ei::MIN_TOLERANCE`],
    /// [`ei::MAX_TOLERANCE`]), where the exact EI design is supported.
    pub fn from_name(name: &str, ei_tolerance: Option<f64>) -> Result<ShaperKind, Error> {
        let kind = match name {
            "zv" => ShaperKind::Zv,
            "zvd" => ShaperKind::Zvd,
            "zvdd" => ShaperKind::Zvdd,
            "mzv" => ShaperKind::Mzv,
            "ei" => {
                let v_tol = ei_tolerance.unwrap_or(DEFAULT_EI_TOLERANCE);
                if !(ei::MIN_TOLERANCE..=ei::MAX_TOLERANCE).contains(&v_tol) {
                    return Err(Error::InvalidParameter(format!(
                        "EI vibration tolerance {v_tol} outside [{}, {}] (use \"zvd\" for less)",
                        ei::MIN_TOLERANCE,
                        ei::MAX_TOLERANCE
                    )));
                }
                ShaperKind::Ei { v_tol }
            }
            "2hump_ei" => ShaperKind::Ei2Hump,
            "3hump_ei" => ShaperKind::Ei3Hump,
            other => return Err(Error::UnknownShaper(other.to_string())),
        };
        if ei_tolerance.is_some() && !matches!(kind, ShaperKind::Ei { .. }) {
            return Err(Error::InvalidParameter(format!(
                "the vibration tolerance option applies to \"ei\" only, not {name:?}"
            )));
        }
        Ok(kind)
    }

    /// The registry name.
    pub fn name(&self) -> &'static str {
        match self {
            ShaperKind::Zv => "zv",
            ShaperKind::Zvd => "zvd",
            ShaperKind::Zvdd => "zvdd",
            ShaperKind::Mzv => "mzv",
            ShaperKind::Ei { .. } => "ei",
            ShaperKind::Ei2Hump => "2hump_ei",
            ShaperKind::Ei3Hump => "3hump_ei",
        }
    }

    /// Largest damping ratio the family's design covers. The closed forms (ZV, ZVD, ZVDD, MZV)
    /// are exact for every underdamped mode and return 1 (exclusive). EI: 0.4 up to `V = 10 %`,
    /// less for larger tolerances ([`ei::max_zeta`]). Beyond the limit the 2- and 3-hump EI
    /// polynomials give negative amplitudes and, further out, times that are no longer sorted,
    /// so [`Impulses::design`] rejects such modes and the time-varying filter designs at the
    /// limit instead.
    pub fn max_zeta(&self) -> f64 {
        match self {
            ShaperKind::Ei { v_tol } => ei::max_zeta(*v_tol),
            ShaperKind::Ei2Hump => 0.3,
            ShaperKind::Ei3Hump => 0.2,
            _ => 1.0,
        }
    }

    /// The impulse sequence for `mode`. Allocation-free; the caller guarantees
    /// `mode.is_valid()` (checked at setup, or held by the time-varying filter).
    #[inline]
    pub fn design(&self, mode: Mode) -> ImpulseArray {
        self.damped_shape(mode.zeta).at(mode.wn_rad_s)
    }

    /// The sequence for damping ratio `zeta` with times as phases `ω_n t` (rad): every
    /// family's shape depends on `ζ` only, and designing for a mode of that `ζ` divides the
    /// phases by `ω_n` ([`DampedShape::at`]). Allocation-free; `0 <= zeta < 1`.
    #[inline]
    pub fn damped_shape(&self, zeta: f64) -> DampedShape {
        match *self {
            ShaperKind::Ei { v_tol } => {
                let ei = ei::design(v_tol, zeta);
                DampedShape::three(&ei.amplitudes, &ei.phases_rad)
            }
            ShaperKind::Ei2Hump => expansion(&EI2_A, &EI2_T, zeta),
            ShaperKind::Ei3Hump => expansion(&EI3_A, &EI3_T, zeta),
            closed => closed.closed_form(zeta),
        }
    }

    /// ZV, ZVD, ZVDD and MZV: their closed forms (`ClosedForm`). Other kinds give
    /// the identity.
    #[inline]
    fn closed_form(&self, zeta: f64) -> DampedShape {
        match ClosedForm::of(*self) {
            Some(ClosedForm::Zv) => DampedShape::closed(&ClosedForm::zv(zeta)),
            Some(ClosedForm::Zvd) => DampedShape::closed(&ClosedForm::zvd(zeta)),
            Some(ClosedForm::Zvdd) => DampedShape::closed(&ClosedForm::zvdd(zeta)),
            Some(ClosedForm::Mzv) => DampedShape::closed(&ClosedForm::mzv(zeta)),
            None => DampedShape::IDENTITY,
        }
    }

    /// The vibration tolerance of the exact EI family (its shape is a Newton solve per `ζ`).
    pub(crate) fn ei_tolerance(&self) -> Option<f64> {
        match *self {
            ShaperKind::Ei { v_tol } => Some(v_tol),
            _ => None,
        }
    }
}

/// The shapers with a closed form in `ζ`: the one definition of each, used by
/// [`ShaperKind::damped_shape`] and, without the general shape's bookkeeping, by the
/// time-varying filter when `ζ` changes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum ClosedForm {
    Zv,
    Zvd,
    Zvdd,
    Mzv,
}

/// A closed-form shape of `N` impulses: amplitudes summing to 1 (up to rounding) at phases
/// `ω_n t_i` (rad), the first at phase 0 and the others at positive, increasing phases.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct ClosedShape<const N: usize> {
    pub(crate) amplitudes: [f64; N],
    pub(crate) phases_rad: [f64; N],
}

impl ClosedForm {
    /// The closed form of `kind`, if it has one.
    #[inline(always)]
    pub(crate) fn of(kind: ShaperKind) -> Option<ClosedForm> {
        match kind {
            ShaperKind::Zv => Some(ClosedForm::Zv),
            ShaperKind::Zvd => Some(ClosedForm::Zvd),
            ShaperKind::Zvdd => Some(ClosedForm::Zvdd),
            ShaperKind::Mzv => Some(ClosedForm::Mzv),
            _ => None,
        }
    }

    /// The terms every closed form is made of, for `0 <= zeta < 1`: the damped half period
    /// `π/√(1−ζ²)` (rad of `ω_n t`) and the decay `K^f = exp(−f ζπ/√(1−ζ²))` of the mode over
    /// the fraction `f` of it.
    #[inline(always)]
    fn half_period_and_decay(zeta: f64, fraction: f64) -> (f64, f64) {
        // π/√u as (π/u)·√u: the division runs beside the square root instead of after it
        // (a shorter dependent chain when ζ changes every cycle; within 2 ulps of π/√u).
        let u = 1.0 - zeta * zeta;
        let pi_per_u = PI / u;
        let root = u.sqrt();
        let half = pi_per_u * root; // ω_n · T_d / 2
        (half, (-(fraction * zeta) * pi_per_u * root).exp())
    }

    /// ZV: `A = [1, K]/(1+K)` at `[0, T_d/2]`.
    #[inline(always)]
    pub(crate) fn zv(zeta: f64) -> ClosedShape<2> {
        let (half, k) = Self::half_period_and_decay(zeta, 1.0);
        let inv_sum = 1.0 / (1.0 + k);
        ClosedShape {
            amplitudes: [inv_sum, k * inv_sum],
            phases_rad: [0.0, half],
        }
    }

    /// ZVD: `A = [1, 2K, K²]/(1+K)²` at `[0, T_d/2, T_d]`.
    #[inline(always)]
    pub(crate) fn zvd(zeta: f64) -> ClosedShape<3> {
        let (half, k) = Self::half_period_and_decay(zeta, 1.0);
        let sum_root = 1.0 + k; // Σ A = (1+K)²
        let inv_sum = 1.0 / (sum_root * sum_root);
        ClosedShape {
            amplitudes: [inv_sum, 2.0 * k * inv_sum, k * k * inv_sum],
            phases_rad: [0.0, half, 2.0 * half],
        }
    }

    /// ZVDD: `A = [1, 3K, 3K², K³]/(1+K)³` at `[0, T_d/2, T_d, 3T_d/2]`.
    #[inline(always)]
    pub(crate) fn zvdd(zeta: f64) -> ClosedShape<4> {
        let (half, k) = Self::half_period_and_decay(zeta, 1.0);
        let raw = [1.0, 3.0 * k, 3.0 * k * k, k * k * k];
        let sum_root = 1.0 + k; // Σ A = (1+K)³
        let inv_sum = 1.0 / (sum_root * sum_root * sum_root);
        ClosedShape {
            amplitudes: raw.map(|a| a * inv_sum),
            phases_rad: [0.0, half, 2.0 * half, 3.0 * half],
        }
    }

    /// MZV: three impulses at `[0, 3/8, 3/4]·T_d` with the damped amplitudes of the standard
    /// modified-ZV form, `[1 − 1/√2, (√2 − 1)K^{3/4}, (1 − 1/√2)K^{3/2}]` normalized.
    #[inline(always)]
    pub(crate) fn mzv(zeta: f64) -> ClosedShape<3> {
        let (half, km) = Self::half_period_and_decay(zeta, 0.75); // km = K^{3/4}
        let a1 = 1.0 - core::f64::consts::FRAC_1_SQRT_2;
        let raw = [a1, (core::f64::consts::SQRT_2 - 1.0) * km, a1 * km * km];
        let inv_sum = 1.0 / ((raw[0] + raw[1]) + raw[2]);
        ClosedShape {
            amplitudes: raw.map(|a| a * inv_sum),
            phases_rad: [0.0, 0.75 * half, 1.5 * half],
        }
    }
}

/// An impulse sequence for one damping ratio with times as phases `ω_n t_i` (rad),
/// normalized to `Σ A = 1`, phases non-decreasing from 0.
///
/// Invariant: `len <= MAX_IMPULSES`; entries past `len` are zero.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DampedShape {
    len: usize,
    amplitudes: [f64; MAX_IMPULSES],
    phases_rad: [f64; MAX_IMPULSES],
}

impl DampedShape {
    /// One unit impulse at phase 0.
    pub const IDENTITY: DampedShape = DampedShape {
        len: 1,
        amplitudes: [1.0, 0.0, 0.0, 0.0, 0.0],
        phases_rad: [0.0; MAX_IMPULSES],
    };

    /// Normalizes `Σ A = 1`; `raw_a` and `raw_phases` have equal length `<= MAX_IMPULSES` at
    /// every call site (extra entries are ignored).
    #[inline]
    fn normalized(raw_a: &[f64], raw_phases: &[f64]) -> DampedShape {
        let mut out = DampedShape {
            len: 0,
            amplitudes: [0.0; MAX_IMPULSES],
            phases_rad: [0.0; MAX_IMPULSES],
        };
        let inv_sum = 1.0 / raw_a.iter().sum::<f64>();
        for ((a, p), (oa, op)) in raw_a
            .iter()
            .zip(raw_phases)
            .zip(out.amplitudes.iter_mut().zip(out.phases_rad.iter_mut()))
        {
            *oa = a * inv_sum;
            *op = *p;
            out.len += 1;
        }
        out
    }

    /// A closed-form shape as it is (already normalized).
    #[inline(always)]
    pub(crate) fn closed<const N: usize>(shape: &ClosedShape<N>) -> DampedShape {
        let mut out = DampedShape {
            len: 0,
            amplitudes: [0.0; MAX_IMPULSES],
            phases_rad: [0.0; MAX_IMPULSES],
        };
        for ((&a, &p), (oa, op)) in shape
            .amplitudes
            .iter()
            .zip(&shape.phases_rad)
            .zip(out.amplitudes.iter_mut().zip(out.phases_rad.iter_mut()))
        {
            *oa = a;
            *op = p;
            out.len += 1;
        }
        out
    }

    /// An EI shaper's amplitudes (summing to 1) and phases.
    #[inline]
    pub(crate) fn three(amplitudes: &[f64; 3], phases_rad: &[f64; 3]) -> DampedShape {
        DampedShape::normalized(amplitudes, phases_rad)
    }

    #[inline]
    pub fn len(&self) -> usize {
        self.len
    }

    #[inline]
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    #[inline]
    pub fn amplitudes(&self) -> &[f64] {
        &self.amplitudes[..self.len]
    }

    /// Impulse phases `ω_n t_i`, rad.
    #[inline]
    pub fn phases_rad(&self) -> &[f64] {
        &self.phases_rad[..self.len]
    }

    /// The sequence for the mode of natural frequency `wn_rad_s`: `t_i = phase_i / ω_n`.
    #[inline]
    pub fn at(&self, wn_rad_s: f64) -> ImpulseArray {
        let mut impulses = ImpulseArray {
            len: self.len,
            amplitudes: self.amplitudes,
            times_s: [0.0; MAX_IMPULSES],
        };
        impulses.retime(self, wn_rad_s);
        impulses
    }
}

/// Shaper from ζ-expansion tables; times are in undamped periods `2π/ω_n`.
fn expansion<const N: usize>(a: &[[f64; 4]; N], t: &[[f64; 4]; N], zeta: f64) -> DampedShape {
    let mut raw_a = [0.0; MAX_IMPULSES];
    let mut raw_phases = [0.0; MAX_IMPULSES];
    for (i, (ca, ct)) in a.iter().zip(t).enumerate().take(MAX_IMPULSES) {
        raw_a[i] = poly(ca, zeta);
        raw_phases[i] = poly(ct, zeta) * (2.0 * PI);
    }
    let n = N.min(MAX_IMPULSES);
    DampedShape::normalized(&raw_a[..n], &raw_phases[..n])
}

/// A heap-backed, validated impulse sequence (custom sets, convolutions, analysis).
///
/// Invariants: non-empty, all values finite, times non-decreasing and `>= 0`, `Σ A = 1`.
#[derive(Debug, Clone, PartialEq)]
pub struct Impulses {
    amplitudes: Vec<f64>,
    times_s: Vec<f64>,
}

impl Impulses {
    /// Validates and normalizes a custom set. Rejects empty or mismatched inputs,
    /// non-finite values, negative or decreasing times, and `Σ A = 0`.
    pub fn new(amplitudes: Vec<f64>, times_s: Vec<f64>) -> Result<Impulses, Error> {
        if amplitudes.is_empty() {
            return Err(Error::InvalidImpulses("the set is empty".into()));
        }
        if amplitudes.len() != times_s.len() {
            return Err(Error::InvalidImpulses(format!(
                "{} amplitudes but {} times",
                amplitudes.len(),
                times_s.len()
            )));
        }
        if let Some(i) = amplitudes
            .iter()
            .chain(&times_s)
            .position(|v| !v.is_finite())
        {
            let (what, idx) = if i < amplitudes.len() {
                ("amplitude", i)
            } else {
                ("time", i - amplitudes.len())
            };
            return Err(Error::InvalidImpulses(format!(
                "{what} {idx} is not finite"
            )));
        }
        if times_s[0] < 0.0 {
            return Err(Error::InvalidImpulses(format!(
                "time 0 is negative ({})",
                times_s[0]
            )));
        }
        if let Some(i) = times_s.windows(2).position(|w| w[1] < w[0]) {
            return Err(Error::InvalidImpulses(format!(
                "times must be non-decreasing: time {} ({}) < time {} ({})",
                i + 1,
                times_s[i + 1],
                i,
                times_s[i]
            )));
        }
        let sum: f64 = amplitudes.iter().sum();
        if sum.abs() < 1e-12 {
            return Err(Error::InvalidImpulses("amplitudes sum to zero".into()));
        }
        let amplitudes = amplitudes.into_iter().map(|a| a / sum).collect();
        Ok(Impulses {
            amplitudes,
            times_s,
        })
    }

    /// The registry shaper `kind` designed for `mode` (validated, including the damping range
    /// of the family's published approximation, [`ShaperKind::max_zeta`]).
    pub fn design(kind: ShaperKind, mode: Mode) -> Result<Impulses, Error> {
        mode.validate(0)?;
        if mode.zeta > kind.max_zeta() {
            return Err(Error::InvalidParameter(format!(
                "zeta = {} is beyond the range of the {:?} shaper's approximation (zeta <= {})",
                mode.zeta,
                kind.name(),
                kind.max_zeta()
            )));
        }
        Ok(Impulses::from(&kind.design(mode)))
    }

    pub fn amplitudes(&self) -> &[f64] {
        &self.amplitudes
    }

    pub fn times_s(&self) -> &[f64] {
        &self.times_s
    }

    pub fn len(&self) -> usize {
        self.amplitudes.len()
    }

    pub fn is_empty(&self) -> bool {
        self.amplitudes.is_empty()
    }

    /// The delay the set adds: its last impulse time, in seconds.
    pub fn duration_s(&self) -> f64 {
        self.times_s.last().copied().unwrap_or(0.0)
    }

    /// Convolution of sequences (eq. 53): all pairwise products, times added, sorted by time,
    /// coincident times (within 1e-12 s) merged.
    pub fn convolve(sets: &[&Impulses]) -> Result<Impulses, Error> {
        let Some((first, rest)) = sets.split_first() else {
            return Err(Error::InvalidImpulses("nothing to convolve".into()));
        };
        let mut pairs: Vec<(f64, f64)> = first
            .times_s
            .iter()
            .copied()
            .zip(first.amplitudes.iter().copied())
            .collect();
        for set in rest {
            let mut next = Vec::with_capacity(pairs.len() * set.len());
            for &(t0, a0) in &pairs {
                for (&t1, &a1) in set.times_s.iter().zip(&set.amplitudes) {
                    next.push((t0 + t1, a0 * a1));
                }
            }
            next.sort_by(|x, y| x.0.total_cmp(&y.0));
            let mut merged: Vec<(f64, f64)> = Vec::with_capacity(next.len());
            for (t, a) in next {
                match merged.last_mut() {
                    Some(last) if (t - last.0).abs() <= 1e-12 => last.1 += a,
                    _ => merged.push((t, a)),
                }
            }
            pairs = merged;
        }
        let (times, amps) = pairs.into_iter().unzip();
        Impulses::new(amps, times)
    }
}

impl From<&ImpulseArray> for Impulses {
    fn from(a: &ImpulseArray) -> Self {
        Impulses {
            amplitudes: a.amplitudes().to_vec(),
            times_s: a.times_s().to_vec(),
        }
    }
}
