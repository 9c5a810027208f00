"""Shaping with the map-driven provider: the paper's Q1 -> Q2 move and bad setups."""

from __future__ import annotations

import numpy as np
import pytest

import tvist
from tvist.trajectory import PAPER_POSES, double_s

DT_S = 0.002
Q1, Q2, Q3 = PAPER_POSES["Q1"], PAPER_POSES["Q2"], PAPER_POSES["Q3"]


def _ur5e_5kg() -> tvist.robots.Robot:
    # Paper section 6.1: 5 kg payload; here 5 cm beyond the flange along its z axis.
    return tvist.robots.ur5e(payload_kg=5.0, payload_com_m=(0.0, 0.0, 0.05))


def _zv_delay_s(robot: tvist.robots.Robot, q: np.ndarray) -> float:
    """Two-mode ZV delay pi/w_d0 + pi/w_d1 at q, from the robot's J and eqs. 47-48, 50-51."""
    j0, j1 = robot.joint_inertia(q)[:2]
    k_b, k_s = 10000.0 + 1060.0 * j1, 10000.0 + 763.0 * j1
    wn0 = np.sqrt(1 + 2.54 / j1) * np.sqrt(k_b / j1)
    z0 = (
        (1 + 2.54 / j0)
        * (1.53 + 0.39 * j0)
        * (1 + 3.81 * j0)
        / (2 * np.sqrt(k_b * j1) * np.sqrt(1 + 2.54 / j1))
    )
    wn1 = np.sqrt(1 + 1.73 / j1) * np.sqrt(k_s / j1)
    z1 = np.sqrt(1 + 1.73 / j1) * (0.27 + 0.038 * j1) * (1 + 47.2 * j1) / (2 * np.sqrt(k_s * j1))
    return np.pi / (wn0 * np.sqrt(1 - z0**2)) + np.pi / (wn1 * np.sqrt(1 - z1**2))


def _end_of_motion_s(q: np.ndarray, q_end: np.ndarray, tol_rad: float) -> float:
    """Time of the first sample from which every later sample is within tol_rad of q_end."""
    away = np.flatnonzero(np.abs(q - q_end).max(axis=1) > tol_rad)
    return (away[-1] + 1) * DT_S


def test_q1_to_q2_is_delayed_by_the_two_mode_zv_delay_at_q2():
    robot = _ur5e_5kg()
    move = double_s(Q1, Q2, dt_s=DT_S, v_max=1.5, a_max=2.0, jerk_time_s=0.02, t_post_s=0.5)
    shaper = tvist.TvShaper(
        tvist.MapDynamics(robot, tvist.DynamicMap.paper_ur5e()), dt_s=DT_S, n_dof=6
    )
    shaped = shaper.shape(move.q)
    assert shaper.last_status == 0 and shaper.status_counts["delay_clamped"] == 0
    # The input reaches Q2 exactly at the end of the move.
    assert _end_of_motion_s(move.q, Q2, 0.0) == pytest.approx(move.t_motion_end_s, abs=1e-12)
    # Shaped end: within 1e-9 rad of Q2 for good. The jerk-limited approach is ~j s^3/6 with
    # j = 100 rad/s^3, so 1e-9 rad is reached well under one sample before the true end; the
    # impulse amplitudes sum to 1 to round-off (~1e-15 rad left after the last impulse).
    shaped_end = _end_of_motion_s(shaped, Q2, 1e-9)
    expected = move.t_motion_end_s + _zv_delay_s(robot, Q2)
    assert abs(shaped_end - expected) <= DT_S, (shaped_end, expected)
    # The shaper's own delay at rest equals the analytic one.
    assert shaper.delay_s == pytest.approx(_zv_delay_s(robot, Q2), rel=1e-12)


def test_modes_follow_the_pose_during_a_q1_to_q3_move():
    robot = _ur5e_5kg()
    move = double_s(Q1, Q3, dt_s=DT_S, t_post_s=0.3)
    shaper = tvist.TvShaper(
        tvist.MapDynamics(robot, tvist.DynamicMap.paper_ur5e()), dt_s=DT_S, n_dof=6
    )
    shaped = shaper.shape(move.q)
    assert shaper.status_counts["delay_clamped"] == 0
    np.testing.assert_allclose(shaped[-1], Q3, atol=1e-12)
    assert shaper.delay_s == pytest.approx(_zv_delay_s(robot, Q3), rel=1e-9)
    # Lighter arm at Q3: higher modes, shorter delay than at Q1.
    assert _zv_delay_s(robot, Q3) < 0.6 * _zv_delay_s(robot, Q1)


def test_map_dynamics_reports_modes_bounds_and_pose_count():
    robot = _ur5e_5kg()
    provider = tvist.MapDynamics(robot, tvist.DynamicMap.paper_ur5e())
    assert provider.n_dof == 6 and provider.n_modes == 2
    assert tvist.MapDynamics.validation_poses >= 1000
    modes = provider.modes(Q1)
    np.testing.assert_allclose(
        modes, tvist.DynamicMap.paper_ur5e().modes(robot, Q1), rtol=0, atol=0
    )
    for (wn_lo, zeta_hi), (wn, zeta) in zip(provider.slowest_modes, modes, strict=True):
        assert wn_lo <= wn and zeta_hi >= zeta


def test_map_dynamics_rejects_a_map_invalid_in_the_workspace():
    robot = _ur5e_5kg()
    overdamped = tvist.DynamicMap(
        [tvist.dynmap.general_mode(1, k_0=1e4, k_j=763.0, k_p=1.73, c_0=1e4, c_2=0.0, c_tau=0.0)]
    )
    with pytest.raises(ValueError, match="no underdamped mode 0"):
        tvist.MapDynamics(robot, overdamped)
    soft = tvist.DynamicMap(
        [tvist.dynmap.general_mode(1, k_0=-1e6, k_j=0.0, k_p=1.73, c_0=1.0, c_2=0.0, c_tau=0.0)]
    )
    with pytest.raises(ValueError, match="no underdamped mode"):
        tvist.MapDynamics(robot, soft)
    too_far = tvist.DynamicMap([tvist.dynmap.general_mode(6, **_shoulder())])
    with pytest.raises(ValueError, match="joints read by the dynamic map"):
        tvist.MapDynamics(robot, too_far)


def _shoulder() -> dict[str, float]:
    return {"k_0": 1e4, "k_j": 763.0, "k_p": 1.73, "c_0": 0.27, "c_2": 0.038, "c_tau": 47.2}


def test_map_dynamics_rejects_wrong_types_and_the_shaper_wrong_n_dof():
    robot = _ur5e_5kg()
    with pytest.raises(TypeError, match="robot must be"):
        tvist.MapDynamics("ur5e", tvist.DynamicMap.paper_ur5e())
    with pytest.raises(TypeError, match="dynmap must be"):
        tvist.MapDynamics(robot, {"modes": []})
    provider = tvist.MapDynamics(robot, tvist.DynamicMap.paper_ur5e())
    with pytest.raises(ValueError, match="n_dof"):
        tvist.TvShaper(provider, dt_s=DT_S, n_dof=5)
    with pytest.raises(ValueError, match="q has 5 values"):
        provider.modes(np.zeros(5))
