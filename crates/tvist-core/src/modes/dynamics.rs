//! The [`Dynamics`] provider trait (where a time-varying shaper gets its modes from each
//! cycle) and the provider of constant modes.

use crate::error::{Error, Status};
use crate::shaping::shapers::Mode;

/// Supplies the modes `(ω_n, ζ)` to shape for, given the configuration `q` (the previous
/// final shaped output, `q**_{n−1}`).
///
/// `modes` runs in the real-time path: implementations must not allocate, lock or panic.
/// Invalid modes may be written (the filter then holds its last valid mode); a provider may
/// also report its own status bits.
pub trait Dynamics {
    /// Number of modes (one cascaded filter each), fixed for the provider's lifetime.
    fn n_modes(&self) -> usize;

    /// Writes `n_modes()` modes for configuration `q` into `out`.
    fn modes(&mut self, q: &[f64], out: &mut [Mode]) -> Status;

    /// For sizing delay lines: the slowest mode `index` can be (lowest `ω_n`, with the highest
    /// `ζ` it can take), or `None` if unknown.
    fn slowest_mode(&self, index: usize) -> Option<Mode>;

    /// The number of joints the provider expects in `q`, if it cares.
    fn n_dof(&self) -> Option<usize> {
        None
    }

    /// Forgets whatever the provider carries from one call to the next (a modal map: the
    /// eigenmode each shaped mode follows), so that the next call chooses as at a first one.
    /// The shaper calls it at a start or reset and whenever it has come to rest, where a new
    /// choice cannot change its output. Allocation-free.
    fn restart(&mut self) {}

    /// `true` if [`Self::modes`] writes the same valid modes every call, whatever `q`, and
    /// reports no status: a shaper then asks once after each start or reset and reuses them.
    fn modes_are_constant(&self) -> bool {
        false
    }
}

/// Fixed modes, independent of the configuration (time-invariant multi-mode shaping).
#[derive(Debug, Clone, PartialEq)]
pub struct ConstantModes {
    modes: Vec<Mode>,
}

impl ConstantModes {
    /// Validates every mode (finite, `ω_n > 0`, `0 <= ζ < 1`); at least one is required, at
    /// most [`crate::limits::MAX_MODES`].
    pub fn new(modes: Vec<Mode>) -> Result<ConstantModes, Error> {
        if modes.is_empty() {
            return Err(Error::InvalidParameter(
                "at least one mode is required".into(),
            ));
        }
        crate::limits::check_n_modes(modes.len(), "a constant-mode provider")?;
        for (i, m) in modes.iter().enumerate() {
            m.validate(i)?;
        }
        Ok(ConstantModes { modes })
    }

    pub fn modes_list(&self) -> &[Mode] {
        &self.modes
    }
}

impl Dynamics for ConstantModes {
    fn n_modes(&self) -> usize {
        self.modes.len()
    }

    fn modes(&mut self, _q: &[f64], out: &mut [Mode]) -> Status {
        for (o, m) in out.iter_mut().zip(&self.modes) {
            *o = *m;
        }
        Status::OK
    }

    fn slowest_mode(&self, index: usize) -> Option<Mode> {
        self.modes.get(index).copied()
    }

    fn modes_are_constant(&self) -> bool {
        true // validated in `new` and never changed
    }
}

impl<D: Dynamics + ?Sized> Dynamics for Box<D> {
    fn n_modes(&self) -> usize {
        (**self).n_modes()
    }
    fn modes(&mut self, q: &[f64], out: &mut [Mode]) -> Status {
        (**self).modes(q, out)
    }
    fn slowest_mode(&self, index: usize) -> Option<Mode> {
        (**self).slowest_mode(index)
    }
    fn n_dof(&self) -> Option<usize> {
        (**self).n_dof()
    }
    fn restart(&mut self) {
        (**self).restart()
    }
    fn modes_are_constant(&self) -> bool {
        (**self).modes_are_constant()
    }
}
