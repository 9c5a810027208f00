//! Multi-channel circular delay line with fractional-delay (Lagrange FIR) reads.
//!
//! The buffer is allocated once in [`DelayLine::new`]; `push` and `accumulate` never allocate,
//! and every read index is reduced modulo the capacity, so no read can leave the buffer.

use crate::error::Error;
use crate::shaping::shapers::MAX_IMPULSES;

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

/// A fractional read prepared once for a delay that stays fixed over many cycles: the
/// stencil's position relative to the newest sample and its weights, oldest sample first.
/// Made by [`DelayLine::tap`]; read by [`DelayLine::read_taps`] (the cubic form of [`Reads`]).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Tap {
    /// `capacity − age of the oldest stencil sample`, in `[1, capacity]`: the stencil's first
    /// slot is `head + lag` in the mirrored buffer.
    lag: usize,
    /// Weights of the stencil's samples, oldest first (linear: the first two are used).
    weights: [f64; 4],
}

/// The prepared reads of one impulse sequence for one line ([`DelayLine::prepare`]): what a
/// cycle whose sequence is unchanged reads, with no per-impulse arithmetic left.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Reads {
    /// Linear: the weight of the newest sample (applied to the input). Cubic: 0.
    now: f64,
    /// Entries of `pairs` (linear) or `taps` (cubic) in use, `<= MAX_IMPULSES`.
    len: usize,
    /// Linear: two-sample stencils of the samples stored before the cycle's push.
    pairs: [Pair; MAX_IMPULSES],
    /// Cubic: four-sample stencils of the samples stored after the push.
    taps: [Tap; MAX_IMPULSES],
    /// Linear, when `whole_len` is the number of `pairs`: the whole-sample part `k` of each
    /// pair's delay, one pair per delayed impulse of the set they were prepared from, every
    /// `k` in `[1, max_delay_samples)` and no delay clamped. A new scale whose delays keep
    /// their whole-sample parts then only re-splits the fraction ([`DelayLine::prepare`]).
    whole: [f64; MAX_IMPULSES],
    /// `len` when `whole` describes `pairs` as above; `usize::MAX` otherwise.
    whole_len: usize,
}

/// A linear stencil read before the push: `w_old · x(age j) + w_new · x(age j − 1)` in ages
/// before the push, `j = capacity − lag`, `lag ∈ [1, capacity − 1]` (so `j >= 1`): the two
/// samples are slots `head + lag` and `head + lag + 1` of the mirrored buffer.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Pair {
    lag: usize,
    w_old: f64,
    w_new: f64,
}

impl Reads {
    /// No reads: a line read through them gives zeros.
    pub const NONE: Reads = Reads {
        now: 0.0,
        len: 0,
        pairs: [Pair {
            lag: 1,
            w_old: 0.0,
            w_new: 0.0,
        }; MAX_IMPULSES],
        taps: [Tap {
            lag: 1,
            weights: [0.0; 4],
        }; MAX_IMPULSES],
        whole: [0.0; MAX_IMPULSES],
        whole_len: usize::MAX,
    };

    #[inline]
    fn pairs(&self) -> &[Pair] {
        self.pairs.get(..self.len).unwrap_or(&[])
    }

    #[inline]
    fn taps(&self) -> &[Tap] {
        self.taps.get(..self.len).unwrap_or(&[])
    }
}

/// An impulse sequence as [`DelayLine::prepare`] reads it: `weights[i] · x(n − delays[i] ·
/// scale)`, made once per sequence (its leading impulses at delay 0, such as every shaper's
/// first, counted and summed, the others stored from index 0), so that a cycle that only
/// rescales the delays does no per-impulse setup.
///
/// Invariants: `undelayed + n_delayed <= MAX_IMPULSES`; `now` is the first `undelayed`
/// entries of `undelayed_weights` summed in order (from 0); entries past the counts are unused.
#[derive(Debug, Clone, PartialEq)]
pub struct Sequence {
    now: f64,
    undelayed: usize,
    undelayed_weights: [f64; MAX_IMPULSES],
    n_delayed: usize,
    delays: [f64; MAX_IMPULSES],
    weights: [f64; MAX_IMPULSES],
}

