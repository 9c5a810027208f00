//! Multi-channel circular delay line with fractional-delay (Lagrange FIR) reads.
//!
//! The buffer is allocated once in [`DelayLine::new`]; `push` and `accumulate` never allocate,
//! and every read index is reduced modulo the capacity, so no read can leave the buffer.

use crate::error::Error;

/// Fractional-delay interpolation: Lagrange order 1 (`Linear`, default) or 3 (`Cubic`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Interpolation {
    #[default]
    Linear,
    Cubic,
}

impl Interpolation {
    pub fn from_name(name: &str) -> Result<Interpolation, Error> {
        match name {
            "linear" => Ok(Interpolation::Linear),
            "cubic" => Ok(Interpolation::Cubic),
            other => Err(Error::UnknownInterpolation(other.to_string())),
        }
    }

    /// Samples the stencil reaches beyond `floor(delay)`.
    fn reach(self) -> usize {
        match self {
            Interpolation::Linear => 1,
            Interpolation::Cubic => 2,
        }
    }
}

/// Circular buffer of the last `capacity` samples of `n_channels` signals.
///
/// Layout: sample-major (`buf[slot * n_channels + channel]`). `head` is the slot of the newest
/// sample ("age 0"); the sample pushed `k` cycles earlier has age `k`.
#[derive(Debug, Clone)]
pub struct DelayLine {
    n_channels: usize,
    capacity: usize,
    head: usize,
    interp: Interpolation,
    buf: Vec<f64>,
}

impl DelayLine {
    /// A line able to read any delay in `[0, max_delay_samples]` with the given interpolation.
    pub fn new(
        n_channels: usize,
        max_delay_samples: f64,
        interp: Interpolation,
    ) -> Result<DelayLine, Error> {
        if n_channels == 0 {
            return Err(Error::InvalidParameter("n_dof must be at least 1".into()));
        }
        if !(max_delay_samples.is_finite() && max_delay_samples >= 0.0) {
            return Err(Error::InvalidParameter(format!(
                "maximum delay {max_delay_samples} samples must be finite and >= 0"
            )));
        }
        if max_delay_samples > 1e7 {
            return Err(Error::InvalidParameter(format!(
                "maximum delay of {max_delay_samples:.0} samples is unreasonably long (> 1e7)"
            )));
        }
        // ceil(max) + reach + 1 slots: the farthest stencil point of the longest delay is
        // age floor(max) + reach <= capacity - 1.
        let capacity = max_delay_samples.ceil() as usize + interp.reach() + 1;
        Ok(DelayLine {
            n_channels,
            capacity,
            head: 0,
            interp,
            buf: vec![0.0; capacity * n_channels],
        })
    }

    pub fn n_channels(&self) -> usize {
        self.n_channels
    }

    /// Number of stored samples.
    pub fn capacity(&self) -> usize {
        self.capacity
    }

    /// The longest delay (in samples) that can be read without clamping.
    pub fn max_delay_samples(&self) -> f64 {
        (self.capacity - 1 - self.interp.reach()) as f64
    }

    /// Sets every stored sample to `x` (the signal has been at rest at `x` forever).
    /// `x.len()` must equal `n_channels` (extra values are ignored, missing ones leave zeros).
    pub fn fill(&mut self, x: &[f64]) {
        for slot in self.buf.chunks_exact_mut(self.n_channels) {
            for (dst, &src) in slot.iter_mut().zip(x) {
                *dst = src;
            }
        }
    }

    /// Appends one sample (all channels), overwriting the oldest.
    #[inline]
    pub fn push(&mut self, x: &[f64]) {
        self.head += 1;
        if self.head >= self.capacity {
            self.head = 0;
        }
        let start = self.head * self.n_channels;
        if let Some(slot) = self.buf.get_mut(start..start + self.n_channels) {
            for (dst, &src) in slot.iter_mut().zip(x) {
                *dst = src;
            }
        }
    }

    /// Adds `weight · x(n − delay)` to `out` for every channel. `delay` is in samples and is
    /// clamped to `[0, max_delay_samples]`; returns `true` if it had to be clamped.
    #[inline]
    pub fn accumulate(&self, delay: f64, weight: f64, out: &mut [f64]) -> bool {
        let max = self.max_delay_samples();
        let clamped = !(delay <= max); // also catches NaN
        let d = if clamped { max } else { delay.max(0.0) };
        let k = d.floor();
        let mu = d - k;
        let k = k as usize;
        match self.interp {
            Interpolation::Linear => {
                self.add_sample(k, weight * (1.0 - mu), out);
                if mu != 0.0 {
                    self.add_sample(k + 1, weight * mu, out);
                }
            }
            Interpolation::Cubic => {
                // Nodes at ages base..base+3, evaluated at x = d − base ∈ [0, 2).
                let base = k.saturating_sub(1);
                let x = d - base as f64;
                let l = [
                    -(x - 1.0) * (x - 2.0) * (x - 3.0) / 6.0,
                    x * (x - 2.0) * (x - 3.0) / 2.0,
                    -x * (x - 1.0) * (x - 3.0) / 2.0,
                    x * (x - 1.0) * (x - 2.0) / 6.0,
                ];
                for (j, lj) in l.iter().enumerate() {
                    if *lj != 0.0 {
                        self.add_sample(base + j, weight * lj, out);
                    }
                }
            }
        }
        clamped
    }

    /// `out += w · sample(age)`. `age < capacity` is guaranteed by the clamping in
    /// `accumulate`; an older age would still give an in-bounds slot (and `get` checks).
    #[inline]
    fn add_sample(&self, age: usize, w: f64, out: &mut [f64]) {
        debug_assert!(age < self.capacity);
        let slot = if age <= self.head {
            self.head - age
        } else {
            (self.head + self.capacity).saturating_sub(age)
        };
        let start = slot * self.n_channels;
        if let Some(s) = self.buf.get(start..start + self.n_channels) {
            for (o, &v) in out.iter_mut().zip(s) {
                *o += w * v;
            }
        }
    }
}
