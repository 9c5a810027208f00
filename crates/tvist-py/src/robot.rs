//! Bindings of the robot model, the dynamic map and the map-driven dynamics provider.

use numpy::{PyArrayDyn, PyReadonlyArray1, PyReadonlyArray2, PyUntypedArrayMethods};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use tvist_core as core;
use tvist_core::{Dynamics, Mode, Status};

use crate::convert::{self, rows, value_error};

fn check_len(what: &str, got: usize, expected: usize) -> PyResult<()> {
    if got == expected {
        Ok(())
    } else {
        Err(PyValueError::new_err(format!(
            "{what} has {got} values, expected {expected}"
        )))
    }
}

fn six(values: &[f64]) -> [f64; 6] {
    let mut out = [0.0; 6];
    out.copy_from_slice(&values[..6]);
    out
}

/// Serial revolute arm (standard DH) with link masses and a payload.
#[pyclass(name = "Robot", module = "tvist._core")]
#[derive(Clone)]
pub struct PyRobot {
    pub inner: core::Robot,
}

impl PyRobot {
    /// Runs `f` on every row of `q` (n_samples, n_dof), writing `width` values per row.
    fn many(
        &mut self,
        q: &PyReadonlyArray2<'_, f64>,
        width: usize,
        mut f: impl FnMut(&mut core::Robot, &[f64], &mut [f64]) -> Status,
    ) -> PyResult<(usize, Vec<f64>)> {
        let n = self.inner.n_dof();
        let (rows_n, data) = rows(q, n, "Q")?;
        let mut out = vec![0.0; rows_n * width];
        if width > 0 {
            for (x, y) in data.chunks_exact(n).zip(out.chunks_exact_mut(width)) {
                f(&mut self.inner, x, y);
            }
        }
        Ok((rows_n, out))
    }
}

#[pymethods]
impl PyRobot {
    /// d, a, alpha: (n,); mass_kg: (n,); com_m: (n, 3) in DH frame i; inertia_kg_m2: (n, 6)
    /// [ixx, iyy, izz, ixy, ixz, iyz] about the COM; payload in the flange frame.
    #[new]
    #[pyo3(signature = (d_m, a_m, alpha_rad, mass_kg, com_m, inertia_kg_m2, payload_mass_kg=0.0, payload_com_m=None, payload_inertia_kg_m2=None))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        d_m: Vec<f64>,
        a_m: Vec<f64>,
        alpha_rad: Vec<f64>,
        mass_kg: Vec<f64>,
        com_m: PyReadonlyArray2<'_, f64>,
        inertia_kg_m2: PyReadonlyArray2<'_, f64>,
        payload_mass_kg: f64,
        payload_com_m: Option<Vec<f64>>,
        payload_inertia_kg_m2: Option<Vec<f64>>,
    ) -> PyResult<Self> {
        let n = d_m.len();
        check_len("a_m", a_m.len(), n)?;
        check_len("alpha_rad", alpha_rad.len(), n)?;
        check_len("mass_kg", mass_kg.len(), n)?;
        let (com_rows, com) = rows(&com_m, 3, "com_m")?;
        check_len("com_m rows", com_rows, n)?;
        let (inertia_rows, inertia) = rows(&inertia_kg_m2, 6, "inertia_kg_m2")?;
        check_len("inertia_kg_m2 rows", inertia_rows, n)?;
        let joints = (0..n)
            .map(|i| core::DhJoint::new(d_m[i], a_m[i], alpha_rad[i]))
            .collect();
        let links = (0..n)
            .map(|i| core::RigidBody {
                mass_kg: mass_kg[i],
                com_m: [com[3 * i], com[3 * i + 1], com[3 * i + 2]],
                inertia_kg_m2: six(&inertia[6 * i..6 * i + 6]),
            })
            .collect();
        let pcom = payload_com_m.unwrap_or_else(|| vec![0.0; 3]);
        check_len("payload_com_m", pcom.len(), 3)?;
        let pinertia = match payload_inertia_kg_m2 {
            Some(v) => {
                check_len("payload_inertia_kg_m2", v.len(), 6)?;
                six(&v)
            }
            None => [0.0; 6],
        };
        let payload = core::RigidBody {
            mass_kg: payload_mass_kg,
            com_m: [pcom[0], pcom[1], pcom[2]],
            inertia_kg_m2: pinertia,
        };
        Ok(PyRobot {
            inner: core::Robot::new(joints, links, payload).map_err(value_error)?,
        })
    }

    #[getter]
    fn n_dof(&self) -> usize {
        self.inner.n_dof()
    }

    /// joint_inertia for every row of Q (n_samples, n_dof).
    fn joint_inertia_many<'py>(
        &mut self,
        py: Python<'py>,
        q: PyReadonlyArray2<'py, f64>,
    ) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
        let n = self.inner.n_dof();
        let (m, out) = self.many(&q, n, |r, x, y| r.joint_inertia(x, y))?;
        convert::array(py, &[m, n], out)
    }

    /// mass_matrix for every row of Q: (n_samples, n, n).
    fn mass_matrix_many<'py>(
        &mut self,
        py: Python<'py>,
        q: PyReadonlyArray2<'py, f64>,
    ) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
        let n = self.inner.n_dof();
        let (m, out) = self.many(&q, n * n, |r, x, y| r.mass_matrix(x, y))?;
        convert::array(py, &[m, n, n], out)
    }

    /// flange_pose for every row of Q: (n_samples, 4, 4).
    fn flange_pose_many<'py>(
        &mut self,
        py: Python<'py>,
        q: PyReadonlyArray2<'py, f64>,
    ) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
        let (m, out) = self.many(&q, 16, |r, x, y| {
            let mut t = [0.0; 16];
            let s = r.flange_pose(x, &mut t);
            y.copy_from_slice(&t);
            s
        })?;
        convert::array(py, &[m, 4, 4], out)
    }

    /// jacobian for every row of Q: (n_samples, 6, n).
    fn jacobian_many<'py>(
        &mut self,
        py: Python<'py>,
        q: PyReadonlyArray2<'py, f64>,
    ) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
        let n = self.inner.n_dof();
        let (m, out) = self.many(&q, 6 * n, |r, x, y| r.jacobian(x, y))?;
        convert::array(py, &[m, 6, n], out)
    }

    /// gravity_torque for every row of Q (n_samples, n_dof).
    fn gravity_torque_many<'py>(
        &mut self,
        py: Python<'py>,
        q: PyReadonlyArray2<'py, f64>,
    ) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
        let n = self.inner.n_dof();
        let (m, out) = self.many(&q, n, |r, x, y| r.gravity_torque(x, y))?;
        convert::array(py, &[m, n], out)
    }

    /// Upper bound of each J_i over all configurations (kg m^2).
    fn joint_inertia_upper_bound(&self) -> Vec<f64> {
        self.inner.joint_inertia_upper_bound()
    }
}

