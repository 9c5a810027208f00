//! Robots for the integration tests, read from the project's one robot-data file.

#![allow(dead_code)]

use tvist_core::{DhJoint, RigidBody, Robot};

/// The robot-parameter file shared with the Python package (one source of truth).
pub const UR_E_SERIES_JSON: &str = include_str!("../../../../python/tvist/robots/ur_e_series.json");

fn numbers(value: &serde_json::Value) -> Vec<f64> {
    value
        .as_array()
        .expect("array")
        .iter()
        .map(|v| v.as_f64().expect("number"))
        .collect()
}

/// Joints and links of robot `name` from the JSON file.
pub fn ur_chain(name: &str) -> (Vec<DhJoint>, Vec<RigidBody>) {
    let doc: serde_json::Value = serde_json::from_str(UR_E_SERIES_JSON).expect("valid JSON");
    let r = &doc["robots"][name];
    let (d, a, alpha) = (
        numbers(&r["dh"]["d"]),
        numbers(&r["dh"]["a"]),
        numbers(&r["dh"]["alpha"]),
    );
    let mass = numbers(&r["mass_kg"]);
    let com: Vec<Vec<f64>> = r["com_m"]
        .as_array()
        .expect("com rows")
        .iter()
        .map(numbers)
        .collect();
    let inertia: Vec<Vec<f64>> = r["inertia_kg_m2"]
        .as_array()
        .expect("inertia rows")
        .iter()
        .map(numbers)
        .collect();
    let joints = (0..d.len())
        .map(|i| DhJoint::new(d[i], a[i], alpha[i]))
        .collect();
    let links = (0..d.len())
        .map(|i| RigidBody {
            mass_kg: mass[i],
            com_m: [com[i][0], com[i][1], com[i][2]],
            inertia_kg_m2: [
                inertia[i][0],
                inertia[i][1],
                inertia[i][2],
                inertia[i][3],
                inertia[i][4],
                inertia[i][5],
            ],
        })
        .collect();
    (joints, links)
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
