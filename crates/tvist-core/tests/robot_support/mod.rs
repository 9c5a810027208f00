//! Robots for the integration tests, read from the project's one robot-data file.

#![allow(dead_code)]

use tvist_core::{DhJoint, RigidBody, Robot};

/// Joints and links of robot `name` from the project's robot-data file.
pub fn ur_chain(name: &str) -> (Vec<DhJoint>, Vec<RigidBody>) {
    tvist_core::robot_data::robot_chain(tvist_core::robot_data::UR_E_SERIES_JSON, name)
        .expect("robot data")
}

/// UR robot `name` with a point payload of `payload_kg` 5 cm beyond the flange (flange z).
pub fn ur_robot(name: &str, payload_kg: f64) -> Robot {
    let (joints, links) = ur_chain(name);
    Robot::new(
        joints,
        links,
        RigidBody::point(payload_kg, [0.0, 0.0, 0.05]),
    )
    .expect("valid robot")
}

/// Deterministic pseudo-random numbers in [0, 1) (xorshift64*), for reproducible poses.
pub struct Rng(pub u64);

impl Rng {
    pub fn next_f64(&mut self) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        (self.0.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 11) as f64 / (1u64 << 53) as f64
    }

    /// A pose with every angle uniform in [-pi, pi).
    pub fn pose(&mut self, n: usize) -> Vec<f64> {
        (0..n)
            .map(|_| std::f64::consts::PI * (2.0 * self.next_f64() - 1.0))
            .collect()
    }
}
