//! Single-mode FD-TVIST filter (eq. 7): `x*(t) = Σ A_i(ζ(t)) x(t − Δ_i(ω_n(t), ζ(t)))`.
//!
//! Each cycle the impulse sequence is redesigned for the mode of that cycle and the delayed
//! samples are read with a fractional-delay FIR, so a slowly varying mode gives a smoothly
//! varying output (no whole-sample jumps, no buffer resets).
//!
//! Cost structure: a cycle whose mode equals the held one reads prepared taps (position and
//! weights per impulse, [`Reads`]) and returns the status stored with them. A new `ω_n` only
//! rescales the delays of the shape, prepared once per shape ([`Sequence`]): one division per
//! mode, and per delayed impulse one multiplication and, while the delay stays within the
//! same whole sample (nearly always when modes drift), only the fraction split again, bit for
//! bit what a fresh preparation gives. A new `ζ` also redesigns the shape (amplitudes and
//! phases depend on `ζ` alone): the closed forms (`ClosedForm`: a square root and a
//! division side by side, an exponential and one more division) are written straight into the
//! line's form and their reads prepared in the same pass, with no general shape in between;
//! the others go through their [`DampedShape`], and for the exact EI shaper a change of `ζ`
//! interpolates its tabulated solution ([`EiTable`], within 1e-9 of the Newton solve) instead
//! of solving.

use crate::error::{Error, Status};
use crate::shaping::delay_line::{DelayLine, Interpolation, Reads, Sequence};
use crate::shaping::ei::EiTable;
use crate::shaping::shapers::{
    ClosedForm, ClosedShape, DampedShape, ImpulseArray, Mode, ShaperKind,
};

