//! The physically based dynamic map (paper eqs. 42–51): modes `(ω_n, ζ)` from joint inertias.
//!
//! One [`ModeMap`] per mode holds the ten coefficients of eqs. 42–43 and says which joint
//! drives it. With `J_f` the inertia of the *frequency joint*, `J_d` that of the *damping
//! joint*, `τ_f` the gravity torque of the frequency joint and `K = k_0 + k_J J_f + k_g |τ_f|`
//! (`|τ_f|` smoothed, see [Gravity term](#gravity-term)):
//!
//! ```text
//! ω_n = √(1 + k_p/J_f) · √(K / J_f)
//! ζ   = (1 + k_p/J_d)^e_d · (1 + k_p/J_f)^e_f · (c_0 + c_1 √J_d + c_2 J_d)(1 + c_τ J_d) / (2 √(K J_f))
//! ```
//!
//! - General map (eqs. 42–43) for joint `j`: `J_f = J_d = J_j`, `e_d = ½`, `e_f = 0`
//!   ([`ModeMap::general`]); the reduced map (eqs. 44–45) is the same with `c_1 = k_g = 0`.
//! - UR5e base mode as printed (eqs. 47–48): `J_f = J_1`, `J_d = J_0`, `e_d = 1` (no square
//!   root on `1 + k_p/J_0`), `e_f = −½`. "Base frequency from `J_0`" (eq. 46) is
//!   `ModeMap::general(coefficients, 0)`.
//!
//! Evaluation is allocation-free. An input that gives no underdamped mode (`J <= 0`, `K <= 0`,
//! `1 + k_p/J <= 0`, non-finite values, or `ζ >= 1`) yields a mode that fails
//! [`Mode::is_valid`], which a [`crate::ModeFilter`] holds over.
//!
//! # Physical sign rules
//!
//! A [`DynamicMap`] (whether built in Rust, from Python or C, or read from a map file) holds
//! only modes that are physical at every inertia they read (their range, `(0, ∞)` without
//! one) and every gravity torque ([`ModeMap::check_physical`]): `k_g >= 0`, the stiffness
//! `k_0 + k_J J_f > 0` (without a range: `k_0 > 0`, `k_J >= 0`), `1 + k_p/J > 0` (without a
//! range: `k_p >= 0`), and `c_0 + c_1 √J_d + c_2 J_d >= 0`, `1 + c_τ J_d >= 0` (without a
//! range: `c_0 >= 0` and neither turns negative at large `J_d`). So a map gives a finite
//! `ω_n > 0` and `ζ >= 0` at every positive inertia. `ζ < 1` is not a rule of the map alone:
//! the published map is overdamped at small inertias no arm reaches;
//! [`crate::MapDynamics::new`] checks it over the poses of the robot.
//!
//! # Validity ranges
//!
//! A map fitted to measurements is only known where it was measured. Each [`ModeMap`] may
//! therefore carry the [`InertiaRange`] `[min, max]` of `J_f` and of `J_d` it was identified on;
//! evaluation saturates each inertia into its range ([`InertiaRange::saturate`]) before the
//! equations see it. Invariant: **a map never extrapolates beyond the inertias it was
//! identified on**: the saturated inertia always lies in `[min, max]`. The saturation is a C²
//! soft clamp with relative blend width `ε` = [`RANGE_BLEND_WIDTH`]:
//!
//! ```text
//! s(J) = min                                   J <= min(1 − ε)
//!        min(1 + ε) − 2 min ε B(v)             min(1 − ε) < J < min(1 + ε),  v = (min(1 + ε) − J)/(2 min ε)
//!        J                                     min(1 + ε) <= J <= max(1 − ε)
//!        max(1 − ε) + 2 max ε B(u)             max(1 − ε) < J < max(1 + ε),  u = (J − max(1 − ε))/(2 max ε)
//!        max                                   J >= max(1 + ε)
//!
//! B(x) = x − x³ + x⁴/2   (B' = 1 − smoothstep(x) = 1 − 3x² + 2x³, B(1) = ½)
//! ```
//!
//! `s` is non-decreasing and twice continuously differentiable (its slope falls from 1 to 0
//! along a smoothstep, whose own slope is 0 at both ends), exact (the identity) in the core of
//! the range and exactly the bound well beyond it; it differs from the hard clamp
//! `min(max(J, min), max)` by at most `3ε/16` of the bound (at the bound itself). A hard clamp
//! has a kink at each bound, and the time-varying shaper turns any kink of the modes along a
//! move into a step of the shaped reference's velocity slope, i.e. a jerk spike; a blend that
//! is only C¹ still steps the reference acceleration where its curvature switches on. A range
//! must leave room for both blend zones: `max/min >= (1 + ε)/(1 − ε)` ([`InertiaRange::new`]).
//!
//! Outside its range a mode keeps the value at the nearest bound: a saturated evaluation is
//! normal operation, not an error, and is not reported. Only inertias that are no inertia at
//! all (`J <= 0`, non-finite) still give an invalid mode. Without a range (`None`, the paper's
//! map) the equations are evaluated as they stand at every positive inertia.
//!
//! # Gravity term
//!
//! The `|τ_f|` of eq. 42 has a kink where the gravity torque changes sign, which would give the
//! same jerk spike. With `k_g != 0` the term is evaluated as
//! `k_g (√(τ_f² + τ_s²) − τ_s)` with `τ_s` = [`GRAVITY_TORQUE_SMOOTHING_NM`]: smooth, zero at
//! `τ_f = 0`, and below `|τ_f|` by less than `τ_s` everywhere. With `k_g = 0` (the paper's map,
//! Table 3) the term is absent and nothing changes.

use crate::error::{Error, Status};
use crate::shaping::shapers::Mode;

/// Relative width `ε` of each blend zone of the soft clamp into an [`InertiaRange`]: the
/// saturation is the identity on `[min(1 + ε), max(1 − ε)]`, exactly `min` below `min(1 − ε)`
/// and exactly `max` above `max(1 + ε)`. 5 % of the bound keeps the map exact over the bulk of
/// its range, moves it by at most `3ε/16` ≈ 0.94 % of a bound, and spreads the bend over an
/// inertia change large enough that the modes change slope gradually along a move.
pub const RANGE_BLEND_WIDTH: f64 = 0.05;

/// Smoothing torque `τ_s` of the gravity term, N m: `k_g |τ|` is evaluated as
/// `k_g (√(τ² + τ_s²) − τ_s)`. Eq. 42's `|τ|` has a kink at `τ = 0` (where the gravity torque
/// changes sign along a move); the smoothed value is below `|τ|` by less than `τ_s`, i.e. by
/// less than `k_g · 1 N m` of stiffness, under 1 % of `k_0` (10⁴ N m/rad for the UR5e) for
/// any published or fitted `k_g` (< 100 N m/rad per N m).
pub const GRAVITY_TORQUE_SMOOTHING_NM: f64 = 1.0;

/// Largest magnitude of a gain exponent `e_d`, `e_f`. The published forms use −½, 0, ½ and 1;
/// an exponent of, say, −10⁶ would silently drive `ζ` to 0 (or to infinity) at every pose.
pub const MAX_GAIN_EXPONENT: f64 = 2.0;

/// Largest joint index a mode may read (one below [`crate::limits::MAX_DOF`]).
pub const MAX_JOINT_INDEX: usize = crate::limits::MAX_DOF - 1;

