"""Residual vibration, spectrum and move measures against signals with known answers."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest
from scipy import signal

import tvist
from tvist.analysis import (
    count_velocity_peaks,
    energy_spectrum,
    estimate_noise_std,
    peak_acceleration,
    peak_jerk,
    peak_velocity,
    residual_vibration,
    sensitivity_grid,
    settling_time,
)
from tvist.trajectory import PAPER_POSES, double_s, trapezoid

DT_S = 0.002
T_STOP_S = 0.5013  # deliberately between samples
RV_TOLERANCE = 0.02  # acceptance: residual vibration amplitude within 2 %

FREQS_HZ = (5.0, 8.0, 12.0, 20.0, 30.0)
ZETAS = (0.02, 0.05, 0.1, 0.2, 0.3)
PHASES = (0.0, 1.3, 2.7, 4.4)


def ringing(
    t: np.ndarray, amplitude: float, freq_hz: float, zeta: float, phase: float
) -> np.ndarray:
    """Free vibration after ``T_STOP_S`` with envelope ``amplitude`` at the stop; before the
    stop an unrelated large, slow 'motion' signal that the analysis must ignore."""
    wn = 2.0 * np.pi * freq_hz
    wd = wn * math.sqrt(1.0 - zeta**2)
    tau = t - T_STOP_S
    free = amplitude * np.exp(-zeta * wn * np.maximum(tau, 0.0)) * np.cos(wd * tau + phase)
    return np.where(tau >= 0.0, free, 3.0 * np.sin(2.0 * np.pi * 1.3 * t))


def grid_errors(
    noise_fraction: float,
    zetas=ZETAS,
    refine: bool = True,
    seed: int = 0,
    smoothing_samples: int = 1,
):
    """Relative amplitude errors over frequencies, damping ratios and phases.

    The noise is white with std ``noise_fraction`` of the amplitude, then averaged over
    ``smoothing_samples`` (a moving-average filter as used on the paper's accelerometer
    data, which makes it coloured) and rescaled to keep that std.
    """
    rng = np.random.default_rng(seed)
    t = np.arange(0.0, 3.0, DT_S)
    amplitude, gravity = 2.0, 9.81
    kernel = np.ones(smoothing_samples) / math.sqrt(smoothing_samples)
    errors = {}
    for f, z, ph in itertools.product(FREQS_HZ, zetas, PHASES):
        white = rng.standard_normal(t.size + smoothing_samples - 1)
        noise = noise_fraction * amplitude * np.convolve(white, kernel, mode="valid")
        accel = ringing(t, amplitude, f, z, ph) + gravity + noise
        rv = residual_vibration(t, accel, T_STOP_S, refine=refine)
        errors[(f, z, ph)] = (abs(rv.amplitude / amplitude - 1.0), rv.method)
    return errors


def test_paper_log_decay_alone_is_within_tolerance_without_noise():
    # The peak extrapolation of the paper (with the envelope correction) by itself; measured
    # worst case 0.5 % over the grid.
    errors = grid_errors(0.0, refine=False)
    worst = max(errors.items(), key=lambda kv: kv[1][0])
    assert worst[1][0] < RV_TOLERANCE, worst
    assert {m for _, m in errors.values()} == {"log_decay"}


def test_residual_vibration_acceptance_grid_without_noise():
    # 5-30 Hz, ζ 0.02-0.3, four phases, with gravity and a motion before the stop.
    # Measured worst: 1e-10 (the single-mode fit is exact on a single mode).
    errors = grid_errors(0.0)
    worst = max(errors.items(), key=lambda kv: kv[1][0])
    assert worst[1][0] < RV_TOLERANCE, worst


# White noise with std 0.5 % or 1 % of the amplitude. Spread measured over 12 seeds x 4 phases
# per (f, ζ) cell: with 0.5 % noise the worst error is 1.2 % up to ζ = 0.2; with 1 % it is
# 1.3 % up to ζ = 0.1. A heavily damped fast mode stays above 5σ for only 2-3 half-waves
# (about 25 samples), so there the RMS error is about 1 % and single realizations reach 3.5 %:
# the estimate is noise-limited, not biased.
@pytest.mark.parametrize(
    ("noise_fraction", "zetas", "tolerance"),
    [
        (0.005, (0.02, 0.05, 0.1, 0.2), RV_TOLERANCE),
        (0.01, (0.02, 0.05, 0.1), RV_TOLERANCE),
        (0.01, (0.2, 0.3), 0.04),
    ],
)
def test_residual_vibration_with_noise(noise_fraction, zetas, tolerance):
    errors = grid_errors(noise_fraction, zetas=zetas, seed=1)
    worst = max(errors.items(), key=lambda kv: kv[1][0])
    assert worst[1][0] < tolerance, worst
    # The RMS error over the grid is well inside the acceptance band.
    assert math.sqrt(np.mean([e * e for e, _ in errors.values()])) < 0.5 * RV_TOLERANCE


@pytest.mark.parametrize(
    ("zetas", "tolerance"), [((0.02, 0.05, 0.1), RV_TOLERANCE), ((0.2, 0.3), 0.04)]
)
def test_residual_vibration_with_coloured_noise(zetas, tolerance):
    # Moving-average (5 samples) filtered noise of 0.5 %: the 4th-difference noise estimate
    # sees only a third of it, so weak noise spikes pass the thresholds; the relative height
    # floor and the end of the regular peak train keep them out of the fit. Measured over
    # 10 seeds x 4 phases per cell: worst 1.4 % up to ζ = 0.1, 2.7 % at ζ = 0.2-0.3; RMS 0.5 %.
    errors = grid_errors(0.005, zetas=zetas, seed=7, smoothing_samples=5)
    worst = max(errors.items(), key=lambda kv: kv[1][0])
    assert worst[1][0] < tolerance, worst


def test_paper_log_decay_degrades_with_noise_but_fit_does_not():
    # Documents why the single-mode fit refines the peak extrapolation: at 0.5 % noise and
    # ζ = 0.3 the few peaks give errors of several percent.
    peaks_only = grid_errors(0.005, zetas=(0.3,), refine=False, seed=2)
    refined = grid_errors(0.005, zetas=(0.3,), refine=True, seed=2)
    assert max(e for e, _ in peaks_only.values()) > max(e for e, _ in refined.values())


def test_three_axis_signal_along_a_tilted_direction():
    rng = np.random.default_rng(3)
    t = np.arange(0.0, 3.0, DT_S)
    gravity = np.array([1.2, -3.4, 9.1])
    for f, z in [(6.9, 0.37), (8.0, 0.26), (19.2, 0.14), (22.0, 0.08)]:  # Table 3 modes
        direction = rng.normal(size=3)
        direction /= np.linalg.norm(direction)
        scalar = ringing(t, 1.5, f, z, rng.uniform(0, 2 * np.pi))
        accel = scalar[:, None] * direction + gravity
        accel += 0.005 * 1.5 / math.sqrt(3) * rng.standard_normal(accel.shape)
        rv = residual_vibration(t, accel, T_STOP_S)
        assert rv.amplitude == pytest.approx(1.5, rel=RV_TOLERANCE), (f, z, rv.note)
        assert rv.reliable
        # Frequency and decay of the mode are recovered too. Measured errors: frequency
        # < 0.02 %, decay rate and ζ < 0.5 %; the bands leave room for the noise.
        wn = 2 * np.pi * f
        assert rv.freq_hz == pytest.approx(f * math.sqrt(1 - z * z), rel=0.002)
        assert rv.decay_rate_1_s == pytest.approx(z * wn, rel=0.015)
        assert rv.zeta == pytest.approx(z, rel=0.015)


def base_excited_tool_acceleration(traj, freq_hz: float, zeta: float):
    """Absolute acceleration of a mode ``e'' + 2ζω e' + ω² e = −u''`` (``y = −2ζω e' − ω² e``)
    driven by the trajectory's acceleration; returns the signal and the state over time."""
    w = 2.0 * np.pi * freq_hz
    plant = signal.StateSpace(
        [[0.0, 1.0], [-w * w, -2 * zeta * w]],
        [[0.0], [-1.0]],
        [[-w * w, -2 * zeta * w]],
        0.0,
    )
    _, y, x = signal.lsim(plant, traj.qdd[:, 0], traj.t_s)
    return y, x