/// Fields of one mode map, in the order the constructor takes them.
pub const MODE_MAP_FIELDS: [&str; 12] = [
    "k_0",
    "k_j",
    "k_g",
    "k_p",
    "c_0",
    "c_1",
    "c_2",
    "c_tau",
    "frequency_joint",
    "damping_joint",
    "damping_gain_exponent",
    "frequency_gain_exponent",
];

/// Optional fields of one mode map: the `[min, max]` inertias (kg m²) of the frequency and
/// the damping joint the map was identified on; missing or `None` is unbounded.
pub const MODE_MAP_RANGE_FIELDS: [&str; 2] = [
    "frequency_inertia_range_kg_m2",
    "damping_inertia_range_kg_m2",
];

fn range_from_dict(
    d: &Bound<'_, pyo3::types::PyDict>,
    index: usize,
    key: &str,
) -> PyResult<Option<core::InertiaRange>> {
    let Some(item) = d.get_item(key)? else {
        return Ok(None);
    };
    if item.is_none() {
        return Ok(None);
    }
    let bounds = item.extract::<Vec<f64>>().ok().filter(|b| b.len() == 2);
    let Some(bounds) = bounds else {
        return Err(PyValueError::new_err(format!(
            "mode {index}: field {key:?} must be [min, max] in kg m² or None"
        )));
    };
    core::InertiaRange::new(bounds[0], bounds[1])
        .map(Some)
        .map_err(|e| PyValueError::new_err(format!("mode {index}: field {key:?}: {e}")))
}

fn range_to_py(range: Option<core::InertiaRange>) -> Option<Vec<f64>> {
    range.map(|r| vec![r.min_kg_m2(), r.max_kg_m2()])
}

