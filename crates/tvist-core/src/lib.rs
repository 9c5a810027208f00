//! tvist-core: real-time, allocation-free time-varying input shaping for robot arms.
//!
//! - [`shaper`]: the shaper library (ZV … 3-hump EI, custom sets, convolution).
//! - [`ei`]: the extra-insensitive shaper designed exactly for a damped mode.
//! - [`prv`](mod@prv): percent residual vibration of any impulse set.
//! - [`delay_line`]: circular buffer with fractional-delay (Lagrange) reads.
//! - [`tvist`]: the single-mode time-varying filter (eq. 7).
//! - [`multimode`]: the multi-mode cascade driven by a [`dynamics::Dynamics`] provider.
//! - [`robot`]: serial revolute chains from DH parameters: flange pose, Jacobian, joint-space
//!   inertia (composite rigid body) and gravity torques, allocation-free per call.
//! - [`dynmap`]: the dynamic map from joint-axis inertias to modes (eqs. 42–51).
//! - [`robot_modes`]: the provider that evaluates the robot and a mode law every cycle;
//!   [`map_dynamics`]: with the dynamic map (joint inertias).
//! - [`modal_map`]: modes from the mass matrix and joint flexibility (the damped eigenproblem:
//!   [`sym_eigen`] for the undamped modes, [`damped_modes`] for the exact damped ones);
//!   [`modal_dynamics`]: the provider with the modal map.
//! - `robot_data` (feature `json`): the UR e-series parameter file (`data/`), embedded and
//!   parsed once.
//! - `map_file` (feature `json`): the map file format: parse, validate, write.
//! - [`limits`]: setup limits shared by every binding (channels, delay-line memory).
//! - [`ztdis`]: zero-time-delay shaping: time scales and the modified-ZTDIS compensator.
//!
//! Conventions: SI units with the unit in the name (`dt_s`, `wn_rad_s`); block data is
//! row-major `(n_samples, n_dof)`. Setup returns `Result<_, Error>`; per-step calls return a
//! [`Status`] and never allocate, lock or panic.

pub mod damped_modes;
pub mod delay_line;
pub mod dynamics;
pub mod dynmap;
pub mod ei;
pub mod error;
mod held_input;
mod inertia_pass;
pub mod limits;
pub mod link_hinges;
pub mod map_dynamics;
#[cfg(feature = "json")]
pub mod map_file;
pub mod modal_dynamics;
pub mod modal_map;
pub mod multimode;
pub mod placement;
pub mod prv;
pub mod robot;
#[cfg(feature = "json")]
pub mod robot_data;
pub mod robot_modes;
pub mod shaper;
pub mod sym_eigen;
pub mod trig;
pub mod tvist;
pub mod ztdis;

pub use delay_line::{DelayLine, Interpolation};
pub use dynamics::{ConstantModes, Dynamics, NoCallback, Provider};
pub use dynmap::{DynamicMap, InertiaRange, MapCoefficients, ModeMap};
pub use error::{Error, Status, StatusCounter};
pub use link_hinges::{split_link, LinkSegment};
pub use map_dynamics::MapDynamics;
pub use modal_dynamics::ModalDynamics;
pub use modal_map::{FlexJoint, LinkHinge, LoadLaw, ModalMap, ModeTrack, ShapedModes};
pub use multimode::{TvShaper, TvShaperConfig};
pub use placement::{JointPlacement, Origin};
pub use prv::prv;
pub use robot::{Chain, DhJoint, RigidBody, Robot};
pub use robot_modes::{ModeLaw, RobotModes};
pub use shaper::{ImpulseArray, Impulses, Mode, ShaperKind, SHAPER_NAMES};
pub use tvist::ModeFilter;
pub use ztdis::{Compensator, Discretization};