def test_residual_vibration_of_a_double_s_move_on_a_flexible_mode():
    traj = double_s([0.0], [np.pi / 2], DT_S, t_pre_s=0.1, t_post_s=2.0)
    freq_hz, zeta = 8.0, 0.1
    y, x = base_excited_tool_acceleration(traj, freq_hz, zeta)
    # Ground truth from the state at the stop: afterwards the input is 0, so the response is
    # y = e^(-στ)(B cos ω_d τ + C sin ω_d τ) with B = y(0), C = (y'(0) + σB)/ω_d.
    w = 2 * np.pi * freq_hz
    sigma, w_d = zeta * w, w * math.sqrt(1 - zeta**2)
    i_stop = round(traj.t_motion_end_s / DT_S)
    e, e_dot = x[i_stop]
    e_ddot = -2 * zeta * w * e_dot - w * w * e
    b = y[i_stop]
    y_dot = -2 * zeta * w * e_ddot - w * w * e_dot
    truth = math.hypot(b, (y_dot + sigma * b) / w_d)
    rv = residual_vibration(traj.t_s, y, traj.t_motion_end_s)
    # The response after the stop is exactly one decaying mode: the fit recovers it to
    # rounding (measured 2e-15); the paper's peak extrapolation to 0.16 % (measured).
    assert rv.method == "damped_sine_fit"
    assert rv.amplitude == pytest.approx(truth, rel=1e-6)
    assert rv.log_decay_amplitude == pytest.approx(truth, rel=RV_TOLERANCE)


