//! Zero-time-delay input shaping (ZTDIS) and its modified form with a compensator.
//!
//! Let `T` be the length of a rest-to-rest move and `Δ_n` the delay of the shaper (its last
//! impulse time; for several modes, the sum over the modes).
//!
//! - **ZTDIS**: compress the move in time by [`ztdis_alpha`] `α = (T − Δ_n)/T`, then shape it
//!   with the ordinary shaper. The result ends at `αT + Δ_n = T`.
//! - **Modified ZTDIS**: compress by [`modified_alpha`] `α' = T/(T + Δ_n)` (> α), pass the
//!   compressed move through the [`Compensator`]
//!   `F(s) = (s² + 2ζω s + ω²)/((α's)² + 2α'ζω s + ω²)` (one section per mode), and shape with
//!   every delay scaled by `α'` ([`scaled_mode`]). Since `F(s)G(s) = G(α's)` for
//!   `G(s) = ω²/(s² + 2ζω s + ω²)`, the plant responds like itself sped up by `1/α'`, and the
//!   output is the conventionally shaped response compressed to length `α'(T + Δ_n) = T`.
//!
//! Time compression is an offline operation on a planned move (done in Python); the
//! compensator runs per control cycle: [`Compensator::step`] never allocates, locks or panics.

use crate::error::{Error, Status};
use crate::shaping::held_input::HeldInput;
use crate::shaping::shapers::Mode;
use core::f64::consts::PI;

/// Checks that a move length `T` and a shaper delay `Δ_n` are usable, naming the culprit.
fn check_lengths(move_s: f64, delay_s: f64) -> Result<(), Error> {
    if !(move_s.is_finite() && move_s > 0.0) {
        return Err(Error::InvalidParameter(format!(
            "move length T = {move_s} s must be finite and > 0"
        )));
    }
    if !(delay_s.is_finite() && delay_s >= 0.0) {
        return Err(Error::InvalidParameter(format!(
            "shaper delay = {delay_s} s must be finite and >= 0"
        )));
    }
    Ok(())
}

/// ZTDIS time scale `α = (T − Δ_n)/T` (eqs. 4–5).
///
/// Fails unless `0 < α`, i.e. the move must be longer than the shaper delay.
pub fn ztdis_alpha(move_s: f64, delay_s: f64) -> Result<f64, Error> {
    check_lengths(move_s, delay_s)?;
    let alpha = (move_s - delay_s) / move_s;
    if alpha > 0.0 {
        Ok(alpha)
    } else {
        Err(Error::InvalidParameter(format!(
            "ZTDIS needs a move longer than the shaper delay: T = {move_s} s <= Δ_n = {delay_s} s \
             gives alpha = {alpha} <= 0"
        )))
    }
}

/// Modified-ZTDIS time scale `α' = T/(T + Δ_n)` (eq. 11); always in `(0, 1]` and `>= α`.
pub fn modified_alpha(move_s: f64, delay_s: f64) -> Result<f64, Error> {
    check_lengths(move_s, delay_s)?;
    Ok(move_s / (move_s + delay_s))
}

/// The mode whose registry shaper is the `alpha`-scaled shaper `IS_f` of eq. 13.
///
/// Every registry shaper has amplitudes that depend on `ζ` only and times proportional to the
/// (damped or undamped) period `∝ 1/ω_n`; designing it for `(ω_n/α, ζ)` therefore gives the
/// same amplitudes `A_i` at times `α Δ_i`. For several modes, the convolution of the scaled
/// per-mode shapers is the `α`-scaled convolution. Returns an invalid mode (NaN) for `alpha`
/// that is not finite and positive.
pub fn scaled_mode(mode: Mode, alpha: f64) -> Mode {
    if alpha.is_finite() && alpha > 0.0 {
        Mode::new(mode.wn_rad_s / alpha, mode.zeta)
    } else {
        Mode::new(f64::NAN, f64::NAN)
    }
}

