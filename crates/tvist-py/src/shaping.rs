//! Bindings of the shaper library: impulse sequences, shaper design, convolution and
//! residual vibration.

use numpy::{IntoPyArray, PyArray1, PyReadonlyArray1};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use tvist_core as core;
use tvist_core::Mode;

use crate::convert::value_error;

/// A validated impulse sequence, normalized to sum(amplitudes) == 1.
#[pyclass(name = "Impulses", module = "tvist._core", frozen)]
#[derive(Clone)]
struct PyImpulses {
    inner: core::Impulses,
}

#[pymethods]
impl PyImpulses {
    #[new]
    fn new(amplitudes: Vec<f64>, times_s: Vec<f64>) -> PyResult<Self> {
        Ok(PyImpulses {
            inner: core::Impulses::new(amplitudes, times_s).map_err(value_error)?,
        })
    }

    /// Amplitudes (sum to 1).
    #[getter]
    fn amplitudes<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        self.inner.amplitudes().to_vec().into_pyarray(py)
    }

    /// Impulse times in seconds, non-decreasing, first one >= 0.
    #[getter]
    fn times_s<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        self.inner.times_s().to_vec().into_pyarray(py)
    }

    /// The delay the sequence adds (its last impulse time), s.
    #[getter]
    fn duration_s(&self) -> f64 {
        self.inner.duration_s()
    }

    fn __len__(&self) -> usize {
        self.inner.len()
    }

    fn __repr__(&self) -> String {
        format!(
            "Impulses(amplitudes={:?}, times_s={:?})",
            self.inner.amplitudes(),
            self.inner.times_s()
        )
    }
}

/// Designs registry shaper `name` for mode (wn_rad_s, zeta).
#[pyfunction]
#[pyo3(signature = (name, wn_rad_s, zeta=0.0, tolerance=None))]
fn design_shaper(
    name: &str,
    wn_rad_s: f64,
    zeta: f64,
    tolerance: Option<f64>,
) -> PyResult<PyImpulses> {
    let kind = core::ShaperKind::from_name(name, tolerance).map_err(value_error)?;
    let inner = core::Impulses::design(kind, Mode::new(wn_rad_s, zeta)).map_err(value_error)?;
    Ok(PyImpulses { inner })
}

/// Convolution of impulse sequences (multi-mode shaper, eq. 53).
#[pyfunction]
#[pyo3(signature = (*sets))]
fn convolve(sets: Vec<PyRef<'_, PyImpulses>>) -> PyResult<PyImpulses> {
    let refs: Vec<&core::Impulses> = sets.iter().map(|s| &s.inner).collect();
    Ok(PyImpulses {
        inner: core::Impulses::convolve(&refs).map_err(value_error)?,
    })
}

/// Residual-vibration fraction of `impulses` for flat arrays of modes (same length).
#[pyfunction]
fn prv_flat<'py>(
    py: Python<'py>,
    impulses: PyRef<'_, PyImpulses>,
    wn_rad_s: PyReadonlyArray1<'py, f64>,
    zeta: PyReadonlyArray1<'py, f64>,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    let (wn, z) = (wn_rad_s.as_slice()?, zeta.as_slice()?);
    if wn.len() != z.len() {
        return Err(PyValueError::new_err(
            "wn_rad_s and zeta must have the same length",
        ));
    }
    let (a, t) = (impulses.inner.amplitudes(), impulses.inner.times_s());
    let out: Vec<f64> = wn
        .iter()
        .zip(z)
        .map(|(&w, &zz)| core::prv(a, t, w, zz))
        .collect();
    Ok(out.into_pyarray(py))
}

/// Registers the classes and functions of this module.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyImpulses>()?;
    m.add_function(wrap_pyfunction!(design_shaper, m)?)?;
    m.add_function(wrap_pyfunction!(convolve, m)?)?;
    m.add_function(wrap_pyfunction!(prv_flat, m)?)?;
    m.add("SHAPERS", core::SHAPER_NAMES.to_vec())?;
    Ok(())
}
