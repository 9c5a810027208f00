//! tvist-core: real-time, allocation-free time-varying input shaping for robot arms.
//!
//! - [`shaping`]: one mode at a time. [`shaping::shapers`]: the shaper library (ZV … 3-hump
//!   EI, custom sets, convolution); [`shaping::ei`]: the extra-insensitive shaper designed
//!   exactly for a damped mode; [`shaping::prv`]: percent residual vibration of any impulse
//!   set; [`shaping::delay_line`]: circular buffer with fractional-delay (Lagrange) reads;
//!   [`shaping::mode_filter`]: the single-mode time-varying filter (eq. 7);
//!   [`shaping::ztdis`]: zero-time-delay shaping: time scales and the modified-ZTDIS
//!   compensator.
//! - [`tv_shaper`]: the multi-mode cascade driven by a [`Dynamics`] provider.
//! - [`robot`]: serial revolute chains from DH parameters or URDF placements: flange pose,
//!   Jacobian, joint-space inertia (composite rigid body) and gravity torques, allocation-free
//!   per call; bending links as hinges.
//! - [`modes`]: where the modes come from. [`modes::dynamics`]: the provider trait and
//!   constant modes; [`modes::provider`]: every built-in provider in one type, for the
//!   bindings; [`modes::robot_law`]: the provider that evaluates the robot and a mode law
//!   every cycle; [`modes::paper10`]: the ten-coefficient dynamic map from joint-axis
//!   inertias (eqs. 42–51); [`modes::modal`]: modes from the mass matrix and joint
//!   flexibility (the damped eigenproblem).
//! - [`math`]: symmetric eigenproblems (Jacobi) and fast `sin`/`cos` for the robot and maps.
//! - `files` (feature `json`): the UR e-series parameter file (`data/`), embedded and parsed
//!   once, and the map file format: parse, validate, write.
//! - [`limits`]: setup limits shared by every binding (channels, delay-line memory).
//! - [`error`]: setup errors and per-step status codes.
//!
//! Conventions: SI units with the unit in the name (`dt_s`, `wn_rad_s`); block data is
//! row-major `(n_samples, n_dof)`. Setup returns `Result<_, Error>`; per-step calls return a
//! [`Status`] and never allocate, lock or panic.

pub mod error;
#[cfg(feature = "json")]
pub mod files;
pub mod limits;
pub mod math;
pub mod modes;
pub mod robot;
pub mod shaping;
pub mod tv_shaper;

pub use error::{Error, Status, StatusCounter};
pub use modes::dynamics::{ConstantModes, Dynamics};
pub use modes::modal::mass_matrix_law::ModalDynamics;
pub use modes::modal::modal_map::{
    FlexJoint, LinkHinge, LoadLaw, ModalMap, ModeTrack, ShapedModes,
};
pub use modes::paper10::dynamic_map::{DynamicMap, InertiaRange, MapCoefficients, ModeMap};
pub use modes::paper10::joint_inertia_law::MapDynamics;
pub use modes::provider::{NoCallback, Provider};
pub use modes::robot_law::{ModeLaw, RobotModes};
pub use robot::chain::{Chain, DhJoint};
pub use robot::link_hinges::{split_link, LinkSegment};
pub use robot::model::Robot;
pub use robot::placement::{JointPlacement, Origin};
pub use robot::rigid_body::RigidBody;
pub use shaping::delay_line::{DelayLine, Interpolation};
pub use shaping::mode_filter::ModeFilter;
pub use shaping::prv::prv;
pub use shaping::shaper_names::SHAPER_NAMES;
pub use shaping::shapers::{ImpulseArray, Impulses, Mode, ShaperKind};
pub use shaping::ztdis::{Compensator, Discretization};
pub use tv_shaper::{TvShaper, TvShaperConfig};
