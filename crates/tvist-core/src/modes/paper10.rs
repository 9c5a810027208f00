//! The published ten-coefficient dynamic map (paper eqs. 42–51): modes from joint inertias.

pub mod dynamic_map;
pub mod joint_inertia_law;
