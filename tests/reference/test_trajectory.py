"""Trajectory generators against closed-form references, and the input checks."""

from __future__ import annotations

import math

import numpy as np
import pytest

from tvist.trajectory import (
    PAPER_POSES,
    check_uniform_time,
    double_s,
    min_jerk,
    trapezoid,
    validate_reference,
)

DT_S = 0.002
V_MAX, A_MAX, JERK_TIME_S = 1.5, 2.0, 0.02  # paper section 6.1
J_MAX = A_MAX / JERK_TIME_S
# ruckig solves its profile equations in double precision; positions agree with the closed
# form to ~1e-15 rad (measured). 1e-9 leaves margin and still fails for a 1 % change of the
# jerk limit, which moves the positions by 4e-6 rad or more.
ATOL_PROFILE = 1e-9


def double_s_reference(h: float, v_max: float, a_max: float, j_max: float):
    """Closed-form rest-to-rest double-S (Biagiotti & Melchiorri, Trajectory Planning for
    Automatic Machines and Robots, 2008, sec. 3.4 with v0 = v1 = 0), written independently of
    ruckig. Returns the duration and a function ``t -> (s, v, a)`` for ``0 <= t``.
    """
    if v_max * j_max >= a_max**2:
        t_j = a_max / j_max
        t_a = t_j + v_max / a_max
    else:
        t_j = math.sqrt(v_max / j_max)
        t_a = 2.0 * t_j
    t_v = h / v_max - t_a
    if t_v < 0.0:  # v_max is not reached
        t_v = 0.0
        t_j = a_max / j_max
        t_a = (a_max**2 / j_max + math.sqrt(a_max**4 / j_max**2 + 4.0 * a_max * h)) / (2.0 * a_max)
        if t_a < 2.0 * t_j:  # a_max is not reached either
            t_j = (h / (2.0 * j_max)) ** (1.0 / 3.0)
            t_a = 2.0 * t_j
    # Piecewise-constant jerk: (duration, jerk) for the seven phases.
    phases = [
        (t_j, j_max),
        (t_a - 2.0 * t_j, 0.0),
        (t_j, -j_max),
        (t_v, 0.0),
        (t_j, -j_max),
        (t_a - 2.0 * t_j, 0.0),
        (t_j, j_max),
    ]
    starts, state = [], np.zeros(3)  # s, v, a at each phase start
    t0 = 0.0
    for length, jerk in phases:
        starts.append((t0, state.copy(), jerk))
        s, v, a = state
        state = np.array(
            [
                s + v * length + a * length**2 / 2 + jerk * length**3 / 6,
                v + a * length + jerk * length**2 / 2,
                a + jerk * length,
            ]
        )
        t0 += length
    duration = t0
    assert abs(state[0] - h) < 1e-9 * max(1.0, h)  # the phases integrate to the distance

    def at(t: float) -> tuple[float, float, float]:
        if t >= duration:
            return h, 0.0, 0.0
        for start, (s, v, a), jerk in reversed(starts):
            if t >= start:
                x = t - start
                return (
                    s + v * x + a * x**2 / 2 + jerk * x**3 / 6,
                    v + a * x + jerk * x**2 / 2,
                    a + jerk * x,
                )
        raise AssertionError("unreachable")

    return duration, at


# Distances covering the three cases: jerk-limited only, acceleration reached, both reached.
@pytest.mark.parametrize("h", [0.001, 0.05, 0.5, 5 * np.pi / 6])
def test_double_s_matches_closed_form(h):
    q0 = np.array([0.1, -0.2, 0.3])
    q1 = q0 + h * np.array([1.0, -0.5, 0.25])  # joint 0 is the limiting joint
    traj = double_s(q0, q1, DT_S, V_MAX, A_MAX, JERK_TIME_S, snap_to_grid=False)
    duration, at = double_s_reference(h, V_MAX, A_MAX, J_MAX)
    assert traj.duration_s == pytest.approx(duration, abs=1e-12)
    ref = np.array([at(t) for t in traj.t_s])
    np.testing.assert_allclose(traj.q[:, 0] - q0[0], ref[:, 0], atol=ATOL_PROFILE)
    np.testing.assert_allclose(traj.qd[:, 0], ref[:, 1], atol=ATOL_PROFILE)
    np.testing.assert_allclose(traj.qdd[:, 0], ref[:, 2], atol=ATOL_PROFILE)
    # Phase synchronization: every joint follows the same normalized profile (straight line).
    s = (traj.q - q0) / (q1 - q0)
    np.testing.assert_allclose(s, np.repeat(s[:, :1], 3, axis=1), atol=ATOL_PROFILE)
    assert np.array_equal(traj.q[-1], q1)
    assert np.array_equal(traj.q[0], q0)