def decay_signal(envelope_and_modes, t_stop_s: float, t: np.ndarray) -> np.ndarray:
    """Free vibration after ``t_stop_s`` (``envelope_and_modes(τ)``), an unrelated large, slow
    'motion' before it, and gravity."""
    tau = t - t_stop_s
    free = envelope_and_modes(np.maximum(tau, 0.0))
    return np.where(tau >= 0.0, free, 3.0 * np.sin(2.0 * np.pi * 1.3 * t)) + 9.81


def log_decay_reference(free, n_peaks: int = 12, f_max_hz: float = 60.0) -> float:
    """The documented log-decay method applied to the continuous signal ``free(τ)``.

    The magnitude is evaluated every 10 µs (so peak times and heights are exact to ~1e-6),
    its peaks are those at least 2 % of the largest magnitude high and prominent, at least
    half a period of ``f_max_hz`` apart, up to the first gap of 2.5 typical spacings, the
    first ``n_peaks``; ``log(peak)`` is fitted by a line weighted by the peak height and
    extrapolated to the stop, and the peak-to-envelope factor ``|s| / ω_d`` applied.
    """
    step = 1e-5
    tau = np.arange(0.0, 2.4, step)
    mag = np.abs(free(tau))
    threshold = 0.02 * mag.max()
    index, _ = signal.find_peaks(
        mag, height=threshold, prominence=threshold, distance=round(0.5 / (f_max_hz * step))
    )
    spacing = np.diff(index)
    gaps = np.flatnonzero(spacing > 2.5 * np.median(spacing[:3]))
    index = (index if gaps.size == 0 else index[: gaps[0] + 1])[:n_peaks]
    slope, intercept = np.polyfit(tau[index], np.log(mag[index]), 1, w=mag[index])
    w_d = math.pi / float(np.median(np.diff(tau[index])))
    return math.exp(intercept) * math.hypot(slope, w_d) / w_d


def damped_modes(modes):
    """``Σ a e^(−ζωτ) cos(ω_d τ + φ)`` over ``modes = [(a, f_n Hz, ζ, φ), ...]``."""

    def free(tau):
        out = np.zeros_like(tau)
        for a, f, z, ph in modes:
            wn = 2.0 * np.pi * f
            out = out + a * np.exp(-z * wn * tau) * np.cos(wn * math.sqrt(1 - z * z) * tau + ph)
        return out

    return free


