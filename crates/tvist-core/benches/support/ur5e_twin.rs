//! The UR5e twin's gear laws for the benchmarks: base, shoulder and elbow flexible, with
//! load-dependent stiffness and damping (so a modal map built on them needs gravity torques).

use tvist_core::{FlexJoint, LoadLaw};

/// The [`LoadLaw`] `at_zero + per_nm |L|_s + per_nm2 L²` of a joint's static load L (N m).
fn law(at_zero: f64, per_nm: f64, per_nm2: f64) -> LoadLaw {
    LoadLaw {
        at_zero,
        per_nm,
        per_nm2,
    }
}

/// Base (joint 0), shoulder (1) and elbow (2): stiffness in N m/rad, damping in N m s/rad;
/// the base's damping grows with the shoulder's load.
pub fn base_shoulder_elbow() -> Vec<FlexJoint> {
    vec![
        FlexJoint {
            joint: 0,
            stiffness_nm_per_rad: LoadLaw::constant(22_000.0),
            damping_nms_per_rad: law(5.0, 0.56, 0.0157),
            damping_load_joint: 1,
        },
        FlexJoint {
            joint: 1,
            stiffness_nm_per_rad: law(18_000.0, 0.0, 0.234),
            damping_nms_per_rad: law(60.0, 0.6, 0.0),
            damping_load_joint: 1,
        },
        FlexJoint {
            joint: 2,
            stiffness_nm_per_rad: law(120_000.0, 0.0, 1.56),
            damping_nms_per_rad: law(40.0, 0.4, 0.0),
            damping_load_joint: 2,
        },
    ]
}
