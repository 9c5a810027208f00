//! Bindings of the robot model, the dynamic map and the map-driven dynamics provider.

use numpy::{PyArrayDyn, PyReadonlyArray2, PyUntypedArrayMethods};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use tvist_core as core;
use tvist_core::{Mode, Status};

use crate::convert::{self, rows, value_error};
use crate::json::{self, NonFinite};
use crate::modal::PyModalMap;
use crate::robot_modes;
use pyo3::types::PyDict;
use tvist_core::files::map_file::{self, MapFile, MapForm};
use tvist_core::files::paper10_doc;
use tvist_core::files::robot_data;

pub(crate) fn check_len(what: &str, got: usize, expected: usize) -> PyResult<()> {
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

/// `n` links from mass_kg (n,), com_m (n, 3) and inertia_kg_m2 (n, 6).
fn links(
    n: usize,
    mass_kg: &[f64],
    com_m: &PyReadonlyArray2<'_, f64>,
    inertia_kg_m2: &PyReadonlyArray2<'_, f64>,
) -> PyResult<Vec<core::RigidBody>> {
    check_len("mass_kg", mass_kg.len(), n)?;
    let (com_rows, com) = rows(com_m, 3, "com_m")?;
    check_len("com_m rows", com_rows, n)?;
    let (inertia_rows, inertia) = rows(inertia_kg_m2, 6, "inertia_kg_m2")?;
    check_len("inertia_kg_m2 rows", inertia_rows, n)?;
    Ok((0..n)
        .map(|i| core::RigidBody {
            mass_kg: mass_kg[i],
            com_m: [com[3 * i], com[3 * i + 1], com[3 * i + 2]],
            inertia_kg_m2: six(&inertia[6 * i..6 * i + 6]),
        })
        .collect())
}

/// The payload body (a point mass without an inertia).
fn payload(
    mass_kg: f64,
    com_m: Option<Vec<f64>>,
    inertia_kg_m2: Option<Vec<f64>>,
) -> PyResult<core::RigidBody> {
    let com = com_m.unwrap_or_else(|| vec![0.0; 3]);
    check_len("payload_com_m", com.len(), 3)?;
    let inertia = match inertia_kg_m2 {
        Some(v) => {
            check_len("payload_inertia_kg_m2", v.len(), 6)?;
            six(&v)
        }
        None => [0.0; 6],
    };
    Ok(core::RigidBody {
        mass_kg,
        com_m: [com[0], com[1], com[2]],
        inertia_kg_m2: inertia,
    })
}

/// Serial revolute arm (DH or URDF placement) with link masses and a payload.
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
    #[pyo3(signature = (d_m, a_m, alpha_rad, mass_kg, com_m, inertia_kg_m2, payload_mass_kg=0.0, payload_com_m=None, payload_inertia_kg_m2=None, name=None))]
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
        name: Option<String>,
    ) -> PyResult<Self> {
        let n = d_m.len();
        check_len("a_m", a_m.len(), n)?;
        check_len("alpha_rad", alpha_rad.len(), n)?;
        check_len("mass_kg", mass_kg.len(), n)?;
        let joints = (0..n)
            .map(|i| core::DhJoint::new(d_m[i], a_m[i], alpha_rad[i]))
            .collect();
        let links = links(n, &mass_kg, &com_m, &inertia_kg_m2)?;
        let payload = payload(payload_mass_kg, payload_com_m, payload_inertia_kg_m2)?;
        let robot = core::Robot::new(joints, links, payload).map_err(value_error)?;
        Ok(PyRobot {
            inner: match name {
                Some(name) => robot.with_name(name),
                None => robot,
            },
        })
    }

    /// Joints placed as URDF places them: origin_xyz_m, origin_rpy_rad, axis (n, 3);
    /// flange_xyz_m, flange_rpy_rad (3,) in the last link's frame; links (mass_kg (n,), com_m
    /// (n, 3), inertia_kg_m2 (n, 6)) in the link frame after each joint; payload in the
    /// flange frame.
    #[staticmethod]
    #[pyo3(signature = (origin_xyz_m, origin_rpy_rad, axis, flange_xyz_m, flange_rpy_rad, mass_kg, com_m, inertia_kg_m2, payload_mass_kg=0.0, payload_com_m=None, payload_inertia_kg_m2=None, name=None))]
    #[allow(clippy::too_many_arguments)]
    fn placed(
        origin_xyz_m: PyReadonlyArray2<'_, f64>,
        origin_rpy_rad: PyReadonlyArray2<'_, f64>,
        axis: PyReadonlyArray2<'_, f64>,
        flange_xyz_m: Vec<f64>,
        flange_rpy_rad: Vec<f64>,
        mass_kg: Vec<f64>,
        com_m: PyReadonlyArray2<'_, f64>,
        inertia_kg_m2: PyReadonlyArray2<'_, f64>,
        payload_mass_kg: f64,
        payload_com_m: Option<Vec<f64>>,
        payload_inertia_kg_m2: Option<Vec<f64>>,
        name: Option<String>,
    ) -> PyResult<Self> {
        let n = mass_kg.len();
        let three = |a: &PyReadonlyArray2<'_, f64>, what: &str| -> PyResult<Vec<[f64; 3]>> {
            let (r, v) = rows(a, 3, what)?;
            check_len(&format!("{what} rows"), r, n)?;
            Ok(v.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect())
        };
        let (xyz, rpy, ax) = (
            three(&origin_xyz_m, "origin_xyz_m")?,
            three(&origin_rpy_rad, "origin_rpy_rad")?,
            three(&axis, "axis")?,
        );
        check_len("flange_xyz_m", flange_xyz_m.len(), 3)?;
        check_len("flange_rpy_rad", flange_rpy_rad.len(), 3)?;
        let joints = (0..n)
            .map(|i| core::JointPlacement::new(core::Origin::new(xyz[i], rpy[i]), ax[i]))
            .collect();
        let flange = core::Origin::new(
            [flange_xyz_m[0], flange_xyz_m[1], flange_xyz_m[2]],
            [flange_rpy_rad[0], flange_rpy_rad[1], flange_rpy_rad[2]],
        );
        let links = links(n, &mass_kg, &com_m, &inertia_kg_m2)?;
        let payload = payload(payload_mass_kg, payload_com_m, payload_inertia_kg_m2)?;
        let robot =
            core::Robot::from_placements(joints, flange, links, payload).map_err(value_error)?;
        Ok(PyRobot {
            inner: match name {
                Some(name) => robot.with_name(name),
                None => robot,
            },
        })
    }

    #[getter]
    fn n_dof(&self) -> usize {
        self.inner.n_dof()
    }

    /// The robot's name (maps identified on another robot are refused), or None.
    #[getter]
    fn name(&self) -> Option<String> {
        self.inner.name().map(str::to_owned)
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

    /// The robot with a hinge pair inserted in each of `links` (increasing) at `fractions`
    /// of its length (tvist-core `Robot::with_link_hinges`): the arm a modal map with link
    /// hinges evaluates.
    fn with_link_hinges(&self, links: Vec<usize>, fractions: Vec<f64>) -> PyResult<PyRobot> {
        check_len("fractions", fractions.len(), links.len())?;
        let hinges: Vec<(usize, f64)> = links.into_iter().zip(fractions).collect();
        Ok(PyRobot {
            inner: self
                .inner
                .with_link_hinges(&hinges)
                .map_err(convert::value_error)?,
        })
    }
}

