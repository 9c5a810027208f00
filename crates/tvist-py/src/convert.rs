//! numpy <-> Rust conversions shared by the bindings, with the error messages users see.

use numpy::ndarray::{ArrayD, IxDyn};
use numpy::{
    IntoPyArray, PyArrayDescrMethods, PyArrayDyn, PyReadonlyArray2, PyUntypedArray,
    PyUntypedArrayMethods,
};
use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;

/// The rows of a `(n, cols)` array, row-major whatever its memory layout (`as_slice` also
/// accepts Fortran order, which would transpose the data). Returns `(n, data)`.
pub fn rows(
    arr: &PyReadonlyArray2<'_, f64>,
    cols: usize,
    what: &str,
) -> PyResult<(usize, Vec<f64>)> {
    let shape = arr.shape();
    if shape[1] != cols {
        return Err(PyValueError::new_err(format!(
            "{what} has shape ({}, {}), expected (n_samples, {cols})",
            shape[0], shape[1]
        )));
    }
    let data: Vec<f64> = match arr.as_slice() {
        Ok(s) if arr.is_c_contiguous() => s.to_vec(),
        _ => arr.as_array().iter().copied().collect(),
    };
    Ok((shape[0], data))
}

/// Gravity torques (N m) for `n` poses: the rows of `gravity_torque_nm`, `(n, cols)`, or
/// `None` when it is omitted and nothing reads it. `needed` is why it is read ("the map uses
/// gravity torques ...") when the caller's map or mode reads it, `None` when not; omitting it
/// then is an error that says so.
pub fn gravity_rows(
    gravity_torque_nm: Option<PyReadonlyArray2<'_, f64>>,
    cols: usize,
    n: usize,
    needed: Option<&str>,
) -> PyResult<Option<Vec<f64>>> {
    match (gravity_torque_nm, needed) {
        (Some(t), _) => {
            let (tn, tau) = rows(&t, cols, "gravity_torque_nm")?;
            if tn != n {
                return Err(PyValueError::new_err(format!(
                    "gravity_torque_nm has {tn} rows, expected {n} (one per pose)"
                )));
            }
            Ok(Some(tau))
        }
        (None, Some(why)) => Err(PyValueError::new_err(format!(
            "{why}: pass gravity_torque_nm, shape ({n}, {cols})"
        ))),
        (None, None) => Ok(None),
    }
}

/// Checks that a start pose has `n` finite values.
pub fn check_start_pose(q0: &[f64], n: usize) -> PyResult<()> {
    if q0.len() != n {
        return Err(PyValueError::new_err(format!(
            "q0 has {} values, expected n_dof = {n}",
            q0.len()
        )));
    }
    if q0.iter().any(|v| !v.is_finite()) {
        return Err(PyValueError::new_err("q0 must be finite"));
    }
    Ok(())
}

/// A row-major buffer as a numpy array of the given shape.
pub fn array<'py>(
    py: Python<'py>,
    shape: &[usize],
    data: Vec<f64>,
) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
    let arr = ArrayD::from_shape_vec(IxDyn(shape), data)
        .map_err(|e| PyValueError::new_err(e.to_string()))?;
    Ok(arr.into_pyarray(py))
}

/// A setup error of the core as a Python `ValueError`.
pub fn value_error(e: tvist_core::Error) -> PyErr {
    PyValueError::new_err(e.to_string())
}

/// `obj` if it holds real numbers, as a numpy array for a sequence (numpy's own conversion,
/// which tells what it holds). A complex array, scalar or element is refused: converting it to
/// float64 would silently drop the imaginary part. `what` names the argument in the error.
pub fn real_input<'py>(obj: &Bound<'py, PyAny>, what: &str) -> PyResult<Bound<'py, PyAny>> {
    let array = match obj.cast::<PyUntypedArray>() {
        Ok(array) => array.clone(),
        Err(_) => {
            let numpy = obj.py().import("numpy")?;
            numpy
                .call_method1("asarray", (obj,))?
                .cast_into::<PyUntypedArray>()
                .map_err(PyErr::from)?
        }
    };
    let dtype = array.dtype();
    if dtype.kind() == b'c' {
        return Err(PyTypeError::new_err(format!(
            "{what} must hold real numbers, got {} values (their imaginary part would be \
             dropped)",
            dtype.str()?
        )));
    }
    Ok(array.into_any())
}

/// `got` values where `expected` are needed: a `ValueError` naming `what` otherwise.
pub fn check_len(what: &str, got: usize, expected: usize) -> PyResult<()> {
    if got == expected {
        Ok(())
    } else {
        Err(PyValueError::new_err(format!(
            "{what} has {got} values, expected {expected}"
        )))
    }
}
