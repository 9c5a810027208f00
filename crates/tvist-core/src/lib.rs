//! tvist-core: real-time, allocation-free time-varying input shaping for robot arms.
//!
//! - [`shaper`]: the shaper library (ZV … 3-hump EI, custom sets, convolution).
//! - [`prv`]: percent residual vibration of any impulse set.
//! - [`delay_line`]: circular buffer with fractional-delay (Lagrange) reads.
//! - [`tvist`]: the single-mode time-varying filter (eq. 7).
//! - [`multimode`]: the multi-mode cascade driven by a [`dynamics::Dynamics`] provider.
//!
//! Conventions: SI units with the unit in the name (`dt_s`, `wn_rad_s`); block data is
//! row-major `(n_samples, n_dof)`. Setup returns `Result<_, Error>`; per-step calls return a
//! [`Status`] and never allocate, lock or panic.

pub mod delay_line;
pub mod dynamics;
pub mod error;
pub mod multimode;
pub mod prv;
pub mod shaper;
pub mod tvist;

pub use delay_line::{DelayLine, Interpolation};
pub use dynamics::{ConstantModes, Dynamics};
pub use error::{Error, Status};
pub use multimode::{TvShaper, TvShaperConfig};
pub use prv::prv;
pub use shaper::{ImpulseArray, Impulses, Mode, ShaperKind, SHAPER_NAMES};
pub use tvist::ModeFilter;