/// The ten coefficients of eqs. 42–43 (SI units: N m/rad, N m s, kg m²).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MapCoefficients {
    /// Stiffness at zero inertia, N m/rad.
    pub k_0: f64,
    /// Stiffness per unit inertia, N m/rad/(kg m²).
    pub k_j: f64,
    /// Stiffness per unit gravity torque, 1/rad.
    pub k_g: f64,
    /// Proportional-gain coefficient, kg m².
    pub k_p: f64,
    /// Damping coefficients: constant (N m s), per √J, per J.
    pub c_0: f64,
    pub c_1: f64,
    pub c_2: f64,
    /// Torque coefficient, 1/(kg m²).
    pub c_tau: f64,
}

impl MapCoefficients {
    /// The reduced map's coefficients (eqs. 44–45: `k_g = c_1 = 0`).
    pub const fn reduced(k_0: f64, k_j: f64, k_p: f64, c_0: f64, c_2: f64, c_tau: f64) -> Self {
        MapCoefficients {
            k_0,
            k_j,
            k_g: 0.0,
            k_p,
            c_0,
            c_1: 0.0,
            c_2,
            c_tau,
        }
    }

    fn as_array(&self) -> [(&'static str, f64); 8] {
        [
            ("k_0", self.k_0),
            ("k_j", self.k_j),
            ("k_g", self.k_g),
            ("k_p", self.k_p),
            ("c_0", self.c_0),
            ("c_1", self.c_1),
            ("c_2", self.c_2),
            ("c_tau", self.c_tau),
        ]
    }
}

/// A closed range `[min, max]` of joint inertias, kg m², with `0 < min` and
/// `max/min >= (1 + ε)/(1 − ε)` (both finite, `ε` = [`RANGE_BLEND_WIDTH`]).
///
/// The fields are private, so every value was checked by [`InertiaRange::new`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct InertiaRange {
    min_kg_m2: f64,
    max_kg_m2: f64,
}

impl InertiaRange {
    /// Rejects non-finite bounds, `min <= 0`, `min >= max`, and a range too narrow for the
    /// two blend zones of [`Self::saturate`] not to overlap (`max(1 − ε) < min(1 + ε)`).
    pub fn new(min_kg_m2: f64, max_kg_m2: f64) -> Result<InertiaRange, Error> {
        if !(min_kg_m2.is_finite() && max_kg_m2.is_finite()) {
            return Err(Error::InvalidParameter(format!(
                "inertia range [{min_kg_m2}, {max_kg_m2}] kg m²: bounds must be finite"
            )));
        }
        if min_kg_m2 <= 0.0 {
            return Err(Error::InvalidParameter(format!(
                "inertia range [{min_kg_m2}, {max_kg_m2}] kg m²: min must be > 0"
            )));
        }
        if min_kg_m2 >= max_kg_m2 {
            return Err(Error::InvalidParameter(format!(
                "inertia range [{min_kg_m2}, {max_kg_m2}] kg m²: min must be < max"
            )));
        }
        let eps = RANGE_BLEND_WIDTH;
        if max_kg_m2 * (1.0 - eps) < min_kg_m2 * (1.0 + eps) {
            return Err(Error::InvalidParameter(format!(
                "inertia range [{min_kg_m2}, {max_kg_m2}] kg m²: too narrow, max/min = {} must \
                 be at least (1 + ε)/(1 − ε) = {:.4} so that the soft clamp's blend zones \
                 (ε = {eps} of each bound) do not overlap",
                max_kg_m2 / min_kg_m2,
                (1.0 + eps) / (1.0 - eps)
            )));
        }
        Ok(InertiaRange {
            min_kg_m2,
            max_kg_m2,
        })
    }

    /// Lower bound, kg m².
    pub fn min_kg_m2(&self) -> f64 {
        self.min_kg_m2
    }

    /// Upper bound, kg m².
    pub fn max_kg_m2(&self) -> f64 {
        self.max_kg_m2
    }

    /// `j_kg_m2` saturated into the range by the C² soft clamp of the module docs: unchanged
    /// on `[min(1 + ε), max(1 − ε)]`, exactly `min` at or below `min(1 − ε)`, exactly `max` at
    /// or above `max(1 + ε)`, quartic blends in between. The result always lies in
    /// `[min, max]`, is non-decreasing in `j_kg_m2`, and NaN stays NaN. Never panics.
    #[inline]
    pub fn saturate(&self, j_kg_m2: f64) -> f64 {
        let (lo, hi, eps) = (self.min_kg_m2, self.max_kg_m2, RANGE_BLEND_WIDTH);
        let (lo_out, lo_in) = (lo * (1.0 - eps), lo * (1.0 + eps));
        let (hi_in, hi_out) = (hi * (1.0 - eps), hi * (1.0 + eps));
        let j = j_kg_m2;
        // Every branch is a positive comparison, so NaN falls through to the last one.
        if j >= hi_out {
            hi
        } else if j > hi_in {
            // At most `hi` (reached at hi_out, where slope and curvature are 0); slope 1 and
            // curvature 0 at hi_in.
            let u = (j - hi_in) / (2.0 * hi * eps);
            (hi_in + 2.0 * hi * eps * blend(u)).min(hi)
        } else if j >= lo_in {
            j
        } else if j > lo_out {
            let v = (lo_in - j) / (2.0 * lo * eps);
            (lo_in - 2.0 * lo * eps * blend(v)).max(lo)
        } else if j <= lo_out {
            lo
        } else {
            j
        }
    }
}

impl core::fmt::Display for InertiaRange {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(f, "[{}, {}] kg m²", self.min_kg_m2, self.max_kg_m2)
    }
}

/// `B(x) = x − x³ + x⁴/2` on `[0, 1]`: the integral of `1 − smoothstep(x)`, so `B' = 1` and
/// `B'' = 0` at 0, `B' = B'' = 0` at 1, `B(1) = ½`.
#[inline]
fn blend(x: f64) -> f64 {
    x * (1.0 - x * x * (1.0 - 0.5 * x))
}

/// `j` saturated into `range` ([`InertiaRange::saturate`]), or unchanged without one.
#[inline]
fn saturate_to(range: Option<InertiaRange>, j: f64) -> f64 {
    match range {
        Some(r) => r.saturate(j),
        None => j,
    }
}

/// `√(τ² + τ_s²) − τ_s` with `τ_s` = [`GRAVITY_TORQUE_SMOOTHING_NM`]: the smooth stand-in for
/// `|τ|` in the gravity term (see the module docs), N m. In `[|τ| − τ_s, |τ|]`; NaN stays NaN.
#[inline]
pub fn smooth_abs_torque_nm(tau_nm: f64) -> f64 {
    tau_nm.hypot(GRAVITY_TORQUE_SMOOTHING_NM) - GRAVITY_TORQUE_SMOOTHING_NM
}

/// The map of one mode: coefficients plus which joint inertias drive frequency and damping.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ModeMap {
    pub coefficients: MapCoefficients,
    /// Joint whose inertia (and gravity torque) sets the frequency: `J_f`, `τ_f`.
    pub frequency_joint: usize,
    /// Joint whose inertia sets the damping numerator: `J_d`.
    pub damping_joint: usize,
    /// Exponent `e_d` of `(1 + k_p/J_d)` in `ζ`.
    pub damping_gain_exponent: f64,
    /// Exponent `e_f` of `(1 + k_p/J_f)` in `ζ`.
    pub frequency_gain_exponent: f64,
    /// Inertias of the frequency joint the map was identified on; `J_f` is saturated into it.
    /// `None`: unbounded.
    pub frequency_range: Option<InertiaRange>,
    /// Inertias of the damping joint the map was identified on; `J_d` is saturated into it.
    /// `None`: unbounded. When both roles read the same joint the two ranges are equal
    /// (checked by [`DynamicMap::new`]).
    pub damping_range: Option<InertiaRange>,
}