/// How the continuous compensator section is turned into a difference equation.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Discretization {
    /// Matched pole-zero: every pole and zero `s_i` maps to `exp(s_i dt)`, DC gain 1. The
    /// zeros land exactly on the poles of the sampled plant (any hold-equivalent discretization
    /// of `G` has its poles at `exp(s_i dt)`), so the cancellation of the plant's mode — the
    /// whole point of the compensator — is exact at any control rate; the poles land exactly
    /// on the sampled sped-up mode that the `α`-scaled shaper cancels. Default.
    #[default]
    Matched,
    /// Bilinear (Tustin) with frequency pre-warping at the plant's `ω_n`. Maps `ω_n` exactly
    /// but moves the zeros' damping and the poles' frequency by `O((ω dt)²)`.
    Tustin,
}

impl Discretization {
    pub fn from_name(name: &str) -> Result<Discretization, Error> {
        match name {
            "matched" => Ok(Discretization::Matched),
            "tustin" => Ok(Discretization::Tustin),
            other => Err(Error::InvalidParameter(format!(
                "unknown discretization {other:?}; expected \"matched\" or \"tustin\""
            ))),
        }
    }

    pub fn name(&self) -> &'static str {
        match self {
            Discretization::Matched => "matched",
            Discretization::Tustin => "tustin",
        }
    }
}

/// A second-order section `H(z) = (b0 + b1 z⁻¹ + b2 z⁻²)/(1 + a1 z⁻¹ + a2 z⁻²)`, run in
/// transposed direct form II.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Biquad {
    pub b: [f64; 3],
    /// `[a1, a2]`; `a0 = 1`.
    pub a: [f64; 2],
}

impl Biquad {
    /// The compensator section of one mode for time scale `alpha`, sampled every `dt_s`.
    ///
    /// The caller has validated `mode`, `alpha > 0` and `dt_s > 0` and checked that the
    /// sped-up mode `ω_n/α` lies below the Nyquist frequency.
    pub fn compensator(mode: Mode, alpha: f64, dt_s: f64, method: Discretization) -> Biquad {
        let (w, z) = (mode.wn_rad_s, mode.zeta);
        match method {
            Discretization::Matched => {
                // Monic z-polynomial with roots exp(dt·(−ζω ± jω_d)).
                let poly = |wn: f64| {
                    let r = (-z * wn * dt_s).exp();
                    let theta = wn * (1.0 - z * z).sqrt() * dt_s;
                    [1.0, -2.0 * r * theta.cos(), r * r]
                };
                let num = poly(w);
                let den = poly(w / alpha);
                // F(0) = 1 ⇔ H(z = 1) = 1.
                let k = (den[0] + den[1] + den[2]) / (num[0] + num[1] + num[2]);
                Biquad {
                    b: [k * num[0], k * num[1], k * num[2]],
                    a: [den[1], den[2]],
                }
            }
            Discretization::Tustin => {
                // s = c (z − 1)/(z + 1) with c = ω/tan(ω dt/2): exact at s = jω.
                let c = w / (0.5 * w * dt_s).tan();
                let quad = |a2: f64, a1: f64| {
                    [
                        a2 * c * c + a1 * c + w * w,
                        2.0 * (w * w - a2 * c * c),
                        a2 * c * c - a1 * c + w * w,
                    ]
                };
                let num = quad(1.0, 2.0 * z * w);
                let den = quad(alpha * alpha, 2.0 * alpha * z * w);
                let d0 = den[0];
                Biquad {
                    b: [num[0] / d0, num[1] / d0, num[2] / d0],
                    a: [den[1] / d0, den[2] / d0],
                }
            }
        }
    }

    /// Gain at `z = 1`.
    pub fn dc_gain(&self) -> f64 {
        (self.b[0] + self.b[1] + self.b[2]) / (1.0 + self.a[0] + self.a[1])
    }