def test_paper_move_reaches_all_limits_and_ends_on_grid():
    q0, q1 = PAPER_POSES["Q1"], PAPER_POSES["Q3"]
    traj = double_s(q0, q1, DT_S)
    h = float(np.max(np.abs(q1 - q0)))
    duration, _ = double_s_reference(h, V_MAX, A_MAX, J_MAX)
    # Snapped to the grid: the next whole sample at or after the time-optimal duration.
    n = round(traj.duration_s / DT_S)
    assert traj.duration_s == pytest.approx(n * DT_S, abs=1e-12)
    assert duration <= traj.duration_s < duration + DT_S
    np.testing.assert_array_equal(traj.t_s, DT_S * np.arange(traj.n_samples))
    assert np.array_equal(traj.q[-1], q1)
    # Joint 2 (5π/6 rad) limits the move: it cruises at v_max and accelerates at a_max for
    # 0.73 s, so the samples hit the limits (to ruckig's precision) and never exceed them.
    assert np.max(np.abs(traj.qd)) == pytest.approx(V_MAX, rel=1e-6)
    assert np.max(np.abs(traj.qdd)) == pytest.approx(A_MAX, rel=1e-6)
    jerk = np.abs(np.diff(traj.qdd, axis=0)) / DT_S
    # Each 20 ms ramp spans 10 samples, so several differences lie inside a ramp and equal
    # the jerk limit; none exceeds it.
    assert np.max(jerk) == pytest.approx(J_MAX, rel=1e-6)
    assert np.max(np.abs(traj.qd)) <= V_MAX * (1 + 1e-9)
    assert np.max(jerk) <= J_MAX * (1 + 1e-6)
    # Unmoved joints stay exactly where they are; the moved ones keep a straight line in
    # joint space after the stretch to the grid too.
    np.testing.assert_array_equal(traj.q[:, 3:], np.tile(q0[3:], (traj.n_samples, 1)))
    s = (traj.q[:, :3] - q0[:3]) / (q1[:3] - q0[:3])
    np.testing.assert_allclose(s, np.repeat(s[:, :1], 3, axis=1), atol=ATOL_PROFILE)


def test_velocity_integrates_to_position():
    traj = double_s(PAPER_POSES["Q1"], PAPER_POSES["Q2"], DT_S)
    # The trapezoid rule on qd is exact up to the third-order term dt³/12·jerk' = 0 inside a
    # phase and O(dt² · a) where a phase boundary falls between samples: 4e-6 rad at most.
    integrated = PAPER_POSES["Q1"] + np.concatenate(
        [np.zeros((1, 6)), np.cumsum(0.5 * (traj.qd[1:] + traj.qd[:-1]) * DT_S, axis=0)]
    )
    np.testing.assert_allclose(integrated, traj.q, atol=1e-5)


def test_padding_and_rest():
    q0, q1 = PAPER_POSES["Q3"], PAPER_POSES["Q1"]
    traj = double_s(q0, q1, DT_S, t_pre_s=0.1, t_post_s=0.5)
    n_pre = 50
    assert traj.t_motion_start_s == pytest.approx(0.1)
    np.testing.assert_array_equal(traj.q[: n_pre + 1], np.tile(q0, (n_pre + 1, 1)))
    assert not np.any(traj.qd[:n_pre]) and not np.any(traj.qdd[:n_pre])
    i_end = round(traj.t_motion_end_s / DT_S)
    assert traj.t_s[i_end] == pytest.approx(traj.t_motion_end_s, abs=1e-12)
    np.testing.assert_array_equal(traj.q[i_end:], np.tile(q1, (traj.n_samples - i_end, 1)))
    assert traj.t_s[-1] - traj.t_motion_end_s == pytest.approx(0.5, abs=1e-12)
    assert np.all(np.abs(traj.qd[n_pre + 1 : i_end, 0]) > 0.0)  # moving in between


