"""Time to settled (``tvist.analysis.settling_time`` from the start of a move) on signals whose
decay is known in closed form."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.optimize import brentq

from tvist.analysis import settling_time

DT_S = 0.002
#: A decaying mode: 8 Hz natural, ζ 0.05 (σ = ζ ω_n = 2.51 /s), amplitude 1.3 m/s² when the
#: move starts at T0 (off the sample grid: 0.2013 s).
F_N_HZ, ZETA, AMP, T0 = 8.0, 0.05, 1.3, 0.2013
WN = 2 * math.pi * F_N_HZ
SIGMA = ZETA * WN
WD = WN * math.sqrt(1 - ZETA**2)


def _envelope_crossing(threshold: float) -> float:
    """Time after T0 at which ``AMP e^(-σ τ)`` falls to ``threshold``: ``ln(A/thr) / (ζ ω_n)``."""
    return math.log(AMP / threshold) / (ZETA * WN)


def test_a_circular_decay_settles_at_the_analytic_envelope_crossing():
    # Two axes in quadrature: |ψ| = A e^(-σ τ) exactly, so the signal leaves the band for good
    # when the envelope does. Before T0 the arm moves (ψ far above the band).
    t = np.arange(0.0, 3.0, DT_S)
    tau = t - T0
    env = np.where(tau >= 0, AMP * np.exp(-SIGMA * np.clip(tau, 0, None)), 5.0)
    psi = np.column_stack([env * np.cos(WD * tau), env * np.sin(WD * tau), np.zeros(t.size)])
    for threshold in (0.05, 0.01):
        expected = _envelope_crossing(threshold)
        # The crossing falls between samples (T0 is off the grid); the chord between the two
        # samples around it lies above the convex exponential by at most x'' dt²/8, i.e. the
        # estimate is late by at most σ dt²/8 = 1.3e-6 s (plus round-off).
        got = settling_time(t, psi, T0, threshold)
        assert 0.0 <= got - expected <= SIGMA * DT_S**2 / 8 + 1e-12
        assert (T0 + expected) / DT_S % 1.0 > 1e-3  # off the grid indeed


def test_a_ringing_axis_settles_after_its_last_peak_above_the_band():
    # One axis: x = A e^(-σ τ) sin(ω_d τ + φ). It leaves the band for good at its last
    # downward crossing of the threshold, which lies within half a damped period before the
    # envelope crossing. Found here on the continuous signal by root finding.
    phi = 0.4
    t = np.arange(0.0, 3.0, DT_S)
    tau = t - T0

    def x(s: float) -> float:
        return AMP * math.exp(-SIGMA * s) * math.sin(WD * s + phi)

    threshold = 0.05
    t_env = _envelope_crossing(threshold)
    # The last peak of |x| above the band: peaks of |x| sit at ω_d τ + φ - atan(ω_d/σ) = kπ.
    lag = math.atan2(WD, SIGMA)
    peaks = [(k * math.pi + lag - phi) / WD for k in range(200)]
    peaks = [p for p in peaks if 0 < p and abs(x(p)) > threshold]
    last_peak = peaks[-1]
    # |x| falls monotonically from that peak to the next zero of x.
    zero = (math.ceil((WD * last_peak + phi) / math.pi) * math.pi - phi) / WD
    exact = brentq(lambda s: abs(x(s)) - threshold, last_peak, zero, xtol=1e-14)
    assert t_env - math.pi / WD <= exact <= t_env
    signal = np.where(tau >= 0, [x(s) for s in np.clip(tau, 0, None)], 3.0)
    got = settling_time(t, signal, T0, threshold)
    # The exact crossing and the estimate lie in the same 2 ms sample interval (|x| is
    # monotone there), so they differ by less than one sample period.
    assert abs(got - exact) < DT_S


def test_never_settled_and_already_settled():
    t = np.arange(0.0, 2.0, DT_S)
    # Sustained ringing above the band: never settles within the record.
    ring = 0.2 * np.sin(2 * math.pi * 8.0 * t)
    ring[np.abs(ring) < 0.1] = 0.15  # no dip into the band either
    assert settling_time(t, ring, 0.2, 0.05) == math.inf
    # Inside the band from the start of the move on: settled at once.
    quiet = np.where(t < 0.2, 1.0, 0.01)
    assert settling_time(t, quiet, 0.2, 0.05) == 0.0
    # Above the band until 10 ms before the end of the record: a dip that short is not
    # seen to settle when the record must show 0.1 s inside the band, and counts otherwise.
    late = np.where(t < t[-1] - 0.01, 1.0, 0.0)
    assert settling_time(t, late, 0.2, 0.05, hold_s=0.1) == math.inf
    assert math.isfinite(settling_time(t, late, 0.2, 0.05))
    # Already settled, but the record after the move start is shorter than the hold.
    assert settling_time(t, quiet, t[-1] - 0.05, 0.05, hold_s=0.1) == math.inf
    with pytest.raises(ValueError, match="hold_s"):
        settling_time(t, quiet, 0.2, 0.05, hold_s=-1.0)


def test_a_logged_moves_settle_times_match_the_analytic_decay():
    """:func:`tvist.live.settle_times` on a log-shaped record: the target leaves its start on
    the grid at ``t0``, the tool acceleration rings in quadrature after the stop (so its
    magnitude is exactly ``A e^(-σ τ)``) on top of gravity; the settle time from ``t0`` is
    ``t_stop - t0 + ln(A / band) / σ`` for each band. Tolerance: the chord between samples
    (late by at most ``σ dt² / 8`` = 1.25 µs here) plus 1 ns for the rest estimate, whose
    bias (the decay left in the last 0.2 s, < 1e-12 m/s²) moves the crossing by less."""
    from tvist.analysis import SETTLE_BANDS_M_S2
    from tvist.live import moving_span, settle_times

    dt, t0, t_stop, amp, sigma, wd = 0.002, 0.5, 1.3, 0.8, 2.5, 2 * math.pi * 9.0
    t = np.arange(0.0, 14.0, dt)
    ramp = np.clip((t - t0) / (t_stop - t0), 0.0, 1.0)
    target = np.outer(ramp, [0.4, -0.2, 0, 0, 0, 0])
    tau = np.maximum(t - t_stop, 0.0)
    ring = amp * np.exp(-sigma * tau) * (t >= t_stop)
    accel = np.column_stack([ring * np.cos(wd * tau), ring * np.sin(wd * tau), np.zeros_like(t)])
    accel += [0.3, -0.1, 9.81]
    times = settle_times(t, target, accel)
    start, end = moving_span(target)  # the move itself: t0 to t_stop, on the grid
    assert (t[start], t[end]) == pytest.approx((t0, t_stop), abs=1e-12)
    for band in SETTLE_BANDS_M_S2:
        want = t_stop - t0 + math.log(amp / band) / sigma
        assert want <= times[band] <= want + sigma * dt**2 / 8 + 1e-9, band
    # A log that ends ringing has not settled; a target that never moves is no move.
    assert settle_times(t[:1500], target[:1500], accel[:1500])[SETTLE_BANDS_M_S2[-1]] == math.inf
    with pytest.raises(ValueError, match="never moves"):
        settle_times(t, np.zeros_like(target), accel)