    /// One sample through the section with state `s` (transposed direct form II).
    #[inline]
    pub fn process(&self, x: f64, s: &mut [f64; 2]) -> f64 {
        let y = self.b[0] * x + s[0];
        s[0] = self.b[1] * x - self.a[0] * y + s[1];
        s[1] = self.b[2] * x - self.a[1] * y;
        y
    }

    /// The state of a section that has seen the constant input `x0` forever (output `g·x0`,
    /// `g` the DC gain).
    #[inline]
    pub fn rest_state(&self, x0: f64) -> [f64; 2] {
        let y0 = self.dc_gain() * x0;
        let s1 = self.b[2] * x0 - self.a[1] * y0;
        [self.b[1] * x0 - self.a[0] * y0 + s1, s1]
    }
}

/// The modified-ZTDIS compensator: a cascade of one [`Biquad`] per mode, on `n_channels`
/// independent signals (one per joint).
///
/// Every section has DC gain 1, so a move keeps its end points; its high-frequency gain is
/// `1/α²`, so steps in the input's acceleration come out sharper.
#[derive(Debug, Clone)]
pub struct Compensator {
    sections: Vec<Biquad>,
    /// Section states, channel-major: `state[ch * n_sections + sec]`.
    state: Vec<[f64; 2]>,
    /// Last valid input (held when a non-finite sample arrives).
    input: HeldInput,
    n_channels: usize,
    alpha: f64,
    dt_s: f64,
    method: Discretization,
}

impl Compensator {
    /// A matched pole-zero compensator for `modes`, time scale `alpha` (`α'`), control period
    /// `dt_s` and `n_channels` signals. See [`Compensator::with_discretization`].
    pub fn new(
        modes: &[Mode],
        alpha: f64,
        dt_s: f64,
        n_channels: usize,
    ) -> Result<Compensator, Error> {
        Compensator::with_discretization(modes, alpha, dt_s, n_channels, Discretization::Matched)
    }

    /// Validates everything and allocates all state.
    ///
    /// Fails for: no modes, an invalid mode, `alpha` or `dt_s` not finite and positive,
    /// `n_channels == 0`, or a sped-up mode `ω_n/α` at or above the Nyquist frequency `π/dt`
    /// (for Tustin also the pre-warp frequency `ω_n`).
    pub fn with_discretization(
        modes: &[Mode],
        alpha: f64,
        dt_s: f64,
        n_channels: usize,
        method: Discretization,
    ) -> Result<Compensator, Error> {
        if modes.is_empty() {
            return Err(Error::InvalidParameter(
                "at least one mode is required".into(),
            ));
        }
        if !(alpha.is_finite() && alpha > 0.0) {
            return Err(Error::InvalidParameter(format!(
                "alpha = {alpha} must be finite and > 0"
            )));
        }
        if !(dt_s.is_finite() && dt_s > 0.0) {
            return Err(Error::InvalidParameter(format!(
                "dt_s = {dt_s} must be finite and > 0"
            )));
        }
        if n_channels == 0 {
            return Err(Error::InvalidParameter("n_dof must be at least 1".into()));
        }
        let nyquist_rad_s = PI / dt_s;
        let mut sections = Vec::with_capacity(modes.len());
        for (i, &mode) in modes.iter().enumerate() {
            mode.validate(i)?;
            let fastest = mode.wn_rad_s * (1.0 / alpha).max(1.0);
            if fastest >= nyquist_rad_s {
                return Err(Error::InvalidParameter(format!(
                    "mode {i}: the compensator pole at wn/alpha = {fastest:.4} rad/s is not \
                     below the Nyquist frequency pi/dt_s = {nyquist_rad_s:.4} rad/s; use a \
                     faster control rate or a longer move"
                )));
            }
            sections.push(Biquad::compensator(mode, alpha, dt_s, method));
        }
        let n_sections = sections.len();
        Ok(Compensator {
            sections,
            state: vec![[0.0; 2]; n_sections * n_channels],
            input: HeldInput::new(n_channels),
            n_channels,
            alpha,
            dt_s,
            method,
        })
    }