def test_time_synchronization_starts_and_stops_together():
    q0, q1 = PAPER_POSES["Q1"], PAPER_POSES["Q3"]
    traj = double_s(q0, q1, DT_S, synchronization="time")
    moving = np.abs(traj.qd[:, :3]) > 0.0
    last = [int(np.flatnonzero(moving[:, j])[-1]) for j in range(3)]
    first = [int(np.flatnonzero(moving[:, j])[0]) for j in range(3)]
    assert len(set(last)) == 1 and len(set(first)) == 1
    assert np.array_equal(traj.q[-1], q1)
    # Time synchronization lets the shorter joints take their own (non-proportional) profile.
    s = (traj.q[:, :3] - q0[:3]) / (q1[:3] - q0[:3])
    assert np.max(np.abs(s[:, 0] - s[:, 2])) > 1e-3


def test_zero_length_move_is_rest():
    q = PAPER_POSES["Q2"]
    for traj in (
        double_s(q, q, DT_S, t_pre_s=0.01, t_post_s=0.02),
        trapezoid(q, q, 1.0, 1.0, DT_S, t_pre_s=0.01, t_post_s=0.02),
    ):
        assert traj.duration_s == 0.0
        np.testing.assert_array_equal(traj.q, np.tile(q, (traj.n_samples, 1)))
        assert not np.any(traj.qd) and not np.any(traj.qdd)
        assert traj.n_samples == 5 + 1 + 10


def test_trapezoid_closed_form_and_double_s_relation():
    q0, q1 = np.zeros(2), np.array([2.0, -1.0])
    v, a = 1.5, 2.0
    traj = trapezoid(q0, q1, v, a, DT_S, snap_to_grid=False)
    assert traj.duration_s == pytest.approx(2.0 / v + v / a, abs=1e-12)
    assert np.max(np.abs(traj.qd[:, 0])) == pytest.approx(v, abs=1e-12)
    assert set(np.round(np.unique(traj.qdd[:, 0]), 12)) <= {-a, 0.0, a}
    # A double-S with acceleration ramps of length T_j lasts exactly T_j longer than the
    # trapezoid when both reach v_max and a_max (each ramp pair replaces a step by a ramp).
    ds = double_s(q0, q1, DT_S, v_max=v, a_max=a, jerk_time_s=0.02, snap_to_grid=False)
    assert ds.duration_s == pytest.approx(traj.duration_s + 0.02, abs=1e-9)
    # Triangular case: T = 2 sqrt(h / a).
    short = trapezoid(q0, np.array([0.5, 0.0]), v, a, DT_S, snap_to_grid=False)
    assert short.duration_s == pytest.approx(2.0 * math.sqrt(0.5 / a), abs=1e-12)
    assert np.max(short.qd[:, 0]) <= math.sqrt(0.5 * a) + 1e-12


def test_trapezoid_snapped_to_grid_keeps_limits():
    q0, q1 = PAPER_POSES["Q1"], PAPER_POSES["Q3"]
    traj = trapezoid(q0, q1, 1.5, 2.0, DT_S)
    assert traj.duration_s / DT_S == pytest.approx(round(traj.duration_s / DT_S), abs=1e-9)
    assert np.max(np.abs(traj.qd)) <= 1.5 + 1e-12
    assert np.max(np.abs(traj.qdd)) == pytest.approx(2.0, abs=1e-12)
    assert np.array_equal(traj.q[-1], q1)
    # Straight line in joint space.
    s = (traj.q[:, :3] - q0[:3]) / (q1[:3] - q0[:3])
    np.testing.assert_allclose(s, np.repeat(s[:, :1], 3, axis=1), atol=1e-12)
    # Position is the integral of the piecewise-linear velocity (trapezoid rule is exact
    # except in the two samples that straddle each of the 4 breakpoints: < a dt² = 8e-6).
    integrated = q0 + np.concatenate(
        [np.zeros((1, 6)), np.cumsum(0.5 * (traj.qd[1:] + traj.qd[:-1]) * DT_S, axis=0)]
    )
    np.testing.assert_allclose(integrated, traj.q, atol=1e-5)


