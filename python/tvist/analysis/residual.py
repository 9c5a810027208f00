"""Residual vibration after a move: the paper's log-decay extrapolation of acceleration peaks.

The residual vibration (RV) of a move is the amplitude of the tool acceleration at the moment
the motion stops (``t_b`` unshaped, ``t_b*`` shaped; paper section 6.2). It is found by
fitting a straight line to the logarithm of the acceleration peaks after the stop and
evaluating it at the stop time. When one decaying mode explains the signal, a least-squares
fit of that mode to every sample after the stop refines the same quantity with far less
sensitivity to noise than the few peaks alone.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike

from tvist.analysis._signals import as_channels, magnitude, positive
from tvist.trajectory.validation import check_time_stamps

__all__ = ["ResidualVibration", "estimate_noise_std", "residual_vibration"]

#: Sum of squared coefficients of the 4th difference [1, -4, 6, -4, 1]: the factor by which it
#: scales the variance of white noise.
_DIFF4_NOISE_GAIN = math.sqrt(70.0)
#: Scale from the median absolute deviation to the standard deviation of Gaussian noise.
_MAD_TO_STD = 1.4826


@dataclass(frozen=True)
class ResidualVibration:
    """Result of :func:`residual_vibration`. Amplitudes are in the unit of the input signal.

    Attributes
    ----------
    amplitude
        Residual vibration: envelope amplitude of the vibration at ``t_stop_s``, from the
        method named in ``method``.
    method
        ``"damped_sine_fit"``: a single decaying mode fitted to all samples explains the
        signal to within the noise; ``amplitude`` is its envelope at ``t_stop_s``.
        ``"log_decay"``: the peak extrapolation (``log_decay_amplitude``), used when the
        single-mode model does not fit (several modes, non-exponential decay).
        ``"max_abs"``: fewer than ``min_peaks`` peaks stand out of the noise and no single
        mode fits (or fewer than 2 peaks); ``amplitude`` is the largest magnitude after the
        stop, an upper bound at the noise level.
    log_decay_amplitude
        The paper's estimate: ``peak_amplitude / sqrt(1 - zeta²)``, because the peaks of
        ``e^(-σt) cos(ω_d t + φ)`` lie a factor ``ω_d / ω_n`` below its envelope.
    peak_amplitude
        The fitted log-decay line of the peaks evaluated at ``t_stop_s``, uncorrected.
    decay_rate_1_s
        Decay rate ``σ = ζ ω_n`` of the chosen method, 1/s (NaN for ``"max_abs"``).
    freq_hz
        Damped frequency of the chosen method, Hz; for ``"log_decay"`` from the median peak
        spacing (two peaks of the magnitude per period).
    zeta
        Damping ratio implied by ``decay_rate_1_s`` and ``freq_hz``.
    t_stop_s
        The stop time the amplitude refers to, s.
    t_peaks_s, peaks
        Times (s) and sub-sample refined heights of the peaks used in the log-decay fit.
    r_squared
        Weighted coefficient of determination of the log-linear peak fit.
    fit_residual_rms
        RMS (over samples, of the residual vector norm) of the single-mode fit; NaN if none.
    noise_std
        Noise level used for the thresholds (RMS of the noise vector).
    reliable
        True for ``"damped_sine_fit"``, and for ``"log_decay"`` with decaying peaks and
        ``r_squared`` at or above the threshold; False for ``"max_abs"``.
    note
        How the amplitude was obtained and why it is or is not reliable.
    """

    amplitude: float
    method: Literal["damped_sine_fit", "log_decay", "max_abs"]
    log_decay_amplitude: float
    peak_amplitude: float
    decay_rate_1_s: float
    freq_hz: float
    zeta: float
    t_stop_s: float
    t_peaks_s: np.ndarray
    peaks: np.ndarray
    r_squared: float
    fit_residual_rms: float
    noise_std: float
    reliable: bool
    note: str

    @property
    def n_peaks(self) -> int:
        """Number of peaks used in the log-decay fit."""
        return int(self.peaks.size)


def estimate_noise_std(x: ArrayLike) -> float:
    """Robust white-noise level of a signal from its 4th differences.

    The 4th difference removes smooth content (a 30 Hz sine sampled at 500 Hz keeps 0.2 % of
    its amplitude relative to the noise gain) and multiplies white noise variance by 70; the
    median absolute deviation makes the estimate insensitive to the few samples where the
    signal changes fast. For ``(n, k)`` input the per-channel levels are combined as the RMS
    of the noise vector, ``sqrt(Σ σ_k²)``. Coloured (low-pass filtered) noise is
    under-estimated; pass a measured level to :func:`residual_vibration` in that case.

    Parameters
    ----------
    x
        Signal, shape ``(n_samples,)`` or ``(n_samples, k)``, ``n_samples >= 5``.

    Returns
    -------
    float
        Estimated noise standard deviation (combined over channels).
    """
    arr = as_channels("x", x)
    if arr.shape[0] < 5:
        raise ValueError(f"need at least 5 samples to estimate noise, got {arr.shape[0]}")
    d4 = np.diff(arr, n=4, axis=0)
    mad = np.median(np.abs(d4 - np.median(d4, axis=0)), axis=0)
    per_channel = _MAD_TO_STD * mad / _DIFF4_NOISE_GAIN
    return float(np.sqrt(np.sum(per_channel**2)))


def _refine_peak(y: np.ndarray, t: np.ndarray, i: int, half_width: int) -> tuple[float, float]:
    """Maximum (time, height) of a least-squares cubic through ``y[i - hw : i + hw + 1]``.

    Averaging ``2 hw + 1`` samples cuts the noise of the height and removes the upward bias of
    taking the largest noisy sample. A cubic rather than a parabola follows the skew of a
    strongly damped peak, whose vertex time a parabola misplaces (0.7 ms at 12 Hz, ζ = 0.3,
    which the extrapolation back to the stop turns into a 1.6 % amplitude error). Without a
    positive maximum inside the window the sample itself is returned.
    """
    lo, hi = max(0, i - half_width), min(y.size, i + half_width + 1)
    if hi - lo < 5:
        return _refine_three_point(y, t, i)
    tau = t[lo:hi] - t[i]
    scale = max(abs(tau[0]), abs(tau[-1]))  # fit in [-1, 1] for conditioning
    c3, c2, c1, c0 = np.polyfit(tau / scale, y[lo:hi], 3)
    # Stationary points: 3 c3 x² + 2 c2 x + c1 = 0; keep the maximum (6 c3 x + 2 c2 < 0).
    roots = np.roots([3.0 * c3, 2.0 * c2, c1]) if c3 != 0.0 else np.array([-c1 / (2.0 * c2)])
    x_lo, x_hi = tau[0] / scale, tau[-1] / scale
    best = None
    for x in roots:
        if abs(x.imag) > 1e-12 or not x_lo <= x.real <= x_hi or 6.0 * c3 * x.real + 2.0 * c2 >= 0.0:
            continue
        value = ((c3 * x.real + c2) * x.real + c1) * x.real + c0
        if best is None or value > best[1]:
            best = (x.real, value)
    if best is None or best[1] <= 0.0:  # no usable maximum (log needs a positive height)
        return float(t[i]), float(y[i])
    return float(t[i] + best[0] * scale), float(best[1])


def _refine_three_point(y: np.ndarray, t: np.ndarray, i: int) -> tuple[float, float]:
    """Vertex of the parabola through samples ``i - 1, i, i + 1`` (for narrow windows)."""
    if i == 0 or i == y.size - 1:
        return float(t[i]), float(y[i])
    left, mid, right = y[i - 1], y[i], y[i + 1]
    curvature = left - 2.0 * mid + right
    if curvature >= 0.0:
        return float(t[i]), float(mid)
    offset = 0.5 * (left - right) / curvature  # in samples, within [-0.5, 0.5] for a maximum
    step = t[i + 1] - t[i] if offset >= 0.0 else t[i] - t[i - 1]
    return float(t[i] + offset * step), float(mid - 0.25 * (left - right) * offset)


def _baseline(
    a: np.ndarray, after_stop: np.ndarray, baseline: str | ArrayLike, tail_fraction: float
) -> np.ndarray:
    """Static level to subtract: the mean of the record's tail, a given value, or none."""
    n_channels = a.shape[1]
    if isinstance(baseline, str):
        if baseline == "none":
            return np.zeros(n_channels)
        if baseline != "tail":
            raise ValueError(f"baseline must be 'tail', 'none' or an array, got {baseline!r}")
        post = a[after_stop]
        n_tail = max(1, math.ceil(tail_fraction * post.shape[0]))
        return post[-n_tail:].mean(axis=0)
    level = np.broadcast_to(np.asarray(baseline, dtype=float), (n_channels,)).copy()
    if not np.all(np.isfinite(level)):
        raise ValueError("baseline must be finite")
    return level


