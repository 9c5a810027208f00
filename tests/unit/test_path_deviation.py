"""tvist.analysis.path_deviation: distance of the shaped tool path from the planned one."""

from __future__ import annotations

import numpy as np
import pytest

import tvist
from tvist.analysis.path import path_deviation, point_to_polyline_distance


@pytest.fixture(scope="module")
def ur5e():
    return tvist.robots.ur5e()


def base_arc(theta_end: float, n: int = 400) -> np.ndarray:
    """Only the base joint turns (0 -> theta_end): the flange moves on a horizontal circle."""
    q = np.zeros((n, 6))
    s = np.linspace(0.0, 1.0, n)
    q[:, 0] = theta_end * s**3 * (10 - 15 * s + 6 * s**2)
    return q


def test_identical_paths_and_a_path_run_late_have_zero_deviation(ur5e):
    q = base_arc(1.0)
    same = path_deviation(ur5e, q, q)
    assert same.max_m == 0.0 and same.distance_m.shape == (q.shape[0],)
    # Running behind along the same path is not a deviation (the same-time distance is large).
    late = np.vstack([np.repeat(q[:1], 37, axis=0), q])
    assert path_deviation(ur5e, q, late).max_m == 0.0
    tool = ur5e.flange_pose_many(q)[:, :3, 3]
    tool_late = ur5e.flange_pose_many(late[: q.shape[0]])[:, :3, 3]
    assert np.max(np.linalg.norm(tool - tool_late, axis=1)) > 0.05


def test_overshoot_beyond_the_end_is_the_chord_from_the_end_point(ur5e):
    # Hand computation from the DH table (not from the kinematics code): at q = 0 a UR's flange
    # lies at x = a2 + a3, y = -(d4 + d6) from the base axis, so turning the base moves it on a
    # circle of radius r = hypot(a2 + a3, d4 + d6). A shaped path that overshoots the planned
    # end angle by delta and comes back is farthest from the planned path at the overshoot,
    # whose nearest planned point is the end point: distance 2 r sin(delta / 2).
    p = tvist.robots.params("ur5e")
    r = np.hypot(p.a_m[1] + p.a_m[2], p.d_m[3] + p.d_m[5])
    assert r == pytest.approx(np.hypot(0.8172, 0.2329), abs=1e-12)
    theta, delta = 1.0, 0.02
    planned = base_arc(theta)
    back = np.linspace(theta + delta, theta, 50)[:, None] * np.eye(6)[0]
    shaped = np.vstack([base_arc(theta + delta), back])
    dev = path_deviation(ur5e, planned, shaped)
    # The overshoot point lies beyond the last planned chord, so the polyline's nearest point
    # is exactly the end vertex: agreement to rounding.
    assert dev.max_m == pytest.approx(2.0 * r * np.sin(delta / 2.0), rel=1e-9)
    assert dev.path_fraction == pytest.approx(1.0, abs=1e-12)
    assert shaped[dev.index, 0] == pytest.approx(theta + delta, abs=1e-12)


def test_polyline_distance_on_a_constructed_example():
    line = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 2.0, 0.0]])
    pts = np.array([[0.5, 0.3, 0.0], [-1.0, 0.0, 0.0], [1.5, 1.0, 0.4], [1.0, 3.0, 0.0]])
    d, arc = point_to_polyline_distance(pts, line)
    np.testing.assert_allclose(d, [0.3, 1.0, np.hypot(0.5, 0.4), 1.0], rtol=0, atol=1e-15)
    np.testing.assert_allclose(arc, [0.5, 0.0, 2.0, 3.0], rtol=0, atol=1e-15)
    d1, arc1 = point_to_polyline_distance(pts[:1], line[:1])  # a single-point path
    assert d1[0] == pytest.approx(np.hypot(0.5, 0.3)) and arc1[0] == 0.0


def test_bad_arrays_are_refused(ur5e):
    q = base_arc(0.5, 10)
    with pytest.raises(ValueError, match="Q_shaped must have shape"):
        path_deviation(ur5e, q, q[:, :5])
    with pytest.raises(ValueError, match="Q_planned must have shape"):
        path_deviation(ur5e, np.zeros((0, 6)), q)
    with pytest.raises(ValueError, match="tcp_m"):
        path_deviation(ur5e, q, q, tcp_m=(0.0, 0.1))
    bad = q.copy()
    bad[3, 2] = np.nan
    with pytest.raises(ValueError, match="row 3"):
        path_deviation(ur5e, q, bad)


def test_shaping_keeps_a_joint_space_line_and_bends_a_curved_joint_path(ur5e):
    # The statement of docs/guides/planners.md. A phase-synchronized double-S move (the
    # demo's Q1 -> Q3) is a straight line in joint space; ZV shaping blends points of that
    # line with positive weights, so the flange stays on the planned path up to the
    # resolution of the polyline through the 2 ms samples (its chords cut the arcs by at
    # most ~2 µm here).
    from tvist.trajectory import PAPER_POSES, double_s

    traj = double_s(PAPER_POSES["Q1"], PAPER_POSES["Q3"], dt_s=0.002, t_post_s=0.2)
    modes = [(2 * np.pi * 8.0, 0.2), (2 * np.pi * 7.0, 0.3)]
    shaped = tvist.TvShaper(tvist.ConstantModes(modes), 0.002, 6).shape(traj.q)
    on_line = path_deviation(ur5e, traj.q, shaped).max_m
    assert on_line < 3e-6, on_line
    # The same shaper on a path that is curved in joint space (joint 1 on a different timing
    # from the others: a bend in joint space) leaves the planned path: measured 0.62 mm
    # against 1.8 µm on the line.
    bent = np.array(traj.q)
    s = (bent[:, 0] - bent[0, 0]) / (bent[-1, 0] - bent[0, 0])
    bent[:, 1] = bent[0, 1] + (bent[-1, 1] - bent[0, 1]) * s**3
    off_line = path_deviation(
        ur5e, bent, tvist.TvShaper(tvist.ConstantModes(modes), 0.002, 6).shape(bent)
    )
    assert off_line.max_m > 1e-4, off_line.max_m