def test_trapezoid_per_joint_limits():
    q0, q1 = np.zeros(2), np.array([1.0, 1.0])
    traj = trapezoid(q0, q1, v_max=[2.0, 0.5], a_max=[1.0, 4.0], dt_s=DT_S, snap_to_grid=False)
    # Joint 1 limits speed (0.5), joint 0 limits acceleration (1.0); both move together.
    assert np.max(traj.qd) == pytest.approx(0.5, abs=1e-12)
    assert np.max(traj.qdd) == pytest.approx(1.0, abs=1e-12)
    assert traj.duration_s == pytest.approx(1.0 / 0.5 + 0.5 / 1.0, abs=1e-12)


def test_min_jerk_closed_form():
    q0, q1, duration = np.array([0.0, 1.0]), np.array([1.0, -1.0]), 1.0
    traj = min_jerk(q0, q1, duration, DT_S, t_pre_s=0.02)
    h = q1 - q0
    mid = round((0.02 + duration / 2) / DT_S)
    np.testing.assert_allclose(traj.q[mid], q0 + h / 2, atol=1e-12)
    np.testing.assert_allclose(traj.qd[mid], 1.875 * h / duration, atol=1e-12)
    np.testing.assert_allclose(np.max(np.abs(traj.qd), axis=0), 1.875 * np.abs(h), atol=1e-12)
    # Peak acceleration of the quintic: 10 / sqrt(3) h / T² at τ = 1/2 ∓ sqrt(3)/6.
    np.testing.assert_allclose(
        np.max(np.abs(traj.qdd), axis=0), 10 / math.sqrt(3) * np.abs(h), rtol=1e-4
    )
    # Central differences of q agree with the analytic velocity to O(dt²·q''') = 1e-4.
    np.testing.assert_allclose(np.gradient(traj.q, DT_S, axis=0)[1:-1], traj.qd[1:-1], atol=1e-4)
    assert np.array_equal(traj.q[-1], q1)
    # A duration off the grid keeps its exact end time; the next sample is at q1.
    odd = min_jerk(q0, q1, 0.1003, DT_S)
    assert odd.t_motion_end_s == pytest.approx(0.1003)
    assert odd.t_s[-1] == pytest.approx(0.102) and np.array_equal(odd.q[-1], q1)


def test_paper_poses_are_the_published_ones_and_read_only():
    np.testing.assert_allclose(PAPER_POSES["Q1"], [0, -np.pi, 0, -np.pi / 2, 0, 0])
    np.testing.assert_allclose(PAPER_POSES["Q2"], [np.pi / 2, -np.pi, 0, -np.pi / 2, 0, 0])
    np.testing.assert_allclose(
        PAPER_POSES["Q3"], [np.pi / 2, -np.pi / 2, 5 * np.pi / 6, -np.pi / 2, 0, 0]
    )
    with pytest.raises(ValueError):
        PAPER_POSES["Q1"][0] = 1.0
    with pytest.raises(TypeError):
        PAPER_POSES["Q4"] = np.zeros(6)  # type: ignore[index]


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"q0": [0.0, np.nan]}, r"q0\[1\] is nan"),
        ({"q1": [0.0, 1.0, 2.0]}, "same shape"),
        ({"q0": [[0.0, 1.0]]}, "1-D"),
        ({"v_max": 0.0}, "v_max"),
        ({"a_max": [1.0, -1.0]}, r"a_max\[1\]"),
        ({"a_max": [1.0, 1.0, 1.0]}, "a_max must be a scalar or have shape"),
        ({"dt_s": 0.0}, "dt_s"),
        ({"jerk_time_s": -0.02}, "jerk_time_s"),
        ({"t_pre_s": math.inf}, "t_pre_s"),
        ({"joint_limits_rad": [[-1.0, 1.0], [-1.0, 0.5]]}, r"q1\[1\] = 1 rad is outside"),
        ({"joint_limits_rad": [[-1.0, 1.0]]}, r"shape \(2, 2\)"),
        ({"joint_limits_rad": [[1.0, -1.0], [-2.0, 2.0]]}, "lower < upper"),
        ({"synchronization": "none"}, "synchronization"),
    ],
)
def test_double_s_rejects_bad_input(kwargs, message):
    args = {"q0": [0.0, 0.0], "q1": [0.5, 1.0], "dt_s": DT_S} | kwargs
    with pytest.raises(ValueError, match=message):
        double_s(**args)