/// One time-varying shaper for one mode, applied to all channels.
#[derive(Debug, Clone)]
pub struct ModeFilter {
    kind: ShaperKind,
    /// The closed form of `kind`, if it has one (and covers every `ζ < 1`).
    closed_form: Option<ClosedForm>,
    /// The largest damping ratio `kind` designs for ([`ShaperKind::max_zeta`]).
    max_zeta: f64,
    /// `1 / dt_s`, samples per second.
    rate_hz: f64,
    dt_s: f64,
    /// The Nyquist frequency `π / dt_s`, rad/s.
    nyquist_rad_s: f64,
    line: DelayLine,
    /// Last valid mode seen; NaN until the first one (the filter then passes through), so
    /// that it compares unequal to every mode.
    held: Mode,
    /// Whether a valid mode has been seen (`held` is a mode).
    shaping: bool,
    /// Damping ratio the current shape was designed for (after limiting); NaN before the
    /// first design (the shape is then the identity).
    shape_zeta: f64,
    /// Whether the current shape is the EI table's ([`Self::shape`]).
    shape_from_table: bool,
    /// The current shape ([`Self::shape`]) as the line reads it: its amplitudes at its phases
    /// times `rate_hz`, i.e. its delays in samples for `ω_n = 1` rad/s (divided by `ω_n` for
    /// a mode).
    shape_samples: Sequence,
    /// The reads of the sequence used in the latest cycle (`shape` at `held.wn_rad_s`, or the
    /// identity before the first valid mode), prepared for `line`.
    reads: Reads,
    /// [`Status::ZETA_CLAMPED`] if the held mode's `ζ` was limited to the shaper's range.
    zeta_status: Status,
    /// What the current design reports every cycle: [`Status::ZETA_CLAMPED`] if `ζ` was
    /// limited to the shaper's range, [`Status::DELAY_CLAMPED`] if a delay exceeds the line.
    design_status: Status,
    /// The exact EI solution over `ζ` (EI shapers only).
    ei_table: Option<EiTable>,
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
        let mut filter = ModeFilter {
            kind,
            // The direct path designs ζ as given: only for the closed forms whose range is
            // every underdamped mode (a valid mode's ζ is below 1).
            closed_form: ClosedForm::of(kind).filter(|_| kind.max_zeta() >= 1.0),
            max_zeta: kind.max_zeta(),
            rate_hz: 1.0 / dt_s,
            dt_s,
            nyquist_rad_s: core::f64::consts::PI / dt_s,
            line: DelayLine::new(n_channels, max_delay_s / dt_s, interp)?,
            held: Mode::new(f64::NAN, f64::NAN),
            shaping: false,
            shape_zeta: f64::NAN,
            shape_from_table: false,
            shape_samples: Sequence::IDENTITY,
            reads: Reads::NONE,
            zeta_status: Status::OK,
            design_status: Status::OK,
            ei_table: kind.ei_tolerance().map(EiTable::new),
            output: vec![0.0; n_channels],
        };
        filter.forget_mode();
        Ok(filter)
    }

    /// Puts the filter at rest at `x0`: its whole history equals `x0`.
    pub fn reset(&mut self, x0: &[f64]) {
        self.line.fill(x0);
        for (o, &x) in self.output.iter_mut().zip(x0) {
            *o = x;
        }
    }

    /// Whether the filter is at rest near `x`: its whole delay line and its latest output are
    /// within `tolerance` of `x`, so it has seen only `x` for longer than any delay it can read.
    pub fn rests_near(&self, x: &[f64], tolerance: f64) -> bool {
        self.line.stays_near(x, tolerance)
            && self
                .output
                .iter()
                .zip(x)
                .all(|(y, x)| (y - x).abs() <= tolerance)
    }

    /// Forgets the held mode (used when a shaper is reset).
    pub fn forget_mode(&mut self) {
        self.held = Mode::new(f64::NAN, f64::NAN);
        self.shaping = false;
        self.shape_zeta = f64::NAN;
        self.shape_from_table = false;
        self.shape_samples = Sequence::IDENTITY;
        // One impulse at delay 0: the reads pass the input through.
        self.line.prepare(&self.shape_samples, 1.0, &mut self.reads);
        self.zeta_status = Status::OK;
        self.design_status = Status::OK;
    }

    /// One cycle: push `input`, design the sequence for `mode` (or hold the last valid one),
    /// and compute [`Self::output`]. Allocation-free.
    ///
    /// The sequence is redesigned only when the mode differs from the held one. A damping
    /// ratio beyond [`ShaperKind::max_zeta`] is limited to it ([`Status::ZETA_CLAMPED`]); a
    /// mode at or above the Nyquist frequency is shaped as given and reported
    /// ([`Status::MODE_ABOVE_NYQUIST`]).
    #[inline]
    pub fn step(&mut self, input: &[f64], mode: Mode) -> Status {
        let status = self.take(mode);
        self.line
            .push_and_read(input, &self.reads, &mut self.output);
        status
    }

    /// The design part of [`Self::step`]: takes `mode` (or holds the last valid one) and
    /// returns the cycle's status; [`Self::step_held_fixed`] then shapes the cycle's sample.
    #[inline(always)]
    pub(crate) fn take(&mut self, mode: Mode) -> Status {
        if self.held.zeta == mode.zeta {
            if self.held.wn_rad_s == mode.wn_rad_s {
                return self.design_status;
            }
            // Only ω_n changed (a valid held ζ): rescale the delays if ω_n is valid.
            if (f64::MIN_POSITIVE..=f64::MAX).contains(&mode.wn_rad_s) {
                return self.take_wn(mode.wn_rad_s);
            }
        }
        self.take_mode(mode)
    }

    /// [`Self::step`] for exactly `N` channels (the filter's channel count) with the held
    /// design ([`Self::take`] first if the mode may have changed), returning the output too.
    #[inline(always)]
    pub(crate) fn step_held_fixed<const N: usize>(
        &mut self,
        input: &[f64; N],
    ) -> (Status, [f64; N]) {
        (self.design_status, self.read_fixed(input))
    }

    /// [`Self::step`] with the held mode (the caller knows the mode is unchanged).
    #[inline]
    pub(crate) fn step_held(&mut self, input: &[f64]) -> Status {
        self.line
            .push_and_read(input, &self.reads, &mut self.output);
        self.design_status
    }

    /// Pushes `input`, reads the current design and keeps the output.
    #[inline(always)]
    pub(crate) fn read_fixed<const N: usize>(&mut self, input: &[f64; N]) -> [f64; N] {
        let y = self.line.push_and_read_fixed(input, &self.reads);
        if let Ok(output) = <&mut [f64; N]>::try_from(self.output.as_mut_slice()) {
            *output = y;
        }
        y
    }

    /// A new natural frequency for the held shape: the delays scale by `1/ω_n` (the shape
    /// and its `ζ` status stay). Returns the cycle's status.
    #[inline]
    fn take_wn(&mut self, wn_rad_s: f64) -> Status {
        self.held.wn_rad_s = wn_rad_s;
        self.prepare_reads()
    }

    /// A mode other than the held one: redesign for it if valid, hold otherwise. Returns the
    /// cycle's status.
    ///
    /// A new `ζ` of a closed-form shaper ([`ClosedForm`]) is written straight into the
    /// line's form; the other shapers go through their general design
    /// ([`Self::take_zeta_general`], kept out of line so that this path stays small).
    #[inline(never)]
    fn take_mode(&mut self, mode: Mode) -> Status {
        if !mode.is_valid() {
            let unshaped = if !self.shaping {
                Status::UNSHAPED
            } else {
                Status::OK
            };
            return Status::MODES_HELD | unshaped | self.design_status;
        }
        match self.closed_form {
            // The closed forms cover every underdamped mode (their limit is ζ < 1): `ζ` is
            // designed as given, and each form's reads are prepared right after it.
            Some(form) => {
                self.held = mode;
                self.shaping = true;
                self.zeta_status = Status::OK;
                if mode.zeta == self.shape_zeta {
                    return self.prepare_reads();
                }
                self.shape_zeta = mode.zeta;
                match form {
                    ClosedForm::Zv => self.take_closed(&ClosedForm::zv(mode.zeta)),
                    ClosedForm::Zvd => self.take_closed(&ClosedForm::zvd(mode.zeta)),
                    ClosedForm::Zvdd => self.take_closed(&ClosedForm::zvdd(mode.zeta)),
                    ClosedForm::Mzv => self.take_closed(&ClosedForm::mzv(mode.zeta)),
                }
            }
            None => {
                // Designed before `shaping` is set: the first design after a start is solved.
                self.take_zeta_general(mode.zeta);
                self.held = mode;
                self.shaping = true;
                self.prepare_reads()
            }
        }
    }

    /// Prepares the reads of `impulses` (designed for `held`) and returns the status they
    /// report every cycle ([`Self::step`]).
    #[inline(always)]
    fn prepare_reads(&mut self) -> Status {
        let mut status = self.zeta_status;
        // A mode at or above the Nyquist frequency π/dt_s is shaped as given (its impulses
        // fall within about one sample) and reported every cycle it is held.
        if self.held.wn_rad_s >= self.nyquist_rad_s {
            status |= Status::MODE_ABOVE_NYQUIST;
        }
        let per_rad = 1.0 / self.held.wn_rad_s; // the same division as `impulses`' times
        if self
            .line
            .prepare(&self.shape_samples, per_rad, &mut self.reads)
        {
            status |= Status::DELAY_CLAMPED;
        }
        self.design_status = status;
        status
    }

    /// Takes the shape of a closed-form shaper (designed for `held`): as the line reads it,
    /// its phases times `rate_hz` (the same sequence [`Sequence::assign`] makes of
    /// [`Self::design_shape`]'s, since both come from the one closed form and only its first
    /// impulse is undelayed); then prepares its reads. Returns the cycle's status.
    #[inline(always)]
    fn take_closed<const N: usize>(&mut self, shape: &ClosedShape<N>) -> Status {
        self.shape_samples.assign_first_undelayed(
            &shape.phases_rad,
            &shape.amplitudes,
            self.rate_hz,
        );
        self.shape_from_table = false;
        self.prepare_reads()
    }

    /// The shape of a shaper without a closed form for the damping ratio `zeta` of a valid
    /// mode, limited to the shaper's range ([`Status::ZETA_CLAMPED`]), unless it is the
    /// current one. A change of ζ while shaping with the exact EI shaper reads its tabulated
    /// solution; the first design (after construction or a reset) is solved, so constant
    /// modes get exactly the offline design.
    #[inline(never)]
    fn take_zeta_general(&mut self, zeta: f64) {
        let limited = zeta > self.max_zeta;
        let zeta = if limited { self.max_zeta } else { zeta };
        self.zeta_status = if limited {
            Status::ZETA_CLAMPED
        } else {
            Status::OK
        };
        if zeta != self.shape_zeta {
            let from_table = self.shaping && self.ei_table.is_some();
            let shape = self.design_shape(zeta, from_table);
            self.shape_samples
                .assign(shape.phases_rad(), shape.amplitudes(), self.rate_hz);
            self.shape_zeta = zeta;
            self.shape_from_table = from_table;
        }
    }

    /// The mode the filter holds (the last valid one it took), if any.
    #[inline]
    pub fn held_mode(&self) -> Option<Mode> {
        self.shaping.then_some(self.held)
    }

    /// The output of the latest cycle.
    #[inline]
    pub fn output(&self) -> &[f64] {
        &self.output
    }

    /// The delay of the current sequence (its last impulse), in seconds.
    pub fn delay_s(&self) -> f64 {
        self.impulses().duration_s()
    }

    /// The impulse sequence used in the latest cycle: the held shape at the held `ω_n`
    /// (the identity before the first valid mode).
    pub fn impulses(&self) -> ImpulseArray {
        if self.shaping {
            self.shape().at(self.held.wn_rad_s)
        } else {
            ImpulseArray::IDENTITY
        }
    }

    /// The current shape (impulse times as phases `ω_n t`), designed again: the shape for
    /// `shape_zeta` as [`Self::design_shape`] made it (deterministic, so the same bits).
    fn shape(&self) -> DampedShape {
        if self.shape_zeta.is_nan() {
            DampedShape::IDENTITY
        } else {
            self.design_shape(self.shape_zeta, self.shape_from_table)
        }
    }

    /// The shape for damping ratio `zeta`: the family's design, or for the exact EI shaper
    /// with `from_table` the tabulated solution.
    #[inline(always)]
    fn design_shape(&self, zeta: f64, from_table: bool) -> DampedShape {
        match &self.ei_table {
            Some(table) if from_table => {
                let (amplitudes, phases_rad) = table.shape(zeta);
                DampedShape::three(&amplitudes, &phases_rad)
            }
            _ => self.kind.damped_shape(zeta),
        }
    }

    /// The longest delay the line can hold, in seconds.
    pub fn max_delay_s(&self) -> f64 {
        self.line.max_delay_samples() * self.dt_s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_new_zeta_of_a_closed_form_gives_the_general_designs_sequence_to_the_bit() {
        // The closed forms are written straight into the line's form when ζ changes
        // (`take_closed`); the general path makes a `DampedShape` and assigns it. Both must
        // give the same sequence, bit for bit, for damping ratios over all of [0, 1): zero,
        // tiny, the usual range, and so close to 1 that K underflows to 0. `fresh` designs
        // from scratch every time; `kept` redesigns over its previous ζ.
        let mut zetas = vec![0.0, 1e-300, 1e-12, 0.999, 0.999_999_9, 1.0f64.next_down()];
        zetas.extend((0..2000).map(|i| (i as f64 * 0.618_033_988_75).fract()));
        for kind in [
            ShaperKind::Zv,
            ShaperKind::Zvd,
            ShaperKind::Zvdd,
            ShaperKind::Mzv,
        ] {
            let new =
                || ModeFilter::new(kind, 2, 0.002, 0.5, Interpolation::Linear).expect("valid");
            let (mut fresh, mut kept) = (new(), new());
            for (i, &zeta) in zetas.iter().enumerate() {
                let mode = Mode::new(40.0 + i as f64 * 1e-3, zeta);
                fresh.forget_mode();
                let status = fresh.take_mode(mode);
                assert_eq!(kept.take_mode(mode), status, "{kind:?} ζ = {zeta}");
                assert!(
                    !status.contains(Status::ZETA_CLAMPED),
                    "{kind:?} ζ = {zeta}"
                );
                let shape = kind.damped_shape(zeta);
                let general = Sequence::new(shape.phases_rad(), shape.amplitudes(), fresh.rate_hz);
                assert_eq!(fresh.shape_samples, general, "{kind:?} ζ = {zeta}");
                assert_eq!(kept.shape_samples, general, "{kind:?} ζ = {zeta}");
                assert_eq!(fresh.impulses(), kind.design(mode), "{kind:?} ζ = {zeta}");
            }
        }
    }

    #[test]
    fn the_exact_ei_shaper_solves_its_first_design_and_reads_its_table_after() {
        // After construction and after a reset the design is the Newton solve itself (the
        // offline design, to the bit); a later change of ζ reads the table, which differs
        // from a solve (by rounding at least) but stays within its 1e-9.
        let kind = ShaperKind::Ei { v_tol: 0.05 };
        let mut filter =
            ModeFilter::new(kind, 1, 0.002, 0.5, Interpolation::Linear).expect("valid");
        let (first, second) = (Mode::new(50.0, 0.26), Mode::new(50.0, 0.2612345));
        for _ in 0..2 {
            let _ = filter.take_mode(first);
            assert!(!filter.shape_from_table);
            assert_eq!(filter.impulses(), kind.design(first));
            let _ = filter.take_mode(second);
            assert!(filter.shape_from_table);
            let (got, solved) = (filter.impulses(), kind.design(second));
            assert_ne!(got, solved);
            for (a, b) in got
                .amplitudes()
                .iter()
                .zip(solved.amplitudes())
                .chain(got.times_s().iter().zip(solved.times_s()))
            {
                assert!((a - b).abs() <= 1e-9, "{a} vs {b}");
            }
            filter.forget_mode();
        }
    }
}
