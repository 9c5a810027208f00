//! What the Python classes of the two robot-driven providers (`MapDynamics`, `ModalDynamics`)
//! share: construction, per-pose evaluation and the delay-sizing bounds of a
//! [`core::RobotModes`], whatever its mode law.

use numpy::PyReadonlyArray1;
use pyo3::prelude::*;
use tvist_core as core;
use tvist_core::{Dynamics, Mode, ModeLaw, RobotModes};

use crate::convert::value_error;
use crate::robot::check_len;

/// The provider of `robot` and `law`; `allow_other_robot` accepts a law identified on another
/// robot (research use). Setup errors become `ValueError`.
pub fn new_provider<L: ModeLaw>(
    robot: core::Robot,
    law: L,
    allow_other_robot: bool,
) -> PyResult<RobotModes<L>> {
    if allow_other_robot {
        RobotModes::new_allowing_other_robot(robot, law)
    } else {
        RobotModes::new(robot, law)
    }
    .map_err(value_error)
}

/// Modes `[(wn_rad_s, zeta), ...]` at configuration `q` (invalid ones as NaN).
pub fn modes_at<L: ModeLaw>(
    provider: &mut RobotModes<L>,
    q: PyReadonlyArray1<'_, f64>,
) -> PyResult<Vec<(f64, f64)>> {
    let q = q.as_slice()?;
    check_len("q", q.len(), provider.robot().n_dof())?;
    let mut out = vec![Mode::new(0.0, 0.0); provider.n_modes()];
    provider.modes(q, &mut out);
    Ok(pairs(&out))
}

/// `(wn_rad_s, zeta)` pairs.
pub fn pairs(modes: &[Mode]) -> Vec<(f64, f64)> {
    modes.iter().map(|m| (m.wn_rad_s, m.zeta)).collect()
}