@pytest.mark.parametrize("t_stop_s", [0.5, T_STOP_S], ids=["on-grid", "off-grid"])
@pytest.mark.parametrize("phase", [0.0, 1.3, 2.7, 4.4])
@pytest.mark.parametrize(
    "second", [(0.6, 20.0, 0.05), (0.3, 20.0, 0.1), (0.5, 11.0, 0.05)], ids=str
)
def test_two_modes_fall_back_to_the_peak_extrapolation(t_stop_s, phase, second):
    """Two modes (8 Hz plus a weaker one): no single mode explains the signal, so the
    result is the peak extrapolation, checked against (a) the same method on the continuous
    signal and (b) the ground truth, the upper envelope Σ a_k at the stop (reached where the
    modes are in phase)."""
    modes = [(1.0, 8.0, 0.05, phase), (*second[:2], second[2], 0.7 * phase + 0.5)]
    t = np.arange(0.0, 3.0, DT_S)
    rv = residual_vibration(t, decay_signal(damped_modes(modes), t_stop_s, t), t_stop_s)
    assert rv.method == "log_decay"
    # The single-mode fit leaves the weaker mode (rms ≥ 0.04) against a noise of ~4e-7.
    assert "does not explain" in rv.note and rv.fit_residual_rms > 0.02
    # Beating peaks lie off a straight line: reliable only with a good enough line.
    assert rv.reliable == (rv.r_squared >= 0.9)
    # (a) Sampling at 500 Hz and the cubic peak refinement: measured within 2.6 %.
    assert rv.amplitude == pytest.approx(log_decay_reference(damped_modes(modes)), rel=0.03)
    # (b) The line through beating peaks lies below the upper envelope by how often the
    # modes meet in phase near the stop: measured 0.70-0.93 of Σ a_k over these cases.
    upper = sum(m[0] for m in modes)
    assert 0.65 * upper <= rv.amplitude <= upper


@pytest.mark.parametrize("t_stop_s", [0.5, T_STOP_S], ids=["on-grid", "off-grid"])
@pytest.mark.parametrize("phase", [0.0, 2.7])
@pytest.mark.parametrize("freq_hz", [5.0, 8.0, 20.0])
@pytest.mark.parametrize("law", ["velocity_squared", "coulomb"])
def test_non_exponential_decays_against_their_envelope(t_stop_s, phase, freq_hz, law):
    """One frequency with a non-exponential envelope A(τ), A(0) = 1 at the stop (the ground
    truth): ``1/(1 + 3τ)`` (velocity-squared damping) or ``1 − τ/1.2 s`` (Coulomb friction)."""
    if law == "velocity_squared":

        def free(tau):
            return np.cos(2 * np.pi * freq_hz * tau + phase) / (1.0 + 3.0 * tau)
    else:

        def free(tau):
            return np.maximum(1.0 - tau / 1.2, 0.0) * np.cos(2 * np.pi * freq_hz * tau + phase)

    t = np.arange(0.0, 3.0, DT_S)
    rv = residual_vibration(t, decay_signal(free, t_stop_s, t), t_stop_s)
    # The method on the sampled signal equals the method on the continuous one: measured
    # within 0.55 % (5 Hz, velocity-squared, where the peaks are widest), so 1 %.
    assert rv.log_decay_amplitude == pytest.approx(log_decay_reference(free), rel=0.01)
    # Against the truth a straight line through log A(τ) over 12 peaks extrapolates below a
    # convex log-envelope (velocity-squared: measured 0.81-0.98, closer at higher frequency,
    # whose peaks lie nearer the stop) and above a concave one (Coulomb: 1.004-1.12).
    if law == "velocity_squared":
        assert 0.75 < rv.amplitude < 1.0
    else:
        assert 1.0 < rv.amplitude < 1.15


def test_noise_only_gives_flagged_max_abs():
    rng = np.random.default_rng(4)
    t = np.arange(0.0, 2.0, DT_S)
    accel = 9.81 + 0.01 * rng.standard_normal((t.size, 3))
    rv = residual_vibration(t, accel, 0.5)
    assert rv.method == "max_abs" and not rv.reliable
    assert "upper bound" in rv.note
    post = accel[t >= 0.5]
    dynamic = post - post[-math.ceil(0.25 * len(post)) :].mean(axis=0)  # tail baseline
    assert rv.amplitude == pytest.approx(np.max(np.linalg.norm(dynamic, axis=1)))