fn mode_map_from_dict(d: &Bound<'_, pyo3::types::PyDict>, index: usize) -> PyResult<core::ModeMap> {
    let get_f = |key: &str| -> PyResult<f64> {
        let item = d
            .get_item(key)?
            .ok_or_else(|| PyValueError::new_err(format!("mode {index}: missing field {key:?}")))?;
        item.extract::<f64>().map_err(|_| {
            PyValueError::new_err(format!("mode {index}: field {key:?} must be a number"))
        })
    };
    let get_u = |key: &str| -> PyResult<usize> {
        let item = d
            .get_item(key)?
            .ok_or_else(|| PyValueError::new_err(format!("mode {index}: missing field {key:?}")))?;
        item.extract::<usize>().map_err(|_| {
            PyValueError::new_err(format!(
                "mode {index}: field {key:?} must be a non-negative integer"
            ))
        })
    };
    Ok(core::ModeMap {
        coefficients: core::MapCoefficients {
            k_0: get_f("k_0")?,
            k_j: get_f("k_j")?,
            k_g: get_f("k_g")?,
            k_p: get_f("k_p")?,
            c_0: get_f("c_0")?,
            c_1: get_f("c_1")?,
            c_2: get_f("c_2")?,
            c_tau: get_f("c_tau")?,
        },
        frequency_joint: get_u("frequency_joint")?,
        damping_joint: get_u("damping_joint")?,
        damping_gain_exponent: get_f("damping_gain_exponent")?,
        frequency_gain_exponent: get_f("frequency_gain_exponent")?,
        frequency_range: range_from_dict(d, index, MODE_MAP_RANGE_FIELDS[0])?,
        damping_range: range_from_dict(d, index, MODE_MAP_RANGE_FIELDS[1])?,
    })
}

/// Dynamic map (eqs. 42-51): one dict of coefficients per mode, in cascade order. Optional
/// inertia ranges per mode (MODE_MAP_RANGE_FIELDS) clamp the inertias the mode reads.
#[pyclass(name = "DynamicMap", module = "tvist._core", frozen)]
#[derive(Clone)]
pub struct PyDynamicMap {
    pub inner: core::DynamicMap,
}

#[pymethods]
impl PyDynamicMap {
    #[new]
    fn new(modes: Vec<Bound<'_, pyo3::types::PyDict>>) -> PyResult<Self> {
        let maps = modes
            .iter()
            .enumerate()
            .map(|(i, d)| mode_map_from_dict(d, i))
            .collect::<PyResult<Vec<_>>>()?;
        Ok(PyDynamicMap {
            inner: core::DynamicMap::new(maps).map_err(value_error)?,
        })
    }

    /// The UR5e map of the paper (Tables 1-2, eqs. 47-48 and 50-51).
    #[staticmethod]
    fn paper_ur5e() -> Self {
        PyDynamicMap {
            inner: core::DynamicMap::paper_ur5e(),
        }
    }

    /// Modes [(wn_rad_s, zeta), ...] from joint inertias (and gravity torques when k_g != 0),
    /// each inertia clamped into its mode's range. Invalid modes come back as NaN.
    #[pyo3(signature = (inertia_kg_m2, gravity_torque_nm=None))]
    fn modes_from_inertia(
        &self,
        inertia_kg_m2: Vec<f64>,
        gravity_torque_nm: Option<Vec<f64>>,
    ) -> PyResult<Vec<(f64, f64)>> {
        let need = self.inner.required_joints();
        if inertia_kg_m2.len() < need {
            return Err(PyValueError::new_err(format!(
                "the map reads {need} joint inertias, got {}",
                inertia_kg_m2.len()
            )));
        }
        let tau = gravity_torque_nm.unwrap_or_default();
        if self.inner.uses_gravity() && tau.len() < need {
            return Err(PyValueError::new_err(format!(
                "the map uses gravity torques (k_g != 0): pass {need} of them"
            )));
        }
        let mut out = vec![Mode::new(0.0, 0.0); self.inner.n_modes()];
        self.inner
            .modes_from_inertia(&inertia_kg_m2, &tau, &mut out);
        Ok(out.iter().map(|m| (m.wn_rad_s, m.zeta)).collect())
    }

