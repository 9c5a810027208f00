"""TvShaper (multi-mode FD-TVIST, SPEC section 2) against independent numpy references.

- Constant modes: equal to sum_i A_i x(t - Delta_i) evaluated with np.interp (linear) or a
  scipy Lagrange interpolator (cubic), cascaded once per mode.
- Time-varying modes: a double-S move shaped by a mode whose frequency follows the shaped
  output stays as smooth as the move itself, unlike a shaper that rounds delays to whole
  samples (the baseline described in SPEC section 2).
- Held and clamped cycles are reported through ``last_status`` and ``status_counts``.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import pytest
from scipy.interpolate import BarycentricInterpolator

import tvist

DT_S = 0.002


def make_signal(n: int, n_dof: int = 2) -> np.ndarray:
    """Smooth motion plus a step: exercises every fractional-delay phase. (n, n_dof)."""
    t = np.arange(n) * DT_S
    cols = [
        0.3 * np.sin((7.0 + 3 * j) * t) + 0.1 * np.cos(31.0 * t) + 0.25 * (t > t[n // 2])
        for j in range(n_dof)
    ]
    return np.column_stack(cols)


def shape_linear_reference(x: np.ndarray, s: tvist.Impulses) -> np.ndarray:
    """sum_i A_i x(t - Delta_i) with np.interp on the sample grid (held at x[0] before t=0)."""
    t = np.arange(len(x)) * DT_S
    out = np.zeros_like(x)
    for a, d in zip(s.amplitudes, s.times_s, strict=True):
        for j in range(x.shape[1]):
            out[:, j] += a * np.interp(t - d, t, x[:, j])
    return out


def lagrange_read(x: np.ndarray, n: int, delay: float) -> float:
    """x(n - delay) by 4-point Lagrange interpolation, scipy's barycentric form.

    Stencil: samples n-k-2 .. n-k+1 around k = floor(delay) (nodes at delays k-1 .. k+2); for
    delay < 1 the newest four samples. Samples before the start hold x[0].
    """
    k = int(np.floor(delay))
    first_age = max(k - 1, 0)
    ages = np.arange(first_age, first_age + 4)
    values = x[np.maximum(n - ages, 0)]
    return float(BarycentricInterpolator(-ages.astype(float), values)(-delay))


def shape_cubic_reference(x: np.ndarray, s: tvist.Impulses) -> np.ndarray:
    out = np.zeros_like(x)
    for j in range(x.shape[1]):
        for n in range(len(x)):
            out[n, j] = sum(
                a * lagrange_read(x[:, j], n, d / DT_S)
                for a, d in zip(s.amplitudes, s.times_s, strict=True)
            )
    return out


MODES = [(2 * np.pi * 8.0, 0.26), (2 * np.pi * 6.9, 0.37), (93.0, 0.05)]


@pytest.mark.parametrize("name", ["zv", "zvd", "mzv", "ei", "2hump_ei"])
@pytest.mark.parametrize("n_modes", [1, 2, 3])
def test_constant_modes_equal_the_numpy_reference(name: str, n_modes: int) -> None:
    modes = MODES[:n_modes]
    if name == "2hump_ei":
        modes = [(wn, min(z, 0.3)) for wn, z in modes]
    x = make_signal(600)
    shaper = tvist.TvShaper(tvist.ConstantModes(modes), DT_S, 2, shaper=name)
    y = shaper.shape(x)
    assert shaper.last_status == 0
    ref = x
    for m in modes:  # one filter per mode, in cascade
        ref = shape_linear_reference(ref, tvist.shaper(name, *m))
    # Identical arithmetic up to summation order: rounding differences only.
    np.testing.assert_allclose(y, ref, rtol=0, atol=1e-12)
    assert shaper.delay_s == pytest.approx(sum(tvist.shaper(name, *m).duration_s for m in modes))


def whole_sample_mode(samples: int, zeta: float) -> tuple[float, float]:
    """A mode whose ZV delay pi/wd is exactly ``samples`` control periods."""
    return np.pi / (samples * DT_S * np.sqrt(1 - zeta**2)), zeta


def test_cascade_equals_convolution_for_whole_sample_delays() -> None:
    # With delays on the sample grid, interpolation is exact and the cascade of filters is the
    # convolved (multi-mode) impulse sequence of eq. 53, applied once.
    modes = [whole_sample_mode(25, 0.1), whole_sample_mode(17, 0.3), whole_sample_mode(9, 0.0)]
    x = make_signal(500, 3)
    for n_modes in (2, 3):
        shaper = tvist.TvShaper(tvist.ConstantModes(modes[:n_modes]), DT_S, 3, shaper="zvd")
        conv = tvist.convolve(*(tvist.shaper("zvd", *m) for m in modes[:n_modes]))
        np.testing.assert_allclose(shaper.shape(x), shape_linear_reference(x, conv), atol=1e-12)


def test_cascade_differs_from_convolution_only_by_interpolation_error() -> None:
    x = make_signal(500, 1)
    shaper = tvist.TvShaper(tvist.ConstantModes(MODES[:2]), DT_S, 1, shaper="zv")
    conv = tvist.convolve(*(tvist.shaper("zv", *m) for m in MODES[:2]))
    err = np.abs(shaper.shape(x) - shape_linear_reference(x, conv))
    # Linear interpolation error <= dt^2/8 max|x''| per read (|x''| <= 0.3*9^2 + 0.1*31^2 here,
    # away from the step); two reads in cascade. Near the step the error is O(step height).
    smooth = np.ones(len(x), bool)
    smooth[250 - 5 : 250 + 80] = False
    bound = 2 * DT_S**2 / 8 * (0.3 * 9**2 + 0.1 * 31**2)
    assert err[smooth].max() <= bound
    assert err.max() > 1e-8  # they are different filters


@pytest.mark.parametrize("name", ["zv", "zvd", "ei"])
@pytest.mark.parametrize("n_modes", [1, 2])
def test_cubic_interpolation_equals_a_lagrange_reference(name: str, n_modes: int) -> None:
    x = make_signal(260, 1)
    modes = MODES[:n_modes]
    shaper = tvist.TvShaper(tvist.ConstantModes(modes), DT_S, 1, shaper=name, interp="cubic")
    y = shaper.shape(x)
    ref = x
    for m in modes:
        ref = shape_cubic_reference(ref, tvist.shaper(name, *m))
    np.testing.assert_allclose(y, ref, rtol=0, atol=1e-12)
    # ...and it is not the linear reference (the comparison can fail).
    lin = tvist.TvShaper(tvist.ConstantModes(modes), DT_S, 1, shaper=name).shape(x)
    assert np.abs(lin - y).max() > 1e-7


def test_streaming_equals_batch_and_reset_restarts() -> None:
    # 2500 samples: longer than the chunks `shape` copies its input in.
    x = make_signal(2500, 2)
    modes = tvist.ConstantModes(MODES[:2])
    batch = tvist.TvShaper(modes, DT_S, 2, shaper="zvd").shape(x)
    streaming = tvist.TvShaper(modes, DT_S, 2, shaper="zvd")
    steps = np.array([streaming.step(row) for row in x])
    np.testing.assert_array_equal(steps, batch)
    # Blocks continue the streaming state.
    split = tvist.TvShaper(modes, DT_S, 2, shaper="zvd")
    np.testing.assert_array_equal(np.vstack([split.shape(x[:1234]), split.shape(x[1234:])]), batch)
    # reset(None) forgets history; reset(q0) puts the filter at rest at q0.
    split.reset()
    np.testing.assert_array_equal(split.shape(x), batch)
    split.reset(np.array([1.0, -1.0]))
    np.testing.assert_allclose(split.step(np.array([1.0, -1.0])), [1.0, -1.0], atol=1e-15)
    # Fortran-ordered and strided input is read in row order.
    np.testing.assert_array_equal(
        tvist.TvShaper(modes, DT_S, 2, shaper="zvd").shape(np.asfortranarray(x)), batch
    )
    wide = np.repeat(x, 2, axis=1)[:, ::2]
    np.testing.assert_array_equal(tvist.TvShaper(modes, DT_S, 2, shaper="zvd").shape(wide), batch)


# --- time-varying smoothness -------------------------------------------------------------


def double_s(
    distance: float, v_max: float, a_max: float, jerk_time_s: float, pre_s: float, post_s: float
) -> np.ndarray:
    """Rest-to-rest jerk-limited move (piecewise-constant jerk, integrated exactly), sampled
    at DT_S. Requires the distance to reach v_max. Returns positions, shape (n_samples,)."""
    jerk = a_max / jerk_time_s
    t_const_acc = v_max / a_max - jerk_time_s
    t_cruise = (distance - v_max * (v_max / a_max + jerk_time_s)) / v_max
    assert t_const_acc >= 0 and t_cruise >= 0
    segments = [
        (pre_s, 0.0),
        (jerk_time_s, jerk),
        (t_const_acc, 0.0),
        (jerk_time_s, -jerk),
        (t_cruise, 0.0),
        (jerk_time_s, -jerk),
        (t_const_acc, 0.0),
        (jerk_time_s, jerk),
        (post_s, 0.0),
    ]
    starts, states = [0.0], [(0.0, 0.0, 0.0)]
    for d, j in segments:
        p, v, a = states[-1]
        states.append(
            (p + v * d + a * d**2 / 2 + j * d**3 / 6, v + a * d + j * d**2 / 2, a + j * d)
        )
        starts.append(starts[-1] + d)
    t = np.arange(int(np.ceil(starts[-1] / DT_S)) + 1) * DT_S
    k = np.clip(np.searchsorted(starts, t, side="right") - 1, 0, len(segments) - 1)
    tau = t - np.asarray(starts)[k]
    p, v, a = (np.asarray(c)[k] for c in zip(*states[:-1], strict=True))
    j = np.asarray([s[1] for s in segments])[k]
    return p + v * tau + a * tau**2 / 2 + j * tau**3 / 6


DISTANCE = 2.0
ZETA = 0.05


def ramp_mode(q: np.ndarray) -> list[tuple[float, float]]:
    """The mode drifts from 7 to 22 Hz as the (shaped) position goes from 0 to DISTANCE."""
    f_hz = 7.0 + 15.0 * np.clip(q[0] / DISTANCE, 0.0, 1.0)
    return [(2 * np.pi * f_hz, ZETA)]


def rounding_baseline(
    x: np.ndarray, modes: Callable[[np.ndarray], list[tuple[float, float]]], reseed: bool
) -> np.ndarray:
    """Time-varying ZV that rounds the delay to whole samples and, with ``reseed``, refills
    its buffer with the current input whenever the rounded length changes (SPEC section 2)."""
    out = np.empty_like(x)
    previous = x[0]
    buffer: list[float] = []
    length = -1
    for n, xn in enumerate(x):
        wn, zeta = modes(np.array([previous]))[0]
        k = np.exp(-zeta * np.pi / np.sqrt(1 - zeta**2))
        delay = int(round(np.pi / (wn * np.sqrt(1 - zeta**2)) / DT_S))
        if reseed and delay != length:
            buffer = [xn] * (delay + 1)
            length = delay
            delayed = buffer[0]
        elif reseed:
            buffer = buffer[1:] + [xn]
            delayed = buffer[0]
        else:
            delayed = x[max(n - delay, 0)]
        out[n] = (xn + k * delayed) / (1 + k)
        previous = out[n]
    return out


def peak_jerk(q: np.ndarray) -> float:
    return float(np.abs(np.diff(q, 3)).max() / DT_S**3)


def peak_accel(q: np.ndarray) -> float:
    return float(np.abs(np.diff(q, 2)).max() / DT_S**2)


def test_time_varying_shaping_is_as_smooth_as_the_move() -> None:
    x = double_s(DISTANCE, 1.5, 2.0, 0.02, pre_s=0.2, post_s=1.0)
    max_delay_s = 1.5 * np.pi / (2 * np.pi * 7.0 * np.sqrt(1 - ZETA**2))
    shaper = tvist.TvShaper(ramp_mode, DT_S, 1, shaper="zv", max_delay_s=max_delay_s)
    y = shaper.shape(x[:, None])[:, 0]
    assert shaper.status_counts == dict.fromkeys(shaper.status_counts, 0)
    # The mode really varied: 7 Hz at the start, 22 Hz at the end.
    assert shaper.current_modes[0][0] == pytest.approx(2 * np.pi * 22.0)
    assert shaper.delay_s == pytest.approx(np.pi / (2 * np.pi * 22 * np.sqrt(1 - ZETA**2)))

    jerk_move = peak_jerk(x)  # 100 rad/s^3 by construction
    assert jerk_move == pytest.approx(100.0, rel=1e-6)
    # FD-TVIST: no jerk beyond the move's own, acceleration within 15 % (the delay shrinks as
    # the mode stiffens, which compresses the second impulse's copy of the move in time).
    assert peak_jerk(y) <= jerk_move
    assert peak_accel(y) <= 1.15 * peak_accel(x)

    # Delays rounded to whole samples inject a step each time the rounded delay changes.
    rounded = rounding_baseline(x, ramp_mode, reseed=False)
    reseeded = rounding_baseline(x, ramp_mode, reseed=True)
    assert peak_jerk(rounded) >= 100 * peak_jerk(y)
    assert peak_jerk(reseeded) >= peak_jerk(rounded)

    # Final value: once the move has stopped and the shaper settled, output == input.
    assert y[-1] == pytest.approx(DISTANCE, abs=1e-12)
    np.testing.assert_allclose(y[-50:], x[-50:], rtol=0, atol=1e-12)


# --- held / clamped cycles -----------------------------------------------------------------


def test_non_finite_input_holds_the_last_valid_sample() -> None:
    modes = tvist.ConstantModes([(40.0, 0.1)])
    x = make_signal(200, 2)
    corrupt = x.copy()
    corrupt[[20, 21, 90], 1] = [np.nan, np.inf, -np.inf]
    held = x.copy()
    for i in (20, 21, 90):
        held[i] = held[i - 1] if i != 21 else held[19]
    a = tvist.TvShaper(modes, DT_S, 2)
    b = tvist.TvShaper(modes, DT_S, 2)
    ya = a.shape(corrupt)
    np.testing.assert_array_equal(ya, b.shape(held))
    assert np.all(np.isfinite(ya))
    assert a.status_counts["input_held"] == 3
    a.step(np.array([np.nan, 0.0]))
    assert a.last_status & tvist.Status.INPUT_HELD
    a.step(np.array([0.0, 0.0]))
    assert a.last_status == tvist.Status.OK


def test_invalid_modes_from_a_callable_are_held() -> None:
    calls = {"n": 0}

    def flaky(q: np.ndarray) -> list[tuple[float, float]]:
        calls["n"] += 1
        bad = 30 <= calls["n"] < 40  # construction probes once: cycles 29..38 are invalid
        return [(np.nan if bad else 40.0, 0.1), (90.0, 1.5 if bad else 0.05)]

    x = make_signal(200, 2)
    shaper = tvist.TvShaper(flaky, DT_S, 2, shaper="zvd", max_delay_s=0.5)
    reference = tvist.TvShaper(tvist.ConstantModes([(40.0, 0.1), (90.0, 0.05)]), DT_S, 2, "zvd")
    np.testing.assert_array_equal(shaper.shape(x), reference.shape(x))
    assert shaper.status_counts["modes_held"] == 10
    assert shaper.status_counts["unshaped"] == 0

    never = tvist.TvShaper(lambda q: [(-1.0, 0.1)], DT_S, 2, max_delay_s=0.5)
    np.testing.assert_array_equal(never.shape(x), x)  # passes through, flagged
    assert never.last_status == tvist.Status.MODES_HELD | tvist.Status.UNSHAPED


def test_a_jumping_mode_is_slew_limited_and_reported() -> None:
    # A callback whose mode jumps from 14.9 to 30.9 Hz mid-move: the filter approaches it by
    # 1 % a cycle (tvist.MAX_LN_WN_RATE_PER_S = 5/s at 2 ms), so the delay never steps, and
    # every cycle that binds is reported. ln(30.9/14.9) / 0.01 = 72.9: 72 limited cycles,
    # the 73rd lands on the mode.
    calls = {"n": 0}

    def jumping(q: np.ndarray) -> list[tuple[float, float]]:
        calls["n"] += 1
        return [(2 * np.pi * (14.9 if calls["n"] < 100 else 30.9), 0.1)]

    assert tvist.MAX_LN_WN_RATE_PER_S * DT_S == pytest.approx(0.01)
    shaper = tvist.TvShaper(jumping, DT_S, 1, shaper="zv", max_delay_s=0.1)
    delays = []
    for i in range(300):
        shaper.step(np.array([1e-3 * i]))
        delays.append(shaper.delay_s)
    assert shaper.status_counts["mode_slew_limited"] == 72
    # ZV delay pi / ω_d changes by at most 1 % of itself a cycle (rounding: 1e-9).
    ratio = np.array(delays[1:]) / np.array(delays[:-1])
    assert np.all(np.abs(np.log(ratio)) <= 0.01 * (1 + 1e-9))
    assert delays[-1] == pytest.approx(tvist.shaper("zv", 2 * np.pi * 30.9, 0.1).duration_s)


def test_delays_beyond_the_buffer_are_clamped() -> None:
    # ZV delay at 10 rad/s is 0.316 s; the line holds 0.1 s. The read stays inside the buffer.
    shaper = tvist.TvShaper(lambda q: [(10.0, 0.1)], DT_S, 1, max_delay_s=0.1)
    assert shaper.max_delay_s == [pytest.approx(0.1)]
    ramp = np.arange(300.0)[:, None] * 0.01
    y = shaper.shape(ramp)
    assert shaper.last_status & tvist.Status.DELAY_CLAMPED
    assert shaper.status_counts["delay_clamped"] == 300
    s = tvist.shaper("zv", 10.0, 0.1)
    expected = s.amplitudes[0] * ramp[-1, 0] + s.amplitudes[1] * (ramp[-1, 0] - 50 * 0.01)
    assert y[-1, 0] == pytest.approx(expected, abs=1e-12)
    assert np.all((y >= 0) & (y <= ramp))


def test_damping_beyond_a_fit_is_limited_at_run_time() -> None:
    shaper = tvist.TvShaper(lambda q: [(40.0, 0.5)], DT_S, 1, shaper="ei", max_delay_s=1.0)
    shaper.step(np.array([0.0]))
    assert shaper.last_status == tvist.Status.ZETA_CLAMPED
    assert shaper.status_counts["zeta_clamped"] == 1
    assert shaper.delay_s == pytest.approx(tvist.shaper("ei", 40.0, 0.4).duration_s)


def test_status_flags_are_distinct_powers_of_two() -> None:
    values = [f.value for f in tvist.Status if f.value]
    assert len(set(values)) == len(values)
    assert all(v & (v - 1) == 0 for v in values)
