//! What the Python classes of the two robot-driven providers (`MapDynamics`, `ModalDynamics`)
//! share: construction, per-pose evaluation and the delay-sizing bounds of a
//! [`core::RobotModes`], whatever its mode law, and their methods ([`robot_modes_class`]).

use numpy::PyReadonlyArray1;
use pyo3::prelude::*;
use tvist_core as core;
use tvist_core::{Dynamics, Mode, ModeLaw, RobotModes};

use crate::convert::{check_len, value_error};

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
    // At `q` alone: nothing carried over from an earlier call (a modal map's branches).
    provider.restart();
    provider.modes(q, &mut out);
    Ok(pairs(&out))
}

/// `(wn_rad_s, zeta)` pairs.
pub fn pairs(modes: &[Mode]) -> Vec<(f64, f64)> {
    modes.iter().map(|m| (m.wn_rad_s, m.zeta)).collect()
}

/// The methods of a provider class `$class` (a `#[pyclass]` with `inner: RobotModes<_>`)
/// whose constructor takes `(robot, $map_arg: $map_class, allow_other_robot=False)`.
macro_rules! robot_modes_class {
    ($class:ident, $map_arg:ident, $map_class:ty) => {
        #[pymethods]
        impl $class {
            /// `allow_other_robot`: accept a map identified on another robot (research use).
            #[new]
            #[pyo3(signature = (robot, $map_arg, allow_other_robot=false))]
            fn new(
                robot: PyRef<'_, PyRobot>,
                $map_arg: PyRef<'_, $map_class>,
                allow_other_robot: bool,
            ) -> PyResult<Self> {
                let (robot, map) = (robot.inner.clone(), $map_arg.inner.clone());
                let inner = $crate::robot_law::new_provider(robot, map, allow_other_robot)?;
                Ok($class { inner })
            }

            /// Modes [(wn_rad_s, zeta), ...] at configuration q alone (invalid ones as NaN).
            fn modes(&mut self, q: numpy::PyReadonlyArray1<'_, f64>) -> PyResult<Vec<(f64, f64)>> {
                $crate::robot_law::modes_at(&mut self.inner, q)
            }

            /// Per-mode (wn_rad_s, zeta) bounds used to size the delay lines.
            #[getter]
            fn slowest_modes(&self) -> Vec<(f64, f64)> {
                $crate::robot_law::pairs(self.inner.slowest_modes())
            }

            /// Number of configurations checked at construction.
            #[classattr]
            fn validation_poses() -> usize {
                tvist_core::modes::robot_law::VALIDATION_POSES
            }

            #[getter]
            fn n_dof(&self) -> usize {
                self.inner.robot().n_dof()
            }

            #[getter]
            fn n_modes(&self) -> usize {
                tvist_core::Dynamics::n_modes(&self.inner)
            }
        }
    };
}
pub(crate) use robot_modes_class;