def test_estimate_noise_std_ignores_slow_content():
    rng = np.random.default_rng(5)
    t = np.arange(0.0, 2.0, DT_S)
    x = 2.0 * np.sin(2 * np.pi * 20 * t) + 0.05 * rng.standard_normal(t.size)
    # 1000 samples: the MAD-based estimate scatters by about 4 %; the 20 Hz leak is 0.3 %.
    assert estimate_noise_std(x) == pytest.approx(0.05, rel=0.1)
    xyz = 0.05 * rng.standard_normal((t.size, 3))
    assert estimate_noise_std(xyz) == pytest.approx(0.05 * math.sqrt(3), rel=0.1)


def test_residual_vibration_rejects_bad_input():
    t = np.arange(0.0, 1.0, DT_S)
    a = np.zeros(t.size)
    with pytest.raises(ValueError, match="t_stop_s"):
        residual_vibration(t, a, 2.0)
    with pytest.raises(ValueError, match="samples but t_s has"):
        residual_vibration(t, a[:-1], 0.5)
    bad = a.copy()
    bad[10] = np.nan
    with pytest.raises(ValueError, match=r"accel\[10, 0\] is nan"):
        residual_vibration(t, bad, 0.5)
    with pytest.raises(ValueError, match="need at least 5"):
        residual_vibration(t, a, t[-3])
    with pytest.raises(ValueError, match="baseline"):
        residual_vibration(t, a, 0.5, baseline="mean")
    # A relative peak height is a fraction of the largest magnitude, strictly inside (0, 1).
    for height in (0.0, 1.0, 1.2):
        with pytest.raises(ValueError, match="min_relative_height"):
            residual_vibration(t, a, 0.5, min_relative_height=height)
    for fraction in (0.0, 1.01):
        with pytest.raises(ValueError, match="tail_fraction"):
            residual_vibration(t, a, 0.5, tail_fraction=fraction)


@pytest.mark.parametrize("n", [1000, 1001])
def test_energy_spectrum_parseval_and_peak(n):
    rng = np.random.default_rng(6)
    t = DT_S * np.arange(n)
    psi = rng.standard_normal((n, 3))
    freq, energy = energy_spectrum(psi, DT_S)
    assert freq[0] == 0.0 and freq[1] == pytest.approx(1.0 / (n * DT_S))
    doubled = energy[0] + 2 * energy[1:].sum()
    if n % 2 == 0:  # the Nyquist bin has no mirror image
        doubled -= energy[-1]
    assert doubled == pytest.approx(np.sum(psi**2), rel=1e-12)
    # A sinusoid on bin k: |X_k| = A n / 2, so E_k = A² n / 4 (x and z both carry one).
    f0 = 20.0 / (n * DT_S)
    tone = np.column_stack(
        [1.5 * np.sin(2 * np.pi * f0 * t), np.zeros(n), 0.5 * np.cos(2 * np.pi * f0 * t)]
    )
    freq, energy = energy_spectrum(tone, DT_S)
    assert np.argmax(energy) == 20 and freq[20] == pytest.approx(f0)
    assert energy[20] == pytest.approx((1.5**2 + 0.5**2) * n / 4, rel=1e-9)
    # With a static offset, remove_mean clears the 0 Hz bin only.
    _, with_mean = energy_spectrum(tone + 9.81, DT_S, remove_mean=True)
    np.testing.assert_allclose(with_mean[1:], energy[1:], rtol=1e-9, atol=1e-9)


