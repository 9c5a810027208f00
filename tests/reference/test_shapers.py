"""The shaper library against SPEC section 1: closed forms, residual vibration, convolution.

References used here are independent of the Rust core: the closed forms written out from the
specification, a direct numpy evaluation of eqs. 52-55, a scipy ODE simulation of a
second-order mode driven by the shaped step, and a scipy solution of the EI conditions.
"""

from __future__ import annotations

import functools

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.optimize import brentq, fsolve

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


# The exact EI shaper (SPEC section 1, tolerance V): PRV = V at the design point, where it is
# the local maximum between two zeros of vibration, one below and one above. The reference
# below solves those six conditions independently of the Rust core (numpy residuals, scipy's
# hybrid root finder with its own finite-difference Jacobian), following the solution from
# the undamped closed form A = [(1+V)/4, (1-V)/2, (1+V)/4], t = [0, T/2, T] in small steps of
# zeta, so it never uses the published polynomial fit the core starts from.
EI_TOLERANCES = [0.02, 0.05, 0.1, 0.2]
# The EI range: zeta <= 0.4, and for V = 20 % zeta <= 0.28 (the exact design's limit).
EI_MAX_ZETA = {0.02: 0.4, 0.05: 0.4, 0.1: 0.4, 0.2: 0.28}
EI_ZETAS = [0.0, 0.1, 0.2, 0.28, 0.3, 0.4]
#: (tolerance, zeta) pairs inside the EI range.
EI_CASES = [(v, z) for v in EI_TOLERANCES for z in EI_ZETAS if z <= EI_MAX_ZETA[v]]


def ei_conditions(x: np.ndarray, v_tol: float, zeta: float) -> np.ndarray:
    """The six EI conditions in x = [A1, A3, wn*t2, wn*t3, r_lo, r_hi] (r = w / wn)."""
    a1, a3, tau2, tau3, r_lo, r_hi = x
    amplitudes = np.array([a1, 1 - a1 - a3, a3])
    exponents = (zeta + 1j * np.sqrt(1 - zeta**2)) * (np.array([0.0, tau2, tau3]) - tau3)

    def residual(r: float) -> complex:  # |residual(r)| = PRV at frequency ratio r
        return complex(np.sum(amplitudes * np.exp(r * exponents)))

    w = residual(1.0)
    dw = complex(np.sum(amplitudes * exponents * np.exp(exponents)))  # d residual / dr at r = 1
    z_lo, z_hi = residual(r_lo), residual(r_hi)
    return np.array(
        [abs(w) - v_tol, (w.conjugate() * dw).real / abs(w), z_lo.real, z_lo.imag]
        + [z_hi.real, z_hi.imag]
    )


@functools.cache
def ei_reference(v_tol: float, zeta: float) -> np.ndarray:
    """Root of `ei_conditions`, continued from zeta = 0 in steps of at most 0.01."""
    r_lo = np.arccos(-(1 - v_tol) / (1 + v_tol)) / np.pi
    x = np.array([(1 + v_tol) / 4, (1 + v_tol) / 4, np.pi, 2 * np.pi, r_lo, 2 - r_lo])
    for z in np.linspace(0.0, zeta, max(2, int(np.ceil(zeta / 0.01)) + 1)):
        x = fsolve(ei_conditions, x, args=(v_tol, z), xtol=1e-13)
        # Judged by the residual: at a root fsolve may report slow progress on the last digits.
        assert np.abs(ei_conditions(x, v_tol, z)).max() < 1e-12, (v_tol, z)
    return x


@pytest.mark.parametrize("v_tol", EI_TOLERANCES)
def test_undamped_ei_equals_its_closed_form(v_tol: float) -> None:
    wn = 2 * np.pi * 10
    period = 2 * np.pi / wn
    s = tvist.shaper("ei", wn, 0.0, tolerance=v_tol)
    # 1e-12: the core's Newton iteration converges to rounding.
    np.testing.assert_allclose(
        s.amplitudes, [(1 + v_tol) / 4, (1 - v_tol) / 2, (1 + v_tol) / 4], rtol=0, atol=1e-12
    )
    np.testing.assert_allclose(s.times_s, [0, period / 2, period], rtol=0, atol=1e-12 * period)


