//! Multi-mode FD-TVIST (Fig. 5): a cascade of [`ModeFilter`]s, one per mode, all channels each.
//!
//! Every cycle the provider is asked for all modes at `q**_{n−1}`, the *previous final output*
//! of the cascade (it stands in for where the robot is), and filter `m` uses mode `m`. Chaining
//! filters that each update from their own input would be wrong.

use crate::error::{Error, Status};
use crate::modes::dynamics::Dynamics;
use crate::modes::provider::Provider;
use crate::shaping::delay_line::{DelayLine, Interpolation};
use crate::shaping::held_input::HeldInput;
use crate::shaping::mode_filter::ModeFilter;
use crate::shaping::shapers::{Mode, ShaperKind};

/// Default delay-line safety factor over the largest expected delay.
pub const DEFAULT_SAFETY_FACTOR: f64 = 1.5;

/// Largest distance (input units: rad or m) of any delay-line sample or filter output from
/// the held input for which the shaper counts as at rest ([`TvShaper::is_at_rest`]). Far
/// above rounding (about 1e-15 for angles of a few radians), far below any joint encoder
/// resolution (about 1e-5 rad): the output step a replacement at rest may cause.
pub const REST_TOLERANCE: f64 = 1e-9;

/// Fastest change of a shaped mode's natural frequency the shaper follows, `|d ln ω_n/dt|`
/// per second (1 % per cycle at 2 ms); a faster one is approached at this rate and reported
/// ([`Status::MODE_SLEW_LIMITED`]).
///
/// Why 5/s: a mode that changes with the pose moves by a few 10 % over a move of 0.5 s or
/// more, about 0.6/s on average (`1e-3` per 2 ms cycle): a margin of 8 before the limit binds.
/// A filter's delay `τ` (half a damped period for ZV) scales with `1/ω_n`, so the limit bounds
/// its rate `|dτ/dt| = τ |d ln ω_n/dt|` to `5 τ`: 0.17 for a ZV filter at 15 Hz (τ = 33 ms),
/// below 1/2 for every filter with a delay under 0.1 s (ZV above 5 Hz, ZVD above 10 Hz). At
/// `|dτ/dt| = 1` the filter would read its input standing still (the reference would stop);
/// well below it the shaped velocity is changed by no more than that fraction. A jump between
/// two far-apart eigenmodes (14.9 to 30.9 Hz, `Δ ln ω = 0.73`) is spread over 0.15 s.
pub const MAX_LN_WN_RATE_PER_S: f64 = 5.0;

/// Fastest change of a shaped mode's damping ratio the shaper follows, `|dζ/dt|` per second
/// (0.01 per cycle at 2 ms); a faster one is approached at this rate and reported
/// ([`Status::MODE_SLEW_LIMITED`]).
///
/// Why 5/s: ζ changes with the load of a joint (0.1 over a move, 0.2/s) and, fastest, along a
/// branch through a veering of two modes of different damping (0.14 to 0.28 within some
/// 50 ms of a move, about 3/s). A ZV filter's first amplitude changes by about `0.8 Δζ`
/// (ζ near 0.1), which moves the output by `0.8 Δζ · v τ` for a velocity `v`: at the limit
/// the shaped velocity changes by `0.8 · 5 τ`, 13 % for τ = 33 ms.
pub const MAX_ZETA_RATE_PER_S: f64 = 5.0;

/// Setup of a [`TvShaper`].
#[derive(Debug, Clone, PartialEq)]
pub struct TvShaperConfig {
    /// Control period, s.
    pub dt_s: f64,
    /// Number of joint channels.
    pub n_dof: usize,
    pub shaper: ShaperKind,
    pub interp: Interpolation,
    /// Largest delay any single mode filter must hold, s. `None`: derived from the provider's
    /// slowest modes times `safety_factor`.
    pub max_delay_s: Option<f64>,
    /// Multiplies the provider-derived delay bound (ignored when `max_delay_s` is set).
    pub safety_factor: f64,
}

impl TvShaperConfig {
    pub fn new(dt_s: f64, n_dof: usize, shaper: ShaperKind) -> Self {
        TvShaperConfig {
            dt_s,
            n_dof,
            shaper,
            interp: Interpolation::Linear,
            max_delay_s: None,
            safety_factor: DEFAULT_SAFETY_FACTOR,
        }
    }
}