@dataclass(frozen=True)
class _LogDecay:
    t_peaks_s: np.ndarray
    peaks: np.ndarray
    peak_amplitude: float
    amplitude: float
    decay_rate_1_s: float
    freq_hz: float
    r_squared: float


def _log_decay_fit(
    t_use: np.ndarray, level: np.ndarray, index: np.ndarray, t_stop: float
) -> _LogDecay:
    """Straight line through ``log(peak)`` over time, weighted by the peak height."""
    # Window half-width: a quarter of the median spacing between neighbouring peaks.
    half_width = max(1, round(0.25 * float(np.median(np.diff(index)))))
    refined = np.array([_refine_peak(level, t_use, i, half_width) for i in index])
    t_peaks, peaks = refined[:, 0], refined[:, 1]
    x, y = t_peaks - t_stop, np.log(peaks)
    # Additive noise of std s moves log(peak) by about s / peak: weight each point by peak.
    slope, intercept = np.polyfit(x, y, 1, w=peaks)
    w2 = peaks**2
    y_mean = np.sum(w2 * y) / np.sum(w2)
    ss_tot = float(np.sum(w2 * (y - y_mean) ** 2))
    ss_res = float(np.sum(w2 * (y - (slope * x + intercept)) ** 2))
    decay = -float(slope)
    freq = 1.0 / (2.0 * float(np.median(np.diff(t_peaks))))
    w_d = 2.0 * math.pi * freq
    peak_amplitude = math.exp(float(intercept))
    envelope_factor = math.hypot(decay, w_d) / w_d if decay > 0.0 else 1.0
    return _LogDecay(
        t_peaks_s=t_peaks,
        peaks=peaks,
        peak_amplitude=peak_amplitude,
        amplitude=peak_amplitude * envelope_factor,
        decay_rate_1_s=decay,
        freq_hz=freq,
        r_squared=1.0 - ss_res / ss_tot if ss_tot > 0.0 else math.nan,
    )


