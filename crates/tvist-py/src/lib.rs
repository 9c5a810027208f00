//! Thin PyO3 bindings of `tvist-core`: numpy in/out, errors mapped to `ValueError`.
//! No algorithm lives here.

use numpy::{
    AllowTypeChange, IntoPyArray, PyArray1, PyArrayDyn, PyArrayLike1, PyArrayLike2,
    PyReadonlyArray1, PyUntypedArrayMethods,
};
use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;
use tvist_core as core;
use tvist_core::{Dynamics, Mode, Status, StatusCounter};

mod convert;
mod json;
mod modal;
mod robot;
mod robot_modes;
mod ztdis;

use convert::value_error;

fn modes_from_pairs(pairs: Vec<(f64, f64)>) -> Vec<Mode> {
    pairs.into_iter().map(|(wn, z)| Mode::new(wn, z)).collect()
}

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

/// Constant modes [(wn_rad_s, zeta), ...]: time-invariant multi-mode shaping. wn_rad_s is
/// the undamped natural frequency in rad/s (2*pi times Hz; a value below 2 Hz is warned about).
#[pyclass(name = "ConstantModes", module = "tvist._core", frozen)]
#[derive(Clone)]
struct PyConstantModes {
    inner: core::ConstantModes,
}

/// Lowest natural frequency (Hz) of a `ConstantModes` mode taken as meant without a warning.
/// A lower one is more likely a frequency in Hz given where rad/s is meant (8 "rad/s" is
/// 1.27 Hz, below the modes of robot arms); it is warned about, not refused, because a soft
/// payload mount can ring that low.
const LOWEST_PLAUSIBLE_MODE_HZ: f64 = 2.0;

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
struct CallableModes {
    func: Py<PyAny>,
    n_modes: usize,
    n_dof: usize,
    error: Option<PyErr>,
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
type Provider = core::Provider<CallableModes>;

/// Rows per chunk of `TvShaper.shape` (48 kB of 6-DOF samples: cache-resident).
const SHAPE_CHUNK_ROWS: usize = 1024;

/// Multi-mode FD-TVIST shaper (streaming and batch).
#[pyclass(name = "TvShaper", module = "tvist._core")]
struct PyTvShaper {
    inner: core::TvShaper<Provider>,
    /// The configuration `inner` was built with (`set_map` builds again with it).
    config: core::TvShaperConfig,
    last_status: Status,
    counts: StatusCounter,
}

impl PyTvShaper {
    fn take_callable_error(&mut self) -> PyResult<()> {
        if let Provider::Callback(p) = self.inner.dynamics_mut() {
            if let Some(e) = p.error.take() {
                return Err(e);
            }
        }
        Ok(())
    }
}

#[pymethods]
impl PyTvShaper {
    #[new]
    #[pyo3(signature = (dynamics, dt_s, n_dof, shaper="zv", interp="linear", max_delay_s=None, safety_factor=1.5, tolerance=None))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        py: Python<'_>,
        dynamics: &Bound<'_, PyAny>,
        dt_s: f64,
        n_dof: i64,
        shaper: &str,
        interp: &str,
        max_delay_s: Option<f64>,
        safety_factor: f64,
        tolerance: Option<f64>,
    ) -> PyResult<Self> {
        // Limits first: nothing below may allocate per channel before they are checked.
        // A signed count, so that a negative one is a ValueError like any other bad count.
        let n_dof = usize::try_from(n_dof)
            .ok()
            .filter(|&n| n >= 1)
            .ok_or_else(|| {
                PyValueError::new_err(format!("n_dof must be at least 1, got {n_dof}"))
            })?;
        core::limits::check_n_dof(n_dof).map_err(value_error)?;
        let provider = if let Ok(c) = dynamics.cast::<PyConstantModes>() {
            Provider::Constant(c.get().inner.clone())
        } else if let Ok(m) = dynamics.cast::<robot::PyMapDynamics>() {
            Provider::Map(Box::new(m.borrow().inner.clone()))
        } else if let Ok(m) = dynamics.cast::<modal::PyModalDynamics>() {
            Provider::Modal(Box::new(m.borrow().inner.clone()))
        } else if dynamics.is_callable() {
            if max_delay_s.is_none() {
                return Err(PyValueError::new_err(
                    "a callable dynamics provider needs max_delay_s (the longest delay of one \
                     mode filter, s) to size the delay lines",
                ));
            }
            let probe = vec![0.0; n_dof].into_pyarray(py);
            let pairs: Vec<(f64, f64)> = dynamics.call1((probe,))?.extract().map_err(|_| {
                PyTypeError::new_err(
                    "the dynamics callable must return a sequence of (wn_rad_s, zeta)",
                )
            })?;
            if pairs.is_empty() {
                return Err(PyValueError::new_err(
                    "the dynamics callable returned no modes",
                ));
            }
            Provider::Callback(CallableModes {
                func: dynamics.clone().unbind(),
                n_modes: pairs.len(),
                n_dof,
                error: None,
            })
        } else {
            return Err(PyTypeError::new_err(
                "dynamics must be a tvist provider (ConstantModes, MapDynamics) or a callable f(q) -> [(wn_rad_s, zeta), ...]",
            ));
        };
        let config = core::TvShaperConfig {
            dt_s,
            n_dof,
            shaper: core::ShaperKind::from_name(shaper, tolerance).map_err(value_error)?,
            interp: core::Interpolation::from_name(interp).map_err(value_error)?,
            max_delay_s,
            safety_factor,
        };
        let inner = core::TvShaper::new(provider, &config).map_err(value_error)?;
        Ok(PyTvShaper {
            inner,
            config,
            last_status: Status::OK,
            counts: StatusCounter::default(),
        })
    }