/// The multi-mode time-varying input shaper: streaming (`step`) with a fixed memory footprint.
#[derive(Debug)]
pub struct TvShaper<D: Dynamics> {
    dynamics: D,
    filters: Vec<ModeFilter>,
    /// Scratch for the provider's modes, one per filter.
    modes: Vec<Mode>,
    /// Last valid input sample (held when a non-finite sample arrives).
    input: HeldInput,
    /// Every filter holds the design for the provider's modes of a previous cycle (set by a
    /// step, cleared by a start or reset and by [`Self::dynamics_mut`]). With a provider whose
    /// modes are constant the step then neither asks for modes nor compares them.
    designed: bool,
    n_dof: usize,
    dt_s: f64,
    /// The configuration the shaper was built with (a replacement of its provider reuses it).
    config: TvShaperConfig,
    /// Consecutive cycles whose input did not change (counted up to `rest_cycles`).
    still_cycles: usize,
    /// Cycles of unchanged input after which every delay line holds that input alone (the
    /// sum of the filters' capacities plus margin): the shaper is at rest and a new mode
    /// changes nothing in its output.
    rest_cycles: usize,
    /// Largest factor by which a mode's `ω_n` may change in one cycle
    /// (`exp(MAX_LN_WN_RATE_PER_S dt_s)`).
    wn_step_factor: f64,
    /// Largest change of a mode's `ζ` in one cycle (`MAX_ZETA_RATE_PER_S dt_s`).
    zeta_step: f64,
}

impl<D: Dynamics> TvShaper<D> {
    /// Validates the configuration and allocates all state.
    pub fn new(dynamics: D, config: &TvShaperConfig) -> Result<TvShaper<D>, Error> {
        let TvShaperConfig {
            dt_s,
            n_dof,
            shaper,
            interp,
            max_delay_s,
            safety_factor,
        } = *config;
        if !(dt_s.is_finite() && dt_s > 0.0) {
            return Err(Error::InvalidParameter(format!(
                "dt_s = {dt_s} must be finite and > 0"
            )));
        }
        if n_dof == 0 {
            return Err(Error::InvalidParameter("n_dof must be at least 1".into()));
        }
        crate::limits::check_n_dof(n_dof)?;
        if let Some(expected) = dynamics.n_dof() {
            if expected != n_dof {
                return Err(Error::DimensionMismatch {
                    what: "n_dof of the dynamics provider",
                    expected,
                    got: n_dof,
                });
            }
        }
        if !(safety_factor.is_finite() && safety_factor >= 1.0) {
            return Err(Error::InvalidParameter(format!(
                "safety_factor = {safety_factor} must be >= 1"
            )));
        }
        let n_modes = dynamics.n_modes();
        if n_modes == 0 {
            return Err(Error::InvalidParameter(
                "the dynamics provider has no modes; at least one is required".into(),
            ));
        }
        crate::limits::check_n_modes(n_modes, "the dynamics provider")?;
        let mut max_delays_s = Vec::with_capacity(n_modes);
        for m in 0..n_modes {
            if let Some(slowest) = dynamics.slowest_mode(m) {
                slowest.validate(m)?;
                if slowest.zeta > shaper.max_zeta() {
                    return Err(Error::InvalidParameter(format!(
                        "mode {m} has zeta = {} beyond the range of the {:?} shaper's \
                         approximation (zeta <= {})",
                        slowest.zeta,
                        shaper.name(),
                        shaper.max_zeta()
                    )));
                }
            }
            let max_delay = match max_delay_s {
                Some(d) => d,
                None => {
                    let slowest = dynamics.slowest_mode(m).ok_or(Error::UnknownDelayBound)?;
                    safety_factor * shaper.design(slowest).duration_s()
                }
            };
            max_delays_s.push(max_delay);
        }
        // The memory of every delay line is bounded before any of it is allocated.
        let mut bytes = Some(0usize);
        for &max_delay in &max_delays_s {
            if !(max_delay.is_finite() && max_delay >= 0.0) {
                break; // refused with its own message by ModeFilter::new below
            }
            let line = DelayLine::bytes_for(max_delay / dt_s, interp, n_dof)?;
            bytes = bytes.zip(line).and_then(|(b, l)| b.checked_add(l));
        }
        crate::limits::check_delay_line_bytes(
            bytes,
            &format!("{n_modes} mode(s) × {n_dof} channel(s)"),
        )?;
        let mut filters = Vec::with_capacity(n_modes);
        for max_delay in max_delays_s {
            filters.push(ModeFilter::new(shaper, n_dof, dt_s, max_delay, interp)?);
        }
        // A Lagrange read of order 3 reaches two samples past the delay: 4 per filter is ample.
        let rest_cycles = filters
            .iter()
            .map(|f| (f.max_delay_s() / dt_s).ceil() as usize + 4)
            .sum::<usize>()
            + 1;
        Ok(TvShaper {
            dynamics,
            filters,
            modes: vec![Mode::new(f64::NAN, f64::NAN); n_modes],
            input: HeldInput::new(n_dof),
            designed: false,
            n_dof,
            dt_s,
            config: config.clone(),
            still_cycles: 0,
            rest_cycles,
            wn_step_factor: (MAX_LN_WN_RATE_PER_S * dt_s).exp(),
            zeta_step: MAX_ZETA_RATE_PER_S * dt_s,
        })
    }

