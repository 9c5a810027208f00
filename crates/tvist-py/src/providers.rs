//! Bindings of the dynamics providers that need no robot: constant modes and a Python
//! callable, and the provider type the shaper binding holds.

use numpy::IntoPyArray;
use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;
use tvist_core as core;
use tvist_core::{Dynamics, Mode, Status};

use crate::convert::value_error;

pub(crate) fn modes_from_pairs(pairs: Vec<(f64, f64)>) -> Vec<Mode> {
    pairs.into_iter().map(|(wn, z)| Mode::new(wn, z)).collect()
}

/// Constant modes [(wn_rad_s, zeta), ...]: time-invariant multi-mode shaping. wn_rad_s is
/// the undamped natural frequency in rad/s (2*pi times Hz; a value below 2 Hz is warned about).
#[pyclass(name = "ConstantModes", module = "tvist._core", frozen)]
#[derive(Clone)]
pub(crate) struct PyConstantModes {
    pub(crate) inner: core::ConstantModes,
}

/// Lowest natural frequency (Hz) of a `ConstantModes` mode taken as meant without a warning.
/// A lower one is more likely a frequency in Hz given where rad/s is meant (8 "rad/s" is
/// 1.27 Hz, below the modes of robot arms); it is warned about, not refused, because a soft
/// payload mount can ring that low.
pub(crate) const LOWEST_PLAUSIBLE_MODE_HZ: f64 = 2.0;

#[pymethods]
impl PyConstantModes {
    #[new]
    fn new(py: Python<'_>, modes: Vec<(f64, f64)>) -> PyResult<Self> {
        let inner =
            core::ConstantModes::new(modes_from_pairs(modes.clone())).map_err(value_error)?;
        for (i, (wn_rad_s, _)) in modes.into_iter().enumerate() {
            let hz = wn_rad_s / std::f64::consts::TAU;
            if hz < LOWEST_PLAUSIBLE_MODE_HZ {
                let message = format!(
                    "ConstantModes: mode {i} has wn_rad_s = {wn_rad_s:.6} rad/s, i.e. {hz:.3} \
                     Hz, below {LOWEST_PLAUSIBLE_MODE_HZ} Hz, lower than a robot arm's modes; \
                     wn_rad_s is in rad/s (2*pi times the frequency in Hz)"
                );
                let message = std::ffi::CString::new(message)
                    .map_err(|e| PyValueError::new_err(e.to_string()))?;
                let category = py.get_type::<pyo3::exceptions::PyUserWarning>();
                PyErr::warn(py, category.as_any(), &message, 1)?;
            }
        }
        Ok(PyConstantModes { inner })
    }

    /// The modes as [(wn_rad_s, zeta), ...].
    #[getter]
    fn modes(&self) -> Vec<(f64, f64)> {
        self.inner
            .modes_list()
            .iter()
            .map(|m| (m.wn_rad_s, m.zeta))
            .collect()
    }

    fn __repr__(&self) -> String {
        format!("ConstantModes({:?})", self.modes())
    }
}

/// A Python callable `f(q) -> [(wn_rad_s, zeta), ...]` used as a provider (slow research
/// path: it takes the interpreter lock every cycle). A raised exception is kept and re-raised
/// after the step; invalid modes are held like any provider's.
pub(crate) struct CallableModes {
    pub(crate) func: Py<PyAny>,
    pub(crate) n_modes: usize,
    pub(crate) n_dof: usize,
    pub(crate) error: Option<PyErr>,
}

impl CallableModes {
    fn call(&self, py: Python<'_>, q: &[f64], out: &mut [Mode]) -> PyResult<()> {
        let arg = q.to_vec().into_pyarray(py);
        let result = self.func.bind(py).call1((arg,))?;
        let pairs: Vec<(f64, f64)> = result.extract().map_err(|_| {
            PyTypeError::new_err("the dynamics callable must return a sequence of (wn_rad_s, zeta)")
        })?;
        if pairs.len() != out.len() {
            return Err(PyValueError::new_err(format!(
                "the dynamics callable returned {} modes, expected {}",
                pairs.len(),
                out.len()
            )));
        }
        for (o, (wn, z)) in out.iter_mut().zip(pairs) {
            *o = Mode::new(wn, z);
        }
        Ok(())
    }
}

impl Dynamics for CallableModes {
    fn n_modes(&self) -> usize {
        self.n_modes
    }

    fn modes(&mut self, q: &[f64], out: &mut [Mode]) -> Status {
        let result = Python::attach(|py| self.call(py, q, out));
        if let Err(e) = result {
            out.fill(Mode::new(f64::NAN, f64::NAN));
            if self.error.is_none() {
                self.error = Some(e);
            }
        }
        Status::OK
    }

    fn slowest_mode(&self, _index: usize) -> Option<Mode> {
        None
    }

    fn n_dof(&self) -> Option<usize> {
        Some(self.n_dof)
    }
}

/// Every provider the Python API accepts: the core's provider type with a Python callable
/// as its callback.
pub(crate) type Provider = core::Provider<CallableModes>;

/// Registers the classes of this module.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyConstantModes>()?;
    Ok(())
}