def test_settling_time_of_known_decays():
    t = np.arange(0.0, 3.0, 0.001)
    t_stop = 1.0
    decay = np.where(t >= t_stop, 2.0 * np.exp(-(t - t_stop) / 0.1), 5.0)
    # |x| = 2 e^(-τ/0.1) falls through 0.02 at τ = 0.1 ln 100. The chord between 1 ms samples
    # lies above the exponential by at most x'' dt² / 8 = 2.5e-7, i.e. 1.25e-6 s at the
    # slope 0.2 /s of the crossing.
    expected = 0.1 * math.log(100)
    assert settling_time(t, decay, t_stop, 0.02) == pytest.approx(expected, abs=1.5e-6)
    assert settling_time(t, decay, t_stop, 3.0) == 0.0
    assert settling_time(t, np.ones(t.size), t_stop, 0.5) == math.inf
    # Oscillating: the last excursion above the band ends after the last peak above it.
    ring = ringing(t, 1.0, 5.0, 0.05, 0.0)
    settle = settling_time(t, ring, T_STOP_S, 0.1)
    after = t >= T_STOP_S + settle + 0.002
    assert np.all(np.abs(ring[after]) <= 0.1)
    assert np.max(np.abs(ring[(t > T_STOP_S + settle - 0.1) & (t < T_STOP_S + settle)])) > 0.1
    # Envelope reaches 0.1 at τ = ln 10 / σ; the last peak above the band is at most half a
    # period before.
    assert (
        math.log(10) / (0.05 * 2 * np.pi * 5) - 0.1
        <= settle
        <= math.log(10) / (0.05 * 2 * np.pi * 5)
    )


def test_peak_rates_of_profiles():
    # Cubic q = c t³: every third difference is exactly 6 c dt³.
    t = DT_S * np.arange(50)
    q = np.column_stack([0.7 * t**3, -0.2 * t**3])
    assert peak_jerk(q, DT_S) == pytest.approx(6 * 0.7, rel=1e-6)
    traj = double_s(PAPER_POSES["Q1"], PAPER_POSES["Q3"], DT_S)
    # Differences of a sampled profile: velocity and acceleration to O(dt) of the limits,
    # jerk never above the 100 rad/s³ limit (a difference quotient is an average).
    assert peak_velocity(traj.q, DT_S) == pytest.approx(1.5, rel=1e-3)
    assert peak_acceleration(traj.q, DT_S) == pytest.approx(2.0, rel=1e-3)
    assert 99.0 < peak_jerk(traj.q, DT_S) <= 100.0 * (1 + 1e-6)
    # A trapezoid steps its acceleration: the third difference sees a / dt = 1000 rad/s³
    # spread over up to two samples.
    trap = trapezoid(PAPER_POSES["Q1"], PAPER_POSES["Q3"], 1.5, 2.0, DT_S)
    assert peak_jerk(trap.q, DT_S) > 400.0
    with pytest.raises(ValueError, match="at least 4"):
        peak_jerk(q[:3], DT_S)


def test_count_velocity_peaks_on_known_shapes():
    traj = double_s(PAPER_POSES["Q1"], PAPER_POSES["Q3"], DT_S, t_post_s=0.1)
    np.testing.assert_array_equal(count_velocity_peaks(traj.qd), [1, 1, 1, 0, 0, 0])
    # A flat cruise with rounding ripple counts once: synthetic, and the velocity of a
    # double-S by central differences, whose plateau holds maxima of exactly equal height.
    plateau = np.concatenate([np.linspace(0, 1, 50), 1 + 1e-12 * np.sin(np.arange(200)), [0.0]])
    assert count_velocity_peaks(plateau) == 1
    cruise = double_s([0.0], [np.pi / 2], DT_S, t_post_s=0.1)
    assert count_velocity_peaks(np.gradient(cruise.q[:, 0], DT_S)) == 1
    # A dip of 30 % between two maxima separates two humps; one of 2 % does not.
    x = np.linspace(0, 1, 400)
    dip = 1 - 0.3 * np.exp(-(((x - 0.5) / 0.05) ** 2))
    assert count_velocity_peaks(np.sin(np.pi * x) ** 0.2 * dip) == 2
    assert count_velocity_peaks(np.sin(np.pi * x) ** 0.2 * (1 - (1 - dip) / 15)) == 1
    # Two separated humps; a small wiggle below the threshold does not count.
    x = np.linspace(0, 1, 500)
    two = np.exp(-(((x - 0.3) / 0.05) ** 2)) + 0.8 * np.exp(-(((x - 0.7) / 0.05) ** 2))
    assert count_velocity_peaks(two + 0.01 * np.sin(80 * x)) == 2
    # ZV shaping of a short move with a delay longer than the move: two separate humps.
    short = double_s([0.0], [0.05], DT_S, t_post_s=0.5)
    shaper = tvist.TvShaper(tvist.ConstantModes([(2 * np.pi * 2.0, 0.0)]), dt_s=DT_S, n_dof=1)
    shaped = shaper.shape(short.q)
    assert count_velocity_peaks(np.gradient(shaped[:, 0], DT_S)) == 2
    assert count_velocity_peaks(-short.qd[:, 0]) == 1  # sign does not matter