impl ModeMap {
    /// The general map of eqs. 42–43 with `J = J_joint`.
    pub const fn general(coefficients: MapCoefficients, joint: usize) -> Self {
        ModeMap {
            coefficients,
            frequency_joint: joint,
            damping_joint: joint,
            damping_gain_exponent: 0.5,
            frequency_gain_exponent: 0.0,
            frequency_range: None,
            damping_range: None,
        }
    }

    /// The UR5e base-mode form of eqs. 47–48 as printed: frequency from `J_1`, damping
    /// numerator from `J_0` with `(1 + k_p/J_0)` unsquared, divided by `√(1 + k_p/J_1)`.
    pub const fn base_from_shoulder(
        coefficients: MapCoefficients,
        base: usize,
        shoulder: usize,
    ) -> Self {
        ModeMap {
            coefficients,
            frequency_joint: shoulder,
            damping_joint: base,
            damping_gain_exponent: 1.0,
            frequency_gain_exponent: -0.5,
            frequency_range: None,
            damping_range: None,
        }
    }

    /// The same map limited to the inertias it was identified on (see the module docs).
    pub const fn with_ranges(
        mut self,
        frequency_range: Option<InertiaRange>,
        damping_range: Option<InertiaRange>,
    ) -> Self {
        self.frequency_range = frequency_range;
        self.damping_range = damping_range;
        self
    }

    /// Largest joint index used, plus one.
    pub fn required_joints(&self) -> usize {
        self.frequency_joint.max(self.damping_joint) + 1
    }

    /// Checks the physical sign rules of the mode (see [`DynamicMap::new`]): over every
    /// inertia it reads (its range, or `(0, ∞)` without one) and every gravity torque, the
    /// stiffness `K` and both gain terms `1 + k_p/J` are positive and the damping
    /// `(c_0 + c_1 √J_d + c_2 J_d)(1 + c_τ J_d)` is not negative, so that every evaluation
    /// gives a finite `ω_n > 0` and `ζ >= 0`. Whether `ζ < 1` at the inertias a robot
    /// reaches is the robot's question ([`crate::MapDynamics::new`]). The text says which
    /// rule fails, with the coefficient and the inertia.
    pub fn check_physical(&self) -> Result<(), String> {
        let c = &self.coefficients;
        let (f, d) = (
            Domain::of(self.frequency_range),
            Domain::of(self.damping_range),
        );
        // The coefficients are finite (checked first); a least value may still overflow to
        // NaN, which fails its rule.
        if c.k_g < 0.0 {
            return Err(format!(
                "k_g = {} must be >= 0 (gears stiffen under load; a negative k_g makes the \
                 stiffness negative at a large enough gravity torque)",
                c.k_g
            ));
        }
        // K = k_0 + k_J J_f + k_g |τ|_s, least at τ = 0 (k_g >= 0).
        let (k, at) = f.least_linear(c.k_0, c.k_j);
        if k.is_nan() || k <= 0.0 {
            return Err(format!(
                "the stiffness k_0 + k_j J_f must be > 0 for every J_f in {f}, but with k_0 = \
                 {}, k_j = {} it is {k} N m/rad at J_f = {at} kg m²",
                c.k_0, c.k_j
            ));
        }
        for (name, domain) in [("J_f", f), ("J_d", d)] {
            // 1 + k_p/J > 0 for J > 0 in the domain: J + k_p > 0 at its least J.
            if !(c.k_p >= 0.0 || domain.lo + c.k_p > 0.0) {
                return Err(format!(
                    "the gain 1 + k_p/{name} must be > 0 for every {name} in {domain}, but \
                     k_p = {} makes it <= 0 for {name} <= {} kg m²",
                    c.k_p, -c.k_p
                ));
            }
        }
        let (damping, at) = d.least_root_quadratic(c.c_0, c.c_1, c.c_2);
        if damping.is_nan() || damping < 0.0 {
            return Err(format!(
                "the damping c_0 + c_1 √J_d + c_2 J_d must be >= 0 for every J_d in {d}, but \
                 with c_0 = {}, c_1 = {}, c_2 = {} it is {damping} N m s/rad at J_d = {at} kg m²",
                c.c_0, c.c_1, c.c_2
            ));
        }
        let (factor, at) = d.least_linear(1.0, c.c_tau);
        if factor.is_nan() || factor < 0.0 {
            return Err(format!(
                "the torque factor 1 + c_tau J_d must be >= 0 for every J_d in {d}, but with \
                 c_tau = {} it is {factor} at J_d = {at} kg m²",
                c.c_tau
            ));
        }
        Ok(())
    }

    /// True if the gravity-torque term is active (`k_g != 0`).
    pub fn uses_gravity(&self) -> bool {
        self.coefficients.k_g != 0.0
    }

    /// Mode for inertias `j` and gravity torques `tau_g` (ignored when `k_g == 0`).
    ///
    /// `J_f` and `J_d` are saturated into their ranges first (if any, see the module docs);
    /// the gravity term uses [`smooth_abs_torque_nm`]. Returns an invalid mode (NaN) when an
    /// inertia read is not finite and positive, or the (saturated) inertias give no positive
    /// stiffness or gain term. Allocation-free.
    #[inline]
    pub fn evaluate(&self, j: &[f64], tau_g: &[f64]) -> Mode {
        self.evaluate_in_form(self.form(), j, tau_g)
    }

    /// What of the evaluation is fixed by the map itself (see [`ModeForm`]).
    fn form(&self) -> ModeForm {
        let (e_d, e_f) = (self.damping_gain_exponent, self.frequency_gain_exponent);
        ModeForm {
            // Equal ranges, so the two saturated inertias are equal too.
            one_joint: self.frequency_joint == self.damping_joint
                && self.frequency_range == self.damping_range,
            gains: if e_d == 0.5 && e_f == 0.0 {
                GainForm::SquareRoot
            } else if e_d == 1.0 && e_f == -0.5 {
                GainForm::DampingGain
            } else {
                GainForm::Powers
            },
        }
    }

    /// [`Self::evaluate`] with `form == self.form()` (resolved once by [`DynamicMap`]).
    #[inline(always)]
    fn evaluate_in_form(&self, form: ModeForm, j: &[f64], tau_g: &[f64]) -> Mode {
        let invalid = Mode::new(f64::NAN, f64::NAN);
        let Some(&j_f_raw) = j.get(self.frequency_joint) else {
            return invalid;
        };
        let j_d_raw = if form.one_joint {
            j_f_raw
        } else {
            match j.get(self.damping_joint) {
                Some(&v) => v,
                None => return invalid,
            }
        };
        // A broken input stays an error: saturation must not turn it into a plausible mode.
        if !(is_positive_and_finite(j_f_raw) & is_positive_and_finite(j_d_raw)) {
            return invalid;
        }
        // Both stay positive and finite: a range lies in (0, ∞).
        let j_f = saturate_to(self.frequency_range, j_f_raw);
        let j_d = if form.one_joint {
            j_f
        } else {
            saturate_to(self.damping_range, j_d_raw)
        };
        let c = &self.coefficients;
        let gravity = if c.k_g != 0.0 {
            match tau_g.get(self.frequency_joint) {
                Some(&t) => c.k_g * smooth_abs_torque_nm(t),
                None => return invalid,
            }
        } else {
            0.0
        };
        let stiffness = c.k_0 + c.k_j * j_f + gravity;
        // ω_n² = (1 + k_p/J_f) K/J_f = P/J_f² with P = (J_f + k_p) K, so ω_n = √P / J_f and
        // 2 √(K J_f) = 2 ω_n J_f / √g_f: ζ = g_d^e_d g_f^(e_f + ½) num / (2 √P). The square
        // root and the divisions by J_f and P are independent of each other (they overlap).
        let inv_j_f = 1.0 / j_f;
        let p_f = j_f + c.k_p;
        let gain_f = p_f * inv_j_f;
        // One joint in both roles (the general map): one division.
        let same = form.one_joint || j_d == j_f;
        let gain_d = if same { gain_f } else { 1.0 + c.k_p / j_d };
        // Written as positive tests so that NaN inputs fail them.
        if !(stiffness > 0.0 && gain_f > 0.0 && gain_d > 0.0) {
            return invalid;
        }
        let p = p_f * stiffness;
        let root_p = p.sqrt();
        let inv_p = 1.0 / p;
        let wn_rad_s = root_p * inv_j_f;
        // The square root only where it is read (c_1 = 0 in the reduced and published maps).
        let root_term = if c.c_1 != 0.0 {
            c.c_1 * j_d.sqrt()
        } else {
            0.0
        };
        let numerator = (c.c_0 + root_term + c.c_2 * j_d) * (1.0 + c.c_tau * j_d);
        let gains = self.gain_product(form.gains, gain_d, gain_f, same);
        let zeta = (0.5 * numerator * gains * inv_p) * root_p;
        Mode::new(wn_rad_s, zeta)
    }