def _damped_sine_fit(
    tau: np.ndarray, y: np.ndarray, decay0: float, w_d0: float
) -> tuple[float, float, float, float]:
    """Fit ``y_k(τ) ≈ e^(-στ) (B_k cos ω_d τ + C_k sin ω_d τ) + D_k`` to ``(n, k)`` samples.

    Variable projection: for given ``(σ, ω_d)`` the amplitudes are a linear least-squares
    problem, so only ``(σ, ω_d)`` are searched, starting from the peak fit. Returns the
    envelope ``sqrt(Σ_k B_k² + C_k²)`` at ``τ = 0``, ``σ``, ``ω_d`` and the residual RMS.
    """
    from scipy.optimize import least_squares

    def design(params: np.ndarray) -> np.ndarray:
        decay, w_d = params
        envelope = np.exp(-decay * tau)
        return np.column_stack(
            [envelope * np.cos(w_d * tau), envelope * np.sin(w_d * tau), np.ones_like(tau)]
        )

    def residual(params: np.ndarray) -> np.ndarray:
        basis = design(params)
        coef, *_ = np.linalg.lstsq(basis, y, rcond=None)
        return (y - basis @ coef).ravel()

    x0 = np.array([max(decay0, 1e-6), w_d0])
    fit = least_squares(residual, x0, bounds=([0.0, 0.5 * w_d0], [np.inf, 2.0 * w_d0]), x_scale=x0)
    coef, *_ = np.linalg.lstsq(design(fit.x), y, rcond=None)
    amplitude = float(np.sqrt(np.sum(coef[:2] ** 2)))
    rms = float(np.sqrt(np.sum(fit.fun**2) / tau.size))
    return amplitude, float(fit.x[0]), float(fit.x[1]), rms


