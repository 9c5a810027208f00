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
        let capacity = Self::capacity_for(max_delay_samples, interp)?;
        Ok(DelayLine {
            n_channels,
            capacity,
            head: 0,
            interp,
            buf: vec![0.0; capacity * n_channels],
        })
    }

    /// Slots of a line that reads delays up to `max_delay_samples` (finite, `>= 0`).
    pub fn capacity_for(max_delay_samples: f64, interp: Interpolation) -> Result<usize, Error> {
        if max_delay_samples > 1e7 {
            return Err(Error::InvalidParameter(format!(
                "maximum delay of {max_delay_samples:.0} samples is unreasonably long (> 1e7)"
            )));
        }
        // ceil(max) + reach + 1 slots: the farthest stencil point of the longest delay is
        // age floor(max) + reach <= capacity - 1.
        Ok(max_delay_samples.ceil() as usize + interp.reach() + 1)
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
        let clamped = delay.is_nan() || delay > max;
        let d = if clamped { max } else { delay.max(0.0) };
        // d ∈ [0, max]: truncation is the floor and the cast cannot overflow.
        let k = d as usize;
        match self.interp {
            Interpolation::Linear => {
                let mu = d - k as f64;
                // Ages k and k + 1 <= floor(max) + 1 = capacity − 1.
                self.add_two(k, [weight * (1.0 - mu), weight * mu], out);
            }
            Interpolation::Cubic => {
                // Nodes at ages base..base+3 (<= floor(max) + 2 = capacity − 1), evaluated at
                // x = d − base: centred (x ∈ [1, 2)) except for delays below one sample.
                let base = k.saturating_sub(1);
                let x = d - base as f64;
                let l = [
                    -(x - 1.0) * (x - 2.0) * (x - 3.0) / 6.0,
                    x * (x - 2.0) * (x - 3.0) / 2.0,
                    -x * (x - 1.0) * (x - 3.0) / 2.0,
                    x * (x - 1.0) * (x - 2.0) / 6.0,
                ];
                self.add_four(base, l.map(|lj| weight * lj), out);
            }
        }
        clamped
    }

    /// Slot of the sample of age `age` (`age < capacity`, guaranteed by the clamping in
    /// `accumulate`; an older age still gives an in-bounds slot).
    #[inline]
    fn slot(&self, age: usize) -> usize {
        debug_assert!(age < self.capacity);
        if age <= self.head {
            self.head - age
        } else {
            (self.head + self.capacity).saturating_sub(age)
        }
    }

    /// The stored sample (all channels) of age `age`; empty only if the invariants broke.
    #[inline]
    fn row(&self, age: usize) -> &[f64] {
        let start = self.slot(age) * self.n_channels;
        self.buf.get(start..start + self.n_channels).unwrap_or(&[])
    }

    /// `out += w0 · sample(age) + w1 · sample(age + 1)` over all channels, in one pass.
    #[inline]
    fn add_two(&self, age: usize, [w0, w1]: [f64; 2], out: &mut [f64]) {
        let (r0, r1) = (self.row(age), self.row(age + 1));
        // Equal-length views: the loop below has no bounds checks and vectorizes.
        let n = out.len().min(r0.len()).min(r1.len());
        let (out, r0, r1) = (&mut out[..n], &r0[..n], &r1[..n]);
        for i in 0..n {
            out[i] += w0 * r0[i] + w1 * r1[i];
        }
    }

    /// `out += Σ_{j<4} w_j · sample(age + j)` over all channels, in one pass.
    #[inline]
    fn add_four(&self, age: usize, [w0, w1, w2, w3]: [f64; 4], out: &mut [f64]) {
        let (r0, r1, r2, r3) = (
            self.row(age),
            self.row(age + 1),
            self.row(age + 2),
            self.row(age + 3),
        );
        let n = out
            .len()
            .min(r0.len())
            .min(r1.len())
            .min(r2.len())
            .min(r3.len());
        let (out, r0, r1, r2, r3) = (&mut out[..n], &r0[..n], &r1[..n], &r2[..n], &r3[..n]);
        for i in 0..n {
            out[i] += (w0 * r0[i] + w1 * r1[i]) + (w2 * r2[i] + w3 * r3[i]);
        }
    }
}