def test_other_generators_reject_bad_input():
    with pytest.raises(ValueError, match="duration_s"):
        min_jerk([0.0], [1.0], 0.0, DT_S)
    with pytest.raises(ValueError, match=r"q0\[0\] is inf"):
        min_jerk([np.inf], [1.0], 1.0, DT_S)
    with pytest.raises(ValueError, match="v_max"):
        trapezoid([0.0], [1.0], -1.0, 1.0, DT_S)
    with pytest.raises(ValueError, match=r"q0\[0\] = -2 rad is outside"):
        trapezoid([-2.0], [1.0], 1.0, 1.0, DT_S, joint_limits_rad=[[-1.5, 1.5]])


def test_limits_inside_pass():
    limits = np.array([[-np.pi, np.pi], [-2 * np.pi, 0.0], [-np.pi, np.pi]])
    traj = double_s(PAPER_POSES["Q1"][:3], PAPER_POSES["Q3"][:3], DT_S, joint_limits_rad=limits)
    assert traj.n_dof == 3


def test_validate_reference_names_row_and_joint():
    q = np.zeros((10, 3))
    out = validate_reference(q, DT_S)
    assert out.shape == (10, 3) and out.dtype == np.float64
    bad = q.copy()
    bad[4, 2] = np.nan
    with pytest.raises(ValueError, match=r"Q\[4, 2\] is nan \(row 4, joint 2\)"):
        validate_reference(bad, DT_S)
    high = q.copy()
    high[7, 1] = 2.0
    with pytest.raises(ValueError, match=r"Q\[7, 1\] = 2 rad is outside .* of joint 1"):
        validate_reference(high, DT_S, np.tile([-1.0, 1.0], (3, 1)))
    with pytest.raises(ValueError, match="n_samples, n_dof"):
        validate_reference(np.zeros(5), DT_S)
    with pytest.raises(ValueError, match="dt_s"):
        validate_reference(q, -1.0)


def test_check_uniform_time():
    t = 1000.0 + DT_S * np.arange(200)
    assert check_uniform_time(t) == pytest.approx(DT_S)
    # Stamps printed with 6 decimals (ur_rtde) are accepted.
    assert check_uniform_time(np.round(t + 1.2345e-7, 6)) == pytest.approx(DT_S)
    dropped = np.delete(t, 57)
    with pytest.raises(ValueError, match="not uniform at row 57"):
        check_uniform_time(dropped)
    backwards = t.copy()
    backwards[120] = backwards[119]
    # The stamps are printed as numbers, as the user's file has them (not np.float64(...)).
    stamp = f"{float(backwards[120])!r}".replace(".", r"\.")
    with pytest.raises(ValueError, match=rf"not increasing at row 120: t_s\[120\] = {stamp} <="):
        check_uniform_time(backwards)
    with_nan = t.copy()
    with_nan[3] = np.nan
    with pytest.raises(ValueError, match=r"t_s\[3\] is nan \(row 3\)"):
        check_uniform_time(with_nan)
    with pytest.raises(ValueError, match="at least 2"):
        check_uniform_time([1.0])