impl Sequence {
    /// One impulse of weight 1 at delay 0: the reads pass the input through.
    pub const IDENTITY: Sequence = Sequence {
        now: 1.0,
        undelayed: 1,
        undelayed_weights: [1.0, 0.0, 0.0, 0.0, 0.0],
        n_delayed: 0,
        delays: [0.0; MAX_IMPULSES],
        weights: [0.0; MAX_IMPULSES],
    };

    /// The sequence `weights[i]` at `delays[i] · delay_scale` (entries past
    /// [`MAX_IMPULSES`] or past the shorter slice are ignored).
    pub fn new(delays: &[f64], weights: &[f64], delay_scale: f64) -> Sequence {
        let mut sequence = Sequence::IDENTITY;
        sequence.assign(delays, weights, delay_scale);
        sequence
    }

    /// Makes this [`Self::new`]`(delays, weights, delay_scale)` in place.
    #[inline]
    pub fn assign(&mut self, delays: &[f64], weights: &[f64], delay_scale: f64) {
        let len = delays.len().min(weights.len()).min(MAX_IMPULSES);
        let (delays, weights) = (&delays[..len], &weights[..len]);
        let undelayed = delays.iter().take_while(|&&t| t == 0.0).count();
        let (now_weights, delayed_weights) = weights.split_at(undelayed);
        // Every slot, zero past the undelayed ones: a fixed count, unrolled (a copy of a
        // length known only now would be a library call).
        self.now = 0.0;
        for (i, slot) in self.undelayed_weights.iter_mut().enumerate() {
            *slot = now_weights.get(i).copied().unwrap_or(0.0);
            if i < undelayed {
                self.now += *slot;
            }
        }
        self.undelayed = undelayed;
        for ((st, sw), (&t, &w)) in self
            .delays
            .iter_mut()
            .zip(self.weights.iter_mut())
            .zip(delays[undelayed..].iter().zip(delayed_weights))
        {
            *st = t * delay_scale;
            *sw = w;
        }
        self.n_delayed = len - undelayed;
    }

    /// [`Self::assign`] for `N` impulses of which only the first has delay 0 (`delays[0] == 0`
    /// and every other delay `> 0`, as in every closed-form shaper, [`crate::shaping::shapers`]), whose
    /// first weight is not `−0.0`: the same sequence (`now` is the first weight, as `0 + w`
    /// is), with nothing left to count or to test at run time.
    #[inline(always)]
    pub(crate) fn assign_first_undelayed<const N: usize>(
        &mut self,
        delays: &[f64; N],
        weights: &[f64; N],
        delay_scale: f64,
    ) {
        let now = weights.first().copied().unwrap_or(0.0);
        self.now = now;
        self.undelayed = 1;
        self.undelayed_weights = [now, 0.0, 0.0, 0.0, 0.0];
        for ((st, sw), (&t, &w)) in self
            .delays
            .iter_mut()
            .zip(self.weights.iter_mut())
            .zip(delays.iter().zip(weights).skip(1))
        {
            *st = t * delay_scale;
            *sw = w;
        }
        self.n_delayed = N.saturating_sub(1).min(MAX_IMPULSES);
    }

    /// Every impulse `(delay, weight)`, in order.
    #[inline(always)]
    fn all(&self) -> impl Iterator<Item = (&f64, &f64)> {
        let undelayed = self.undelayed.min(MAX_IMPULSES);
        core::iter::repeat(&0.0)
            .zip(&self.undelayed_weights[..undelayed])
            .chain(self.delayed())
    }

    /// The impulses after the leading undelayed ones `(delay, weight)`, in order.
    #[inline(always)]
    fn delayed(&self) -> impl Iterator<Item = (&f64, &f64)> {
        let n = self.n_delayed.min(MAX_IMPULSES);
        self.delays[..n].iter().zip(&self.weights[..n])
    }

