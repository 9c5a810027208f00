//! Bindings of `tvist_core::shaping::ztdis`: the zero-time-delay time scales and the modified-ZTDIS
//! compensator. Thin wrappers only; the equations live in the core.

use numpy::{IntoPyArray, PyArray1, PyArrayDyn, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use tvist_core::shaping::ztdis::{self, Compensator, Discretization};
use tvist_core::{Mode, Status};

use crate::convert;

/// ZTDIS time scale alpha = (T - delay)/T; ValueError unless the move is longer than the delay.
#[pyfunction]
fn ztdis_alpha(move_s: f64, delay_s: f64) -> PyResult<f64> {
    ztdis::ztdis_alpha(move_s, delay_s).map_err(convert::value_error)
}

/// Modified-ZTDIS time scale alpha' = T/(T + delay).
#[pyfunction]
fn modified_alpha(move_s: f64, delay_s: f64) -> PyResult<f64> {
    ztdis::modified_alpha(move_s, delay_s).map_err(convert::value_error)
}

/// The mode (wn_rad_s/alpha, zeta) whose registry shaper has every delay scaled by alpha.
#[pyfunction]
fn scaled_mode(wn_rad_s: f64, zeta: f64, alpha: f64) -> PyResult<(f64, f64)> {
    let m = ztdis::scaled_mode(Mode::new(wn_rad_s, zeta), alpha);
    m.validate(0).map_err(convert::value_error)?;
    Ok((m.wn_rad_s, m.zeta))
}

/// Modified-ZTDIS compensator: one biquad per mode, n_dof independent channels.
#[pyclass(name = "Compensator", module = "tvist._core")]
struct PyCompensator {
    inner: Compensator,
    last_status: Status,
}

#[pymethods]
impl PyCompensator {
    #[new]
    #[pyo3(signature = (modes, alpha, dt_s, n_dof, discretization="matched"))]
    fn new(
        modes: Vec<(f64, f64)>,
        alpha: f64,
        dt_s: f64,
        n_dof: usize,
        discretization: &str,
    ) -> PyResult<Self> {
        let modes: Vec<Mode> = modes.into_iter().map(|(w, z)| Mode::new(w, z)).collect();
        let method = Discretization::from_name(discretization).map_err(convert::value_error)?;
        let inner = Compensator::with_discretization(&modes, alpha, dt_s, n_dof, method)
            .map_err(convert::value_error)?;
        Ok(PyCompensator {
            inner,
            last_status: Status::OK,
        })
    }

    /// One control cycle: q (n_dof,) -> compensated q (n_dof,).
    fn step<'py>(
        &mut self,
        py: Python<'py>,
        q: PyReadonlyArray1<'py, f64>,
    ) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let q = q.as_slice()?;
        if q.len() != self.inner.n_channels() {
            return Err(PyValueError::new_err(format!(
                "q has {} values, expected n_dof = {}",
                q.len(),
                self.inner.n_channels()
            )));
        }
        let mut out = vec![0.0; q.len()];
        self.last_status = self.inner.step(q, &mut out);
        Ok(out.into_pyarray(py))
    }

    /// Filters a (n_samples, n_dof) array, continuing the streaming state. Releases the GIL.
    fn filter<'py>(
        &mut self,
        py: Python<'py>,
        q: PyReadonlyArray2<'py, f64>,
    ) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
        let (n, input) = convert::rows(&q, self.inner.n_channels(), "Q")?;
        let mut output = vec![0.0; input.len()];
        let inner = &mut self.inner;
        self.last_status = py.detach(|| inner.filter_into(&input, &mut output));
        convert::array(py, &[n, self.inner.n_channels()], output)
    }

    /// Puts the compensator at rest at q0, or (None) lets the next sample start it at rest.
    #[pyo3(signature = (q0=None))]
    fn reset(&mut self, q0: Option<PyReadonlyArray1<'_, f64>>) -> PyResult<()> {
        match q0 {
            Some(q0) => {
                let q0 = q0.as_slice()?;
                convert::check_start_pose(q0, self.inner.n_channels())?;
                self.inner.reset(q0);
            }
            None => self.inner.clear(),
        }
        Ok(())
    }

    /// Per-mode sections as [((b0, b1, b2), (1, a1, a2)), ...] in cascade order.
    #[getter]
    #[allow(clippy::type_complexity)]
    fn sections(&self) -> Vec<((f64, f64, f64), (f64, f64, f64))> {
        self.inner
            .sections()
            .iter()
            .map(|s| ((s.b[0], s.b[1], s.b[2]), (1.0, s.a[0], s.a[1])))
            .collect()
    }

    #[getter]
    fn alpha(&self) -> f64 {
        self.inner.alpha()
    }

    #[getter]
    fn dt_s(&self) -> f64 {
        self.inner.dt_s()
    }

    #[getter]
    fn n_dof(&self) -> usize {
        self.inner.n_channels()
    }

    #[getter]
    fn discretization(&self) -> &'static str {
        self.inner.discretization().name()
    }

    /// Status bits of the latest step or block (see tvist.Status).
    #[getter]
    fn last_status(&self) -> i32 {
        self.last_status.0
    }

    fn __repr__(&self) -> String {
        format!(
            "Compensator(alpha={}, dt_s={}, n_dof={}, sections={}, discretization={:?})",
            self.inner.alpha(),
            self.inner.dt_s(),
            self.inner.n_channels(),
            self.inner.sections().len(),
            self.inner.discretization().name()
        )
    }
}

/// Adds this module's functions and classes to `tvist._core`.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyCompensator>()?;
    m.add_function(wrap_pyfunction!(ztdis_alpha, m)?)?;
    m.add_function(wrap_pyfunction!(modified_alpha, m)?)?;
    m.add_function(wrap_pyfunction!(scaled_mode, m)?)?;
    Ok(())
}
