//! Small numerical kernels shared by the robot model and the mode maps: allocation-free,
//! fixed-size, no panics.

pub(crate) mod mat3;
pub mod sym_eigen;
pub mod trig;