    /// Puts the shaper at rest at `q0` (history and previous output equal `q0`).
    /// Non-finite entries of `q0` are taken as 0. Modes are re-read on the next step.
    pub fn reset(&mut self, q0: &[f64]) {
        self.input.set(q0);
        self.start_at_input();
        for f in &mut self.filters {
            f.forget_mode();
        }
        self.designed = false;
        self.dynamics.restart();
        self.still_cycles = self.rest_cycles;
    }

    /// Whether the shaper is between moves: not started, or every filter's whole delay line
    /// and latest output are within [`REST_TOLERANCE`] of the held input, i.e. the input has
    /// not moved for longer than the delay any filter can read and the output has settled on
    /// it. Setup-time check, not for the control loop (it reads every delay line).
    ///
    /// Not an exact equality: with modes read at the previous output, a shaper at rest may
    /// keep toggling the last bits of its output (the modes, and so the rounding of the
    /// amplitude sum, follow those bits).
    pub fn is_at_rest(&self) -> bool {
        !self.input.started()
            || self
                .filters
                .iter()
                .all(|f| f.rests_near(self.input.value(), REST_TOLERANCE))
    }

    /// Replaces the provider between moves ([`Self::is_at_rest`]) by a new shaper built from
    /// `dynamics` with `config` (allocates: a setup call), at rest on the held input if the
    /// shaper has started. The next move is then shaped exactly as a new shaper built from
    /// `dynamics` would shape it starting at that input. Refused with
    /// [`Error::InvalidParameter`] mid-move and with the constructor's error for an invalid
    /// provider or configuration; the shaper is unchanged on every error.
    pub fn replace_dynamics(&mut self, dynamics: D, config: &TvShaperConfig) -> Result<(), Error> {
        self.check_at_rest("replace its dynamics")?;
        let mut next = TvShaper::new(dynamics, config)?;
        if next.n_dof != self.n_dof {
            return Err(Error::DimensionMismatch {
                what: "n_dof of the replacement",
                expected: self.n_dof,
                got: next.n_dof,
            });
        }
        if self.input.started() {
            next.reset(self.input.value());
        }
        *self = next;
        Ok(())
    }

    /// [`Error::InvalidParameter`] naming `what` to do between moves, unless
    /// [`Self::is_at_rest`].
    fn check_at_rest(&self, what: &str) -> Result<(), Error> {
        if self.is_at_rest() {
            return Ok(());
        }
        Err(Error::InvalidParameter(format!(
            "the shaper is mid-move (its delay lines are not at rest on the input); {what} \
             between moves"
        )))
    }

    /// The configuration the shaper was built with.
    pub fn config(&self) -> &TvShaperConfig {
        &self.config
    }

    /// Forgets all history: the next `step` starts at rest on its input.
    pub fn clear(&mut self) {
        self.input.clear();
        for f in &mut self.filters {
            f.forget_mode();
        }
        self.designed = false;
        self.dynamics.restart();
    }

    /// One control cycle: shapes `input` (length `n_dof`) into `output` (length `n_dof`).
    ///
    /// Never allocates or panics. Non-finite input values hold the last valid sample
    /// ([`Status::INPUT_HELD`]); on a length mismatch nothing is computed and
    /// [`Status::BAD_LENGTH`] is returned.
    pub fn step(&mut self, input: &[f64], output: &mut [f64]) -> Status {
        // The common channel counts run with fixed-size rows (unrolled, no copies through
        // library calls); the arithmetic is the same for every count.
        match self.n_dof {
            1 => self.step_fixed::<1>(input, output),
            2 => self.step_fixed::<2>(input, output),
            3 => self.step_fixed::<3>(input, output),
            4 => self.step_fixed::<4>(input, output),
            5 => self.step_fixed::<5>(input, output),
            6 => self.step_fixed::<6>(input, output),
            7 => self.step_fixed::<7>(input, output),
            _ => self.step_any(input, output),
        }
    }