def _regular_train(index: np.ndarray, max_gap: float = 2.5) -> np.ndarray:
    """Leading peaks up to the first gap wider than ``max_gap`` times the typical spacing.

    Vibration peaks of the magnitude come every half period; once the decay has reached the
    noise, the peaks that still pass the thresholds are sporadic noise spikes far apart. The
    typical spacing is the median of the first three spacings, which belong to the strongest
    peaks.
    """
    if index.size < 3:
        return index
    spacing = np.diff(index)
    typical = float(np.median(spacing[:3]))
    gaps = np.flatnonzero(spacing > max_gap * typical)
    return index if gaps.size == 0 else index[: gaps[0] + 1]


def _max_abs_result(
    largest: float,
    t_stop: float,
    t_peaks: np.ndarray,
    peaks: np.ndarray,
    noise: float,
    note: str,
) -> ResidualVibration:
    return ResidualVibration(
        amplitude=largest,
        method="max_abs",
        log_decay_amplitude=math.nan,
        peak_amplitude=math.nan,
        decay_rate_1_s=math.nan,
        freq_hz=math.nan,
        zeta=math.nan,
        t_stop_s=t_stop,
        t_peaks_s=np.asarray(t_peaks, dtype=float),
        peaks=np.asarray(peaks, dtype=float),
        r_squared=math.nan,
        fit_residual_rms=math.nan,
        noise_std=noise,
        reliable=False,
        note=note,
    )