@pytest.mark.parametrize(("v_tol", "zeta"), EI_CASES)
def test_ei_equals_an_independent_solution_of_its_conditions(v_tol: float, zeta: float) -> None:
    wn = 2 * np.pi * 10
    s = tvist.shaper("ei", wn, zeta, tolerance=v_tol)
    a1, a3, tau2, tau3, _, _ = ei_reference(v_tol, zeta)
    # Both solve to residuals below 1e-12; 1e-9 (times relative to the undamped period)
    # allows for the conditioning of the system and is far below the published fit's error
    # (amplitudes up to 0.023, times up to 0.048 periods).
    np.testing.assert_allclose(s.amplitudes, [a1, 1 - a1 - a3, a3], rtol=0, atol=1e-9)
    np.testing.assert_allclose(s.times_s * wn, [0.0, tau2, tau3], rtol=0, atol=1e-9 * 2 * np.pi)


def band_edge(s: tvist.Impulses, wn: float, zeta: float, v_tol: float, start: float, stop: float):
    """First frequency ratio from ``start`` towards ``stop`` where PRV exceeds ``v_tol``
    (grid of 1e-3, then Brent's method to 1e-14), or None if PRV stays within it."""
    ratio = np.arange(start, stop, 1e-3 if stop > start else -1e-3)
    above = np.nonzero(tvist.prv(s, ratio * wn, zeta) > v_tol)[0]
    if len(above) == 0:
        return None
    i = above[0]
    return brentq(lambda r: tvist.prv(s, r * wn, zeta) - v_tol, ratio[i - 1], ratio[i], xtol=1e-14)


@pytest.mark.parametrize(("v_tol", "zeta"), EI_CASES)
def test_ei_tolerance_at_design_point_and_over_its_band(v_tol: float, zeta: float) -> None:
    wn = 2 * np.pi * 10
    s = tvist.shaper("ei", wn, zeta, tolerance=v_tol)
    # Exact design: V at the design point to rounding (1e-9), a local maximum there.
    assert tvist.prv(s, wn, zeta) == pytest.approx(v_tol, abs=1e-9)
    assert prv_numpy(s.amplitudes, s.times_s, wn, zeta) == pytest.approx(v_tol, abs=1e-9)
    assert max(tvist.prv(s, np.array([0.99, 1.01]) * wn, zeta)) < v_tol
    # Two zeros of vibration, one each side (from the independent reference).
    r_lo, r_hi = ei_reference(v_tol, zeta)[4:]
    assert r_lo < 1 < r_hi
    assert max(tvist.prv(s, np.array([r_lo, r_hi]) * wn, zeta)) < 1e-9
    # The band: PRV <= V from the lower edge to the upper one. Far above the design frequency
    # PRV tends to the last amplitude A3; if A3 < V, as at the most damped corners, the band
    # has no upper edge (searched up to 20).
    lo = band_edge(s, wn, zeta, v_tol, r_lo, 0.0)
    hi = band_edge(s, wn, zeta, v_tol, r_hi, 20.0)
    assert lo is not None
    ratio = np.arange(lo, hi if hi is not None else 20.0, 1e-4)
    assert tvist.prv(s, ratio * wn, zeta).max() <= v_tol + 1e-9
    assert tvist.prv(s, (lo - 1e-3) * wn, zeta) > v_tol
    if hi is None:
        assert s.amplitudes[-1] < v_tol and zeta >= 0.28
    else:
        assert tvist.prv(s, (hi + 1e-3) * wn, zeta) > v_tol
    # Insensitivity: at least +-10 % (undamped 5 % EI: +-20 %).
    assert lo < 0.9 and (hi is None or hi > 1.1)
    if zeta == 0.0:
        # Undamped: PRV(r) = |(1-V)/2 + (1+V)/2 cos(pi r)| <= V for cos(pi r) <= (3V-1)/(1+V).
        r_edge = np.arccos((3 * v_tol - 1) / (1 + v_tol)) / np.pi
        assert lo == pytest.approx(r_edge, abs=1e-9)
        assert hi == pytest.approx(2 - r_edge, abs=1e-9)


@pytest.mark.parametrize(
    "tolerance, zeta, message",
    [(0.004, 0.1, "tolerance"), (0.21, 0.1, "tolerance"), (0.2, 0.3, "ei"), (0.05, 0.41, "ei")],
)
def test_ei_rejects_tolerances_and_damping_outside_its_range(
    tolerance: float, zeta: float, message: str
) -> None:
    with pytest.raises(ValueError, match=message):
        tvist.shaper("ei", 30.0, zeta, tolerance=tolerance)
    # ...while the limits themselves are accepted.
    tvist.shaper("ei", 30.0, 0.28, tolerance=0.2)
    tvist.shaper("ei", 30.0, 0.4, tolerance=0.005)


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