    /// `g_d^e_d · g_f^(e_f + ½)` for `g_d, g_f > 0` (`same`: `g_d == g_f`), without `powf`
    /// for the published forms: the general map (`e_d = ½`, `e_f = 0`: `g` for one joint,
    /// `√(g_d g_f)` for two) and the UR5e base form (`e_d = 1`, `e_f = −½`: `g_d`).
    #[inline(always)]
    fn gain_product(&self, form: GainForm, gain_d: f64, gain_f: f64, same: bool) -> f64 {
        match form {
            GainForm::SquareRoot if same => gain_f,
            GainForm::SquareRoot => (gain_d * gain_f).sqrt(),
            GainForm::DampingGain => gain_d,
            GainForm::Powers => {
                let (e_d, e_f) = (self.damping_gain_exponent, self.frequency_gain_exponent);
                gain_d.powf(e_d) * gain_f.powf(e_f + 0.5)
            }
        }
    }
}

/// The inertias a mode reads in one role (`J_f` or `J_d`), kg m²: `[min, max]` of its range,
/// or `(0, ∞)` without one (`lo = 0`, `hi = ∞`; the bounds of a closure, for the least values
/// below).
#[derive(Debug, Clone, Copy)]
struct Domain {
    lo: f64,
    hi: f64,
}

impl Domain {
    fn of(range: Option<InertiaRange>) -> Domain {
        range.map_or(
            Domain {
                lo: 0.0,
                hi: f64::INFINITY,
            },
            |r| Domain {
                lo: r.min_kg_m2,
                hi: r.max_kg_m2,
            },
        )
    }

    /// The least value of `a + b J` over the domain and the `J` where it is taken
    /// (`−∞` at `J = ∞` when it decreases without bound).
    fn least_linear(&self, a: f64, b: f64) -> (f64, f64) {
        if b >= 0.0 {
            (a + b * self.lo, self.lo)
        } else if self.hi.is_finite() {
            (a + b * self.hi, self.hi)
        } else {
            (f64::NEG_INFINITY, f64::INFINITY)
        }
    }

    /// The least value of `a + b √J + c J` over the domain and the `J` where it is taken: a
    /// quadratic in `u = √J`, least at an end or at its vertex `u = −b/(2c)` (`c > 0`).
    fn least_root_quadratic(&self, a: f64, b: f64, c: f64) -> (f64, f64) {
        let at = |u: f64| a + b * u + c * u * u;
        let (u_lo, u_hi) = (self.lo.sqrt(), self.hi.sqrt());
        let mut least = (at(u_lo), self.lo);
        if u_hi.is_finite() {
            least = min_of(least, (at(u_hi), self.hi));
        } else if c < 0.0 || (c == 0.0 && b < 0.0) {
            return (f64::NEG_INFINITY, f64::INFINITY);
        }
        if c > 0.0 {
            let u = -b / (2.0 * c);
            if u > u_lo && u < u_hi {
                least = min_of(least, (at(u), u * u));
            }
        }
        least
    }
}

/// The pair with the smaller value.
fn min_of(a: (f64, f64), b: (f64, f64)) -> (f64, f64) {
    if b.0 < a.0 {
        b
    } else {
        a
    }
}

impl core::fmt::Display for Domain {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        if self.hi.is_finite() {
            write!(f, "[{}, {}] kg m²", self.lo, self.hi)
        } else {
            write!(f, "(0, ∞) kg m² (no inertia range)")
        }
    }
}

/// What of a [`ModeMap`]'s evaluation its definition fixes, resolved once instead of tested
/// every cycle.
#[derive(Debug, Clone, Copy, PartialEq)]
struct ModeForm {
    /// One joint drives both frequency and damping (with one range): `J_d = J_f`.
    one_joint: bool,
    gains: GainForm,
}

/// How `g_d^e_d · g_f^(e_f + ½)` is formed ([`ModeMap::gain_product`]).
#[derive(Debug, Clone, Copy, PartialEq)]
enum GainForm {
    /// `e_d = ½`, `e_f = 0`: `√(g_d g_f)` (`g` when both are equal).
    SquareRoot,
    /// `e_d = 1`, `e_f = −½`: `g_d`.
    DampingGain,
    /// Any other exponents: `powf`.
    Powers,
}

/// `0 < x < ∞` (false for NaN) as one integer comparison: the positive finite non-zero
/// values are exactly the bit patterns `1..=f64::MAX.to_bits()` (sign bit clear, exponent not
/// all ones); `+0` wraps around to the largest pattern, negative values, infinities and NaN
/// lie above.
#[inline(always)]
fn is_positive_and_finite(x: f64) -> bool {
    x.to_bits().wrapping_sub(1) < f64::MAX.to_bits()
}

/// The robot the paper's map ([`DynamicMap::paper_ur5e`]) was identified on.
pub const PAPER_MAP_ROBOT: &str = "ur5e";

/// A dynamic map: one [`ModeMap`] per mode, in cascade order, and the robot it was
/// identified on (if known).
#[derive(Debug, Clone, PartialEq)]
pub struct DynamicMap {
    modes: Vec<ModeMap>,
    robot: Option<String>,
    /// [`Self::required_joints`] and [`Self::uses_gravity`], fixed by the modes.
    required_joints: usize,
    uses_gravity: bool,
    /// Each mode's [`ModeMap::form`], resolved once.
    forms: Vec<ModeForm>,
}

