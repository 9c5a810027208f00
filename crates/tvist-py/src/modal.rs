//! Bindings of the modal map and its per-cycle provider.

use numpy::{PyArrayDyn, PyReadonlyArray2};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use tvist_core as core;
use tvist_core::Mode;

use crate::convert::{self, gravity_rows, rows, value_error};
use crate::json::{self, NonFinite};
use crate::robot::PyRobot;
use crate::robot_law;

use tvist_core::files::modal_doc::{self, FLEX_JOINT_FIELDS};

/// Modal map: flexible joints (dicts of FLEX_JOINT_FIELDS, laws as [at_zero, per_nm,
/// per_nm2]) and the shaped modes: exactly one of the joints naming them in cascade order
/// (`mode_joints`) or the number of lowest-frequency modes (`shaped_modes`). Read by the
/// core's map-file parser, as the fields of a `modal` document (errors name the field).
#[pyclass(name = "ModalMap", module = "tvist._core", frozen)]
#[derive(Clone)]
pub struct PyModalMap {
    pub inner: core::ModalMap,
}

#[pymethods]
impl PyModalMap {
    #[new]
    #[pyo3(signature = (flex_joints, mode_joints=None, shaped_modes=None))]
    fn new(
        flex_joints: Vec<Bound<'_, PyDict>>,
        mode_joints: Option<Vec<usize>>,
        shaped_modes: Option<usize>,
    ) -> PyResult<Self> {
        // The modal form's fields of a map document, read by the core's map-file parser.
        let flex = flex_joints
            .iter()
            .enumerate()
            .map(|(i, d)| json::to_value(d, &format!("flex_joints[{i}]"), NonFinite::Refuse))
            .collect::<PyResult<Vec<_>>>()?;
        let mut doc = serde_json::Map::new();
        doc.insert("flex_joints".into(), serde_json::Value::Array(flex));
        if let Some(joints) = mode_joints {
            doc.insert("mode_joints".into(), joints.into());
        }
        if let Some(k) = shaped_modes {
            doc.insert("shaped_modes".into(), k.into());
        }
        Ok(PyModalMap {
            inner: modal_doc::modal_from(&doc).map_err(value_error)?,
        })
    }

