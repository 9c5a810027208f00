"""tvist.trajectory.resample: planner waypoints to the control grid, against independent
references (scipy's CubicHermiteSpline and B-splines, a hand-written quintic Hermite)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.interpolate import CubicHermiteSpline, make_interp_spline

from tvist.trajectory import interpolant, resample

DT = 0.002


def waypoints(n: int = 9, n_dof: int = 3, seed: int = 1):
    """Uneven, off-grid time stamps and an analytic motion with exact derivatives."""
    rng = np.random.default_rng(seed)
    t = np.concatenate([[0.0], np.cumsum(rng.uniform(0.07, 0.23, n - 1))])
    w = np.array([1.3, 2.1, 3.7])[:n_dof]
    q = np.sin(np.outer(t, w))
    v = w * np.cos(np.outer(t, w))
    a = -(w**2) * np.sin(np.outer(t, w))
    return t, q, v, a


def quintic_hermite(t_wp, q, v, a, t):
    """Per segment, the quintic matching q, v, a at both ends (basis written out by hand)."""
    k = np.clip(np.searchsorted(t_wp, t, side="right") - 1, 0, len(t_wp) - 2)
    h = (t_wp[k + 1] - t_wp[k])[:, None]
    s = ((t - t_wp[k]) / h[:, 0])[:, None]
    h00 = 1 - 10 * s**3 + 15 * s**4 - 6 * s**5
    h10 = s - 6 * s**3 + 8 * s**4 - 3 * s**5
    h20 = 0.5 * (s**2 - 3 * s**3 + 3 * s**4 - s**5)
    h01 = 10 * s**3 - 15 * s**4 + 6 * s**5
    h11 = -4 * s**3 + 7 * s**4 - 3 * s**5
    h21 = 0.5 * (s**3 - 2 * s**4 + s**5)
    return (
        h00 * q[k]
        + h10 * h * v[k]
        + h20 * h**2 * a[k]
        + h01 * q[k + 1]
        + h11 * h * v[k + 1]
        + h21 * h**2 * a[k + 1]
    )


def test_grid_starts_at_the_first_waypoint_steps_by_dt_and_covers_the_last():
    t_wp, q, v, _ = waypoints()
    t, Q = resample(t_wp + 0.5, q, DT, v)
    assert t[0] == 0.5 and Q.shape == (t.size, 3)
    np.testing.assert_allclose(np.diff(t), DT, rtol=0, atol=1e-12)
    assert t_wp[-1] + 0.5 <= t[-1] < t_wp[-1] + 0.5 + DT
    # After the last waypoint the end pose is held.
    np.testing.assert_array_equal(Q[-1], q[-1])


def test_velocities_give_the_cubic_hermite_of_joint_trajectory_controller():
    t_wp, q, v, _ = waypoints()
    t, Q = resample(t_wp, q, DT, v)
    inside = t <= t_wp[-1]
    ref = CubicHermiteSpline(t_wp, q, v, axis=0)
    # Same polynomial evaluated two ways: agreement to rounding (measured 4e-16).
    np.testing.assert_allclose(Q[inside], ref(t[inside]), rtol=0, atol=1e-12)
    f = interpolant(t_wp, q, v)
    np.testing.assert_allclose(f(t_wp), q, rtol=0, atol=1e-12)
    np.testing.assert_allclose(f(t_wp, 1), v, rtol=0, atol=1e-9)
    # The check can fail: with other velocities the samples move by far more than the bound.
    assert np.max(np.abs(resample(t_wp, q, DT, 0.9 * v)[1] - Q)) > 1e-4


def test_velocities_and_accelerations_give_the_quintic_hermite():
    t_wp, q, v, a = waypoints()
    t, Q = resample(t_wp, q, DT, v, a)
    inside = t <= t_wp[-1]
    np.testing.assert_allclose(
        Q[inside], quintic_hermite(t_wp, q, v, a, t[inside]), rtol=0, atol=1e-12
    )
    f = interpolant(t_wp, q, v, a)
    np.testing.assert_allclose(f(t_wp), q, rtol=0, atol=1e-12)
    np.testing.assert_allclose(f(t_wp, 1), v, rtol=0, atol=1e-9)
    np.testing.assert_allclose(f(t_wp, 2), a, rtol=0, atol=1e-8)
    # A quintic Hermite of a smooth motion is close to it (here 5e-6 rad at ~0.2 s steps).
    assert np.max(np.abs(Q[inside] - np.sin(np.outer(t[inside], [1.3, 2.1, 3.7])))) < 1e-4


def test_positions_only_give_a_c2_spline_at_rest_at_both_ends():
    t_wp, q, _, _ = waypoints()
    f = interpolant(t_wp, q)
    zero = np.zeros(q.shape[1])
    ref = make_interp_spline(t_wp, q, k=3, bc_type=([(1, zero)], [(1, zero)]), axis=0)
    t, Q = resample(t_wp, q, DT)
    inside = t <= t_wp[-1]
    np.testing.assert_allclose(Q[inside], ref(t[inside]), rtol=0, atol=1e-12)
    np.testing.assert_allclose(f(t_wp), q, rtol=0, atol=1e-12)
    np.testing.assert_allclose(f(t_wp[[0, -1]], 1), 0.0, atol=1e-12)
    # C²: value, slope and curvature continuous at every interior waypoint. Values 1e-9 s
    # either side differ by the next derivative times 2e-9 s (|v| <= 5 rad/s, |a| <= 20
    # rad/s², |jerk| <= 60 rad/s³ here) plus rounding: bounds 5e-8, 5e-7, 5e-6.
    eps = 1e-9
    for nu, bound in ((0, 5e-8), (1, 5e-7), (2, 5e-6)):
        jump = f(t_wp[1:-1] + eps, nu) - f(t_wp[1:-1] - eps, nu)
        assert np.max(np.abs(jump)) < bound, (nu, np.max(np.abs(jump)))
    # Control: the cubic Hermite through the same points with finite-difference slopes has
    # curvature jumps of order 1 rad/s² — the check above can fail.
    hermite = CubicHermiteSpline(t_wp, q, np.gradient(q, t_wp, axis=0), axis=0)
    jump = hermite(t_wp[1:-1] + eps, 2) - hermite(t_wp[1:-1] - eps, 2)
    assert np.max(np.abs(jump)) > 0.1


def test_on_grid_waypoints_are_reproduced_exactly_and_1d_input_stays_1d():
    # 10 Hz waypoints (0.1 s is 50.000000000000004 periods of 2 ms in floating point).
    t_wp = 0.1 * np.arange(11)
    q = np.sin(3.0 * t_wp)
    t, Q = resample(t_wp, q, DT)
    assert Q.ndim == 1 and t.size == 501
    k = np.rint(t_wp / DT).astype(int)
    np.testing.assert_allclose(Q[k], q, rtol=0, atol=1e-12)


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"times_s": [0.0, 0.2, 0.2], "positions": np.zeros((3, 2))}, "strictly increasing"),
        ({"times_s": [0.0, 0.3, 0.2], "positions": np.zeros((3, 2))}, r"times_s\[2\]"),
        ({"times_s": [0.0, np.nan], "positions": np.zeros((2, 2))}, "finite"),
        ({"times_s": [0.0, 1.0], "positions": [[0.0, 1.0], [np.nan, 0.0]]}, r"positions\[1, 0\]"),
        ({"times_s": [0.0, 1.0], "positions": np.zeros((3, 2))}, "3 waypoints but times_s has 2"),
        (
            {"times_s": [0.0, 1.0], "positions": np.zeros((2, 2)), "velocities": np.zeros((2, 3))},
            "velocities has shape",
        ),
        (
            {"times_s": [0, 1], "positions": np.zeros((2, 2)), "velocities": [[0, 0], [0, np.inf]]},
            r"velocities\[1, 1\]",
        ),
        (
            {"times_s": [0, 1], "positions": np.zeros((2, 2)), "accelerations": np.ones((2, 2))},
            "without velocities",
        ),
        ({"times_s": [], "positions": np.zeros((0, 2))}, "empty"),
        ({"times_s": [0.0], "positions": np.zeros((1, 2))}, "at least 2 waypoints"),
        ({"times_s": [0.0, 1.0], "positions": np.zeros((2, 0))}, "empty"),
        ({"times_s": [0.0, 1.0], "positions": np.zeros((2, 2)), "dt_s": 0.0}, "dt_s"),
        ({"times_s": [0.0, 1e6], "positions": np.zeros((2, 2))}, "are the times in seconds"),
    ],
)
def test_bad_waypoints_are_refused_naming_the_problem(kwargs, match):
    kwargs = {"dt_s": DT, **kwargs}
    with pytest.raises(ValueError, match=match):
        resample(**kwargs)
