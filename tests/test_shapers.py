"""The shaper library against SPEC section 1: closed forms, residual vibration, convolution.

References used here are independent of the Rust core: the closed forms written out from the
specification, a direct numpy evaluation of eqs. 52-55, and a scipy ODE simulation of a
second-order mode driven by the shaped step.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import tvist

# (wn_rad_s, zeta): low and high frequency, undamped to strongly damped.
MODES = [
    (2 * np.pi * 8.0, 0.0),
    (2 * np.pi * 8.0, 0.05),
    (50.0, 0.1),
    (2 * np.pi * 22.0, 0.26),
    (3.0, 0.37),
    (120.0, 0.6),
]


def prv_numpy(amplitudes: np.ndarray, times_s: np.ndarray, wn_rad_s: float, zeta: float) -> float:
    """Eqs. 52-55 written out directly (complex form)."""
    wd = wn_rad_s * np.sqrt(1 - zeta**2)
    z = np.sum(amplitudes * np.exp(zeta * wn_rad_s * times_s) * np.exp(1j * wd * times_s))
    return float(np.exp(-zeta * wn_rad_s * times_s[-1]) * abs(z))


@pytest.mark.parametrize("wn, zeta", MODES)
def test_zv_and_zvd_match_the_closed_forms(wn: float, zeta: float) -> None:
    k = np.exp(-zeta * np.pi / np.sqrt(1 - zeta**2))
    wd = wn * np.sqrt(1 - zeta**2)
    td = 2 * np.pi / wd
    zv = tvist.shaper("zv", wn, zeta)
    zvd = tvist.shaper("zvd", wn, zeta)
    # 1e-12: same formulas, different evaluation order; rounding differs around 1e-16.
    np.testing.assert_allclose(zv.amplitudes, [1 / (1 + k), k / (1 + k)], rtol=0, atol=1e-12)
    np.testing.assert_allclose(zv.times_s, [0, np.pi / wd], rtol=1e-12, atol=0)
    np.testing.assert_allclose(
        zvd.amplitudes, np.array([1, 2 * k, k**2]) / (1 + k) ** 2, rtol=0, atol=1e-12
    )
    np.testing.assert_allclose(zvd.times_s, [0, td / 2, td], rtol=1e-12, atol=0)
    zvdd = tvist.shaper("zvdd", wn, zeta)
    np.testing.assert_allclose(
        zvdd.amplitudes, np.array([1, 3 * k, 3 * k**2, k**3]) / (1 + k) ** 3, rtol=0, atol=1e-12
    )


@pytest.mark.parametrize("name", ["zv", "zvd", "zvdd", "mzv"])
@pytest.mark.parametrize("wn, zeta", MODES)
def test_zero_vibration_at_the_design_point(name: str, wn: float, zeta: float) -> None:
    s = tvist.shaper(name, wn, zeta)
    # Exact cancellation in theory: 1e-9 leaves room for rounding only.
    assert tvist.prv(s, wn, zeta) <= 1e-9
    assert prv_numpy(s.amplitudes, s.times_s, wn, zeta) <= 1e-9
    # The check can fail: 40 % off the design frequency vibration remains.
    if zeta <= 0.3:
        assert tvist.prv(s, 1.4 * wn, zeta) > 1e-3


@pytest.mark.parametrize("name", tvist.SHAPERS)
def test_core_prv_equals_the_direct_formula(name: str) -> None:
    s = tvist.shaper(name, 40.0, 0.1)
    wn = np.linspace(5.0, 120.0, 57)
    for zeta in (0.0, 0.03, 0.2, 0.5):
        expected = [prv_numpy(s.amplitudes, s.times_s, w, zeta) for w in wn]
        np.testing.assert_allclose(tvist.prv(s, wn, zeta), expected, rtol=1e-12, atol=1e-15)


def simulated_residual_ratio(s: tvist.Impulses, wn: float, zeta: float) -> float:
    """Residual amplitude of a mode driven by the shaped unit step, relative to the unshaped
    step's residual at the moment each input stops changing (the definition behind PRV).

    The mode ``y'' + 2 zeta wn y' + wn^2 y = wn^2 u`` is integrated piecewise between impulse
    times with a tight-tolerance ODE solver; the residual ``y - 1`` after the last impulse is
    then fitted by least squares as a damped sinusoid and its amplitude taken at the last
    impulse time.
    """
    wd = wn * np.sqrt(1 - zeta**2)

    def rhs(_t: float, x: np.ndarray, u: float) -> list[float]:
        return [x[1], wn**2 * (u - x[0]) - 2 * zeta * wn * x[1]]

    state = np.zeros(2)
    level = 0.0
    bounds = list(s.times_s) + [s.times_s[-1] + 4 * 2 * np.pi / wd]
    t_fit = y_fit = None
    for i, a in enumerate(s.amplitudes):
        level += a
        t0, t1 = bounds[i], bounds[i + 1]
        if t1 <= t0:
            continue
        last = i == len(s.amplitudes) - 1
        t_eval = np.linspace(t0, t1, 2000) if last else None
        sol = solve_ivp(rhs, (t0, t1), state, args=(level,), rtol=1e-12, atol=1e-14, t_eval=t_eval)
        if last:
            t_fit, y_fit = sol.t, sol.y[0] - 1.0
        state = sol.y[:, -1]
    tau = t_fit - s.times_s[-1]
    basis = np.exp(-zeta * wn * tau)[:, None] * np.column_stack(
        [np.cos(wd * tau), np.sin(wd * tau)]
    )
    coef, *_ = np.linalg.lstsq(basis, y_fit, rcond=None)
    # The unshaped unit step leaves y - 1 = -e^{-zeta wn t}(cos wd t + zeta/sqrt(1-zeta^2) sin wd t)
    # whose amplitude at t = 0 is 1/sqrt(1 - zeta^2).
    return float(np.hypot(*coef) * np.sqrt(1 - zeta**2))


@pytest.mark.parametrize(
    "shaper_mode, plant_mode, name",
    [
        ((2 * np.pi * 5.0, 0.1), (2 * np.pi * 5.0, 0.1), "zv"),
        ((2 * np.pi * 5.0, 0.1), (2 * np.pi * 6.0, 0.1), "zv"),
        ((2 * np.pi * 5.0, 0.05), (2 * np.pi * 4.2, 0.08), "zvd"),
        ((30.0, 0.1), (30.0, 0.1), "ei"),
        ((30.0, 0.0), (36.0, 0.02), "3hump_ei"),
    ],
)
def test_prv_agrees_with_an_ode_simulation(shaper_mode, plant_mode, name) -> None:
    s = tvist.shaper(name, *shaper_mode)
    simulated = simulated_residual_ratio(s, *plant_mode)
    # Solver tolerance 1e-12 and an exact model fit: agreement to ~1e-9; 1e-6 is comfortable.
    assert simulated == pytest.approx(tvist.prv(s, *plant_mode), abs=1e-6)
    if plant_mode != shaper_mode:
        assert simulated > 0.01  # off-design: the comparison is not 0 == 0


# Accuracy of the published EI polynomial fit at the design point, per tolerance. Measured
# worst |PRV - V| over zeta in [0, 0.2]: 3.5e-4 (V = 3 %), 1.22e-3 (5 %, at zeta = 0),
# 4.8e-3 (10 %, at zeta = 0). The exact undamped EI (A = [(1+V)/4, (1-V)/2, (1+V)/4]) has zero
# error; the fit trades it for accuracy when damped.
EI_FIT_ACCURACY = {0.03: 1e-3, 0.05: 1.5e-3, 0.1: 5e-3}


def band_around_one(ratio: np.ndarray, prv: np.ndarray, limit: float) -> tuple[float, float]:
    """The contiguous interval of frequency ratios containing 1 where ``prv <= limit``."""
    ok = prv <= limit
    centre = int(np.searchsorted(ratio, 1.0))
    assert ok[centre]
    lo = centre
    while lo > 0 and ok[lo - 1]:
        lo -= 1
    hi = centre
    while hi + 1 < len(ok) and ok[hi + 1]:
        hi += 1
    assert 0 < lo and hi + 1 < len(ok), "band reaches the edge of the sweep"
    return float(ratio[lo]), float(ratio[hi])


@pytest.mark.parametrize("v_tol", [0.03, 0.05, 0.1])
@pytest.mark.parametrize("zeta", [0.0, 0.05, 0.1, 0.2])
def test_ei_tolerance_at_design_point_and_over_its_band(v_tol: float, zeta: float) -> None:
    wn = 2 * np.pi * 10
    s = tvist.shaper("ei", wn, zeta, tolerance=v_tol)
    acc = EI_FIT_ACCURACY[v_tol]
    assert tvist.prv(s, wn, zeta) == pytest.approx(v_tol, abs=acc)
    ratio = np.linspace(0.5, 1.6, 11001)
    prv = tvist.prv(s, ratio * wn, zeta)
    lo, hi = band_around_one(ratio, prv, v_tol + acc)
    # Insensitivity: at least +-10 % (undamped 5 % EI: +-20 %) within the tolerance...
    assert lo < 0.9 and hi > 1.1
    # ...with two zeros of vibration inside, one each side of the design point...
    inner = prv[(ratio >= lo) & (ratio <= hi)]
    r_in = ratio[(ratio >= lo) & (ratio <= hi)]
    assert inner[r_in < 1].min() < 0.1 * v_tol and inner[r_in > 1].min() < 0.1 * v_tol
    # ...and just outside the band the tolerance is exceeded (the band is real, not the sweep).
    assert tvist.prv(s, 0.97 * lo * wn, zeta) > v_tol + acc
    assert tvist.prv(s, 1.03 * hi * wn, zeta) > v_tol + acc


def test_exact_undamped_ei_gives_the_band_the_fit_reproduces() -> None:
    # Exact undamped EI: PRV(r) = |(1-V)/2 + (1+V)/2 cos(pi r)|, <= V for
    # cos(pi r) <= (3V-1)/(1+V): r in [0.7996, 1.2004] at V = 5 %.
    v = 0.05
    r_edge = np.arccos((3 * v - 1) / (1 + v)) / np.pi
    s = tvist.shaper("ei", 1.0, 0.0, tolerance=v)
    ratio = np.linspace(0.5, 1.6, 110001)
    lo, hi = band_around_one(ratio, tvist.prv(s, ratio, 0.0), v)
    # The fit's band edges lie within 1.2e-3 of the exact ones (measured: 0.8014 and 1.1986
    # against 0.8003 and 1.1997); 5e-3 still fails a shaper of any other shape.
    assert abs(lo - r_edge) < 5e-3 and abs(hi - (2 - r_edge)) < 5e-3


def extrema(y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    i = np.arange(1, len(y) - 1)
    maxima = i[(y[i] > y[i - 1]) & (y[i] > y[i + 1])]
    minima = i[(y[i] < y[i - 1]) & (y[i] < y[i + 1])]
    return maxima, minima


@pytest.mark.parametrize("name, humps", [("2hump_ei", 2), ("3hump_ei", 3)])
@pytest.mark.parametrize("zeta", [0.0, 0.05, 0.1, 0.2])
def test_multi_hump_ei(name: str, humps: int, zeta: float) -> None:
    wn = 40.0
    s = tvist.shaper(name, wn, zeta)
    # Tabulated for V = 5 %; measured humps of the published fit reach 5.51 % for zeta <= 0.2.
    limit = 0.05 + 0.006
    ratio = np.linspace(0.35, 1.9, 15501)
    prv = tvist.prv(s, ratio * wn, zeta)
    lo, hi = band_around_one(ratio, prv, limit)
    inside = (ratio >= lo) & (ratio <= hi)
    maxima, minima = extrema(prv[inside])
    assert len(maxima) == humps
    assert len(minima) == humps + 1
    assert np.all(prv[inside][maxima] > 0.03)
    assert np.all(prv[inside][minima] < 0.02)
    if humps == 2:
        assert tvist.prv(s, wn, zeta) < 0.004  # a zero at the design point
    else:
        assert tvist.prv(s, wn, zeta) == pytest.approx(0.05, abs=0.006)  # middle hump
    assert lo < 0.75 and hi > 1.25
    assert tvist.prv(s, 0.97 * lo * wn, zeta) > limit
    assert tvist.prv(s, 1.03 * hi * wn, zeta) > limit


@pytest.mark.parametrize(
    "names", [("zv", "zv"), ("zvd", "mzv"), ("ei", "zv", "3hump_ei"), ("2hump_ei", "zvdd")]
)
def test_convolution(names: tuple[str, ...]) -> None:
    modes = [(2 * np.pi * 8.0, 0.26), (2 * np.pi * 6.9, 0.1), (2 * np.pi * 19.2, 0.14)][
        : len(names)
    ]
    sets = [tvist.shaper(n, *m) for n, m in zip(names, modes, strict=True)]
    c = tvist.convolve(*sets)
    assert c.amplitudes.sum() == pytest.approx(1.0, abs=1e-12)
    assert np.all(np.diff(c.times_s) > 0)
    assert c.duration_s == pytest.approx(sum(s.duration_s for s in sets), abs=1e-12)
    assert len(c) <= np.prod([len(s) for s in sets])
    # The residual vibration of a convolution is the product of the factors' (eq. 53),
    # at each design mode and anywhere else.
    probe = modes + [(30.0, 0.05), (70.0, 0.3)]
    for wn, zeta in probe:
        product = np.prod([tvist.prv(s, wn, zeta) for s in sets])
        assert tvist.prv(c, wn, zeta) == pytest.approx(product, abs=1e-12)
    for (wn, zeta), name in zip(modes, names, strict=True):
        if name in ("zv", "zvd", "zvdd", "mzv"):
            assert tvist.prv(c, wn, zeta) <= 1e-9


def test_custom_sets_are_normalized() -> None:
    s = tvist.Impulses([2.0, 6.0], [0.0, 0.05])
    np.testing.assert_array_equal(s.amplitudes, [0.25, 0.75])
    assert s.duration_s == 0.05
    assert len(s) == 2


@pytest.mark.parametrize(
    "amplitudes, times_s, message",
    [
        ([], [], "empty"),
        ([1.0, 1.0], [0.0], "2 amplitudes but 1 times"),
        ([1.0, np.nan], [0.0, 0.1], "amplitude 1 is not finite"),
        ([1.0, 1.0], [0.0, np.inf], "time 1 is not finite"),
        ([1.0, 1.0, 1.0], [0.0, 0.2, 0.1], "non-decreasing"),
        ([1.0, -1.0], [0.0, 0.1], "sum to zero"),
        ([1.0], [-0.1], "negative"),
    ],
)
def test_invalid_custom_sets(amplitudes, times_s, message) -> None:
    with pytest.raises(ValueError, match=message):
        tvist.Impulses(amplitudes, times_s)


def test_prv_broadcasts_and_flags_invalid_modes() -> None:
    s = tvist.shaper("zvd", 30.0, 0.1)
    out = tvist.prv(s, np.array([[20.0], [30.0], [40.0]]), np.array([0.0, 0.1]))
    assert out.shape == (3, 2)
    assert out[1, 1] <= 1e-9
    assert isinstance(tvist.prv(s, 30.0, 0.1), float)
    assert np.isnan(tvist.prv(s, -1.0, 0.1))
    assert np.isnan(tvist.prv(s, 30.0, 1.0))