    /// The flexible joints as dicts (see the constructor).
    #[getter]
    fn flex_joints<'py>(&self, py: Python<'py>) -> PyResult<Vec<Bound<'py, PyDict>>> {
        self.inner
            .flex_joints()
            .iter()
            .map(|f| {
                let d = PyDict::new(py);
                let law = |l: &core::LoadLaw| vec![l.at_zero, l.per_nm, l.per_nm2];
                d.set_item("joint", f.joint)?;
                d.set_item("stiffness_nm_per_rad", law(&f.stiffness_nm_per_rad))?;
                d.set_item("damping_nms_per_rad", law(&f.damping_nms_per_rad))?;
                d.set_item("damping_load_joint", f.damping_load_joint)?;
                Ok(d)
            })
            .collect()
    }

    /// The bending links as dicts (`link`, `at_fraction`, `stiffness_nm_per_rad`,
    /// `damping_nms_per_rad`), in link order; empty for a map of joints only.
    #[getter]
    fn link_hinges<'py>(&self, py: Python<'py>) -> PyResult<Vec<Bound<'py, PyDict>>> {
        self.inner
            .link_hinges()
            .iter()
            .map(|h| {
                let d = PyDict::new(py);
                d.set_item("link", h.link)?;
                d.set_item("at_fraction", h.at_fraction)?;
                d.set_item("stiffness_nm_per_rad", h.stiffness_nm_per_rad)?;
                d.set_item("damping_nms_per_rad", h.damping_nms_per_rad)?;
                Ok(d)
            })
            .collect()
    }

    /// Joints of the evaluated arm (the hinged arm, `Robot.with_link_hinges`, if the map has
    /// link hinges) that the map reads: the `n_dof` that `modes_from_mass_matrix_many` needs
    /// at least.
    #[getter]
    fn model_joints(&self) -> usize {
        self.inner.model_joints()
    }

    /// The robot the map was identified on (`metadata.robot` of its file), or None.
    #[getter]
    fn robot(&self) -> Option<String> {
        self.inner.robot().map(str::to_owned)
    }

    /// The joints naming the shaped modes in cascade order, or None for a map shaping its
    /// lowest-frequency modes.
    #[getter]
    fn mode_joints(&self) -> Option<Vec<usize>> {
        self.inner.mode_joints().map(<[usize]>::to_vec)
    }

    /// The number of lowest-frequency modes shaped, or None for a map naming its modes by
    /// joint.
    #[getter]
    fn shaped_modes(&self) -> Option<usize> {
        match self.inner.shaped_modes() {
            core::ShapedModes::Lowest(k) => Some(*k),
            core::ShapedModes::ByJoint(_) => None,
        }
    }

    /// Stiffness (N m/rad) and damping (N m s/rad) of every flexible joint (in the order of
    /// `flex_joints`) under gravity torques (n_poses, n_dof) (N m; read only when the laws
    /// use them): (n_poses, n_flex, 2).
    fn joint_laws_many<'py>(
        &self,
        py: Python<'py>,
        gravity_torque_nm: PyReadonlyArray2<'py, f64>,
    ) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
        let n_dof = gravity_torque_nm.as_array().ncols();
        let need = self.inner.required_joints();
        if n_dof < need {
            return Err(PyValueError::new_err(format!(
                "the modal map reads {need} joints, gravity_torque_nm has {n_dof} columns"
            )));
        }
        let (n_poses, tau) = rows(&gravity_torque_nm, n_dof, "gravity_torque_nm")?;
        let nf = self.inner.flex_joints().len();
        let mut out = Vec::with_capacity(n_poses * nf * 2);
        for row in tau.chunks_exact(n_dof.max(1)) {
            let (k, c) = self.inner.joint_laws_at(row);
            for i in 0..nf {
                out.extend([k[i], c[i]]);
            }
        }
        convert::array(py, &[n_poses, nf, 2], out)
    }

    #[getter]
    fn n_modes(&self) -> usize {
        self.inner.n_modes()
    }

    #[getter]
    fn required_joints(&self) -> usize {
        self.inner.required_joints()
    }

    #[getter]
    fn uses_gravity(&self) -> bool {
        self.inner.uses_gravity()
    }

    /// Shaped modes for every pose: mass matrices (n_poses, n_dof * n_dof) row-major, gravity
    /// torques (n_poses, n_dof) or None when the map reads none -> (n_poses, n_modes, 2) of
    /// (wn_rad_s, zeta); NaN where the eigenproblem has no valid solution. `tracked`: the
    /// poses are a path, each slot following its eigenmode branch from the first pose on (as
    /// the streaming shaper does); otherwise the map's rule at each pose alone.
    #[pyo3(signature = (mass_kg_m2, n_dof, gravity_torque_nm=None, tracked=false))]
    fn modes_from_mass_matrix_many<'py>(
        &self,
        py: Python<'py>,
        mass_kg_m2: PyReadonlyArray2<'py, f64>,
        n_dof: usize,
        gravity_torque_nm: Option<PyReadonlyArray2<'py, f64>>,
        tracked: bool,
    ) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
        let need = self.inner.model_joints();
        if n_dof < need {
            return Err(PyValueError::new_err(format!(
                "the modal map reads {need} joints, got n_dof = {n_dof}"
            )));
        }
        let (n, mass) = rows(&mass_kg_m2, n_dof * n_dof, "mass_kg_m2")?;
        let needed = self
            .inner
            .uses_gravity()
            .then_some("the modal map's laws read gravity torques");
        let tau = gravity_rows(gravity_torque_nm, n_dof, n, needed)?.unwrap_or_default();
        let m = self.inner.n_modes();
        let mut modes = vec![Mode::new(0.0, 0.0); m];
        let mut out = vec![0.0; n * m * 2];
        let nn = n_dof * n_dof;
        let mut track = core::ModeTrack::default();
        for (r, chunk) in out.chunks_exact_mut(2 * m).enumerate() {
            let tau_row = if tau.is_empty() {
                &[][..]
            } else {
                &tau[r * n_dof..(r + 1) * n_dof]
            };
            if !tracked {
                track.clear();
            }
            self.inner.modes_tracked(
                &mass[r * nn..(r + 1) * nn],
                n_dof,
                tau_row,
                &mut track,
                &mut modes,
            );
            for (pair, mode) in chunk.chunks_exact_mut(2).zip(&modes) {
                pair[0] = mode.wn_rad_s;
                pair[1] = mode.zeta;
            }
        }
        convert::array(py, &[n, m, 2], out)
    }
}

/// Provider for TvShaper: robot mass matrix at the previous shaped output -> modal map ->
/// modes.
#[pyclass(name = "ModalDynamics", module = "tvist._core", subclass)]
pub struct PyModalDynamics {
    pub inner: core::ModalDynamics,
}

robot_law::robot_modes_class!(PyModalDynamics, modal_map, PyModalMap);

/// Registers the classes of this module.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyModalMap>()?;
    m.add_class::<PyModalDynamics>()?;
    m.add("FLEX_JOINT_FIELDS", FLEX_JOINT_FIELDS.to_vec())?;
    Ok(())
}