/// The segments of a link (tvist-core `link_hinges::split_link`): offset of the next joint
/// (3,), mass, centre of mass (3,), inertia about it (3, 3) in the link's frame, hinge
/// fractions -> ([(hinge point or None, mass, com, inertia (3, 3))], bending axes (2, 3)).
#[pyfunction]
#[allow(clippy::type_complexity)]
fn split_link(
    offset_m: [f64; 3],
    mass_kg: f64,
    com_m: [f64; 3],
    inertia_kg_m2: [[f64; 3]; 3],
    hinge_fractions: Vec<f64>,
) -> PyResult<(
    Vec<(Option<[f64; 3]>, f64, [f64; 3], [[f64; 3]; 3])>,
    [[f64; 3]; 2],
)> {
    let i = inertia_kg_m2;
    let body = core::RigidBody {
        mass_kg,
        com_m,
        inertia_kg_m2: [i[0][0], i[1][1], i[2][2], i[0][1], i[0][2], i[1][2]],
    };
    let (segments, axes) =
        core::split_link(offset_m, &body, &hinge_fractions).map_err(convert::value_error)?;
    let out = segments
        .iter()
        .map(|s| {
            let [xx, yy, zz, xy, xz, yz] = s.body.inertia_kg_m2;
            let inertia = [[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]];
            (s.hinge_m, s.body.mass_kg, s.body.com_m, inertia)
        })
        .collect();
    Ok((out, axes))
}

/// A map document (Python object) checked by the core's map-file validation.
fn map_file_from(doc: &Bound<'_, PyAny>) -> PyResult<MapFile> {
    let value = match doc.cast::<PyDict>() {
        // Metadata may hold statistics that could not be computed (NaN): written as null.
        // Everything else must be finite, and the error names the field.
        Ok(d) => {
            let mut map = serde_json::Map::new();
            for (k, v) in d.iter() {
                let key: String = k
                    .extract()
                    .map_err(|_| PyValueError::new_err("map document: keys must be strings"))?;
                let nf = if key == "metadata" {
                    NonFinite::AsNull
                } else {
                    NonFinite::Refuse
                };
                let value = json::to_value(&v, &key, nf)?;
                map.insert(key, value);
            }
            serde_json::Value::Object(map)
        }
        Err(_) => json::to_value(doc, "(document)", NonFinite::Refuse)?,
    };
    MapFile::from_value(&value).map_err(value_error)
}

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

