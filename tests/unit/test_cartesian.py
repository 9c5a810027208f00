"""Cartesian-space shaping: inverse kinematics, straight lines that stay straight, shaping."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import tvist
from tvist import cartesian, robots

#: The UR5e's control period (its robot data), s.
DT_S = robots.params("ur5e").control_period_s
# A pose in front of the base with the flange pointing down, away from singularities.
Q_START = np.array([math.pi, -2.0, 1.8, -1.37, -math.pi / 2, 0.0])
MODE = (2.0 * math.pi * 2.55, 0.04)


def dh_flange(q: np.ndarray) -> np.ndarray:
    """Flange pose by the standard DH chain of the parameter file, plain numpy (independent
    of the Rust model the inverse kinematics uses)."""
    p = robots.params("ur5e")
    t = np.eye(4)
    for qi, d, a, alpha in zip(q, p.d_m, p.a_m, p.alpha_rad, strict=True):
        c, s, ca, sa = math.cos(qi), math.sin(qi), math.cos(alpha), math.sin(alpha)
        t = t @ np.array(
            [[c, -s * ca, s * sa, a * c], [s, c * ca, -c * sa, a * s], [0, sa, ca, d], [0, 0, 0, 1]]
        )
    return t


def distance_to_line(points: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Distance of ``points`` (n, 3) from the infinite line through ``a`` and ``b``."""
    u = (b - a) / np.linalg.norm(b - a)
    rel = points - a
    return np.linalg.norm(rel - np.outer(rel @ u, u), axis=1)


@pytest.fixture(scope="module")
def robot() -> robots.Robot:
    return robots.ur5e(payload_kg=0.0)


@pytest.fixture(scope="module")
def line(robot):
    traj, r0 = cartesian.straight_line(
        robot, Q_START, (0.3, 0.0, 0.0), 0.734, DT_S, t_pre_s=0.1, t_post_s=0.5
    )
    return np.asarray(traj.q), r0


def test_inverse_kinematics_reaches_poses_of_an_independent_forward_model(robot):
    rng = np.random.default_rng(4)
    for _ in range(20):
        q_true = Q_START + rng.uniform(-0.4, 0.4, 6)
        target = dh_flange(q_true)
        seed = q_true + rng.uniform(-0.1, 0.1, 6)
        q = cartesian.solve_ik(robot, target[:3, 3], target[:3, :3], seed)
        reached = dh_flange(q)
        # IK stops at 1e-10 m / rad on the Rust model; the numpy chain agrees with it to
        # round-off, so 1e-9 allows for both.
        assert np.max(np.abs(reached[:3, 3] - target[:3, 3])) < 1e-9
        assert np.max(np.abs(reached[:3, :3] - target[:3, :3])) < 1e-9


def test_unreachable_target_is_refused(robot):
    with pytest.raises(ValueError, match="out of reach"):
        cartesian.solve_ik(robot, [2.0, 0.0, 0.5], np.eye(3), Q_START)


def test_cartesian_shaping_keeps_the_line_and_joint_shaping_leaves_it(robot, line):
    x, r0 = line
    q_planned = cartesian.joints_from_tcp(robot, x, r0, Q_START)
    shaped = cartesian.shape_cartesian(robot, Q_START, x, r0, DT_S, [MODE], shaper="zvd")
    a, b = x[0, :3], x[-1, :3]
    flange = np.array([dh_flange(q)[:3, 3] for q in shaped.Q])
    # On the line to the IK tolerance (1e-10 m), and at the shaped position.
    assert np.max(distance_to_line(flange, a, b)) < 1e-9
    assert np.max(np.abs(flange - shaped.X[:, :3])) < 1e-9
    # Orientation held.
    rot = np.array([dh_flange(q)[:3, :3] for q in shaped.Q])
    assert np.max(np.abs(rot - r0)) < 1e-9
    # The same ZVD on the joint reference bends the path by far more (it is ~0.1 mm here).
    joint = tvist.TvShaper(tvist.ConstantModes([MODE]), DT_S, 6, shaper="zvd")
    joint.reset(q_planned[0])
    q_joint = joint.shape(q_planned)
    off = distance_to_line(np.array([dh_flange(q)[:3, 3] for q in q_joint]), a, b)
    assert np.max(off) > 1e-5
    # The library's deviation measure agrees with the analytic point-to-line distance (the
    # planned polyline lies on the line to IK tolerance; shaped points project inside it).
    measured = cartesian.tcp_path_deviation_m(robot, q_planned, q_joint)
    assert np.max(np.abs(measured - off)) < 1e-9
    assert np.max(cartesian.tcp_path_deviation_m(robot, q_planned, shaped.Q)) < 1e-9