def residual_vibration(
    t_s: ArrayLike,
    accel: ArrayLike,
    t_stop_s: float,
    *,
    baseline: str | ArrayLike = "tail",
    tail_fraction: float = 0.25,
    noise_std: float | None = None,
    snr_min: float = 5.0,
    min_relative_height: float = 0.02,
    f_max_hz: float = 60.0,
    skip_s: float = 0.0,
    window_s: float | None = None,
    max_peaks: int = 12,
    min_peaks: int = 3,
    min_r_squared: float = 0.9,
    refine: bool = True,
) -> ResidualVibration:
    """Residual vibration at ``t_stop_s`` from the decay of the acceleration after the stop.

    1. The static level (gravity) is subtracted. For a multi-axis signal the vibration is the
       Euclidean norm of the dynamic part: the norm does not depend on the sensor orientation
       (which turns with the tool between poses), and for a mode vibrating along one direction
       it equals the magnitude of that direction's signal, so its peaks are the peaks of both
       half-waves with the envelope of the mode. Combining per-axis amplitudes instead would
       add weak, noise-dominated axes.
    2. Peaks of the magnitude are found with :func:`scipy.signal.find_peaks` (height and
       prominence above ``snr_min`` times the noise), refined by a local least-squares cubic,
       and ``log(peak)`` is fitted with a straight line over time and extrapolated to the stop
       (the paper's method; ``log_decay_amplitude``).
    3. With ``refine``, one decaying mode with a shared ``(σ, ω_d)`` and per-axis amplitudes is
       fitted (with a constant per axis, which absorbs a baseline error) to every sample from
       the stop to two periods after the last peak used. If its residual is within
       ``3 * noise_std + 0.02 * rms(signal)`` the mode explains the signal and its envelope
       at the stop is the result; otherwise the log-decay estimate is.

    Parameters
    ----------
    t_s
        Time stamps, shape ``(n_samples,)``, s, increasing.
    accel
        Acceleration, shape ``(n_samples,)`` or ``(n_samples, k)`` (e.g. the tool
        accelerometer's x, y, z), any unit; the results use the same unit.
    t_stop_s
        When the motion (the reference sent to the robot) stops, s.
    baseline
        Static level to subtract: ``"tail"`` (default) the mean of the last ``tail_fraction``
        of the samples after ``t_stop_s``; ``"none"``; or a scalar / ``(k,)`` array.
    tail_fraction
        Fraction of the post-stop record averaged for ``baseline="tail"``, in (0, 1].
    noise_std
        Noise level of the signal (RMS of the noise vector). Default: estimated from the
        post-stop samples by :func:`estimate_noise_std`; pass a level measured at standstill
        if the noise is coloured (filtered).
    snr_min
        A peak is used only if its height and its prominence exceed ``snr_min * noise_std``.
    min_relative_height
        ... and ``min_relative_height`` times the largest post-stop magnitude. Such small
        peaks carry little weight in the fit and are the first to be noise (or, without
        noise, rounding ripples), which matters when the noise level is under-estimated.
    f_max_hz
        Highest vibration frequency of interest, Hz; peaks of the magnitude closer than half
        its period are merged.
    skip_s
        Ignore samples in ``[t_stop_s, t_stop_s + skip_s)``, e.g. while a servo still settles;
        the fits are still extrapolated back to ``t_stop_s``.
    window_s
        Use only samples before ``t_stop_s + window_s`` (default: to the end of the record).
    max_peaks
        Use at most this many (the earliest) peaks.
    min_peaks
        Fewest peaks for the log-decay estimate; with fewer (but at least 2, which seed the
        single-mode fit) the result falls back to ``"max_abs"`` unless the single-mode fit
        explains the signal.
    min_r_squared
        A log-linear fit below this coefficient of determination is reported as not reliable.
    refine
        Try the single-mode fit of step 3 (default true). False gives the paper's log-decay
        estimate alone.

    Returns
    -------
    ResidualVibration
        The amplitude and the details of the fits; check ``method`` and ``reliable``.

    Raises
    ------
    ValueError
        On malformed input, or when fewer than 5 samples remain to analyse.
    """
    from scipy.signal import find_peaks

    t = check_time_stamps(t_s)
    a = as_channels("accel", accel, t.size)
    t_stop = float(t_stop_s)
    if not math.isfinite(t_stop) or not t[0] <= t_stop < t[-1]:
        raise ValueError(
            f"t_stop_s = {t_stop_s!r} must lie in [t_s[0], t_s[-1]) = [{t[0]}, {t[-1]})"
        )
    if not 0.0 < tail_fraction <= 1.0:
        raise ValueError(f"tail_fraction must be in (0, 1], got {tail_fraction}")
    positive("snr_min", snr_min)
    if not 0.0 < min_relative_height < 1.0:
        raise ValueError(f"min_relative_height must be in (0, 1), got {min_relative_height}")
    f_max = positive("f_max_hz", f_max_hz)
    if not (math.isfinite(skip_s) and skip_s >= 0.0):
        raise ValueError(f"skip_s must be finite and >= 0, got {skip_s}")
    if min_peaks < 2 or max_peaks < min_peaks:
        raise ValueError(f"need 2 <= min_peaks <= max_peaks, got {min_peaks} and {max_peaks}")

    after_stop = t >= t_stop
    t_end = t[-1] if window_s is None else t_stop + positive("window_s", window_s)
    use = after_stop & (t >= t_stop + skip_s) & (t <= t_end)
    if np.count_nonzero(use) < 5:
        raise ValueError(
            f"only {np.count_nonzero(use)} samples between t_stop_s + skip_s and the end of the "
            "window; need at least 5"
        )
    dynamic = (a - _baseline(a, after_stop, baseline, tail_fraction))[use]
    t_use = t[use]
    level = magnitude(dynamic)
    noise = estimate_noise_std(dynamic) if noise_std is None else float(noise_std)
    if not (math.isfinite(noise) and noise >= 0.0):
        raise ValueError(f"noise_std must be finite and >= 0, got {noise_std!r}")

    largest = float(level.max())
    threshold = max(snr_min * noise, min_relative_height * largest)
    dt_median = float(np.median(np.diff(t_use)))
    distance = max(1, int(0.5 / (f_max * dt_median)))
    index, _ = find_peaks(level, height=threshold, prominence=threshold, distance=distance)
    index = _regular_train(index)[:max_peaks]

    few_note = (
        f"only {index.size} peaks exceed the threshold {threshold:.3g} (snr_min x noise "
        f"{noise:.3g}); amplitude is the largest magnitude after the stop, an upper bound at "
        "the noise level"
    )
    if index.size < 2:
        return _max_abs_result(largest, t_stop, t_use[index], level[index], noise, few_note)

    peaks = _log_decay_fit(t_use, level, index, t_stop)
    decay, w_d = peaks.decay_rate_1_s, 2.0 * math.pi * peaks.freq_hz
    amplitude, method = peaks.amplitude, "log_decay"
    residual_rms = math.nan
    reliable = decay > 0.0 and peaks.r_squared >= min_r_squared
    if decay <= 0.0:
        note = "the peaks do not decay; the extrapolation is not meaningful"
    elif not reliable:
        note = f"log-linear peak fit is poor (r_squared {peaks.r_squared:.3f} < {min_r_squared})"
    else:
        note = f"log-decay fit over {index.size} peaks"

    if refine and decay > 0.0:
        span = t_use <= peaks.t_peaks_s[-1] + 2.0 / peaks.freq_hz
        y = dynamic[span]
        fit_amp, fit_decay, fit_w_d, residual_rms = _damped_sine_fit(
            t_use[span] - t_stop, y, decay, w_d
        )
        signal_rms = float(np.sqrt(np.mean(np.sum((y - y.mean(axis=0)) ** 2, axis=1))))
        if fit_decay > 0.0 and residual_rms <= 3.0 * noise + 0.02 * signal_rms:
            amplitude, method, reliable = fit_amp, "damped_sine_fit", True
            decay, w_d = fit_decay, fit_w_d
            note = (
                f"one decaying mode fits all samples (residual rms {residual_rms:.3g}, noise "
                f"{noise:.3g}); log-decay over {index.size} peaks gave {peaks.amplitude:.4g}"
            )
        else:
            note += (
                f"; a single decaying mode does not explain the signal (residual rms "
                f"{residual_rms:.3g} vs noise {noise:.3g}), so the peak extrapolation is used"
            )

    if method == "log_decay" and index.size < min_peaks:
        return _max_abs_result(largest, t_stop, peaks.t_peaks_s, peaks.peaks, noise, few_note)
    return ResidualVibration(
        amplitude=amplitude,
        method=method,
        log_decay_amplitude=peaks.amplitude,
        peak_amplitude=peaks.peak_amplitude,
        decay_rate_1_s=decay,
        freq_hz=w_d / (2.0 * math.pi),
        zeta=decay / math.hypot(decay, w_d) if decay > 0.0 else math.nan,
        t_stop_s=t_stop,
        t_peaks_s=peaks.t_peaks_s,
        peaks=peaks.peaks,
        r_squared=peaks.r_squared,
        fit_residual_rms=residual_rms,
        noise_std=noise,
        reliable=reliable,
        note=note,
    )