impl DynamicMap {
    /// Validates (1 to [`crate::limits::MAX_MODES`] modes, finite coefficients, exponents
    /// within ±[`MAX_GAIN_EXPONENT`], joint indices up to [`MAX_JOINT_INDEX`], equal ranges
    /// for a joint that drives both frequency and damping, and the physical sign rules of
    /// [`ModeMap::check_physical`]). So a map, however it was made (a file, Python, C, Rust),
    /// gives a finite `ω_n > 0` and `ζ >= 0` at every inertia; `ζ < 1` over the poses of a
    /// robot is checked with the robot ([`crate::MapDynamics::new`]). The robot is unknown
    /// until [`Self::for_robot`].
    pub fn new(modes: Vec<ModeMap>) -> Result<DynamicMap, Error> {
        if modes.is_empty() {
            return Err(Error::InvalidParameter(
                "a dynamic map needs at least one mode".into(),
            ));
        }
        crate::limits::check_n_modes(modes.len(), "a dynamic map")?;
        for (m, mode) in modes.iter().enumerate() {
            for (name, value) in mode.coefficients.as_array() {
                if !value.is_finite() {
                    return Err(Error::InvalidParameter(format!(
                        "dynamic map mode {m}: coefficient {name} = {value} must be finite"
                    )));
                }
            }
            for (name, e) in [
                ("damping_gain_exponent", mode.damping_gain_exponent),
                ("frequency_gain_exponent", mode.frequency_gain_exponent),
            ] {
                if !(e.is_finite() && e.abs() <= MAX_GAIN_EXPONENT) {
                    return Err(Error::InvalidParameter(format!(
                        "dynamic map mode {m}: {name} = {e} must be finite and within \
                         ±{MAX_GAIN_EXPONENT} (the published forms use -0.5, 0, 0.5 and 1)"
                    )));
                }
            }
            for (name, joint) in [
                ("frequency_joint", mode.frequency_joint),
                ("damping_joint", mode.damping_joint),
            ] {
                if joint > MAX_JOINT_INDEX {
                    return Err(Error::InvalidParameter(format!(
                        "dynamic map mode {m}: {name} = {joint} exceeds the largest joint \
                         index {MAX_JOINT_INDEX}"
                    )));
                }
            }
            if mode.frequency_joint == mode.damping_joint
                && mode.frequency_range != mode.damping_range
            {
                return Err(Error::InvalidParameter(format!(
                    "dynamic map mode {m}: frequency and damping both read joint {}, so their \
                     inertia ranges must be equal (got {:?} and {:?})",
                    mode.frequency_joint, mode.frequency_range, mode.damping_range
                )));
            }
            mode.check_physical()
                .map_err(|why| Error::InvalidParameter(format!("dynamic map mode {m}: {why}")))?;
        }
        Ok(DynamicMap::of(modes, None))
    }

    /// The same map, marked as identified on robot `name` (for example `"ur5e"`).
    pub fn for_robot(mut self, name: impl Into<String>) -> DynamicMap {
        self.robot = Some(name.into());
        self
    }

    /// The robot the map was identified on, if known.
    pub fn robot(&self) -> Option<&str> {
        self.robot.as_deref()
    }

    /// The UR5e map of the paper (identified on [`PAPER_MAP_ROBOT`]): Table 1 for the base mode (eqs. 47–48, joint 0) and
    /// Table 2 for the shoulder mode (eqs. 50–51, joint 1). It carries no inertia ranges (the
    /// paper publishes none), so Table 3 is reproduced exactly at any inertia.
    pub fn paper_ur5e() -> DynamicMap {
        let base = MapCoefficients::reduced(10_000.0, 1060.0, 2.54, 1.53, 0.39, 3.81);
        let shoulder = MapCoefficients::reduced(10_000.0, 763.0, 1.73, 0.27, 0.038, 47.2);
        DynamicMap::of(
            vec![
                ModeMap::base_from_shoulder(base, 0, 1),
                ModeMap::general(shoulder, 1),
            ],
            Some(PAPER_MAP_ROBOT.to_string()),
        )
    }

    /// The map of checked `modes` (what it reads is derived once, here).
    fn of(modes: Vec<ModeMap>, robot: Option<String>) -> DynamicMap {
        DynamicMap {
            required_joints: modes
                .iter()
                .map(ModeMap::required_joints)
                .max()
                .unwrap_or(0),
            uses_gravity: modes.iter().any(ModeMap::uses_gravity),
            forms: modes.iter().map(ModeMap::form).collect(),
            modes,
            robot,
        }
    }

    pub fn n_modes(&self) -> usize {
        self.modes.len()
    }

    pub fn mode_maps(&self) -> &[ModeMap] {
        &self.modes
    }

    /// Number of joint inertias the map reads (largest index plus one).
    pub fn required_joints(&self) -> usize {
        self.required_joints
    }

    /// True if any mode uses the gravity-torque term.
    pub fn uses_gravity(&self) -> bool {
        self.uses_gravity
    }