    /// [`Self::step`] for exactly `N` channels.
    #[inline(always)]
    fn step_fixed<const N: usize>(&mut self, input: &[f64], output: &mut [f64]) -> Status {
        let (Ok(input), Ok(output)) = (
            <&[f64; N]>::try_from(input),
            <&mut [f64; N]>::try_from(output),
        ) else {
            return Status::BAD_LENGTH;
        };
        let moves = self.input.moves(input);
        let (mut stage, mut status, first) = self.input.accept_fixed(input);
        self.count_rest(moves, first);
        if first {
            self.start_at_input();
        }
        if self.designed && self.dynamics.modes_are_constant() {
            for filter in &mut self.filters {
                let (filter_status, filtered) = filter.step_held_fixed(&stage);
                status |= filter_status;
                stage = filtered;
            }
        } else {
            status |= self.ask_modes();
            status |= self.limit_mode_slew();
            // Every filter takes its mode first (a design never depends on the signal), then
            // the signal runs through the cascade.
            for (filter, &mode) in self.filters.iter_mut().zip(&self.modes) {
                status |= filter.take(mode);
            }
            for filter in &mut self.filters {
                stage = filter.read_fixed(&stage);
            }
            self.designed = true;
        }
        *output = stage;
        status
    }

    /// [`Self::step`] for any channel count.
    fn step_any(&mut self, input: &[f64], output: &mut [f64]) -> Status {
        if input.len() != self.n_dof || output.len() != self.n_dof {
            return Status::BAD_LENGTH;
        }
        let moves = self.input.moves(input);
        let (mut status, first) = self.input.accept(input);
        self.count_rest(moves, first);
        if first {
            self.start_at_input();
        }
        let constant = self.designed && self.dynamics.modes_are_constant();
        if !constant {
            status |= self.ask_modes();
            status |= self.limit_mode_slew();
        }
        // Filter m shapes the output of filter m − 1 (the held input for the first).
        let mut stage: &[f64] = self.input.value();
        for (filter, &mode) in self.filters.iter_mut().zip(&self.modes) {
            status |= if constant {
                filter.step_held(stage)
            } else {
                filter.step(stage, mode)
            };
            let done: &ModeFilter = filter;
            stage = done.output();
        }
        self.designed = true;
        output.copy_from_slice(stage);
        status
    }

    /// The provider's modes at `q**_{n−1}`, the previous final output, kept by the last filter
    /// (at rest on the input after a start or reset), into `modes`.
    #[inline]
    fn ask_modes(&mut self) -> Status {
        let previous_output = match self.filters.last() {
            Some(last) => last.output(),
            None => self.input.value(),
        };
        self.dynamics.modes(previous_output, &mut self.modes)
    }

    /// Counts the cycles of unchanged input; at the cycle the shaper comes to rest (and at a
    /// first sample, where it starts at rest) the provider may choose its modes afresh
    /// ([`Dynamics::restart`]): every delay line then holds one value, so no choice of modes
    /// changes the output.
    #[inline]
    fn count_rest(&mut self, moves: bool, first: bool) {
        if first {
            self.still_cycles = self.rest_cycles;
            self.dynamics.restart();
        } else if moves {
            self.still_cycles = 0;
        } else if self.still_cycles < self.rest_cycles {
            self.still_cycles += 1;
            if self.still_cycles == self.rest_cycles {
                self.dynamics.restart();
            }
        }
    }

    /// Limits each mode's change from the one its filter holds to the per-cycle steps of
    /// [`MAX_LN_WN_RATE_PER_S`] and [`MAX_ZETA_RATE_PER_S`] ([`Status::MODE_SLEW_LIMITED`]
    /// where that binds), except at rest, where a mode changes nothing in the output. Invalid
    /// modes are left to the filters (they hold theirs).
    #[inline]
    fn limit_mode_slew(&mut self) -> Status {
        if self.still_cycles >= self.rest_cycles {
            return Status::OK;
        }
        let mut status = Status::OK;
        for (mode, filter) in self.modes.iter_mut().zip(&self.filters) {
            let Some(held) = filter.held_mode() else {
                continue;
            };
            if !mode.is_valid() {
                continue;
            }
            // max/min rather than clamp: no panic whatever the values.
            let wn = mode
                .wn_rad_s
                .max(held.wn_rad_s / self.wn_step_factor)
                .min(held.wn_rad_s * self.wn_step_factor);
            let zeta = mode
                .zeta
                .max(held.zeta - self.zeta_step)
                .min(held.zeta + self.zeta_step);
            if wn != mode.wn_rad_s || zeta != mode.zeta {
                *mode = Mode::new(wn, zeta);
                status |= Status::MODE_SLEW_LIMITED;
            }
        }
        status
    }

