//! Setup errors and per-step status codes.
//!
//! Construction (`new`) validates everything and returns [`Error`]. The per-step path never
//! fails: it returns a [`Status`] whose bits say what was held or clamped in that cycle.

use core::fmt;

/// Everything that can go wrong while configuring a filter. Returned only at setup time.
#[derive(Debug, Clone, PartialEq)]
pub enum Error {
    /// A shaper name not in the registry ([`crate::shaper::SHAPER_NAMES`]).
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
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Error::UnknownShaper(name) => write!(
                f,
                "unknown shaper {name:?}; expected one of {:?}",
                crate::shaper::SHAPER_NAMES
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
    /// ([`crate::shaper::ShaperKind::max_zeta`]); the shaper was designed at that limit.
    pub const ZETA_CLAMPED: Status = Status(32);

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
