"""Shaping with the map-driven provider: the paper's Q1 -> Q2 move and bad setups."""

from __future__ import annotations

import numpy as np
import pytest

import tvist
from map_reference import PAPER_MODES, modes_reference
from map_smoothing_reference import smooth_abs_torque, soft_clamp
from tvist.analysis.metrics import peak_jerk
from tvist.trajectory import PAPER_POSES, double_s

DT_S = 0.002
Q1, Q2, Q3 = PAPER_POSES["Q1"], PAPER_POSES["Q2"], PAPER_POSES["Q3"]


def _ur5e_5kg() -> tvist.robots.Robot:
    # Paper section 6.1: 5 kg payload; here 5 cm beyond the flange along its z axis.
    return tvist.robots.ur5e(payload_kg=5.0, payload_com_m=(0.0, 0.0, 0.05))


def _zv_delay_s(robot: tvist.robots.Robot, q: np.ndarray) -> float:
    """Two-mode ZV delay pi/w_d0 + pi/w_d1 at q, from the robot's J and eqs. 47-48, 50-51
    (the independent transcription in tests/map_reference.py)."""
    modes = modes_reference(PAPER_MODES, [robot.joint_inertia(q)])[0]
    return float(sum(np.pi / (wn * np.sqrt(1 - zeta**2)) for wn, zeta in modes))


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
    # The paper map's equations at Q1's inertias (independent transcription): same formulas,
    # different operation order, ~1e-15 relative.
    reference = modes_reference(PAPER_MODES, [robot.joint_inertia(Q1)])[0]
    np.testing.assert_allclose(modes, reference, rtol=1e-12)
    for (wn_lo, zeta_hi), (wn, zeta) in zip(provider.slowest_modes, modes, strict=True):
        assert wn_lo <= wn and zeta_hi >= zeta


def test_map_dynamics_rejects_a_map_invalid_in_the_workspace():
    robot = _ur5e_5kg()
    overdamped = tvist.DynamicMap(
        [
            tvist.maps.paper10.general_mode(
                1, k_0=1e4, k_j=763.0, k_p=1.73, c_0=1e4, c_2=0.0, c_tau=0.0
            )
        ]
    )
    with pytest.raises(ValueError, match="no underdamped mode 0"):
        tvist.MapDynamics(robot, overdamped)
    # A negative stiffness is no map at all (the map's own sign rules, before any robot).
    with pytest.raises(ValueError, match=r"modes\[0\]: the stiffness k_0 \+ k_j J_f must be > 0"):
        tvist.maps.paper10.general_mode(1, k_0=-1e6, k_j=0.0, k_p=1.73, c_0=1.0, c_2=0.0, c_tau=0.0)
    too_far = tvist.DynamicMap([tvist.maps.paper10.general_mode(6, **_shoulder())])
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


# ---- a C¹ map keeps the shaped reference free of jerk spikes ----

#: The paper map with a gravity-stiffness term on both modes (k_g in N m/rad per N m, like a
#: fitted map's 20-30) and inertia ranges that the Q1 -> Q3 move leaves at both ends
#: (J_0: 8.9 -> 0.88 kg m², J_1: 8.4 -> 1.2 kg m²; the shoulder torque goes 107 -> -26 N m).
K_G = 20.0
RANGE_KG_M2 = (2.0, 7.0)
# The documented smoothing (tvist-core dynmap module docs), typed in independently.


def _kinked_map_parts() -> tuple[dict, dict]:
    base, shoulder = tvist.DynamicMap.paper_ur5e().mode_maps
    ranges = dict.fromkeys(tvist.maps.paper10.RANGE_FIELDS, list(RANGE_KG_M2))
    return {**base, "k_g": K_G, **ranges}, {**shoulder, "k_g": K_G, **ranges}


def _hard_clamp(j: float, lo: float, hi: float) -> float:
    return min(max(j, lo), hi)