    /// Modes from joint inertias `j` (kg m²) and gravity torques `tau_g` (N m; may be empty
    /// when [`Self::uses_gravity`] is false). `out` must hold [`Self::n_modes`] modes.
    /// Inertias are saturated into each mode's ranges ([`ModeMap::evaluate`]); that is not a
    /// status. Allocation-free; [`Status::BAD_LENGTH`] if `j` or `out` is too short.
    pub fn modes_from_inertia(&self, j: &[f64], tau_g: &[f64], out: &mut [Mode]) -> Status {
        if out.len() != self.modes.len() || j.len() < self.required_joints() {
            return Status::BAD_LENGTH;
        }
        if self.uses_gravity() && tau_g.len() < self.required_joints() {
            return Status::BAD_LENGTH;
        }
        for (o, (mode, form)) in out.iter_mut().zip(self.modes.iter().zip(&self.forms)) {
            *o = mode.evaluate_in_form(*form, j, tau_g);
        }
        Status::OK
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn damped_hz(m: Mode) -> f64 {
        m.wd_rad_s() / (2.0 * core::f64::consts::PI)
    }

    #[test]
    fn paper_table3_q1() {
        // SPEC section 3: Q1 (J0, J1) = (9.73, 9.25) -> 8.018 Hz / 0.2645, 6.909 Hz / 0.3730.
        let map = DynamicMap::paper_ur5e();
        let mut out = [Mode::new(0.0, 0.0); 2];
        assert!(map.modes_from_inertia(&[9.73, 9.25], &[], &mut out).is_ok());
        // 1e-3 relative: the reference values are given to 4 significant digits.
        for (got, want) in [
            (damped_hz(out[0]), 8.018),
            (out[0].zeta, 0.2645),
            (damped_hz(out[1]), 6.909),
            (out[1].zeta, 0.3730),
        ] {
            assert!((got / want - 1.0).abs() < 1e-3, "{got} vs {want}");
        }
    }

    #[test]
    fn invalid_inertia_gives_invalid_mode() {
        let map = DynamicMap::paper_ur5e();
        let mut out = [Mode::new(0.0, 0.0); 2];
        map.modes_from_inertia(&[0.0, -1.0], &[], &mut out);
        assert!(!out[0].is_valid() && !out[1].is_valid());
        map.modes_from_inertia(&[f64::NAN, 1.0], &[], &mut out);
        assert!(!out[0].is_valid() && out[1].is_valid());
    }

    fn range(min: f64, max: f64) -> InertiaRange {
        InertiaRange::new(min, max).expect("valid range")
    }

    /// The paper's base mode limited to J_1 in [2, 8] and J_0 in [1, 9] kg m².
    fn ranged_base() -> (ModeMap, ModeMap) {
        let unbounded = DynamicMap::paper_ur5e().mode_maps()[0];
        let ranged = unbounded.with_ranges(Some(range(2.0, 8.0)), Some(range(1.0, 9.0)));
        (unbounded, ranged)
    }

    #[test]
    fn inertia_range_rejects_bad_bounds() {
        for (min, max, why) in [
            (f64::NAN, 1.0, "finite"),
            (0.5, f64::INFINITY, "finite"),
            (0.0, 1.0, "min must be > 0"),
            (-1.0, 1.0, "min must be > 0"),
            (2.0, 2.0, "min must be < max"),
            (3.0, 2.0, "min must be < max"),
            // (1 + ε)/(1 − ε) = 1.1053: the blend zones [0.95, 1.05] and [0.988, 1.092] overlap.
            (1.0, 1.04, "too narrow"),
            (0.95, 1.04, "too narrow"),
        ] {
            let err = InertiaRange::new(min, max).expect_err("bad range");
            assert!(err.to_string().contains(why), "{err}");
        }
        let r = range(0.5, 2.0);
        assert_eq!((r.min_kg_m2(), r.max_kg_m2()), (0.5, 2.0));
        // Just wide enough: max/min = 1.1158 > 1.1053.
        assert!(InertiaRange::new(0.95, 1.06).is_ok());
    }

    /// The four joints of the soft clamp of `r`: min(1 − ε), min(1 + ε), max(1 − ε), max(1 + ε).
    fn joints(r: InertiaRange) -> [f64; 4] {
        let eps = RANGE_BLEND_WIDTH;
        [
            r.min_kg_m2() * (1.0 - eps),
            r.min_kg_m2() * (1.0 + eps),
            r.max_kg_m2() * (1.0 - eps),
            r.max_kg_m2() * (1.0 + eps),
        ]
    }

    #[test]
    fn saturation_is_the_identity_in_the_core_and_the_bound_beyond_the_blends() {
        let r = range(1.0, 9.0);
        let [lo_out, lo_in, hi_in, hi_out] = joints(r);
        for j in [lo_in, 1.2, 4.5, 8.0, hi_in] {
            assert_eq!(r.saturate(j), j, "{j}");
        }
        for j in [lo_out, 0.9, 1e-9, -3.0, f64::NEG_INFINITY] {
            assert_eq!(r.saturate(j), 1.0, "{j}");
        }
        for j in [hi_out, 9.5, 1e6, f64::INFINITY] {
            assert_eq!(r.saturate(j), 9.0, "{j}");
        }
        assert!(r.saturate(f64::NAN).is_nan());
        // At the bounds themselves (u = v = ½, B = 13/32) the blend sits 3ε/16 of the bound
        // inside the range.
        let eps = RANGE_BLEND_WIDTH;
        assert!((r.saturate(1.0) - (1.0 + 1.0 * 3.0 * eps / 16.0)).abs() < 1e-15);
        assert!((r.saturate(9.0) - (9.0 - 9.0 * 3.0 * eps / 16.0)).abs() < 1e-14);
    }

    #[test]
    fn saturation_is_monotone_bounded_and_close_to_the_hard_clamp() {
        let eps = RANGE_BLEND_WIDTH;
        for r in [range(1.0, 9.0), range(0.2, 0.25), range(0.95, 1.06)] {
            let (lo, hi) = (r.min_kg_m2(), r.max_kg_m2());
            let (from, to) = (0.5 * lo, 1.5 * hi);
            let n = 20_000;
            let mut previous = f64::NEG_INFINITY;
            for k in 0..=n {
                let j = from + (to - from) * k as f64 / n as f64;
                let s = r.saturate(j);
                assert!(lo <= s && s <= hi, "{r}: s({j}) = {s}");
                assert!(s >= previous, "{r}: not monotone at {j}");
                previous = s;
                // Largest gap to the hard clamp: 3ε/16 of the nearer bound (at the bound);
                // 1e-12 relative covers the rounding of the quartic.
                let hard = j.clamp(lo, hi);
                let allowed = 3.0 * eps / 16.0 * if j < 0.5 * (lo + hi) { lo } else { hi };
                assert!((s - hard).abs() <= allowed * (1.0 + 1e-12), "{r}: {j}");
            }
        }
    }

    /// One-sided difference quotients of `f` left and right of `x`, step `h`.
    fn one_sided_slopes(f: impl Fn(f64) -> f64, x: f64, h: f64) -> (f64, f64) {
        ((f(x) - f(x - h)) / h, (f(x + h) - f(x)) / h)
    }

    #[test]
    fn saturation_is_c1_at_the_four_joints() {
        let r = range(1.0, 9.0);
        let [lo_out, lo_in, hi_in, hi_out] = joints(r);
        // Slopes: 0 outside, 1 inside, continuous at every joint. Step 1e-8 of the joint: the
        // curvature is 0 at every joint, so a one-sided quotient is off by O(h²) only, and
        // rounding adds ~1e-16 · x / h ~ 1e-8.
        for (x, slope) in [(lo_out, 0.0), (lo_in, 1.0), (hi_in, 1.0), (hi_out, 0.0)] {
            let (left, right) = one_sided_slopes(|j| r.saturate(j), x, 1e-8 * x);
            assert!((left - right).abs() < 1e-6, "at {x}: {left} vs {right}");
            assert!(
                (left - slope).abs() < 1e-6 && (right - slope).abs() < 1e-6,
                "at {x}"
            );
            // Continuity of the value: across 2e-12 x (slope <= 1) both sides meet within
            // 2e-12 x, plus rounding of a few ulp.
            let jump = r.saturate(x + 1e-12 * x) - r.saturate(x - 1e-12 * x);
            assert!(jump.abs() <= 3e-12 * x, "at {x}: {jump}");
        }
        // The hard clamp this replaces fails the same test: its slope jumps by 1.
        let hard = |j: f64| j.clamp(1.0, 9.0);
        let (left, right) = one_sided_slopes(hard, 9.0, 1e-8 * 9.0);
        assert!((left - right).abs() > 0.99);
    }

    #[test]
    fn saturation_is_c2_at_the_four_joints() {
        let r = range(1.0, 9.0);
        // One-sided second difference quotients with step h = 1e-4 x: for a C² function with
        // zero curvature at the joint both sides are O(h |s'''|) ~ 6 h/(2 ε x)² ≈ 0.06/x; a C¹
        // quadratic blend's curvature jumps by 1/(2 ε x) = 10/x there. Rounding: ~4e-16 x/h²
        // = 4e-8/x. Bound: 1/x (a tenth of the jump that a C¹ blend would show).
        let second = |f: &dyn Fn(f64) -> f64, x: f64, h: f64| {
            let left = (f(x) - 2.0 * f(x - h) + f(x - 2.0 * h)) / (h * h);
            let right = (f(x + 2.0 * h) - 2.0 * f(x + h) + f(x)) / (h * h);
            (left, right)
        };
        for x in joints(r) {
            let (left, right) = second(&|j| r.saturate(j), x, 1e-4 * x);
            assert!((left - right).abs() < 1.0 / x, "at {x}: {left} vs {right}");
        }
        // A C¹ quadratic blend fails it: its curvature jumps at hi_in.
        let (hi, eps) = (9.0, RANGE_BLEND_WIDTH);
        let hi_in = hi * (1.0 - eps);
        let quadratic = |j: f64| {
            if j > hi_in {
                j - (j - hi_in) * (j - hi_in) / (4.0 * hi * eps)
            } else {
                j
            }
        };
        let (left, right) = second(&quadratic, hi_in, 1e-4 * hi_in);
        assert!((left - right).abs() > 5.0 / hi_in);
    }

    #[test]
    fn a_ranged_map_is_the_unbounded_map_at_the_saturated_inertias() {
        let (unbounded, ranged) = ranged_base();
        let (r_f, r_d) = (range(2.0, 8.0), range(1.0, 9.0));
        let tau = [0.0; 2];
        // Inside both core zones: bit-identical to the unbounded map.
        for j in [[1.06, 2.2], [4.5, 3.3], [8.5, 7.5], [5.0, 7.0]] {
            assert_eq!(ranged.evaluate(&j, &tau), unbounded.evaluate(&j, &tau));
        }
        // Beyond the blend zones: bit-identical to the unbounded map at the bound, per joint.
        for (j, at) in [
            ([0.2, 0.3], [1.0, 2.0]),
            ([0.2, 5.0], [1.0, 5.0]),
            ([50.0, 1e6], [9.0, 8.0]),
            ([4.0, 1e-9], [4.0, 2.0]),
        ] {
            assert_eq!(ranged.evaluate(&j, &tau), unbounded.evaluate(&at, &tau));
        }
        // Anywhere (blend zones included): the unbounded map at the saturated inertias.
        for j in [[1.0, 2.0], [0.97, 8.1], [9.2, 1.95], [9.0, 8.0]] {
            let at = [r_d.saturate(j[0]), r_f.saturate(j[1])];
            assert_eq!(ranged.evaluate(&j, &tau), unbounded.evaluate(&at, &tau));
        }
    }

    #[test]
    fn a_ranged_map_has_continuous_slopes_along_its_inertias() {
        // ω_n of the base mode against J_1 (frequency range [2, 8]) and ζ against J_0
        // (damping range [1, 9]) across every joint of both soft clamps. The map is smooth in
        // the saturated inertia, so both sides agree to the difference-quotient error (~1e-6
        // relative for steps of 1e-8 of the inertia).
        let (_, ranged) = ranged_base();
        let tau = [0.0; 2];
        for x in joints(range(2.0, 8.0)) {
            let wn = |j1: f64| ranged.evaluate(&[4.0, j1], &tau).wn_rad_s;
            let (left, right) = one_sided_slopes(wn, x, 1e-8 * x);
            let scale = wn(x) / x;
            assert!(
                (left - right).abs() < 1e-5 * scale,
                "J_1 = {x}: {left} vs {right}"
            );
        }
        for x in joints(range(1.0, 9.0)) {
            let zeta = |j0: f64| ranged.evaluate(&[j0, 4.0], &tau).zeta;
            let (left, right) = one_sided_slopes(zeta, x, 1e-8 * x);
            let scale = zeta(x) / x;
            assert!(
                (left - right).abs() < 1e-5 * scale,
                "J_0 = {x}: {left} vs {right}"
            );
        }
    }

    #[test]
    fn the_gravity_term_is_smooth_in_the_torque() {
        let tau_s = GRAVITY_TORQUE_SMOOTHING_NM;
        assert_eq!(smooth_abs_torque_nm(0.0), 0.0);
        for tau in [-300.0, -40.0, -1.0, -1e-3, 1e-3, 0.5, 1.0, 7.0, 250.0] {
            let s = smooth_abs_torque_nm(tau);
            assert_eq!(s, smooth_abs_torque_nm(-tau));
            // Below |τ| by less than τ_s, and by more than τ_s − τ_s²/(2|τ|) for large |τ|.
            assert!(s <= tau.abs() && s > tau.abs() - tau_s, "{tau}: {s}");
        }
        assert!((smooth_abs_torque_nm(250.0) - (250.0 - 1.0 + 1.0 / 500.0)).abs() < 1e-5);
        // Slope 0 from both sides at τ = 0 (|τ| has −1 and +1 there): the second derivative
        // is 1/τ_s, so a step of 1e-6 N m gives one-sided quotients of ±5e-7.
        let (left, right) = one_sided_slopes(smooth_abs_torque_nm, 0.0, 1e-6);
        assert!(left.abs() < 1e-6 && right.abs() < 1e-6, "{left} {right}");
        assert!(smooth_abs_torque_nm(f64::NAN).is_nan());

        // The map uses it: K = k_0 + k_J J + k_g (√(τ² + τ_s²) − τ_s).
        let c = MapCoefficients {
            k_g: 30.0,
            c_1: 0.1,
            ..MapCoefficients::reduced(10_000.0, 763.0, 1.73, 0.27, 0.038, 47.2)
        };
        let mode = ModeMap::general(c, 1);
        let (j, tau) = (3.0, -40.0);
        let k = 10_000.0 + 763.0 * j + 30.0 * ((tau * tau + 1.0_f64).sqrt() - 1.0);
        let wn = ((1.0 + 1.73 / j) * k / j).sqrt();
        let got = mode.evaluate(&[2.0, j], &[0.0, tau]);
        assert!(
            (got.wn_rad_s / wn - 1.0).abs() < 1e-14,
            "{} vs {wn}",
            got.wn_rad_s
        );
        // ω_n is C¹ in τ across the sign change.
        let wn_at = |t: f64| mode.evaluate(&[2.0, j], &[0.0, t]).wn_rad_s;
        let (left, right) = one_sided_slopes(wn_at, 0.0, 1e-6);
        assert!((left - right).abs() < 1e-6 * wn, "{left} vs {right}");
        // Without a gravity term the torque is not read at all (the paper's map, Table 3).
        let paper = DynamicMap::paper_ur5e().mode_maps()[1];
        assert_eq!(
            paper.evaluate(&[2.0, j], &[0.0, tau]),
            paper.evaluate(&[2.0, j], &[])
        );
    }

    #[test]
    fn a_range_does_not_make_broken_inertias_valid() {
        let (_, ranged) = ranged_base();
        for j in [
            [0.0, 3.0],
            [-1.0, 3.0],
            [3.0, f64::NAN],
            [f64::INFINITY, 3.0],
        ] {
            assert!(!ranged.evaluate(&j, &[]).is_valid(), "{j:?}");
        }
    }

    #[test]
    fn clamping_keeps_an_overdamped_extrapolation_out() {
        // Damping grows like 1/J at small J (the (1 + k_p/J) factor): with a large c_0 this
        // mode is overdamped below J ~ 0.35 kg m² (ζ = 2.1 at 0.2, 0.75 at 0.6).
        let c = MapCoefficients::reduced(10_000.0, 763.0, 1.73, 60.0, 0.038, 0.0);
        let unbounded = ModeMap::general(c, 1);
        let r = Some(range(0.6, 10.0));
        let ranged = unbounded.with_ranges(r, r);
        assert!(unbounded.evaluate(&[1.0, 0.2], &[]).zeta >= 1.0);
        assert!(ranged.evaluate(&[1.0, 0.2], &[]).is_valid());
        assert!(unbounded.evaluate(&[1.0, 0.6], &[]).is_valid());
    }

    #[test]
    fn one_joint_has_one_range() {
        let c = MapCoefficients::reduced(10_000.0, 763.0, 1.73, 0.27, 0.038, 47.2);
        let general = ModeMap::general(c, 1);
        let err = DynamicMap::new(vec![general.with_ranges(Some(range(1.0, 2.0)), None)])
            .expect_err("different ranges for one joint");
        assert!(err.to_string().contains("must be equal"), "{err}");
        let both = Some(range(1.0, 2.0));
        assert!(DynamicMap::new(vec![general.with_ranges(both, both)]).is_ok());
        // Different joints may have different ranges.
        let (_, ranged) = ranged_base();
        assert!(DynamicMap::new(vec![ranged]).is_ok());
    }

    /// `mode` evaluated at every inertia of `j_grid` in both roles and at gravity torques of
    /// either sign: the first evaluation that is not a finite `ω_n > 0` with `ζ >= 0`.
    fn first_unphysical(mode: &ModeMap, j_grid: &[f64]) -> Option<([f64; 2], f64, Mode)> {
        for &j_d in j_grid {
            for &j_f in j_grid {
                for tau in [0.0, 40.0, -3000.0] {
                    let m = mode.evaluate(&[j_d, j_f], &[0.0, tau]);
                    if !(m.wn_rad_s.is_finite() && m.wn_rad_s > 0.0 && m.zeta >= 0.0) {
                        return Some(([j_d, j_f], tau, m));
                    }
                }
            }
        }
        None
    }

    /// Inertias from 1e-6 to 1e8 kg m², 4 per decade: well beyond any arm on both sides.
    fn wide_grid() -> Vec<f64> {
        (0..=56)
            .map(|k| 10f64.powf(-6.0 + k as f64 / 4.0))
            .collect()
    }

    /// The base-mode form (frequency from joint 1, damping from joint 0) with `c` and ranges.
    fn base_form(c: MapCoefficients, f: Option<(f64, f64)>, d: Option<(f64, f64)>) -> ModeMap {
        let r = |b: Option<(f64, f64)>| b.map(|(lo, hi)| range(lo, hi));
        ModeMap::base_from_shoulder(c, 0, 1).with_ranges(r(f), r(d))
    }

    #[test]
    fn each_physical_rule_refuses_a_map_that_gives_an_unphysical_mode() {
        let paper = DynamicMap::paper_ur5e().mode_maps()[0].coefficients;
        let grid = wide_grid();
        for (change, rule) in [
            (MapCoefficients { k_0: -1e4, ..paper }, "the stiffness"),
            (
                MapCoefficients {
                    k_j: -10.0,
                    ..paper
                },
                "the stiffness",
            ),
            (
                MapCoefficients { k_g: -5.0, ..paper },
                "k_g = -5 must be >= 0",
            ),
            (
                MapCoefficients { k_p: -0.1, ..paper },
                "the gain 1 + k_p/J_f",
            ),
            (MapCoefficients { c_0: -5.0, ..paper }, "the damping"),
            (
                MapCoefficients {
                    c_2: -0.01,
                    ..paper
                },
                "the damping",
            ),
            (
                MapCoefficients {
                    c_0: 1.0,
                    c_1: -3.0,
                    c_2: 2.0,
                    ..paper
                },
                "the damping",
            ),
            (
                MapCoefficients {
                    c_tau: -0.5,
                    ..paper
                },
                "the torque factor",
            ),
        ] {
            let mode = base_form(change, None, None);
            // Before the rule, this map was built and evaluated to NaN or a negative ζ.
            assert!(
                first_unphysical(&mode, &grid).is_some(),
                "{rule}: {change:?}"
            );
            let err = DynamicMap::new(vec![mode]).expect_err(rule).to_string();
            assert!(
                err.contains("dynamic map mode 0") && err.contains(rule),
                "{err}"
            );
        }
        // c_0 + c_1 √J + c_2 J = 1 − 3u + 2u² (u = √J) is −1/8 at its vertex u = 3/4: between
        // the roots u = ½ and 1, a gap the ends of no range outside it can show.
        let dip = MapCoefficients {
            c_0: 1.0,
            c_1: -3.0,
            c_2: 2.0,
            ..paper
        };
        let err = DynamicMap::new(vec![base_form(dip, None, Some((0.2, 1.5)))])
            .expect_err("negative inside the range")
            .to_string();
        assert!(err.contains("at J_d = 0.5625 kg m²"), "{err}");
        assert!(DynamicMap::new(vec![base_form(dip, None, Some((1.1, 4.0)))]).is_ok());
    }

    #[test]
    fn a_range_admits_coefficients_that_are_physical_only_inside_it() {
        // k_J < 0: K = 1e4 − 500 J_f > 0 for J_f < 20; k_p < 0: 1 + k_p/J > 0 for J > 0.3;
        // c_0 < 0: c_0 + c_2 J_d >= 0 for J_d >= 0.5; c_τ < 0: 1 + c_τ J_d >= 0 for J_d <= 10.
        let c = MapCoefficients {
            k_0: 1e4,
            k_j: -500.0,
            k_g: 0.0,
            k_p: -0.3,
            c_0: -1.0,
            c_1: 0.0,
            c_2: 2.0,
            c_tau: -0.1,
        };
        let inside = base_form(c, Some((0.5, 19.0)), Some((0.5, 9.0)));
        let map = DynamicMap::new(vec![inside]).expect("physical over its ranges");
        let grid: Vec<f64> = (0..200).map(|k| 0.01 * 1.05f64.powi(k)).collect();
        assert_eq!(first_unphysical(&map.mode_maps()[0], &grid), None);
        for (f, d, rule) in [
            ((0.5, 21.0), (0.5, 9.0), "the stiffness"),
            ((0.25, 19.0), (0.5, 9.0), "the gain 1 + k_p/J_f"),
            ((0.5, 19.0), (0.25, 9.0), "the gain 1 + k_p/J_d"),
            ((0.5, 19.0), (0.4, 9.0), "the damping"),
            ((0.5, 19.0), (0.5, 11.0), "the torque factor"),
        ] {
            let mode = base_form(c, Some(f), Some(d));
            assert!(first_unphysical(&mode, &grid).is_some(), "{rule}");
            let err = DynamicMap::new(vec![mode]).expect_err(rule).to_string();
            assert!(err.contains(rule), "{err}");
        }
    }

    #[test]
    fn the_paper_map_obeys_the_physical_rules() {
        let paper = DynamicMap::paper_ur5e();
        for m in paper.mode_maps() {
            assert_eq!(m.check_physical(), Ok(()));
        }
        assert!(DynamicMap::new(paper.mode_maps().to_vec()).is_ok());
    }

    #[test]
    fn more_modes_than_the_limit_are_refused() {
        let one = DynamicMap::paper_ur5e().mode_maps()[1];
        let limit = crate::limits::MAX_MODES;
        assert!(DynamicMap::new(vec![one; limit]).is_ok());
        let err = DynamicMap::new(vec![one; limit + 1]).expect_err("too many");
        assert!(matches!(err, Error::TooLarge(_)), "{err}");
        assert!(err.to_string().contains("65 modes"), "{err}");
    }

    /// Soundness of the rules: a map they admit gives a finite ω_n > 0 and ζ >= 0 at every
    /// inertia from 1e-6 to 1e8 kg m² (both roles) and every sampled torque. 1000 random base
    /// modes: each coefficient 0 (1 in 8), or ±10^e with e uniform in [−3, 4) and a negative
    /// sign 1 in 6; each role with a random range (1 in 2) or none. Both outcomes must occur
    /// often, or the test would not test the rules.
    #[test]
    fn an_admitted_map_never_gives_an_unphysical_mode() {
        let mut state = 0x2545_F491_4F6C_DD1D_u64;
        let mut uniform = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        let grid = wide_grid();
        let (mut admitted, mut refused) = (0, 0);
        for _ in 0..1000 {
            let mut value = || {
                if uniform() < 0.125 {
                    return 0.0;
                }
                let x = 10f64.powf(-3.0 + 7.0 * uniform());
                if uniform() < 1.0 / 6.0 {
                    -x
                } else {
                    x
                }
            };
            let c = MapCoefficients {
                k_0: value(),
                k_j: value(),
                k_g: value(),
                k_p: value(),
                c_0: value(),
                c_1: value(),
                c_2: value(),
                c_tau: value(),
            };
            let mut bounds = || {
                let lo = 0.05 + 5.0 * uniform();
                (uniform() < 0.5).then(|| (lo, lo * (1.2 + 40.0 * uniform())))
            };
            let (f, d) = (bounds(), bounds());
            let mode = base_form(c, f, d);
            if DynamicMap::new(vec![mode]).is_ok() {
                admitted += 1;
                assert_eq!(first_unphysical(&mode, &grid), None, "{mode:?}");
            } else {
                refused += 1;
            }
        }
        assert!(admitted > 150 && refused > 150, "{admitted} / {refused}");
    }

    #[test]
    fn the_paper_map_is_unbounded() {
        for m in DynamicMap::paper_ur5e().mode_maps() {
            assert_eq!((m.frequency_range, m.damping_range), (None, None));
        }
    }
}