    /// modes_from_inertia for every row: inertia (n_poses, n_j), gravity torques likewise (or
    /// None when the map has no gravity term) -> (n_poses, n_modes, 2) of (wn_rad_s, zeta).
    #[pyo3(signature = (inertia_kg_m2, gravity_torque_nm=None))]
    fn modes_from_inertia_many<'py>(
        &self,
        py: Python<'py>,
        inertia_kg_m2: PyReadonlyArray2<'py, f64>,
        gravity_torque_nm: Option<PyReadonlyArray2<'py, f64>>,
    ) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
        let cols = inertia_kg_m2.shape()[1];
        let need = self.inner.required_joints();
        if cols < need {
            return Err(PyValueError::new_err(format!(
                "the map reads {need} joint inertias per row, got {cols}"
            )));
        }
        let (n, j) = rows(&inertia_kg_m2, cols, "inertia_kg_m2")?;
        let tau = match gravity_torque_nm {
            Some(t) => {
                let (tn, tau) = rows(&t, cols, "gravity_torque_nm")?;
                check_len("gravity_torque_nm rows", tn, n)?;
                tau
            }
            None if self.inner.uses_gravity() => {
                return Err(PyValueError::new_err(format!(
                    "the map uses gravity torques (k_g != 0): pass {need} per row"
                )));
            }
            None => Vec::new(),
        };
        let m = self.inner.n_modes();
        let mut modes = vec![Mode::new(0.0, 0.0); m];
        let mut out = vec![0.0; n * m * 2];
        for (r, chunk) in out.chunks_exact_mut(2 * m).enumerate() {
            let tau_row = if tau.is_empty() {
                &[][..]
            } else {
                &tau[r * cols..(r + 1) * cols]
            };
            self.inner
                .modes_from_inertia(&j[r * cols..(r + 1) * cols], tau_row, &mut modes);
            for (pair, mode) in chunk.chunks_exact_mut(2).zip(&modes) {
                pair[0] = mode.wn_rad_s;
                pair[1] = mode.zeta;
            }
        }
        convert::array(py, &[n, m, 2], out)
    }

    /// The coefficients of every mode as dicts (see the constructor), ranges as [min, max]
    /// or None.
    #[getter]
    fn modes<'py>(&self, py: Python<'py>) -> PyResult<Vec<Bound<'py, pyo3::types::PyDict>>> {
        self.inner
            .mode_maps()
            .iter()
            .map(|m| {
                let d = pyo3::types::PyDict::new(py);
                let c = &m.coefficients;
                for (k, v) in [
                    ("k_0", c.k_0),
                    ("k_j", c.k_j),
                    ("k_g", c.k_g),
                    ("k_p", c.k_p),
                    ("c_0", c.c_0),
                    ("c_1", c.c_1),
                    ("c_2", c.c_2),
                    ("c_tau", c.c_tau),
                ] {
                    d.set_item(k, v)?;
                }
                d.set_item("frequency_joint", m.frequency_joint)?;
                d.set_item("damping_joint", m.damping_joint)?;
                d.set_item("damping_gain_exponent", m.damping_gain_exponent)?;
                d.set_item("frequency_gain_exponent", m.frequency_gain_exponent)?;
                d.set_item(MODE_MAP_RANGE_FIELDS[0], range_to_py(m.frequency_range))?;
                d.set_item(MODE_MAP_RANGE_FIELDS[1], range_to_py(m.damping_range))?;
                Ok(d)
            })
            .collect()
    }

    #[getter]
    fn n_modes(&self) -> usize {
        self.inner.n_modes()
    }

    /// Number of joint inertias the map reads.
    #[getter]
    fn required_joints(&self) -> usize {
        self.inner.required_joints()
    }

    #[getter]
    fn uses_gravity(&self) -> bool {
        self.inner.uses_gravity()
    }
}

/// Provider for TvShaper: robot inertia at the previous shaped output -> dynamic map -> modes.
#[pyclass(name = "MapDynamics", module = "tvist._core", subclass)]
pub struct PyMapDynamics {
    pub inner: core::MapDynamics,
}

#[pymethods]
impl PyMapDynamics {
    #[new]
    fn new(robot: PyRef<'_, PyRobot>, dynmap: PyRef<'_, PyDynamicMap>) -> PyResult<Self> {
        let inner = core::MapDynamics::new(robot.inner.clone(), dynmap.inner.clone())
            .map_err(value_error)?;
        Ok(PyMapDynamics { inner })
    }

    /// Modes [(wn_rad_s, zeta), ...] at configuration q (invalid ones as NaN).
    fn modes(&mut self, q: PyReadonlyArray1<'_, f64>) -> PyResult<Vec<(f64, f64)>> {
        let q = q.as_slice()?;
        check_len("q", q.len(), self.inner.robot().n_dof())?;
        let mut out = vec![Mode::new(0.0, 0.0); self.inner.n_modes()];
        self.inner.modes(q, &mut out);
        Ok(out.iter().map(|m| (m.wn_rad_s, m.zeta)).collect())
    }

    /// Per-mode (wn_rad_s, zeta) bounds used to size the delay lines.
    #[getter]
    fn slowest_modes(&self) -> Vec<(f64, f64)> {
        self.inner
            .slowest_modes()
            .iter()
            .map(|m| (m.wn_rad_s, m.zeta))
            .collect()
    }

    /// Number of configurations checked at construction.
    #[classattr]
    fn validation_poses() -> usize {
        core::map_dynamics::VALIDATION_POSES
    }

    #[getter]
    fn n_dof(&self) -> usize {
        self.inner.robot().n_dof()
    }

    #[getter]
    fn n_modes(&self) -> usize {
        self.inner.n_modes()
    }
}

/// Registers the classes of this module.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyRobot>()?;
    m.add_class::<PyDynamicMap>()?;
    m.add_class::<PyMapDynamics>()?;
    m.add("MODE_MAP_FIELDS", MODE_MAP_FIELDS.to_vec())?;
    m.add("MODE_MAP_RANGE_FIELDS", MODE_MAP_RANGE_FIELDS.to_vec())?;
    Ok(())
}
