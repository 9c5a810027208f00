//! Single-mode FD-TVIST filter (eq. 7): `x*(t) = Σ A_i(ζ(t)) x(t − Δ_i(ω_n(t), ζ(t)))`.
//!
//! Each cycle the impulse sequence is redesigned for the mode of that cycle and the delayed
//! samples are read with a fractional-delay FIR, so a slowly varying mode gives a smoothly
//! varying output (no whole-sample jumps, no buffer resets).

use crate::delay_line::{DelayLine, Interpolation};
use crate::error::{Error, Status};
use crate::shaper::{ImpulseArray, Mode, ShaperKind, MAX_IMPULSES};

/// One time-varying shaper for one mode, applied to all channels.
#[derive(Debug, Clone)]
pub struct ModeFilter {
    kind: ShaperKind,
    dt_s: f64,
    line: DelayLine,
    /// Last valid mode seen; `None` until the first one (the filter then passes through).
    held: Option<Mode>,
    /// The sequence used in the latest cycle, designed for `held`.
    impulses: ImpulseArray,
    /// `impulses.times_s() / dt_s`: the delays in samples (entries past its length are 0).
    delays_samples: [f64; MAX_IMPULSES],
    /// True if `impulses` was designed with ζ limited to the shaper's range.
    zeta_clamped: bool,
    /// True if the held mode's `ω_n` is at or above the Nyquist frequency `π/dt_s`.
    above_nyquist: bool,
    /// Output of the latest cycle, one value per channel.
    output: Vec<f64>,
}

impl ModeFilter {
    /// A filter for `n_channels` signals sampled every `dt_s`, able to delay by `max_delay_s`.
    pub fn new(
        kind: ShaperKind,
        n_channels: usize,
        dt_s: f64,
        max_delay_s: f64,
        interp: Interpolation,
    ) -> Result<ModeFilter, Error> {
        if !(dt_s.is_finite() && dt_s > 0.0) {
            return Err(Error::InvalidParameter(format!(
                "dt_s = {dt_s} must be finite and > 0"
            )));
        }
        if !(max_delay_s.is_finite() && max_delay_s >= 0.0) {
            return Err(Error::InvalidParameter(format!(
                "max_delay_s = {max_delay_s} must be finite and >= 0"
            )));
        }
        Ok(ModeFilter {
            kind,
            dt_s,
            line: DelayLine::new(n_channels, max_delay_s / dt_s, interp)?,
            held: None,
            impulses: ImpulseArray::IDENTITY,
            delays_samples: [0.0; MAX_IMPULSES],
            zeta_clamped: false,
            above_nyquist: false,
            output: vec![0.0; n_channels],
        })
    }

    /// Puts the filter at rest at `x0`: its whole history equals `x0`.
    pub fn reset(&mut self, x0: &[f64]) {
        self.line.fill(x0);
        for (o, &x) in self.output.iter_mut().zip(x0) {
            *o = x;
        }
    }

    /// Forgets the held mode (used when a shaper is reset).
    pub fn forget_mode(&mut self) {
        self.held = None;
        self.zeta_clamped = false;
        self.above_nyquist = false;
        self.set_impulses(ImpulseArray::IDENTITY);
    }

    fn set_impulses(&mut self, impulses: ImpulseArray) {
        self.impulses = impulses;
        self.delays_samples = [0.0; MAX_IMPULSES];
        for (d, &t) in self.delays_samples.iter_mut().zip(impulses.times_s()) {
            *d = t / self.dt_s;
        }
    }

    /// One cycle: push `input`, design the sequence for `mode` (or hold the last valid one),
    /// and compute [`Self::output`]. Allocation-free.
    ///
    /// The sequence is redesigned only when the mode differs from the held one. A damping
    /// ratio beyond [`ShaperKind::max_zeta`] is limited to it ([`Status::ZETA_CLAMPED`]); a
    /// mode at or above the Nyquist frequency is shaped as given and reported
    /// ([`Status::MODE_ABOVE_NYQUIST`]).
    pub fn step(&mut self, input: &[f64], mode: Mode) -> Status {
        let mut status = Status::OK;
        if mode.is_valid() {
            if self.held != Some(mode) {
                let (design_mode, limited) = self.kind.within_range(mode);
                self.zeta_clamped = limited;
                self.above_nyquist = mode.wn_rad_s * self.dt_s >= core::f64::consts::PI;
                self.set_impulses(self.kind.design(design_mode));
                self.held = Some(mode);
            }
        } else {
            status |= Status::MODES_HELD;
            if self.held.is_none() {
                status |= Status::UNSHAPED;
            }
        }
        if self.zeta_clamped {
            status |= Status::ZETA_CLAMPED;
        }
        if self.above_nyquist {
            status |= Status::MODE_ABOVE_NYQUIST;
        }
        self.line.push(input);
        self.output.fill(0.0);
        let n = self.impulses.len();
        for (&a, &d) in self
            .impulses
            .amplitudes()
            .iter()
            .zip(&self.delays_samples[..n])
        {
            if self.line.accumulate(d, a, &mut self.output) {
                status |= Status::DELAY_CLAMPED;
            }
        }
        status
    }

    /// The output of the latest cycle.
    #[inline]
    pub fn output(&self) -> &[f64] {
        &self.output
    }

    /// The delay of the current sequence (its last impulse), in seconds.
    pub fn delay_s(&self) -> f64 {
        self.impulses.duration_s()
    }

    /// The impulse sequence used in the latest cycle.
    pub fn impulses(&self) -> &ImpulseArray {
        &self.impulses
    }

    /// The longest delay the line can hold, in seconds.
    pub fn max_delay_s(&self) -> f64 {
        self.line.max_delay_samples() * self.dt_s
    }
}