def _numpy_provider(robot, clamp, magnitude):
    """A callable provider evaluating eqs. 47-48 and 50-51 (plus k_g) in numpy, with the given
    saturation of J into the ranges and stand-in for |τ_1|."""
    base, shoulder = _kinked_map_parts()

    def modes(q: np.ndarray) -> list[tuple[float, float]]:
        j_raw = robot.joint_inertia(q)
        j0, j1 = clamp(j_raw[0], *RANGE_KG_M2), clamp(j_raw[1], *RANGE_KG_M2)
        gravity = K_G * magnitude(robot.gravity_torque(q)[1])
        b, s = base, shoulder
        k_b = b["k_0"] + b["k_j"] * j1 + gravity
        wn0 = np.sqrt(1 + b["k_p"] / j1) * np.sqrt(k_b / j1)
        z0 = (
            (1 + b["k_p"] / j0)
            * (b["c_0"] + b["c_2"] * j0)
            * (1 + b["c_tau"] * j0)
            / (2 * np.sqrt(k_b * j1) * np.sqrt(1 + b["k_p"] / j1))
        )
        k_s = s["k_0"] + s["k_j"] * j1 + gravity
        wn1 = np.sqrt(1 + s["k_p"] / j1) * np.sqrt(k_s / j1)
        z1 = (
            np.sqrt(1 + s["k_p"] / j1)
            * (s["c_0"] + s["c_2"] * j1)
            * (1 + s["c_tau"] * j1)
            / (2 * np.sqrt(k_s * j1))
        )
        return [(wn0, z0), (wn1, z1)]

    return modes


def test_the_smooth_map_keeps_the_shaped_reference_free_of_jerk_spikes():
    robot = _ur5e_5kg()
    move = double_s(Q1, Q3, dt_s=DT_S, v_max=1.5, a_max=2.0, jerk_time_s=0.02, t_post_s=0.5)
    # The move leaves the ranges at both ends and the shoulder gravity torque changes sign.
    inertia = robot.joint_inertia_many(move.q)
    tau_1 = robot.gravity_torque_many(move.q)[:, 1]
    for joint in (0, 1):
        assert inertia[:, joint].min() < 0.9 * RANGE_KG_M2[0]
        assert inertia[:, joint].max() > 1.1 * RANGE_KG_M2[1]
    assert tau_1.min() < -20.0 and tau_1.max() > 100.0
    unshaped = peak_jerk(move.q, DT_S)  # 100 rad/s³: a_max / jerk_time_s

    shaper = tvist.TvShaper(
        tvist.MapDynamics(robot, tvist.DynamicMap(list(_kinked_map_parts()))), dt_s=DT_S, n_dof=6
    )
    smooth = shaper.shape(move.q)
    assert shaper.status_counts["delay_clamped"] == 0
    np.testing.assert_allclose(smooth[-1], Q3, atol=1e-12)

    def shaped_by(clamp, magnitude) -> np.ndarray:
        provider = _numpy_provider(robot, clamp, magnitude)
        s = tvist.TvShaper(provider, dt_s=DT_S, n_dof=6, max_delay_s=0.5)
        out = s.shape(move.q)
        assert s.status_counts["delay_clamped"] == 0
        return out

    # The numpy stand-in with the documented formulas reproduces the real-time path (same
    # modes to ~1e-15, so the shaped outputs agree to round-off; measured 9e-16 rad): the
    # comparison below differs only in the formulas.
    np.testing.assert_allclose(shaped_by(soft_clamp, smooth_abs_torque), smooth, rtol=0, atol=1e-12)

    # C² map: 64 rad/s³ measured, below the planned move's 100 (a C¹ quadratic blend left a
    # step of the reference acceleration where its curvature switched on: 178 rad/s³).
    jerk_smooth = peak_jerk(smooth, DT_S)
    assert jerk_smooth <= unshaped, jerk_smooth
    # The formulas this replaces, hard clamp and |τ|: each kink alone and both together put a
    # step into the slope of the reference velocity. Measured: 4881 rad/s³ with both, 4849
    # with the hard clamp alone, 1125 with |τ| alone, i.e. 17-76x the smooth map's peak.
    kinked = {
        "hard clamp and |τ|": peak_jerk(shaped_by(_hard_clamp, abs), DT_S),
        "hard clamp": peak_jerk(shaped_by(_hard_clamp, smooth_abs_torque), DT_S),
        "|τ|": peak_jerk(shaped_by(soft_clamp, abs), DT_S),
    }
    for kink, jerk in kinked.items():
        assert jerk >= 5.0 * jerk_smooth, (kink, jerk, jerk_smooth)
    assert kinked["hard clamp and |τ|"] >= 20.0 * jerk_smooth, kinked
