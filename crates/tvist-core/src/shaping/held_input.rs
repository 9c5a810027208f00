//! The input stage shared by the streaming filters: the last valid input sample, held when a
//! non-finite one arrives, and whether the filter has started (seen its first sample).

use crate::error::Status;

/// Last valid input of `n` channels. Allocated once; `accept` never allocates.
#[derive(Debug, Clone)]
pub struct HeldInput {
    value: Vec<f64>,
    started: bool,
}

impl HeldInput {
    pub fn new(n: usize) -> HeldInput {
        HeldInput {
            value: vec![0.0; n],
            started: false,
        }
    }

    /// Takes one sample (`input.len()` equals the channel count, checked by the caller): a
    /// finite sample replaces the held one, a sample with any non-finite value is ignored
    /// ([`Status::INPUT_HELD`]). Returns the status and whether this is the filter's first
    /// sample since construction or [`Self::clear`] (the filter then starts at rest on it;
    /// zeros if that first sample was non-finite).
    #[inline]
    pub fn accept(&mut self, input: &[f64]) -> (Status, bool) {
        let status = if input.iter().all(|v| v.is_finite()) {
            self.value.copy_from_slice(input);
            Status::OK
        } else {
            Status::INPUT_HELD
        };
        let first = !self.started;
        self.started = true;
        (status, first)
    }

    /// [`Self::accept`] for exactly `N` channels, also returning the held sample after it (a
    /// held sample of another length is kept, and zeros are returned).
    #[inline]
    pub fn accept_fixed<const N: usize>(&mut self, input: &[f64; N]) -> ([f64; N], Status, bool) {
        // Every value is checked (no early exit), so the check runs on whole vectors.
        let finite = input.iter().fold(true, |all, v| all & v.is_finite());
        let held = <&mut [f64; N]>::try_from(self.value.as_mut_slice());
        let status = if finite {
            Status::OK
        } else {
            Status::INPUT_HELD
        };
        let value = match held {
            Ok(value) => {
                if finite {
                    *value = *input;
                }
                *value
            }
            Err(_) => [0.0; N],
        };
        let first = !self.started;
        self.started = true;
        (value, status, first)
    }

    /// Whether `input` would change the held sample: the filter has started, every value of
    /// `input` is finite and one differs from the held one (bit for bit).
    #[inline]
    pub fn moves(&self, input: &[f64]) -> bool {
        self.started
            && input.iter().fold(true, |all, v| all & v.is_finite())
            && input
                .iter()
                .zip(&self.value)
                .any(|(a, b)| a.to_bits() != b.to_bits())
    }

    /// Sets the held sample to `x0` (non-finite entries taken as 0) and marks the filter
    /// started.
    pub fn set(&mut self, x0: &[f64]) {
        for (dst, &src) in self.value.iter_mut().zip(x0) {
            *dst = if src.is_finite() { src } else { 0.0 };
        }
        self.started = true;
    }

    /// The next accepted sample is a first sample again.
    pub fn clear(&mut self) {
        self.started = false;
    }

    /// Whether a sample has been taken (or set) since construction or [`Self::clear`].
    #[inline]
    pub fn started(&self) -> bool {
        self.started
    }

    /// The held sample.
    #[inline]
    pub fn value(&self) -> &[f64] {
        &self.value
    }
}
