//! Serial revolute arms: how the joints are described and placed, the mass properties of
//! links and payload, the rigid-body model (flange pose, Jacobian, joint-space inertia,
//! gravity torques) and bending links as hinges.

pub mod chain;
mod frame_step;
mod inertia_pass;
pub mod link_hinges;
mod mass_moments;
pub mod model;
pub mod placement;
pub mod rigid_body;