    /// Puts the compensator at rest at `x0` (it has seen `x0` forever; the output is `x0`).
    /// Non-finite entries are taken as 0; missing ones leave the channel as it was.
    pub fn reset(&mut self, x0: &[f64]) {
        self.input.set(x0);
        self.settle_on_input();
    }

    /// Forgets all history: the next `step` starts at rest on its input.
    pub fn clear(&mut self) {
        self.input.clear();
    }

    fn settle_on_input(&mut self) {
        let n_sections = self.sections.len();
        for (&x0, states) in self
            .input
            .value()
            .iter()
            .zip(self.state.chunks_exact_mut(n_sections))
        {
            // Every section has DC gain 1, so each one rests at x0.
            for (sec, s) in self.sections.iter().zip(states.iter_mut()) {
                *s = sec.rest_state(x0);
            }
        }
    }

    /// One control cycle: `input` (length `n_channels`) to `output` (length `n_channels`).
    ///
    /// Never allocates or panics. A non-finite input holds the last valid sample
    /// ([`Status::INPUT_HELD`]); on a length mismatch nothing is computed and
    /// [`Status::BAD_LENGTH`] is returned. The first step after construction or
    /// [`Self::clear`] starts at rest on its input.
    pub fn step(&mut self, input: &[f64], output: &mut [f64]) -> Status {
        if input.len() != self.n_channels || output.len() != self.n_channels {
            return Status::BAD_LENGTH;
        }
        let (status, first) = self.input.accept(input);
        if first {
            self.settle_on_input();
        }
        let n_sections = self.sections.len();
        for ((&x0, y), states) in self
            .input
            .value()
            .iter()
            .zip(output.iter_mut())
            .zip(self.state.chunks_exact_mut(n_sections))
        {
            let mut x = x0;
            for (sec, s) in self.sections.iter().zip(states.iter_mut()) {
                x = sec.process(x, s);
            }
            *y = x;
        }
        status
    }

    /// Filters a block in `(n_samples, n_channels)` row-major layout, continuing the streaming
    /// state. Returns the union of all step statuses.
    pub fn filter_into(&mut self, input: &[f64], output: &mut [f64]) -> Status {
        if input.len() != output.len() || input.len() % self.n_channels != 0 {
            return Status::BAD_LENGTH;
        }
        let mut status = Status::OK;
        for (x, y) in input
            .chunks_exact(self.n_channels)
            .zip(output.chunks_exact_mut(self.n_channels))
        {
            status |= self.step(x, y);
        }
        status
    }

    /// The sections, one per mode, in cascade order.
    pub fn sections(&self) -> &[Biquad] {
        &self.sections
    }

    pub fn alpha(&self) -> f64 {
        self.alpha
    }

    pub fn dt_s(&self) -> f64 {
        self.dt_s
    }

    pub fn n_channels(&self) -> usize {
        self.n_channels
    }