    /// Number of impulses after the leading undelayed ones.
    #[inline(always)]
    fn n_delayed(&self) -> usize {
        self.n_delayed
    }
}

/// Circular buffer of the last `capacity` samples of `n_channels` signals.
///
/// Layout: sample-major, mirrored: slot `s` and slot `s + capacity` hold the same sample
/// (`buf[slot * n_channels + channel]`, `2 · capacity` slots), so every stencil of consecutive
/// ages is one contiguous block, read without wrapping. `head` (in `[0, capacity)`) is the
/// slot of the newest sample ("age 0"); the sample pushed `k` cycles earlier has age `k` and
/// lives in slot `head + capacity − k` (and its mirror).
#[derive(Debug, Clone)]
pub struct DelayLine {
    n_channels: usize,
    capacity: usize,
    /// `capacity − 1 − reach`: the longest delay readable without clamping, samples.
    max_delay: f64,
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
            max_delay: (capacity - 1 - interp.reach()) as f64,
            head: 0,
            interp,
            buf: vec![0.0; 2 * capacity * n_channels],
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

    /// Bytes of sample storage a line of `n_channels` able to delay by `max_delay_samples`
    /// allocates (every slot is stored twice, see the buffer layout); `None` on overflow.
    pub fn bytes_for(
        max_delay_samples: f64,
        interp: Interpolation,
        n_channels: usize,
    ) -> Result<Option<usize>, Error> {
        let slots = Self::capacity_for(max_delay_samples, interp)?;
        Ok(slots
            .checked_mul(n_channels)
            .and_then(|values| values.checked_mul(2 * core::mem::size_of::<f64>())))
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
        self.max_delay
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

    /// Whether every stored sample (all slots and their mirrors) is within `tolerance` of `x`
    /// (per channel): the signal has stayed at `x` for the whole line. Setup-time check,
    /// O(capacity).
    pub fn stays_near(&self, x: &[f64], tolerance: f64) -> bool {
        x.len() == self.n_channels
            && self
                .buf
                .chunks_exact(self.n_channels)
                .all(|slot| slot.iter().zip(x).all(|(a, b)| (a - b).abs() <= tolerance))
    }

    /// Appends one sample (all channels), overwriting the oldest.
    #[inline]
    pub fn push(&mut self, x: &[f64]) {
        self.head += 1;
        if self.head >= self.capacity {
            self.head = 0;
        }
        let n = self.n_channels;
        let (first, second) = (self.head * n, (self.head + self.capacity) * n);
        if let Some(slot) = self.buf.get_mut(first..first + n) {
            for (dst, &src) in slot.iter_mut().zip(x) {
                *dst = src;
            }
        }
        if let Some(slot) = self.buf.get_mut(second..second + n) {
            for (dst, &src) in slot.iter_mut().zip(x) {
                *dst = src;
            }
        }
    }

    /// The read of `weight · x(n − delay)`, prepared: `delay` is in samples and is clamped to
    /// `[0, max_delay_samples]`; the flag is `true` if it had to be clamped.
    #[inline]
    pub fn tap(&self, delay: f64, weight: f64) -> (Tap, bool) {
        let max = self.max_delay_samples();
        let clamped = delay.is_nan() || delay > max;
        let d = if clamped { max } else { delay.max(0.0) };
        // d ∈ [0, max]: truncation is the floor and the cast cannot overflow.
        let k = d as usize;
        let tap = match self.interp {
            Interpolation::Linear => {
                let mu = d - k as f64;
                // Ages k + 1 (oldest, <= floor(max) + 1 = capacity − 1) and k.
                Tap {
                    lag: self.capacity - (k + 1),
                    weights: [weight * mu, weight * (1.0 - mu), 0.0, 0.0],
                }
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
                Tap {
                    lag: self.capacity - (base + 3),
                    weights: [weight * l[3], weight * l[2], weight * l[1], weight * l[0]],
                }
            }
        };
        (tap, clamped)
    }

    /// Prepares the reads of the impulse sequence `set` with its delays multiplied by `scale`
    /// (`weights[i] · x(n − delays[i] · scale)`, in samples, each clamped as in
    /// [`Self::tap`]) into `reads`, for [`Self::push_and_read`]. Returns `true` if any delay
    /// had to be clamped.
    ///
    /// Linear reads are split by the samples they need: the weight of the newest sample (the
    /// set's undelayed impulses, such as every shaper's first, and any stencil ending at age
    /// 0) is applied to the input itself, and the other stencils read samples stored before
    /// the push, so no read waits for the store of the same cycle. A stencil whose stored
    /// weight is zero (a whole-sample delay below one sample) is left out.
    ///
    /// Linear reads whose delays keep their whole-sample parts (see [`Reads`]) only have their
    /// weights re-split, with the same arithmetic as a fresh preparation, so the result is
    /// the same to the bit.
    #[inline(always)]
    pub fn prepare(&self, set: &Sequence, scale: f64, reads: &mut Reads) -> bool {
        // Linear reads only (`whole_len` is usize::MAX for cubic ones).
        if reads.whole_len == set.n_delayed() && Self::resplit(set, scale, reads) {
            return false;
        }
        self.prepare_fresh(set, scale, reads)
    }

    /// [`Self::prepare`] from scratch: every read split and placed again. Out of line: when
    /// modes drift, nearly every cycle re-splits instead, and that path stays small.
    #[inline(never)]
    fn prepare_fresh(&self, set: &Sequence, scale: f64, reads: &mut Reads) -> bool {
        let mut clamped = false;
        let mut len = 0;
        match self.interp {
            Interpolation::Linear => {
                let max = self.max_delay;
                let mut now = set.now;
                // Whether every delayed impulse gets its own pair with k in [1, max).
                let mut whole = true;
                for (&t, &w) in set.delayed() {
                    let delay = t * scale;
                    // NaN and delays beyond `max` read at `max`, negative ones at 0.
                    let within = delay <= max;
                    clamped |= !within;
                    let d = if within { delay } else { max };
                    let d = if d > 0.0 { d } else { 0.0 };
                    // d ∈ [0, max] with max < 1e7 (capacity_for): truncation is the floor.
                    let k = d as i64;
                    let k_f64 = k as f64;
                    let mu = d - k_f64;
                    let (w_old, w_new) = (w * mu, w * (1.0 - mu));
                    whole &= within && k >= 1 && k_f64 < max;
                    // Ages k + 1 and k now are ages k and k − 1 before the push; age 0 now is
                    // the input.
                    let pair = if k == 0 {
                        now += w_new;
                        if w_old == 0.0 {
                            continue;
                        }
                        Pair {
                            lag: self.capacity - 1,
                            w_old: 0.0,
                            w_new: w_old,
                        }
                    } else {
                        // k <= floor(max) = capacity − 2.
                        Pair {
                            lag: self.capacity - k as usize,
                            w_old,
                            w_new,
                        }
                    };
                    if let (Some(slot), Some(k_slot)) =
                        (reads.pairs.get_mut(len), reads.whole.get_mut(len))
                    {
                        *slot = pair;
                        *k_slot = k_f64;
                        len += 1;
                    }
                }
                reads.now = now;
                reads.whole_len = if whole { len } else { usize::MAX };
            }
            Interpolation::Cubic => {
                for ((&t, &w), tap) in set.all().zip(&mut reads.taps) {
                    let (prepared, over) = self.tap(t * scale, w);
                    *tap = prepared;
                    clamped |= over;
                    len += 1;
                }
                reads.now = 0.0;
                reads.whole_len = usize::MAX;
            }
        }
        reads.len = len;
        clamped
    }

    /// The linear reads of `set` at `scale` if every delay keeps the whole-sample part stored
    /// in `reads` (`reads.whole_len == set.n_delayed()`): only the fractions are split again.
    /// Returns `false` (the reads then need a full preparation) if a delay left its sample.
    ///
    /// Same result as [`Self::prepare`]'s general path, bit for bit: for `d` in `[k, k + 1)`
    /// with integer `k >= 1`, `d − k` is exact (Sterbenz), and its sign and whether it is
    /// `< 1` are those of the exact difference, so `mu ∈ [0, 1)` holds exactly when
    /// `floor(d) = k`; then `d < k + 1 <= max` is not clamped, `d > 0`, and the general path
    /// computes the same `mu`, the same weights and the same `lag`, and adds nothing to `now`.
    #[inline(always)]
    fn resplit(set: &Sequence, scale: f64, reads: &mut Reads) -> bool {
        let Some(pairs) = reads.pairs.get_mut(..reads.whole_len) else {
            return false;
        };
        // `pairs` has `set.n_delayed` entries: the zip stops there.
        let delayed = set.delays.iter().zip(&set.weights);
        for ((pair, &k), (&t, &w)) in pairs.iter_mut().zip(&reads.whole).zip(delayed) {
            let mu = t * scale - k;
            if !(0.0..1.0).contains(&mu) {
                return false;
            }
            pair.w_old = w * mu;
            pair.w_new = w * (1.0 - mu);
        }
        reads.now = set.now;
        true
    }

    /// Appends `x` and writes `out = Σ reads(x)` (all channels; `reads` from [`Self::prepare`]
    /// of this line). The common channel counts with linear reads run with fixed-size rows;
    /// the arithmetic is the same for every count.
    #[inline]
    pub fn push_and_read(&mut self, x: &[f64], reads: &Reads, out: &mut [f64]) {
        if self.interp == Interpolation::Linear {
            macro_rules! fixed {
                ($n:literal) => {
                    if let (Ok(x), Ok(out)) = (
                        <&[f64; $n]>::try_from(x),
                        <&mut [f64; $n]>::try_from(&mut *out),
                    ) {
                        *out = self.push_read_linear::<$n>(x, reads);
                        return;
                    }
                };
            }
            match self.n_channels {
                1 => fixed!(1),
                2 => fixed!(2),
                3 => fixed!(3),
                4 => fixed!(4),
                5 => fixed!(5),
                6 => fixed!(6),
                7 => fixed!(7),
                8 => fixed!(8),
                _ => {}
            }
            self.read_linear_before_push(x, reads, out);
            self.push(x);
        } else {
            self.push(x);
            self.read_taps(reads.taps(), out);
        }
    }

    /// [`Self::push_and_read`] for exactly `N` channels (the line's count; another count
    /// reads nothing and returns zeros).
    #[inline(always)]
    pub(crate) fn push_and_read_fixed<const N: usize>(
        &mut self,
        x: &[f64; N],
        reads: &Reads,
    ) -> [f64; N] {
        if self.interp == Interpolation::Linear {
            self.push_read_linear::<N>(x, reads)
        } else {
            let mut out = [0.0; N];
            self.push(x);
            self.read_taps(reads.taps(), &mut out);
            out
        }
    }

    /// Linear reads of exactly `N` channels, then the push. Stencils read samples stored
    /// before this cycle (see [`Self::prepare`]).
    #[inline(always)]
    fn push_read_linear<const N: usize>(&mut self, x: &[f64; N], reads: &Reads) -> [f64; N] {
        let mut acc = [0.0; N];
        for c in 0..N {
            acc[c] = reads.now * x[c];
        }
        for pair in reads.pairs() {
            let start = (self.head + pair.lag) * N;
            let Some(block) = self.buf.get(start..start + 2 * N) else {
                continue;
            };
            let (r0, r1) = block.split_at(N);
            let (Ok(r0), Ok(r1)) = (<&[f64; N]>::try_from(r0), <&[f64; N]>::try_from(r1)) else {
                continue;
            };
            let (w0, w1) = (pair.w_old, pair.w_new);
            for c in 0..N {
                acc[c] += w0 * r0[c] + w1 * r1[c];
            }
        }
        self.head = if self.head + 1 >= self.capacity {
            0
        } else {
            self.head + 1
        };
        for slot in [self.head, self.head + self.capacity] {
            if let Some(row) = self.buf.get_mut(slot * N..slot * N + N) {
                row.copy_from_slice(x);
            }
        }
        acc
    }

    /// The linear reads of [`Self::push_and_read`] for any channel count (before the push).
    fn read_linear_before_push(&self, x: &[f64], reads: &Reads, out: &mut [f64]) {
        let n = self.n_channels;
        for (o, &v) in out.iter_mut().take(n).zip(x) {
            *o = reads.now * v;
        }
        for pair in reads.pairs() {
            let (w0, w1) = (pair.w_old, pair.w_new);
            let (r0, r1) = self.rows2(pair.lag);
            for ((o, a), b) in out.iter_mut().zip(r0).zip(r1) {
                *o += w0 * a + w1 * b;
            }
        }
    }

    /// `out = Σ_taps tap(x)` over all channels (`out` is overwritten; no taps give zeros).
    /// Taps must come from this line (a foreign tap reads in-bounds garbage, never panics).
    #[inline]
    pub fn read_taps(&self, taps: &[Tap], out: &mut [f64]) {
        let n = self.n_channels;
        let len = n.min(out.len());
        let out = &mut out[..len];
        let Some((first, rest)) = taps.split_first() else {
            out.fill(0.0);
            return;
        };
        match self.interp {
            Interpolation::Linear => {
                let [w0, w1, ..] = first.weights;
                let (r0, r1) = self.rows2(first.lag);
                for ((o, a), b) in out.iter_mut().zip(r0).zip(r1) {
                    *o = w0 * a + w1 * b;
                }
                for tap in rest {
                    let [w0, w1, ..] = tap.weights;
                    let (r0, r1) = self.rows2(tap.lag);
                    for ((o, a), b) in out.iter_mut().zip(r0).zip(r1) {
                        *o += w0 * a + w1 * b;
                    }
                }
            }
            Interpolation::Cubic => {
                out.fill(0.0);
                for tap in taps {
                    let [w0, w1, w2, w3] = tap.weights;
                    let block = self.block(tap.lag, 4);
                    let (r01, r23) = block.split_at(block.len() / 2);
                    let (r0, r1) = r01.split_at(r01.len() / 2);
                    let (r2, r3) = r23.split_at(r23.len() / 2);
                    for ((((o, a), b), c), d) in out.iter_mut().zip(r0).zip(r1).zip(r2).zip(r3) {
                        *o += (w0 * a + w1 * b) + (w2 * c + w3 * d);
                    }
                }
            }
        }
    }

    /// Adds `weight · x(n − delay)` to `out` for every channel. `delay` is in samples and is
    /// clamped to `[0, max_delay_samples]`; returns `true` if it had to be clamped.
    #[inline]
    pub fn accumulate(&self, delay: f64, weight: f64, out: &mut [f64]) -> bool {
        let (tap, clamped) = self.tap(delay, weight);
        let n = self.n_channels;
        let block = self.block(tap.lag, self.interp.reach() + 1);
        for (c, o) in out.iter_mut().take(n).enumerate() {
            let mut acc = 0.0;
            for (w, row) in tap.weights.iter().zip(block.chunks_exact(n)) {
                acc += w * row.get(c).copied().unwrap_or(0.0);
            }
            *o += acc;
        }
        clamped
    }

    /// The `rows` consecutive stored samples starting `lag` slots after `head` (oldest first),
    /// `rows · n_channels` values; empty only if the invariants broke.
    #[inline]
    fn block(&self, lag: usize, rows: usize) -> &[f64] {
        let n = self.n_channels;
        let start = (self.head + lag) * n;
        self.buf.get(start..start + rows * n).unwrap_or(&[])
    }

    /// The two stored samples of a linear stencil, oldest first.
    #[inline]
    fn rows2(&self, lag: usize) -> (&[f64], &[f64]) {
        let block = self.block(lag, 2);
        block.split_at(block.len() / 2)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// What a read of `reads` uses (entries past the counts are stale, not compared).
    fn used(reads: &Reads) -> (f64, Vec<Pair>, usize, Vec<f64>) {
        let whole = reads.whole.get(..reads.whole_len).unwrap_or(&[]).to_vec();
        (reads.now, reads.pairs().to_vec(), reads.whole_len, whole)
    }

    #[test]
    fn a_sequence_sums_its_undelayed_weights_in_order_and_keeps_the_delayed_ones() {
        // Three impulses at delay 0 (their weights summed left to right: 0.1 + 0.2 + 0.3 is
        // not 0.3 + 0.2 + 0.1 in floating point), then two delayed; then the same sequence
        // assigned over with one undelayed impulse, which must not keep the others.
        let mut set = Sequence::new(
            &[0.0, 0.0, 0.0, 3.0, 5.0],
            &[0.1, 0.2, 0.3, 0.15, 0.25],
            2.0,
        );
        assert_eq!(set.now.to_bits(), ((0.1 + 0.2) + 0.3f64).to_bits());
        assert_ne!(set.now.to_bits(), ((0.3 + 0.2) + 0.1f64).to_bits());
        assert_eq!(set.undelayed, 3);
        assert_eq!(&set.undelayed_weights[..3], &[0.1, 0.2, 0.3]);
        let delayed: Vec<(f64, f64)> = set.delayed().map(|(&t, &w)| (t, w)).collect();
        assert_eq!(delayed, vec![(6.0, 0.15), (10.0, 0.25)]);
        set.assign(&[0.0, 4.0], &[0.7, 0.3], 0.5);
        assert_eq!((set.now, set.undelayed), (0.7, 1));
        let all: Vec<(f64, f64)> = set.all().map(|(&t, &w)| (t, w)).collect();
        assert_eq!(all, vec![(0.0, 0.7), (2.0, 0.3)]);
        // No undelayed impulse at all: nothing is applied to the input.
        set.assign(&[1.0], &[1.0], 1.0);
        assert_eq!((set.now, set.undelayed, set.n_delayed()), (0.0, 0, 1));
    }

    #[test]
    fn re_split_reads_equal_fresh_ones_and_are_taken_when_whole_samples_stay() {
        // A ZVD-like sequence (one undelayed impulse, two delayed) whose scale drifts slowly
        // across whole samples and out beyond the line (clamped) and back, then below one
        // sample and to negative delays.
        let line = DelayLine::new(3, 40.0, Interpolation::Linear).expect("line");
        let set = Sequence::new(&[0.0, 11.0, 22.0], &[0.25, 0.5, 0.25], 1.0);
        let mut kept = Reads::NONE;
        let (mut resplit, mut clamped) = (0, 0);
        let steps = 20_000;
        for i in 0..steps {
            let scale = match i {
                0..19_000 => 1.2 + 0.9 * (i as f64 * 3e-4).sin(),
                19_000..19_990 => 0.03 + 0.1 * (i - 19_000) as f64 / 1000.0,
                _ => -0.5,
            };
            let mut fresh = Reads::NONE;
            let clamped_fresh = line.prepare(&set, scale, &mut fresh);
            let mut probe = kept;
            let took_resplit =
                kept.whole_len == set.n_delayed() && DelayLine::resplit(&set, scale, &mut probe);
            let clamped_kept = line.prepare(&set, scale, &mut kept);
            assert_eq!(used(&kept), used(&fresh), "step {i}, scale {scale}");
            assert_eq!(clamped_kept, clamped_fresh, "step {i}");
            resplit += usize::from(took_resplit);
            clamped += usize::from(clamped_fresh);
        }
        // The delays (11 and 22 samples per unit scale) move by at most 0.006 samples a step,
        // so nearly every step that is neither clamped nor below one sample re-splits.
        assert!(
            resplit + clamped > steps * 9 / 10,
            "re-split {resplit}, clamped {clamped} of {steps}"
        );
        assert!(clamped > 1000 && resplit > steps / 2, "{resplit} {clamped}");
    }
}
