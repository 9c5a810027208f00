"""tvist.trajectory.shape_waypoints: waypoints in, shaped time-stamped trajectory out, checked
against the library calls it chains (with the resampling done independently by scipy)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.interpolate import CubicHermiteSpline

import tvist
from tvist.trajectory import PAPER_POSES, shape_waypoints

DT = 0.002
MODES = [(2 * np.pi * 8.0, 0.2), (2 * np.pi * 7.0, 0.3)]


def planner_waypoints():
    """A MoveIt-like plan Q1 -> Q3: 12 waypoints over 1.1 s with velocities, rest at both ends.
    Time stamps are whole multiples of 0.1 s so the samples at the waypoints exist."""
    q1, q3 = np.asarray(PAPER_POSES["Q1"]), np.asarray(PAPER_POSES["Q3"])
    t = 0.1 * np.arange(12)
    s = t / t[-1]
    blend = s**3 * (10 - 15 * s + 6 * s**2)
    dblend = (30 * s**2 - 60 * s**3 + 30 * s**4) / t[-1]
    return t, q1 + np.outer(blend, q3 - q1), np.outer(dblend, q3 - q1)


def scipy_grid(t_wp, q, v):
    n = int(round(t_wp[-1] / DT)) + 1
    t = DT * np.arange(n)
    return t, CubicHermiteSpline(t_wp, q, v, axis=0)(t)


def test_fd_tvist_equals_the_shaper_on_the_resampled_plan_and_ends_after_the_delay():
    t_wp, q, v = planner_waypoints()
    out = shape_waypoints(t_wp, q, DT, MODES, velocities=v, shaper="zvd")
    t, q_grid = scipy_grid(t_wp, q, v)
    # The unshaped samples are the cubic Hermite of the waypoints (scipy, independently).
    np.testing.assert_allclose(out.planned[: t.size], q_grid, rtol=0, atol=1e-12)
    shaper = tvist.TvShaper(tvist.ConstantModes(MODES), DT, 6, shaper="zvd")
    held = np.vstack([q_grid, np.repeat(q_grid[-1:], out.q.shape[0] - t.size, axis=0)])
    np.testing.assert_allclose(out.q, shaper.shape(held), rtol=0, atol=1e-12)
    np.testing.assert_allclose(out.t_s, DT * np.arange(out.q.shape[0]), rtol=0, atol=1e-12)
    np.testing.assert_allclose(out.qd, np.gradient(out.q, DT, axis=0), rtol=0, atol=1e-12)
    # It ends the convolved ZVD delay after the plan (plus the linear stencil's one sample).
    delay = sum(tvist.shaper("zvd", w, z).duration_s for w, z in MODES)
    assert out.planned_end_s == pytest.approx(1.1)
    assert out.added_delay_s == pytest.approx(delay, abs=2 * DT)
    k_settled = int(np.ceil((1.1 + delay) / DT - 1e-9)) + 1
    assert k_settled == out.q.shape[0] - 1  # the last sample is the first settled one
    assert np.max(np.abs(out.q[k_settled:] - q[-1])) < 1e-12
    assert np.max(np.abs(out.q[k_settled - 3] - q[-1])) > 1e-9  # still moving just before


def test_any_dynamics_provider_map_and_callable():
    t_wp, q, v = planner_waypoints()
    robot = tvist.robots.ur5e(5.0, (0.0, 0.0, 0.05))
    dynmap = tvist.DynamicMap.paper_ur5e()
    provider = tvist.MapDynamics(robot, dynmap)
    by_map = shape_waypoints(t_wp, q, DT, provider, velocities=v)
    t, q_grid = scipy_grid(t_wp, q, v)
    held = np.vstack([q_grid, np.repeat(q_grid[-1:], by_map.q.shape[0] - t.size, axis=0)])
    ref = tvist.TvShaper(tvist.MapDynamics(robot, dynmap), DT, 6).shape(held)
    np.testing.assert_allclose(by_map.q, ref, rtol=0, atol=1e-12)
    np.testing.assert_allclose(by_map.end_modes, dynmap.modes(robot, q[-1]), rtol=1e-14)
    # A callable provider gives the same modes, so the same trajectory.
    by_callable = shape_waypoints(
        t_wp, q, DT, lambda pose: provider.modes(pose), velocities=v, max_delay_s=0.3
    )
    np.testing.assert_allclose(by_callable.q, by_map.q, rtol=0, atol=1e-12)


@pytest.mark.parametrize(("method", "zd_method"), [("ztdis", "ztdis"), ("modified", "modified")])
def test_zero_delay_methods_end_at_the_planned_end(method, zd_method):
    t_wp, q, v = planner_waypoints()
    out = shape_waypoints(t_wp, q, DT, MODES, velocities=v, method=method)
    t, q_grid = scipy_grid(t_wp, q, v)
    ref = tvist.zero_delay(q_grid, DT, MODES, shaper="zv", method=zd_method, interp="linear")
    assert out.q.shape == q_grid.shape and out.added_delay_s == 0.0
    np.testing.assert_allclose(out.q, ref.Q, rtol=0, atol=1e-12)
    assert out.alpha == pytest.approx(ref.alpha, abs=1e-15)
    assert out.t_s[-1] == pytest.approx(t_wp[-1], abs=1e-12)
    np.testing.assert_allclose(out.q[-1], q[-1], atol=1e-6)


def test_bad_input_is_refused():
    t_wp, q, v = planner_waypoints()
    with pytest.raises(ValueError, match="unknown method"):
        shape_waypoints(t_wp, q, DT, MODES, method="fast")
    with pytest.raises(ValueError, match="strictly increasing"):
        shape_waypoints(t_wp[::-1], q, DT, MODES)
    with pytest.raises(ValueError, match="dynamics must be"):
        shape_waypoints(t_wp, q, DT, 3.0)
