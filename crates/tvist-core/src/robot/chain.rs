//! How the joints of an arm are described: standard DH parameters, or joints placed as URDF
//! places them ([`JointPlacement`]).

use crate::robot::placement::{JointPlacement, Origin};

/// Standard DH parameters of one revolute joint (`θ = q`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DhJoint {
    pub d_m: f64,
    pub a_m: f64,
    pub alpha_rad: f64,
}

impl DhJoint {
    pub const fn new(d_m: f64, a_m: f64, alpha_rad: f64) -> Self {
        DhJoint {
            d_m,
            a_m,
            alpha_rad,
        }
    }
}

/// How the joints of an arm are placed, with the frames its links are given in.
#[derive(Debug, Clone, PartialEq)]
pub enum Chain {
    /// Standard DH: link `i` in DH frame `i + 1`, the payload in DH frame `n`.
    Dh(Vec<DhJoint>),
    /// URDF placement: link `i` in the frame of the link after joint `i` (its URDF link
    /// frame), the payload in the flange frame, whose origin in the last link's frame is
    /// `flange`.
    Urdf {
        joints: Vec<JointPlacement>,
        flange: Origin,
    },
}

impl Chain {
    pub fn n_dof(&self) -> usize {
        match self {
            Chain::Dh(j) => j.len(),
            Chain::Urdf { joints, .. } => joints.len(),
        }
    }
}