def prv_reference(amplitudes, times_s, wn_rad_s: float, zeta: float) -> float:
    """Eqs. 52-55 written out (test oracle for the core implementation)."""
    a, dt = np.asarray(amplitudes), np.asarray(times_s)
    w_d = wn_rad_s * math.sqrt(1 - zeta**2)
    c = np.sum(a * np.exp(zeta * wn_rad_s * dt) * np.cos(w_d * dt))
    s = np.sum(a * np.exp(zeta * wn_rad_s * dt) * np.sin(w_d * dt))
    return math.exp(-zeta * wn_rad_s * dt[-1]) * math.hypot(c, s)


def test_sensitivity_grid():
    imp = tvist.shaper("zvd", 2 * np.pi * 8.0, 0.1)
    wn = 2 * np.pi * np.linspace(4.0, 12.0, 9)
    zetas = np.array([0.0, 0.1, 0.3])
    grid = sensitivity_grid(imp, wn, zetas)
    assert grid.shape == (3, 9)
    assert grid[1, 4] == pytest.approx(0.0, abs=1e-12)  # design point
    for i, j in [(0, 0), (2, 8), (1, 2)]:
        assert grid[i, j] == pytest.approx(
            prv_reference(imp.amplitudes, imp.times_s, wn[j], zetas[i]), rel=1e-9
        )
    with pytest.raises(ValueError, match="1-D"):
        sensitivity_grid(imp, [[1.0]], zetas)


def test_peak_train_ends_at_the_first_wide_gap():
    """Vibration peaks come every half period; a peak more than 2.5 typical spacings after
    the previous one is a noise spike past the decay and ends the train."""
    from tvist.analysis.residual import _regular_train

    train = np.array([0, 10, 20, 31, 40])
    np.testing.assert_array_equal(_regular_train(np.append(train, 40 + 26)), train)
    np.testing.assert_array_equal(_regular_train(np.append(train, 40 + 24)), [*train, 64])
    np.testing.assert_array_equal(_regular_train(np.array([3, 90])), [3, 90])  # too few to judge


def test_peak_refinement_averages_the_noise_of_closely_spaced_peaks():
    """A 30 Hz mode sampled at 500 Hz has magnitude peaks ~8 samples apart, so each peak is
    refined over a 5-sample window (cubic least squares) rather than the 3-point parabola.
    With white noise of 1 % of the amplitude, the RMS error of the log-decay amplitude
    against the method applied to the continuous signal (``log_decay_reference``) over 100
    noise realisations and random phases is 2.3 % (measured); the 3-point parabola on the
    same data gives 2.9 %. The bound 2.6 % is about 2 standard errors of the RMS estimate
    (±7 % relative for 100 realisations) from either."""
    rng = np.random.default_rng(30)
    t = np.arange(0.0, 3.0, DT_S)
    wn, zeta, amplitude = 2.0 * math.pi * 30.0, 0.2, 2.0
    wd = wn * math.sqrt(1.0 - zeta**2)
    errors = []
    for _ in range(100):
        phase = rng.uniform(0.0, 2.0 * math.pi)

        def free(tau, phase=phase):
            return amplitude * np.exp(-zeta * wn * tau) * np.cos(wd * tau + phase)

        accel = decay_signal(free, T_STOP_S, t) + rng.normal(0.0, 0.01 * amplitude, t.size)
        rv = residual_vibration(t, accel, T_STOP_S, refine=False)
        errors.append(rv.log_decay_amplitude / log_decay_reference(free) - 1.0)
    rms = math.sqrt(np.mean(np.square(errors)))
    assert rms < 0.026, rms
