//! Setup errors and per-step status codes.
//!
//! Construction (`new`) validates everything and returns [`Error`]. The per-step path never
//! fails: it returns a [`Status`] whose bits say what was held or clamped in that cycle.

use core::fmt;

/// Everything that can go wrong while configuring a filter. Returned only at setup time.
#[derive(Debug, Clone, PartialEq)]
pub enum Error {
    /// A shaper name not in the registry ([`crate::shaping::shaper_names::SHAPER_NAMES`]).
    UnknownShaper(String),
    /// An interpolation name other than `"linear"` or `"cubic"`.
    UnknownInterpolation(String),
    /// A parameter outside its domain; the string names the parameter and the rule.
    InvalidParameter(String),
    /// A mode `(wn_rad_s, zeta)` that is not finite, has `wn <= 0`, or `zeta` outside `[0, 1)`.
    InvalidMode {
        index: usize,
        wn_rad_s: f64,
        zeta: f64,
    },
    /// An impulse set that is empty, non-finite, unsorted or sums to zero.
    InvalidImpulses(String),
    /// Channel-count mismatch between the parts of a filter.
    DimensionMismatch {
        what: &'static str,
        expected: usize,
        got: usize,
    },
    /// The filter cannot size its delay line: the provider gives no delay bound and none was set.
    UnknownDelayBound,
    /// A malformed document (map file, robot data): `path` names the field (for example
    /// `modes[1].k_0`, or `(document)` for the text as a whole), `reason` says what is wrong.
    Document { path: String, reason: String },
    /// A dynamic map identified on one robot used with another.
    RobotMismatch { map_robot: String, robot: String },
    /// A setup request beyond a documented resource limit ([`crate::limits`]).
    TooLarge(String),
}

impl Error {
    /// A [`Error::Document`] error at field `path`.
    pub fn document(path: impl Into<String>, reason: impl Into<String>) -> Error {
        Error::Document {
            path: path.into(),
            reason: reason.into(),
        }
    }
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Error::UnknownShaper(name) => write!(
                f,
                "unknown shaper {name:?}; expected one of {:?}",
                crate::shaping::shaper_names::SHAPER_NAMES
            ),
            Error::UnknownInterpolation(name) => {
                write!(
                    f,
                    "unknown interpolation {name:?}; expected \"linear\" or \"cubic\""
                )
            }
            Error::InvalidParameter(msg) => write!(f, "invalid parameter: {msg}"),
            Error::InvalidMode {
                index,
                wn_rad_s,
                zeta,
            } => write!(
                f,
                "invalid mode {index}: wn_rad_s={wn_rad_s}, zeta={zeta} \
                 (need finite wn_rad_s > 0 and 0 <= zeta < 1)"
            ),
            Error::InvalidImpulses(msg) => write!(f, "invalid impulse set: {msg}"),
            Error::DimensionMismatch {
                what,
                expected,
                got,
            } => {
                write!(f, "{what}: expected {expected}, got {got}")
            }
            Error::UnknownDelayBound => write!(
                f,
                "the dynamics provider gives no bound on the shaper delay; set max_delay_s"
            ),
            Error::Document { path, reason } => write!(f, "{path}: {reason}"),
            Error::RobotMismatch { map_robot, robot } => write!(
                f,
                "the map was identified on {map_robot}, not on {robot}: identify a \
                 map for {robot} (tvist campaign, tvist fit-map) or explicitly allow a map \
                 of another robot"
            ),
            Error::TooLarge(msg) => write!(f, "setup request too large: {msg}"),
        }
    }
}

impl std::error::Error for Error {}

/// Per-step status: a set of bit flags with stable values, `0` meaning a clean cycle.
///
/// It is `#[repr(transparent)]` over `i32` so it crosses a C boundary unchanged.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[repr(transparent)]
pub struct Status(pub i32);

impl Status {
    /// Nothing held or clamped.
    pub const OK: Status = Status(0);
    /// A non-finite input sample was replaced by the last valid one.
    pub const INPUT_HELD: Status = Status(1);
    /// The provider returned an invalid mode; the last valid mode was used.
    pub const MODES_HELD: Status = Status(2);
    /// A delay exceeded the delay-line capacity and was clamped to it.
    pub const DELAY_CLAMPED: Status = Status(4);
    /// No valid mode has been seen yet for some filter; it passed its input through unshaped.
    pub const UNSHAPED: Status = Status(8);
    /// Input or output slice of the wrong length: nothing was computed.
    pub const BAD_LENGTH: Status = Status(16);
    /// A mode's damping ratio exceeded the range of the shaper's published approximation
    /// ([`crate::shaping::shapers::ShaperKind::max_zeta`]); the shaper was designed at that limit.
    pub const ZETA_CLAMPED: Status = Status(32);
    /// A mode's natural frequency is at or above the Nyquist frequency of the control rate
    /// (`ω_n >= π/dt_s`): the mode cannot be represented at this rate, so shaping cannot
    /// cancel it. The shaper is still designed for the mode as given (its impulses then lie
    /// within one sample: a sub-sample smoothing that changes the reference by little); the
    /// flag says that the mode is out of reach.
    pub const MODE_ABOVE_NYQUIST: Status = Status(64);
    /// A mode changed faster than a slowly varying mode can
    /// ([`crate::tv_shaper::MAX_LN_WN_RATE_PER_S`], [`crate::tv_shaper::MAX_ZETA_RATE_PER_S`]):
    /// the provider's mode jumped (a map that switched eigenmodes, a callback that switched
    /// modes) and the filter approached it at that limit instead, so that the shaped
    /// reference gets no step.
    pub const MODE_SLEW_LIMITED: Status = Status(128);

