//! Bindings of the ten-coefficient dynamic map (paper eqs. 42-51), a trial mode of a fit,
//! and the provider that drives the map with the robot's joint inertias.

use numpy::{PyArrayDyn, PyReadonlyArray2, PyUntypedArrayMethods};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use tvist_core as core;
use tvist_core::Mode;

use crate::convert::{self, gravity_rows, rows, value_error};
use crate::json::{self, map_file_from, NonFinite};
use crate::robot::PyRobot;
use crate::robot_law;
use tvist_core::files::map_file::{self, MapFile, MapForm};
use tvist_core::files::paper10_doc;

fn paper10(file: MapFile) -> PyResult<core::DynamicMap> {
    match file.into_form() {
        MapForm::Paper10(map) => Ok(map),
        other => Err(PyValueError::new_err(format!(
            "kind: a {:?} map, not a {:?} map",
            other.kind(),
            map_file::KIND_PAPER10
        ))),
    }
}

/// A numpy array of doubles.
type NdArray<'py> = Bound<'py, PyArrayDyn<f64>>;

/// `(wn_rad_s, zeta)` arrays of one `paper10` mode (a dict as in a map file, checked for
/// form only) at every row of `inertia_kg_m2` (n_poses, n_j) and of `gravity_torque_nm`
/// (same shape, or None when k_g = 0). The physical rules of a map are not applied: a
/// fit evaluates trial coefficients this way (NaN where they give no mode).
#[pyfunction]
#[pyo3(signature = (mode, inertia_kg_m2, gravity_torque_nm=None))]
fn evaluate_trial_mode<'py>(
    py: Python<'py>,
    mode: &Bound<'py, PyAny>,
    inertia_kg_m2: PyReadonlyArray2<'py, f64>,
    gravity_torque_nm: Option<PyReadonlyArray2<'py, f64>>,
) -> PyResult<(NdArray<'py>, NdArray<'py>)> {
    let value = json::to_value(mode, "mode", NonFinite::Refuse)?;
    let mode = paper10_doc::mode_from(&value, "mode").map_err(value_error)?;
    let cols = inertia_kg_m2.shape()[1];
    if cols < mode.required_joints() {
        return Err(PyValueError::new_err(format!(
            "the mode reads {} joint inertias per row, got {cols}",
            mode.required_joints()
        )));
    }
    let (n, j) = rows(&inertia_kg_m2, cols, "inertia_kg_m2")?;
    let needed = mode
        .uses_gravity()
        .then_some("the mode uses gravity torques (k_g != 0)");
    // Without a gravity term no torque is read; a zero row per pose keeps the pairing below.
    let tau =
        gravity_rows(gravity_torque_nm, cols, n, needed)?.unwrap_or_else(|| vec![0.0; n * cols]);
    let (mut wn, mut zeta) = (Vec::with_capacity(n), Vec::with_capacity(n));
    for (j_row, tau_row) in j.chunks_exact(cols).zip(tau.chunks_exact(cols)) {
        let m = mode.evaluate(j_row, tau_row);
        wn.push(m.wn_rad_s);
        zeta.push(m.zeta);
    }
    Ok((
        convert::array(py, &[n], wn)?,
        convert::array(py, &[n], zeta)?,
    ))
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
    /// Modes as dicts (MODE_MAP_FIELDS, optional MODE_MAP_RANGE_FIELDS), validated as in a
    /// map file; `robot` names the robot the map was identified on.
    #[new]
    #[pyo3(signature = (modes, robot=None))]
    fn new(py: Python<'_>, modes: &Bound<'_, PyAny>, robot: Option<String>) -> PyResult<Self> {
        let doc = PyDict::new(py);
        doc.set_item("schema_version", map_file::SCHEMA_VERSION)?;
        doc.set_item("kind", map_file::KIND_PAPER10)?;
        let meta = PyDict::new(py);
        meta.set_item("robot", robot)?;
        doc.set_item("metadata", meta)?;
        doc.set_item("modes", modes)?;
        Ok(PyDynamicMap {
            inner: paper10(map_file_from(doc.as_any())?)?,
        })
    }

    /// The robot the map was identified on, or None.
    #[getter]
    fn robot(&self) -> Option<String> {
        self.inner.robot().map(str::to_owned)
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
        let needed = self
            .inner
            .uses_gravity()
            .then_some("the map uses gravity torques (k_g != 0)");
        let tau = gravity_rows(gravity_torque_nm, cols, n, needed)?.unwrap_or_default();
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
    fn modes<'py>(&self, py: Python<'py>) -> PyResult<Vec<Bound<'py, PyAny>>> {
        self.inner
            .mode_maps()
            .iter()
            .map(|m| json::to_py(py, &paper10_doc::mode_to_value(m)))
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

robot_law::robot_modes_class!(PyMapDynamics, dynmap, PyDynamicMap);

/// Registers the classes, function and constants of this module.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyDynamicMap>()?;
    m.add_class::<PyMapDynamics>()?;
    m.add("MODE_MAP_FIELDS", paper10_doc::MODE_FIELDS.to_vec())?;
    m.add("MODE_MAP_RANGE_FIELDS", paper10_doc::RANGE_FIELDS.to_vec())?;
    m.add_function(wrap_pyfunction!(evaluate_trial_mode, m)?)?;
    Ok(())
}