def test_conventional_shaping_is_the_impulse_sum_of_the_exact_move(robot, line):
    x, _ = line
    shaped = cartesian.shape_tcp(x, DT_S, [MODE], shaper="zvd")
    impulses = tvist.shaper("zvd", *MODE)
    # Reference: Σ A_i x(t − Δ_i) with the exact minimum-jerk move evaluated off the grid.
    t = DT_S * np.arange(x.shape[0])
    t0, length = 0.1, 0.734

    def exact(tt: np.ndarray) -> np.ndarray:
        tau = np.clip((tt - t0) / length, 0.0, 1.0)
        return x[0, 0] + 0.3 * (10 * tau**3 - 15 * tau**4 + 6 * tau**5)

    expected = sum(
        a * exact(t - d) for a, d in zip(impulses.amplitudes, impulses.times_s, strict=True)
    )
    # The shaper reads its delay line by linear interpolation between samples: error at most
    # dt²/8 max|x''| = 4e-6/8 * 3.5 m/s² ≈ 2e-6 m.
    assert np.max(np.abs(shaped[:, 0] - expected)) < 3e-6
    assert np.max(np.abs(shaped[:, 1:] - x[:, 1:])) < 1e-12  # the other coordinates stay


def test_zero_delay_methods_end_with_the_planned_move(robot, line):
    x, _ = line
    end = int(np.flatnonzero(np.any(x != x[-1], axis=1))[-1]) + 1  # first sample at the end
    for method in ("ztdis", "modified"):
        shaped = cartesian.shape_tcp(x, DT_S, [MODE], method=method, shaper="zvd")
        # At the end from the planned stop on (truncation residue of nanometres).
        assert np.max(np.abs(shaped[end:, :3] - x[-1, :3])) < 1e-7, method
        # ... and still moving just before it: no slack.
        assert np.max(np.abs(shaped[end - 20, :3] - x[-1, :3])) > 1e-4, method


def test_interpolated_orientation_follows_the_same_path_parameter(robot):
    traj, r0 = cartesian.straight_line(
        robot, Q_START, (0.2, 0.05, 0.0), 0.6, DT_S, rotation_rad=(0.0, 0.0, 0.4), t_post_s=0.5
    )
    shaped = cartesian.shape_cartesian(
        robot, Q_START, np.asarray(traj.q), r0, DT_S, [MODE], shaper="zv"
    )
    start = dh_flange(shaped.Q[0])[:3, 3]
    for q in shaped.Q[::25]:
        pose = dh_flange(q)
        s_pos = (pose[0, 3] - start[0]) / 0.2
        # Position on the line at parameter s, orientation rotated by s * 0.4 rad about z.
        assert pose[:3, 3] == pytest.approx(start + s_pos * np.array([0.2, 0.05, 0.0]), abs=1e-9)
        rotvec = Rotation.from_matrix(pose[:3, :3] @ r0.T).as_rotvec()
        assert rotvec == pytest.approx([0.0, 0.0, 0.4 * s_pos], abs=1e-9)


def test_time_varying_modes_are_evaluated_at_the_joints_of_the_previous_output(robot, line):
    x, r0 = line
    seen: list[np.ndarray] = []

    def modes_of(q: np.ndarray) -> list[tuple[float, float]]:
        seen.append(np.array(q))
        return [MODE]

    shaped = cartesian.shape_cartesian(
        robot, Q_START, x, r0, DT_S, modes_of, shaper="zv", max_delay_s=0.5
    )
    constant = cartesian.shape_tcp(x, DT_S, [MODE], shaper="zv")
    # Constant modes through the callable path give the constant-mode result.
    assert np.max(np.abs(shaped.X - constant)) < 1e-12
    # The provider saw joints whose flange is the previous shaped TCP sample: call 0 is the
    # shaper's probe when it is built, call k >= 1 belongs to step k - 1, which reads the
    # output of step k - 2.
    assert len(seen) == x.shape[0] + 1
    for k in (2, len(seen) // 2, len(seen) - 1):
        assert dh_flange(seen[k])[:3, 3] == pytest.approx(shaped.X[k - 2, :3], abs=1e-9)


def test_setup_errors_name_the_problem(robot, line):
    x, _ = line
    with pytest.raises(ValueError, match="unknown method"):
        cartesian.shape_tcp(x, DT_S, [MODE], method="zvd")
    with pytest.raises(ValueError, match="fixed modes"):
        cartesian.shape_tcp(x, DT_S, tvist.DynamicMap.paper_ur5e(), method="modified")
    with pytest.raises(ValueError, match="rest"):
        cartesian.shape_tcp(x[:-240], DT_S, [MODE], shaper="zvd")  # no room for the delay
    with pytest.raises(ValueError, match=r"\(n_samples, 6\)"):
        cartesian.shape_tcp(x[:, :3], DT_S, [MODE])