    /// One control cycle: q (n_dof,) -> shaped q (n_dof,). Any 1-D array-like of real numbers
    /// (converted to float64, any memory layout); complex input is a TypeError.
    fn step<'py>(
        &mut self,
        py: Python<'py>,
        q: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let q: PyArrayLike1<'py, f64, AllowTypeChange> = convert::real_input(q, "q")?.extract()?;
        let q: Vec<f64> = q.as_array().iter().copied().collect();
        if q.len() != self.inner.n_dof() {
            return Err(PyValueError::new_err(format!(
                "q has {} values, expected n_dof = {}",
                q.len(),
                self.inner.n_dof()
            )));
        }
        let mut out = vec![0.0; q.len()];
        let status = self.inner.step(&q, &mut out);
        self.last_status = status;
        self.counts.add(status);
        self.take_callable_error()?;
        Ok(out.into_pyarray(py))
    }

    /// Shapes a (n_samples, n_dof) array of real numbers, continuing the streaming state.
    /// Releases the GIL.
    fn shape<'py>(
        &mut self,
        py: Python<'py>,
        q: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
        let q: PyArrayLike2<'py, f64, AllowTypeChange> = convert::real_input(q, "Q")?.extract()?;
        let shape = q.shape();
        let (n, d) = (shape[0], shape[1]);
        if d != self.inner.n_dof() {
            return Err(PyValueError::new_err(format!(
                "Q has shape ({n}, {d}); expected (n_samples, {})",
                self.inner.n_dof()
            )));
        }
        // The block is copied in chunks of SHAPE_CHUNK_ROWS rows (with the interpreter lock
        // held, so no Python thread can change the array under us) and shaped with the lock
        // released. The chunk buffer stays in cache and, unlike one full-size copy, does not
        // make the allocator hand out fresh pages each call.
        let view = q.as_array();
        let contiguous = q.as_slice().ok().filter(|_| q.is_c_contiguous());
        let mut output: Vec<f64> = Vec::with_capacity(n * d);
        let mut chunk: Vec<f64> = Vec::with_capacity(SHAPE_CHUNK_ROWS.min(n) * d);
        let mut counts = self.counts;
        let mut last = Status::OK;
        let mut row = 0;
        while row < n {
            let rows = SHAPE_CHUNK_ROWS.min(n - row);
            chunk.clear();
            match contiguous {
                // Row-major order whatever the memory layout (`as_slice` alone would also
                // accept a Fortran-ordered array and hand it over in column order).
                Some(all) => chunk.extend_from_slice(&all[row * d..(row + rows) * d]),
                None => (row..row + rows).for_each(|r| chunk.extend(view.row(r).iter())),
            }
            let filled = output.len();
            output.resize(filled + rows * d, 0.0);
            let (inner, out) = (&mut self.inner, &mut output[filled..]);
            let failed = py.detach(|| {
                for (x, y) in chunk.chunks_exact(d).zip(out.chunks_exact_mut(d)) {
                    last = inner.step(x, y);
                    counts.add(last);
                    // A raising callable ends the block: its exception is re-raised below.
                    if let Provider::Callback(p) = inner.dynamics() {
                        if p.error.is_some() {
                            return true;
                        }
                    }
                }
                false
            });
            if failed {
                break;
            }
            row += rows;
        }
        self.counts = counts;
        self.last_status = last;
        self.take_callable_error()?;
        convert::array(py, &[n, d], output)
    }

    /// Replaces the map of a shaper driven by `MapDynamics` or `ModalDynamics` by `map` (a
    /// `DynamicMap` or a `ModalMap`; the same robot and payload), between moves only:
    /// before the first step, after `reset`, or once the input has not moved for longer than
    /// the longest delay the shaper can read. The next move is then shaped exactly as a new
    /// shaper with that map would shape it. A setup call (allocates). Raises `ValueError`
    /// mid-move or for a map the provider refuses (the shaper unchanged), `TypeError` for
    /// another provider or map type.
    #[pyo3(signature = (map, allow_other_robot=false))]
    fn set_map(&mut self, map: &Bound<'_, PyAny>, allow_other_robot: bool) -> PyResult<()> {
        let robot =
            match self.inner.dynamics() {
                Provider::Map(d) => d.robot().clone(),
                Provider::Modal(d) => d.robot().clone(),
                _ => return Err(PyTypeError::new_err(
                    "set_map replaces the map of a shaper driven by MapDynamics or ModalDynamics",
                )),
            };
        if !self.inner.is_at_rest() {
            return Err(PyValueError::new_err(
                "the shaper is mid-move (its delay lines are not at rest on the input); call \
                 set_map between moves",
            ));
        }
        // A Python map document (tvist.DynamicMap, tvist.ModalMap) holds its core map.
        let map = match map.getattr("core") {
            Ok(core) => core,
            Err(_) => map.clone(),
        };
        let provider = if let Ok(m) = map.cast::<robot::PyDynamicMap>() {
            let law = m.get().inner.clone();
            Provider::Map(Box::new(robot_modes::new_provider(
                robot,
                law,
                allow_other_robot,
            )?))
        } else if let Ok(m) = map.cast::<modal::PyModalMap>() {
            let law = m.get().inner.clone();
            Provider::Modal(Box::new(robot_modes::new_provider(
                robot,
                law,
                allow_other_robot,
            )?))
        } else {
            return Err(PyTypeError::new_err(
                "map must be a tvist DynamicMap or ModalMap",
            ));
        };
        self.inner
            .replace_dynamics(provider, &self.config)
            .map_err(value_error)
    }

    /// Shapes the `n_modes` lowest-frequency modes of the shaper's modal map from the next
    /// move on (frequency-ranked, as `ModalMap(..., shaped_modes=n_modes)`, whatever modes
    /// the map shaped before), one filter each: the added delay is that of those modes.
    /// `1 <= n_modes <=` the map's number of flexible joints. Between moves only, as
    /// `set_map` (a setup call). Raises `ValueError` mid-move or for `n_modes` out of range
    /// (the shaper unchanged), `TypeError` for a shaper not driven by `ModalDynamics`.
    fn set_shaped_modes(&mut self, n_modes: usize) -> PyResult<()> {
        if !matches!(self.inner.dynamics(), Provider::Modal(_)) {
            return Err(PyTypeError::new_err(
                "set_shaped_modes sets the number of shaped modes of a shaper driven by \
                 ModalDynamics (a modal map)",
            ));
        }
        if !self.inner.is_at_rest() {
            return Err(PyValueError::new_err(
                "the shaper is mid-move (its delay lines are not at rest on the input); call \
                 set_shaped_modes between moves",
            ));
        }
        self.inner.set_shaped_modes(n_modes).map_err(value_error)
    }

    /// Puts the filter at rest at q0, or (None) forgets history so the next sample starts it.
    /// Accepts what `step` accepts (any 1-D array-like of numbers, any memory layout).
    #[pyo3(signature = (q0=None))]
    fn reset(&mut self, q0: Option<&Bound<'_, PyAny>>) -> PyResult<()> {
        match q0 {
            Some(q0) => {
                let q0: PyArrayLike1<'_, f64, AllowTypeChange> =
                    convert::real_input(q0, "q0")?.extract()?;
                let q0: Vec<f64> = q0.as_array().iter().copied().collect();
                convert::check_start_pose(&q0, self.inner.n_dof())?;
                self.inner.reset(&q0);
            }
            None => self.inner.clear(),
        }
        Ok(())
    }

    /// Current total delay of the cascade (sum over modes of the last impulse time), s.
    #[getter]
    fn delay_s(&self) -> f64 {
        self.inner.delay_s()
    }

    /// Modes used in the latest cycle [(wn_rad_s, zeta), ...] (as returned by the provider).
    #[getter]
    fn current_modes(&self) -> Vec<(f64, f64)> {
        self.inner
            .current_modes()
            .iter()
            .map(|m| (m.wn_rad_s, m.zeta))
            .collect()
    }

    /// Status bits of the latest step (see tvist.Status).
    #[getter]
    fn last_status(&self) -> i32 {
        self.last_status.0
    }

    /// How many steps reported each status flag since construction.
    #[getter]
    fn status_counts(&self) -> std::collections::BTreeMap<String, u64> {
        self.counts
            .named()
            .map(|(name, count)| (name.to_ascii_lowercase(), count))
            .collect()
    }

    /// Longest delay each mode filter can hold, s.
    #[getter]
    fn max_delay_s(&self) -> Vec<f64> {
        self.inner
            .filters()
            .iter()
            .map(|f| f.max_delay_s())
            .collect()
    }

    #[getter]
    fn n_dof(&self) -> usize {
        self.inner.n_dof()
    }

    #[getter]
    fn dt_s(&self) -> f64 {
        self.inner.dt_s()
    }

    #[getter]
    fn n_modes(&self) -> usize {
        self.inner.filters().len()
    }
}