/// A parsed map file as `(DynamicMap or ModalMap, metadata dict)`, by the file's kind.
fn map_parts(py: Python<'_>, file: MapFile) -> PyResult<(Bound<'_, PyAny>, Bound<'_, PyAny>)> {
    let metadata = json::to_py(py, &serde_json::Value::Object(file.metadata().clone()))?;
    let map = match file.into_form() {
        MapForm::Paper10(inner) => Bound::new(py, PyDynamicMap { inner })?.into_any(),
        MapForm::Modal(inner) => Bound::new(py, PyModalMap { inner })?.into_any(),
    };
    Ok((map, metadata))
}

/// The map form of a `DynamicMap` or `ModalMap`.
fn form_of(map: &Bound<'_, PyAny>) -> PyResult<MapForm> {
    if let Ok(m) = map.cast::<PyDynamicMap>() {
        Ok(MapForm::Paper10(m.borrow().inner.clone()))
    } else if let Ok(m) = map.cast::<PyModalMap>() {
        Ok(MapForm::Modal(m.get().inner.clone()))
    } else {
        Err(pyo3::exceptions::PyTypeError::new_err(
            "map must be a _core.DynamicMap or a _core.ModalMap",
        ))
    }
}

/// Validates a map document (a dict as read from JSON) with the core's map-file rules and
/// returns `(DynamicMap or ModalMap, metadata)` by its kind; errors name the field.
#[pyfunction]
fn map_from_document<'py>(
    py: Python<'py>,
    doc: &Bound<'py, PyAny>,
) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyAny>)> {
    map_parts(py, map_file_from(doc)?)
}

/// Reads and validates the map file at `path` (the core's reader: size limit, UTF-8, strict
/// JSON): `(DynamicMap or ModalMap, metadata)`; errors start with the path.
#[pyfunction]
fn load_map_file(
    py: Python<'_>,
    path: std::path::PathBuf,
) -> PyResult<(Bound<'_, PyAny>, Bound<'_, PyAny>)> {
    map_parts(py, MapFile::load(&path).map_err(value_error)?)
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
    let tau = match gravity_torque_nm {
        Some(t) => {
            let (tn, tau) = rows(&t, cols, "gravity_torque_nm")?;
            check_len("gravity_torque_nm rows", tn, n)?;
            tau
        }
        None if mode.uses_gravity() => {
            return Err(PyValueError::new_err(
                "the mode uses gravity torques (k_g != 0): pass them",
            ));
        }
        None => vec![0.0; n * cols],
    };
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

/// The map file of `map` (DynamicMap or ModalMap) with `metadata`, as strict JSON text
/// (non-finite metadata numbers written as null).
#[pyfunction]
fn write_map(map: &Bound<'_, PyAny>, metadata: &Bound<'_, PyAny>) -> PyResult<String> {
    let meta = json::to_value(metadata, "metadata", NonFinite::AsNull)?;
    let file = MapFile::new(form_of(map)?, &meta).map_err(value_error)?;
    Ok(file.to_json())
}

/// The map document of `map` with `metadata` as a dict (what `write_map` writes).
#[pyfunction]
fn map_document<'py>(
    py: Python<'py>,
    map: &Bound<'py, PyAny>,
    metadata: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyAny>> {
    let meta = json::to_value(metadata, "metadata", NonFinite::AsNull)?;
    let file = MapFile::new(form_of(map)?, &meta).map_err(value_error)?;
    json::to_py(py, &file.to_value())
}

/// Names of the robots in the robot data, in file order.
#[pyfunction]
fn robot_names() -> PyResult<Vec<String>> {
    let entries = robot_data::ur_e_series_entries().map_err(value_error)?;
    Ok(entries.iter().map(|e| e.name.clone()).collect())
}

/// Every parameter of robot `name` from the core's robot data, as a dict.
#[pyfunction]
fn robot_params<'py>(py: Python<'py>, name: &str) -> PyResult<Bound<'py, PyDict>> {
    let e = robot_data::ur_e_series_entry(name).map_err(value_error)?;
    entry_dict(py, e)
}

/// Every parameter of the one robot in robot file `path`, as a dict (as robot_params).
#[pyfunction]
fn robot_file_params<'py>(py: Python<'py>, path: &str) -> PyResult<Bound<'py, PyDict>> {
    let e = robot_data::robot_file(std::path::Path::new(path)).map_err(value_error)?;
    entry_dict(py, &e)
}