    /// Every flag with its name: the one list the bindings and `tvist.h` are checked against.
    /// Flag `k` of this list is bit `1 << k`.
    pub const FLAGS: [(&'static str, Status); N_STATUS_FLAGS] = [
        ("INPUT_HELD", Status::INPUT_HELD),
        ("MODES_HELD", Status::MODES_HELD),
        ("DELAY_CLAMPED", Status::DELAY_CLAMPED),
        ("UNSHAPED", Status::UNSHAPED),
        ("BAD_LENGTH", Status::BAD_LENGTH),
        ("ZETA_CLAMPED", Status::ZETA_CLAMPED),
        ("MODE_ABOVE_NYQUIST", Status::MODE_ABOVE_NYQUIST),
        ("MODE_SLEW_LIMITED", Status::MODE_SLEW_LIMITED),
    ];

    /// True if every bit of `flag` is set.
    #[inline]
    pub fn contains(self, flag: Status) -> bool {
        self.0 & flag.0 == flag.0 && flag.0 != 0
    }

    /// True for a clean cycle.
    #[inline]
    pub fn is_ok(self) -> bool {
        self.0 == 0
    }
}

/// Number of status flags ([`Status::FLAGS`]).
pub const N_STATUS_FLAGS: usize = 8;

/// How many cycles reported each status flag: `counts()[k]` counts flag `Status::FLAGS[k]`.
/// Allocation-free; counts saturate at `u64::MAX`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct StatusCounter {
    counts: [u64; N_STATUS_FLAGS],
}

impl StatusCounter {
    /// Counts every flag set in `status` once.
    #[inline]
    pub fn add(&mut self, status: Status) {
        for (count, (_, flag)) in self.counts.iter_mut().zip(Status::FLAGS) {
            *count = count.saturating_add(u64::from(status.contains(flag)));
        }
    }

    /// The count of every flag, in the order of [`Status::FLAGS`].
    pub fn counts(&self) -> &[u64; N_STATUS_FLAGS] {
        &self.counts
    }

    /// The count of one flag (0 for a value that is not a single flag).
    pub fn count(&self, flag: Status) -> u64 {
        Status::FLAGS
            .iter()
            .position(|&(_, f)| f == flag)
            .map_or(0, |k| self.counts[k])
    }

    /// `(flag name, count)` pairs in the order of [`Status::FLAGS`].
    pub fn named(&self) -> impl Iterator<Item = (&'static str, u64)> + '_ {
        Status::FLAGS
            .iter()
            .zip(&self.counts)
            .map(|(&(name, _), &count)| (name, count))
    }

    /// Back to zero.
    pub fn clear(&mut self) {
        self.counts = [0; N_STATUS_FLAGS];
    }
}

impl core::ops::BitOr for Status {
    type Output = Status;
    #[inline]
    fn bitor(self, rhs: Status) -> Status {
        Status(self.0 | rhs.0)
    }
}

impl core::ops::BitOrAssign for Status {
    #[inline]
    fn bitor_assign(&mut self, rhs: Status) {
        self.0 |= rhs.0;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn flags_are_the_distinct_bits_in_order() {
        for (k, (_, flag)) in Status::FLAGS.iter().enumerate() {
            assert_eq!(flag.0, 1 << k);
        }
    }

    #[test]
    fn the_counter_counts_each_flag_of_a_status() {
        let mut c = StatusCounter::default();
        c.add(Status::INPUT_HELD | Status::MODE_ABOVE_NYQUIST);
        c.add(Status::INPUT_HELD);
        c.add(Status::OK);
        assert_eq!(c.count(Status::INPUT_HELD), 2);
        assert_eq!(c.count(Status::MODE_ABOVE_NYQUIST), 1);
        assert_eq!(c.count(Status::MODES_HELD), 0);
        assert_eq!(c.counts().iter().sum::<u64>(), 3);
    }
}
