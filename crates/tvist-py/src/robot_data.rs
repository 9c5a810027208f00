//! Bindings of the core's robot data: the robots' names and parameters as dicts.

use pyo3::prelude::*;
use pyo3::types::PyDict;
use tvist_core as core;
use tvist_core::files::robot_data;

use crate::convert::value_error;

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
/// None). control_period_s is None where the entry does not state it.
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
    d.set_item("control_period_s", e.control_period_s)?;
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

/// Registers the functions and data of this module.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("ROBOT_DATA_JSON", robot_data::UR_E_SERIES_JSON)?;
    m.add_function(wrap_pyfunction!(robot_names, m)?)?;
    m.add_function(wrap_pyfunction!(robot_params, m)?)?;
    m.add_function(wrap_pyfunction!(robot_file_params, m)?)?;
    Ok(())
}
