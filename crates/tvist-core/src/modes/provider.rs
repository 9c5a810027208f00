//! [`Provider`]: every built-in [`Dynamics`] provider in one type, for the bindings.

use crate::error::Status;
use crate::modes::dynamics::{ConstantModes, Dynamics};
use crate::modes::modal::mass_matrix_law::ModalDynamics;
use crate::modes::paper10::joint_inertia_law::MapDynamics;
use crate::shaping::shapers::Mode;

/// Every kind of provider the bindings offer, in one type: fixed modes, a dynamic map, a modal
/// map, or a
/// binding-specific callback `C` (the Python bindings call a Python function; the C API has
/// none and uses [`NoCallback`]). A new provider kind is one more variant here.
#[derive(Debug)]
pub enum Provider<C = NoCallback> {
    Constant(ConstantModes),
    Map(Box<MapDynamics>),
    Modal(Box<ModalDynamics>),
    Callback(C),
}

/// A callback type that has no values: [`Provider`] without its callback variant.
#[derive(Debug, Clone, Copy)]
pub enum NoCallback {}

impl Dynamics for NoCallback {
    fn n_modes(&self) -> usize {
        match *self {}
    }
    fn modes(&mut self, _q: &[f64], _out: &mut [Mode]) -> Status {
        match *self {}
    }
    fn slowest_mode(&self, _index: usize) -> Option<Mode> {
        match *self {}
    }
}

impl<C: Dynamics> Dynamics for Provider<C> {
    fn n_modes(&self) -> usize {
        match self {
            Provider::Constant(p) => p.n_modes(),
            Provider::Map(p) => p.n_modes(),
            Provider::Modal(p) => p.n_modes(),
            Provider::Callback(p) => p.n_modes(),
        }
    }
    #[inline]
    fn modes(&mut self, q: &[f64], out: &mut [Mode]) -> Status {
        match self {
            Provider::Constant(p) => p.modes(q, out),
            Provider::Map(p) => p.modes(q, out),
            Provider::Modal(p) => p.modes(q, out),
            Provider::Callback(p) => p.modes(q, out),
        }
    }
    fn slowest_mode(&self, index: usize) -> Option<Mode> {
        match self {
            Provider::Constant(p) => p.slowest_mode(index),
            Provider::Map(p) => p.slowest_mode(index),
            Provider::Modal(p) => p.slowest_mode(index),
            Provider::Callback(p) => p.slowest_mode(index),
        }
    }
    fn n_dof(&self) -> Option<usize> {
        match self {
            Provider::Constant(p) => p.n_dof(),
            Provider::Map(p) => p.n_dof(),
            Provider::Modal(p) => p.n_dof(),
            Provider::Callback(p) => p.n_dof(),
        }
    }
    fn restart(&mut self) {
        match self {
            Provider::Constant(p) => p.restart(),
            Provider::Map(p) => p.restart(),
            Provider::Modal(p) => p.restart(),
            Provider::Callback(p) => p.restart(),
        }
    }
    #[inline]
    fn modes_are_constant(&self) -> bool {
        match self {
            Provider::Constant(p) => p.modes_are_constant(),
            Provider::Map(p) => p.modes_are_constant(),
            Provider::Modal(p) => p.modes_are_constant(),
            Provider::Callback(p) => p.modes_are_constant(),
        }
    }
}