    pub fn discretization(&self) -> Discretization {
        self.method
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shaping::shaper_names::SHAPER_NAMES;
    use crate::shaping::shapers::ShaperKind;

    fn benchmark_mode() -> Mode {
        Mode::new(2.0 * PI * 2.55, 0.04)
    }

    /// Evaluates `c0 + c1 z⁻¹ + c2 z⁻²` at complex `z = (re, im)`.
    fn poly_at(c: [f64; 3], z: (f64, f64)) -> (f64, f64) {
        let m = z.0 * z.0 + z.1 * z.1;
        let zi = (z.0 / m, -z.1 / m);
        let zi2 = (zi.0 * zi.0 - zi.1 * zi.1, 2.0 * zi.0 * zi.1);
        (
            c[0] + c[1] * zi.0 + c[2] * zi2.0,
            c[1] * zi.1 + c[2] * zi2.1,
        )
    }

    fn exp_root(mode: Mode, dt_s: f64) -> (f64, f64) {
        let r = (-mode.zeta * mode.wn_rad_s * dt_s).exp();
        let th = mode.wd_rad_s() * dt_s;
        (r * th.cos(), r * th.sin())
    }

    #[test]
    fn benchmark_time_scales_match_the_paper() {
        // Paper: 2.55 Hz, ζ = 0.04, ZVD, T = 0.734 s → α = 0.4653, α' = 0.6516 (4 digits).
        let delay = ShaperKind::Zvd.design(benchmark_mode()).duration_s();
        assert!((delay - 0.39247).abs() < 1e-5, "Δ_n = {delay}");
        let a = ztdis_alpha(0.734, delay).expect("valid");
        let am = modified_alpha(0.734, delay).expect("valid");
        assert!((a - 0.4653).abs() < 1e-4, "alpha = {a}");
        assert!((am - 0.6516).abs() < 1e-4, "alpha' = {am}");
        // Both end at T: αT + Δ_n = T and α'(T + Δ_n) = T.
        assert!((a * 0.734 + delay - 0.734).abs() < 1e-12);
        assert!((am * (0.734 + delay) - 0.734).abs() < 1e-12);
        assert!(am > a);
    }

    #[test]
    fn time_scales_reject_bad_lengths() {
        assert!(ztdis_alpha(0.3, 0.3).is_err());
        assert!(ztdis_alpha(0.2, 0.3).is_err());
        assert!(ztdis_alpha(f64::NAN, 0.1).is_err());
        assert!(ztdis_alpha(1.0, -0.1).is_err());
        assert!(modified_alpha(0.0, 0.1).is_err());
        assert!(modified_alpha(1.0, f64::INFINITY).is_err());
        // The modified scale exists for any positive length.
        let am = modified_alpha(0.2, 0.3).expect("valid");
        assert!((am - 0.4).abs() < 1e-15);
    }

    #[test]
    fn scaled_mode_scales_every_registry_shaper_by_alpha() {
        let mode = Mode::new(9.3, 0.07);
        for name in SHAPER_NAMES {
            let kind = ShaperKind::from_name(name, None).expect("registry name");
            for alpha in [0.3, 0.6516, 1.0] {
                let base = kind.design(mode);
                let scaled = kind.design(scaled_mode(mode, alpha));
                for (a0, a1) in base.amplitudes().iter().zip(scaled.amplitudes()) {
                    assert!((a0 - a1).abs() < 1e-12, "{name}: amplitudes changed");
                }
                for (t0, t1) in base.times_s().iter().zip(scaled.times_s()) {
                    assert!(
                        (alpha * t0 - t1).abs() < 1e-12,
                        "{name}: {t1} != {alpha}·{t0}"
                    );
                }
            }
        }
        assert!(!scaled_mode(mode, 0.0).is_valid());
        assert!(!scaled_mode(mode, f64::NAN).is_valid());
    }

    #[test]
    fn matched_section_has_unit_dc_gain_and_sampled_roots() {
        let mode = benchmark_mode();
        let (alpha, dt) = (0.6516, 0.002);
        let sec = Biquad::compensator(mode, alpha, dt, Discretization::Matched);
        assert!((sec.dc_gain() - 1.0).abs() < 1e-12);
        // Zeros at exp(s dt) of the plant's poles; poles at those of the sped-up mode.
        let (re, im) = poly_at(sec.b, exp_root(mode, dt));
        assert!(re.hypot(im) < 1e-12, "zero residual {re} {im}");
        let fast = scaled_mode(mode, alpha);
        let (re, im) = poly_at([1.0, sec.a[0], sec.a[1]], exp_root(fast, dt));
        assert!(re.hypot(im) < 1e-12, "pole residual {re} {im}");
    }

    #[test]
    fn tustin_section_has_unit_dc_gain_and_high_frequency_gain_near_inverse_alpha_squared() {
        let (alpha, dt) = (0.5, 0.001);
        let sec = Biquad::compensator(benchmark_mode(), alpha, dt, Discretization::Tustin);
        assert!((sec.dc_gain() - 1.0).abs() < 1e-12);
        // Tustin maps s = ∞ to z = −1, so H(−1) = F(∞) = 1/α² exactly.
        let hf = (sec.b[0] - sec.b[1] + sec.b[2]) / (1.0 - sec.a[0] + sec.a[1]);
        assert!((hf - 1.0 / (alpha * alpha)).abs() < 1e-9, "H(-1) = {hf}");
    }

    #[test]
    fn unit_alpha_is_the_identity() {
        for method in [Discretization::Matched, Discretization::Tustin] {
            let mut c =
                Compensator::with_discretization(&[benchmark_mode()], 1.0, 0.002, 1, method)
                    .expect("valid");
            let mut y = [0.0];
            for k in 0..200 {
                let x = (0.05 * k as f64).sin() + 0.01 * k as f64;
                c.step(&[x], &mut y);
                assert!(
                    (y[0] - x).abs() < 1e-12,
                    "{}: {} != {x}",
                    method.name(),
                    y[0]
                );
            }
        }
    }

    /// Tolerance of the rest tests: the coefficient sums of a section are `O((ω dt)²)` ≈ 1e-3
    /// while each coefficient is `O(1)`, so rounding (1e-16) is amplified ~1e3–1e4 times.
    const REST_TOL: f64 = 1e-10;

    #[test]
    fn starts_and_stays_at_rest() {
        let modes = [benchmark_mode(), Mode::new(40.0, 0.1)];
        let mut c = Compensator::new(&modes, 0.6, 0.002, 2).expect("valid");
        let mut y = [0.0; 2];
        for _ in 0..5000 {
            assert!(c.step(&[1.5, -0.25], &mut y).is_ok());
            // The state starts at the rest state of the first input and stays there.
            assert!(
                (y[0] - 1.5).abs() < REST_TOL && (y[1] + 0.25).abs() < REST_TOL,
                "{y:?}"
            );
        }
        c.reset(&[2.0, 3.0]);
        assert!(c.step(&[2.0, 3.0], &mut y).is_ok());
        assert!(
            (y[0] - 2.0).abs() < REST_TOL && (y[1] - 3.0).abs() < REST_TOL,
            "{y:?}"
        );
    }

    #[test]
    fn cascade_and_channels_are_independent_sections() {
        let (m1, m2) = (benchmark_mode(), Mode::new(40.0, 0.1));
        let mut both = Compensator::new(&[m1, m2], 0.7, 0.002, 2).expect("valid");
        let mut first = Compensator::new(&[m1], 0.7, 0.002, 1).expect("valid");
        let mut second = Compensator::new(&[m2], 0.7, 0.002, 1).expect("valid");
        let (mut y, mut y1, mut y2) = ([0.0; 2], [0.0], [0.0]);
        for k in 0..300 {
            let x = if k < 50 {
                0.0
            } else {
                (k as f64 * 0.01).min(1.0)
            };
            both.step(&[x, 7.0], &mut y);
            first.step(&[x], &mut y1);
            second.step(&y1, &mut y2);
            assert!((y[0] - y2[0]).abs() < 1e-12);
            assert!(
                (y[1] - 7.0).abs() < REST_TOL,
                "channel 1 must stay at rest: {}",
                y[1]
            );
        }
    }

    #[test]
    fn holds_non_finite_input_and_rejects_bad_lengths() {
        let mut c = Compensator::new(&[benchmark_mode()], 0.6, 0.002, 2).expect("valid");
        let mut y = [0.0; 2];
        assert!(c.step(&[1.0, 2.0], &mut y).is_ok());
        let s = c.step(&[f64::NAN, 2.0], &mut y);
        assert!(s.contains(Status::INPUT_HELD));
        assert!(y.iter().all(|v| v.is_finite()));
        assert!(
            (y[0] - 1.0).abs() < REST_TOL,
            "held input must keep the rest value"
        );
        assert_eq!(c.step(&[1.0], &mut y), Status::BAD_LENGTH);
        let mut short = [0.0; 1];
        assert_eq!(c.step(&[1.0, 2.0], &mut short), Status::BAD_LENGTH);
    }

    #[test]
    fn rejects_bad_setup() {
        let m = [benchmark_mode()];
        assert!(Compensator::new(&[], 0.6, 0.002, 1).is_err());
        assert!(Compensator::new(&m, 0.0, 0.002, 1).is_err());
        assert!(Compensator::new(&m, f64::NAN, 0.002, 1).is_err());
        assert!(Compensator::new(&m, 0.6, 0.0, 1).is_err());
        assert!(Compensator::new(&m, 0.6, 0.002, 0).is_err());
        assert!(Compensator::new(&[Mode::new(10.0, 1.5)], 0.6, 0.002, 1).is_err());
        // ω/α = 16.02/0.01 = 1602 rad/s > π/0.002 = 1571 rad/s.
        let err = Compensator::new(&m, 0.01, 0.002, 1).expect_err("above Nyquist");
        assert!(err.to_string().contains("Nyquist"), "{err}");
        assert!(Discretization::from_name("zoh").is_err());
    }

    mod properties {
        use super::*;
        use proptest::prelude::*;

        proptest! {
            /// For any valid setup below Nyquist: unit DC gain, poles inside (or, for ζ = 0, on)
            /// the unit circle, and a constant input is reproduced exactly after a reset.
            #[test]
            fn sections_are_stable_with_unit_dc_gain(
                wn in 0.5f64..300.0,
                zeta in 0.0f64..0.6,
                alpha in 0.05f64..1.0,
                dt in 1e-4f64..4e-3,
                x0 in -10.0f64..10.0,
                tustin in any::<bool>(),
            ) {
                prop_assume!(wn / alpha * dt < 0.9 * PI);
                let method = if tustin { Discretization::Tustin } else { Discretization::Matched };
                let mode = Mode::new(wn, zeta);
                let sec = Biquad::compensator(mode, alpha, dt, method);
                // DC gain: sums of O(1) coefficients that cancel to O((ω dt)²) (the mode's ω,
                // the lowest of the section), so their rounding, a few ε, is amplified by
                // 1/(ω dt)²: 4e8 at the slowest corner (ω 0.5 rad/s, dt 0.1 ms), where
                // 3.3e-8 was seen. A wrong gain formula is off by O(ω dt) or more.
                let tol = 16.0 * f64::EPSILON / (wn * dt).powi(2) + 1e-12;
                prop_assert!((sec.dc_gain() - 1.0).abs() < tol, "dc gain {}", sec.dc_gain());
                // Poles of z² + a1 z + a2: complex pair with |p|² = a2, or two real roots.
                let (a1, a2) = (sec.a[0], sec.a[1]);
                let disc = a1 * a1 - 4.0 * a2;
                let radius = if disc < 0.0 {
                    a2.sqrt()
                } else {
                    (a1.abs() + disc.sqrt()) / 2.0
                };
                prop_assert!(radius <= 1.0 + 1e-12, "pole radius {radius}");
                let mut c = Compensator::with_discretization(&[mode], alpha, dt, 1, method)
                    .expect("valid");
                // Same conditioning as the DC gain, times |x0| <= 10: 1e-6 absolute is ample.
                c.reset(&[x0]);
                let mut y = [0.0];
                for _ in 0..50 {
                    c.step(&[x0], &mut y);
                }
                prop_assert!((y[0] - x0).abs() < 1e-6 * (1.0 + x0.abs()), "{} != {x0}", y[0]);
            }
        }
    }
}
