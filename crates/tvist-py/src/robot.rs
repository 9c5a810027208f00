//! Bindings of the robot model: construction from DH parameters or URDF placements,
//! kinematics and dynamics over many poses, link hinges.

use numpy::{PyArrayDyn, PyReadonlyArray2};
use pyo3::prelude::*;
use tvist_core as core;
use tvist_core::Status;

use crate::convert::{self, check_len, rows, value_error};

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

/// The segments of a link (tvist-core `robot::link_hinges::split_link`): offset of the next joint
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

/// Registers the class and function of this module.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyRobot>()?;
    m.add_function(wrap_pyfunction!(split_link, m)?)?;
    Ok(())
}