    /// At rest on the held input: history and outputs (so the previous output) equal it.
    fn start_at_input(&mut self) {
        for f in &mut self.filters {
            f.reset(self.input.value());
        }
    }

    /// Shapes a block of samples in `(n_samples, n_dof)` row-major layout, continuing the
    /// streaming state. Returns the union of all step statuses.
    pub fn shape_into(&mut self, input: &[f64], output: &mut [f64]) -> Status {
        if input.len() != output.len() || input.len() % self.n_dof != 0 {
            return Status::BAD_LENGTH;
        }
        let mut status = Status::OK;
        for (x, y) in input
            .chunks_exact(self.n_dof)
            .zip(output.chunks_exact_mut(self.n_dof))
        {
            status |= self.step(x, y);
        }
        status
    }

    /// Current total delay of the cascade (sum of the filters' last impulse times), s.
    pub fn delay_s(&self) -> f64 {
        self.filters.iter().map(ModeFilter::delay_s).sum()
    }

    /// The modes used in the latest cycle: the provider's (possibly invalid), each limited to
    /// the change a cycle allows ([`MAX_LN_WN_RATE_PER_S`], [`MAX_ZETA_RATE_PER_S`]).
    pub fn current_modes(&self) -> &[Mode] {
        &self.modes
    }

    pub fn filters(&self) -> &[ModeFilter] {
        &self.filters
    }

    pub fn dynamics(&self) -> &D {
        &self.dynamics
    }

    /// The provider, to change it: the next step asks it for modes again.
    pub fn dynamics_mut(&mut self) -> &mut D {
        self.designed = false;
        &mut self.dynamics
    }

    pub fn n_dof(&self) -> usize {
        self.n_dof
    }

    pub fn dt_s(&self) -> f64 {
        self.dt_s
    }
}

impl<C: Dynamics> TvShaper<Provider<C>> {
    /// Shapes the `k` lowest-frequency modes of the shaper's modal map from now on
    /// ([`crate::ModalDynamics::shaping_lowest`], whatever modes the map shaped before;
    /// `1 <= k <=` its number of flexible joints), one filter each, so the added delay is
    /// that of those `k` modes. Between moves only, as [`Self::replace_dynamics`] (a setup
    /// call: it builds a new provider and new delay lines); the shaper is unchanged on every
    /// error: mid-move, a provider other than a modal map, or `k` out of range.
    pub fn set_shaped_modes(&mut self, k: usize) -> Result<(), Error> {
        let Provider::Modal(modal) = &self.dynamics else {
            return Err(Error::InvalidParameter(
                "the number of shaped modes is set on a shaper driven by a modal map".into(),
            ));
        };
        self.check_at_rest("set the number of shaped modes")?;
        let next = Provider::Modal(Box::new(modal.shaping_lowest(k)?));
        let config = self.config.clone();
        self.replace_dynamics(next, &config)
    }

    /// Shapes from now on with the modes the shaper's map gives at `pose` (the robot's
    /// joints, rad), held constant instead of followed cycle by cycle; `None` follows the
    /// pose of every cycle again ([`crate::RobotModes::holding_at`]). For a move whose
    /// time-varying shaping the map predicts to leave more ringing than its stop pose's modes
    /// do (`tvist.maps.set_modes_for_move`): pass the move's end pose. [`Self::set_shaped_modes`]
    /// also ends a hold. Between moves only, as [`Self::replace_dynamics`]; the shaper is
    /// unchanged on every error: mid-move, a provider other than a map, a pose of the wrong
    /// length or one where the map gives an invalid mode.
    pub fn hold_modes_at(&mut self, pose: Option<&[f64]>) -> Result<(), Error> {
        self.check_at_rest("hold the modes at a pose")?;
        let next =
            match &self.dynamics {
                Provider::Modal(modal) => Provider::Modal(Box::new(modal.holding_at(pose)?)),
                Provider::Map(map) => Provider::Map(Box::new(map.holding_at(pose)?)),
                _ => return Err(Error::InvalidParameter(
                    "the modes are held at a pose on a shaper driven by a map (dynamic or modal)"
                        .into(),
                )),
            };
        let config = self.config.clone();
        self.replace_dynamics(next, &config)
    }
}