#[pymodule]
fn _core(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyImpulses>()?;
    m.add_class::<PyConstantModes>()?;
    m.add_class::<PyTvShaper>()?;
    robot::register(m)?;
    modal::register(m)?;
    m.add_function(wrap_pyfunction!(design_shaper, m)?)?;
    m.add_function(wrap_pyfunction!(convolve, m)?)?;
    m.add_function(wrap_pyfunction!(prv_flat, m)?)?;
    ztdis::register(m)?;
    m.add("SHAPERS", core::SHAPER_NAMES.to_vec())?;
    let flags = pyo3::types::PyDict::new(m.py());
    for (name, flag) in Status::FLAGS {
        flags.set_item(name, flag.0)?;
    }
    m.add("STATUS_FLAGS", flags)?;
    m.add("MAX_DOF", core::limits::MAX_DOF)?;
    m.add("MAX_MODES", core::limits::MAX_MODES)?;
    m.add("MAX_MAP_FILE_BYTES", core::limits::MAX_MAP_FILE_BYTES)?;
    m.add("MAX_DELAY_LINE_BYTES", core::limits::MAX_DELAY_LINE_BYTES)?;
    m.add(
        "MAX_LN_WN_RATE_PER_S",
        core::tv_shaper::MAX_LN_WN_RATE_PER_S,
    )?;
    m.add("MAX_ZETA_RATE_PER_S", core::tv_shaper::MAX_ZETA_RATE_PER_S)?;
    Ok(())
}
