//! Binding of the multi-mode time-varying shaper (streaming and batch).

use numpy::{
    AllowTypeChange, IntoPyArray, PyArray1, PyArrayDyn, PyArrayLike1, PyArrayLike2,
    PyUntypedArrayMethods,
};
use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;
use tvist_core as core;
use tvist_core::{Status, StatusCounter};

use crate::convert::{self, value_error};
use crate::providers::{CallableModes, Provider, PyConstantModes};
use crate::{modal, paper10, robot_law};

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
        } else if let Ok(m) = dynamics.cast::<paper10::PyMapDynamics>() {
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
        let provider = if let Ok(m) = map.cast::<paper10::PyDynamicMap>() {
            let law = m.get().inner.clone();
            Provider::Map(Box::new(robot_law::new_provider(
                robot,
                law,
                allow_other_robot,
            )?))
        } else if let Ok(m) = map.cast::<modal::PyModalMap>() {
            let law = m.get().inner.clone();
            Provider::Modal(Box::new(robot_law::new_provider(
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

    /// Shapes with the modes the shaper's map gives at `q` (the robot's joints, rad), held
    /// constant, from the next move on; `q=None` follows the pose of every cycle again.
    /// `set_shaped_modes` and `set_map` also end a hold. For a move whose time-varying
    /// shaping leaves more ringing than its end pose's modes would (see
    /// `tvist.maps.set_modes_for_move`): pass the move's end pose. Between moves only, as
    /// `set_map` (a setup call). Raises `ValueError` mid-move, for a pose of the wrong length
    /// or one where the map gives an invalid mode (the shaper unchanged), `TypeError` for a
    /// shaper not driven by `MapDynamics` or `ModalDynamics`.
    #[pyo3(signature = (q=None))]
    fn hold_modes_at(&mut self, q: Option<&Bound<'_, PyAny>>) -> PyResult<()> {
        if !matches!(self.inner.dynamics(), Provider::Map(_) | Provider::Modal(_)) {
            return Err(PyTypeError::new_err(
                "hold_modes_at holds the modes of a shaper driven by MapDynamics or \
                 ModalDynamics",
            ));
        }
        let pose = match q {
            Some(q) => {
                let q: PyArrayLike1<'_, f64, AllowTypeChange> =
                    convert::real_input(q, "q")?.extract()?;
                let q: Vec<f64> = q.as_array().iter().copied().collect();
                convert::check_start_pose(&q, self.inner.n_dof())?;
                Some(q)
            }
            None => None,
        };
        self.inner
            .hold_modes_at(pose.as_deref())
            .map_err(value_error)
    }

    /// The pose whose modes the shaper holds (`hold_modes_at`), or `None`.
    #[getter]
    fn held_pose(&self) -> Option<Vec<f64>> {
        match self.inner.dynamics() {
            Provider::Map(d) => d.held_pose().map(<[f64]>::to_vec),
            Provider::Modal(d) => d.held_pose().map(<[f64]>::to_vec),
            _ => None,
        }
    }

    /// A new shaper with this one's configuration and provider as they are now (map, shaped
    /// modes, hold), not yet started: to try a move without touching this shaper's state.
    /// Raises `TypeError` for a shaper driven by a Python callable.
    fn fresh_copy(&self) -> PyResult<Self> {
        let provider = match self.inner.dynamics() {
            Provider::Constant(c) => Provider::Constant(c.clone()),
            Provider::Map(d) => Provider::Map(d.clone()),
            Provider::Modal(d) => Provider::Modal(d.clone()),
            Provider::Callback(_) => {
                return Err(PyTypeError::new_err(
                    "fresh_copy copies a shaper driven by a tvist provider, not a callable",
                ))
            }
        };
        let mut inner = core::TvShaper::new(provider, &self.config).map_err(value_error)?;
        inner.clear();
        Ok(PyTvShaper {
            inner,
            config: self.config.clone(),
            last_status: Status::OK,
            counts: StatusCounter::default(),
        })
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

/// Registers the class of this module, the shaper's limits on how fast modes may change and
/// the distance from its input within which it counts as at rest.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyTvShaper>()?;
    m.add(
        "MAX_LN_WN_RATE_PER_S",
        core::tv_shaper::MAX_LN_WN_RATE_PER_S,
    )?;
    m.add("MAX_ZETA_RATE_PER_S", core::tv_shaper::MAX_ZETA_RATE_PER_S)?;
    m.add("REST_TOLERANCE", core::tv_shaper::REST_TOLERANCE)?;
    Ok(())
}
