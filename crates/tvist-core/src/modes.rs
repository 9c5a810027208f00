//! Where a time-varying shaper gets its modes `(ω_n, ζ)` from each cycle: the [`Dynamics`]
//! provider trait, constant modes, and the two pose-dependent laws evaluated on a robot
//! ([`paper10`]: the published ten-coefficient map from joint inertias; [`modal`]: the modal
//! map from the mass matrix and joint flexibility).
//!
//! [`Dynamics`]: dynamics::Dynamics

pub mod dynamics;
pub mod modal;
pub mod paper10;
pub mod provider;
pub mod robot_law;