/// A robot entry as a dict: DH chains give d_m, a_m, alpha_rad; URDF placement gives
/// origin_xyz_m, origin_rpy_rad, axis (n, 3) and flange_xyz_m, flange_rpy_rad (the others
/// None).
fn entry_dict<'py>(py: Python<'py>, e: &robot_data::RobotEntry) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("name", &e.name)?;
    d.set_item("description", &e.description)?;
    d.set_item("source", &e.source)?;
    d.set_item("inertia_source", &e.inertia_source)?;
    let none = py.None();
    for key in [
        "d_m",
        "a_m",
        "alpha_rad",
        "origin_xyz_m",
        "origin_rpy_rad",
        "axis",
        "flange_xyz_m",
        "flange_rpy_rad",
    ] {
        d.set_item(key, &none)?;
    }
    match &e.chain {
        core::Chain::Dh(joints) => {
            d.set_item("d_m", joints.iter().map(|j| j.d_m).collect::<Vec<_>>())?;
            d.set_item("a_m", joints.iter().map(|j| j.a_m).collect::<Vec<_>>())?;
            d.set_item(
                "alpha_rad",
                joints.iter().map(|j| j.alpha_rad).collect::<Vec<_>>(),
            )?;
        }
        core::Chain::Urdf { joints, flange } => {
            let rows = |f: fn(&core::JointPlacement) -> [f64; 3]| {
                joints.iter().map(|j| f(j).to_vec()).collect::<Vec<_>>()
            };
            d.set_item("origin_xyz_m", rows(|j| j.origin.xyz_m))?;
            d.set_item("origin_rpy_rad", rows(|j| j.origin.rpy_rad))?;
            d.set_item("axis", rows(|j| j.axis))?;
            d.set_item("flange_xyz_m", flange.xyz_m.to_vec())?;
            d.set_item("flange_rpy_rad", flange.rpy_rad.to_vec())?;
        }
    }
    d.set_item(
        "mass_kg",
        e.links.iter().map(|l| l.mass_kg).collect::<Vec<_>>(),
    )?;
    d.set_item(
        "com_m",
        e.links.iter().map(|l| l.com_m.to_vec()).collect::<Vec<_>>(),
    )?;
    d.set_item(
        "inertia_kg_m2",
        e.links
            .iter()
            .map(|l| l.inertia_kg_m2.to_vec())
            .collect::<Vec<_>>(),
    )?;
    d.set_item(
        "joint_limits_rad",
        e.joint_limits_rad
            .iter()
            .map(|r| r.to_vec())
            .collect::<Vec<_>>(),
    )?;
    d.set_item("max_velocity_rad_s", e.max_velocity_rad_s.clone())?;
    d.set_item("max_payload_kg", e.max_payload_kg)?;
    let cylinders = match &e.inertia_cylinders {
        Some(c) => {
            let block = PyDict::new(py);
            block.set_item("radius_m", c.radius_m.clone())?;
            block.set_item("length_m", c.length_m.clone())?;
            block.set_item("axis", c.axis.clone())?;
            Some(block)
        }
        None => None,
    };
    d.set_item("inertia_cylinders", cylinders)?;
    Ok(d)
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

robot_modes::robot_modes_class!(PyMapDynamics, dynmap, PyDynamicMap);

/// Registers the classes of this module.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyRobot>()?;
    m.add_class::<PyDynamicMap>()?;
    m.add_class::<PyMapDynamics>()?;
    m.add("MODE_MAP_FIELDS", paper10_doc::MODE_FIELDS.to_vec())?;
    m.add("MODE_MAP_RANGE_FIELDS", paper10_doc::RANGE_FIELDS.to_vec())?;
    m.add("MAP_METADATA_FIELDS", map_file::METADATA_FIELDS.to_vec())?;
    m.add("MAP_SCHEMA_VERSION", map_file::SCHEMA_VERSION)?;
    m.add("MAP_KIND_PAPER10", map_file::KIND_PAPER10)?;
    m.add("MAP_KIND_MODAL", map_file::KIND_MODAL)?;
    m.add("ROBOT_DATA_JSON", robot_data::UR_E_SERIES_JSON)?;
    m.add_function(wrap_pyfunction!(split_link, m)?)?;
    m.add_function(wrap_pyfunction!(map_from_document, m)?)?;
    m.add_function(wrap_pyfunction!(load_map_file, m)?)?;
    m.add_function(wrap_pyfunction!(evaluate_trial_mode, m)?)?;
    m.add_function(wrap_pyfunction!(write_map, m)?)?;
    m.add_function(wrap_pyfunction!(map_document, m)?)?;
    m.add_function(wrap_pyfunction!(robot_names, m)?)?;
    m.add_function(wrap_pyfunction!(robot_params, m)?)?;
    m.add_function(wrap_pyfunction!(robot_file_params, m)?)?;
    Ok(())
}
