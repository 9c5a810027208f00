"""Random bang-coast-bang excitation (Algorithm 2) and its URScript export."""

from __future__ import annotations

import math
import re

import numpy as np
import pytest

from tvist.ident.excitation import random_excitation, to_urscript
from tvist.robots import params

#: The UR5e's control period, s (its robot data).
UR5E_DT_S = params("ur5e").control_period_s

Q0 = np.array([0.3, -1.2, 1.0, -1.5, -1.57, 0.2])


def trapezoid_position(t_s: np.ndarray, distance: float, v: float, a: float) -> np.ndarray:
    """Distance travelled by a trapezoidal profile (peak speed v, acceleration a) at t_s."""
    t_acc = v / a
    t_total = distance / v + t_acc
    out = np.empty_like(t_s)
    rise = t_s <= t_acc
    fall = t_s >= t_total - t_acc
    mid = ~rise & ~fall
    out[rise] = 0.5 * a * t_s[rise] ** 2
    out[mid] = 0.5 * a * t_acc**2 + v * (t_s[mid] - t_acc)
    out[fall] = distance - 0.5 * a * (t_total - t_s[fall]) ** 2
    return out


def test_same_seed_same_excitation_and_seeds_differ():
    a = random_excitation(Q0, 0, seed=7, dt_s=UR5E_DT_S)
    b = random_excitation(Q0, 0, seed=7, dt_s=UR5E_DT_S)
    c = random_excitation(Q0, 0, seed=8, dt_s=UR5E_DT_S)
    np.testing.assert_array_equal(a.q, b.q)
    assert a.moves == b.moves
    assert a.q.shape != c.q.shape or not np.array_equal(a.q, c.q)


@pytest.mark.parametrize("seed", range(10))
@pytest.mark.parametrize("joint", [0, 1])
def test_moves_respect_algorithm_2_ranges(seed, joint):
    ex = random_excitation(Q0, joint, seed=seed, dt_s=UR5E_DT_S)
    assert len(ex.moves) >= 3
    others = [j for j in range(6) if j != joint]
    np.testing.assert_array_equal(ex.q[:, others], np.tile(Q0[others], (ex.t_s.size, 1)))
    assert np.all(ex.qd[:, others] == 0) and np.all(ex.qdd[:, others] == 0)
    # Standstill first: nothing moves before the first move starts.
    n0 = ex.standstill_samples
    assert n0 * ex.dt_s == pytest.approx(0.5)
    assert np.all(ex.qdd[:n0, joint] == 0) and np.all(ex.q[: n0 + 1, joint] == Q0[joint])
    for m in ex.moves:
        assert abs(m.q_to_rad - Q0[joint]) <= math.pi / 18
        assert 0.5 <= m.speed_drawn_rad_s <= 2.0 and 0.3 <= m.accel_drawn_rad_s2 <= 7.0
        # rounding phases up to whole samples only lowers the limits
        assert m.speed_rad_s <= m.speed_drawn_rad_s * (1 + 1e-12)
        assert m.accel_rad_s2 <= m.accel_drawn_rad_s2 * (1 + 1e-12)
        assert 0.1 - ex.dt_s / 2 <= m.wait_s <= 1.0 + ex.dt_s / 2
    # Moves start while t < 8 s after the standstill (Algorithm 2's loop condition).
    assert ex.moves[-1].t_start_s - ex.standstill_s < 8.0
    last = ex.moves[-1]
    assert ex.duration_s == pytest.approx(last.t_start_s + last.move_time_s + last.wait_s)
    assert np.max(np.abs(ex.qd[:, joint])) <= 2.0 + 1e-12
    assert np.max(np.abs(ex.qdd[:, joint])) <= 7.0 + 1e-12


def test_sampled_reference_matches_analytic_trapezoids():
    ex = random_excitation(Q0, 1, seed=3, dt_s=UR5E_DT_S)
    j = ex.joint
    for m in ex.moves:
        k0 = int(round(m.t_start_s / ex.dt_s))
        n = int(round(m.move_time_s / ex.dt_s))
        tau = ex.t_s[k0 : k0 + n + 1] - m.t_start_s
        dist = abs(m.q_to_rad - m.q_from_rad)
        sign = math.copysign(1.0, m.q_to_rad - m.q_from_rad)
        expected = m.q_from_rad + sign * trapezoid_position(
            tau, dist, m.speed_rad_s, m.accel_rad_s2
        )
        # exact ZOH integration: only floating-point round-off remains
        np.testing.assert_allclose(ex.q[k0 : k0 + n + 1, j], expected, atol=1e-12)
        assert ex.qd[k0 + n, j] == pytest.approx(0.0, abs=1e-12)
        # waits are true standstills
        k_wait = int(round(m.wait_s / ex.dt_s))
        assert np.all(np.abs(ex.qd[k0 + n : k0 + n + k_wait, j]) < 1e-12)
    # velocity is the running integral of the held acceleration
    np.testing.assert_allclose(np.diff(ex.qd[:, j]), ex.qdd[:-1, j] * ex.dt_s, atol=1e-12)


def test_urscript_export_runs_the_same_moves():
    ex = random_excitation(Q0, 0, seed=11, dt_s=UR5E_DT_S)
    text = to_urscript(ex)
    assert text.startswith("def tvist_excitation():")
    assert text.rstrip().endswith("tvist_excitation()")
    movej = re.findall(r"movej\(\[([^\]]*)\], a=([0-9.]+), v=([0-9.]+)\)", text)
    sleeps = [float(s) for s in re.findall(r"sleep\(([0-9.]+)\)", text)]
    assert len(movej) == len(ex.moves) + 1  # the approach, then one per move
    np.testing.assert_allclose([float(v) for v in movej[0][0].split(",")], Q0, atol=1e-6)
    assert sleeps[0] == pytest.approx(ex.standstill_s)
    for (q_text, a, v), m, wait in zip(movej[1:], ex.moves, sleeps[1:], strict=True):
        q = np.array([float(x) for x in q_text.split(",")])
        assert q[0] == pytest.approx(m.q_to_rad, abs=1e-6)
        np.testing.assert_allclose(q[1:], Q0[1:], atol=1e-6)
        assert float(a) == pytest.approx(m.accel_rad_s2, abs=1e-6)
        assert float(v) == pytest.approx(m.speed_rad_s, abs=1e-6)
        assert wait == pytest.approx(m.wait_s, abs=1e-6)


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"joint": 6}, "joint"),
        ({"q0": np.zeros((2, 6))}, "q0"),  # one angle per joint (any number of joints)
        ({"q0": [0.0, np.nan, 0.0, 0.0, 0.0, 0.0]}, "q0"),
        ({"dt_s": 0.0}, "dt_s"),
        ({"speed_range_rad_s": (2.0, 0.5)}, "speed_range_rad_s"),
        ({"wait_range_s": (-1.0, 1.0)}, "wait_range_s"),
    ],
)
def test_bad_input_is_rejected(kwargs, message):
    args = {"q0": Q0, "joint": 0, "dt_s": UR5E_DT_S, **kwargs}
    with pytest.raises(ValueError, match=message):
        random_excitation(args.pop("q0"), args.pop("joint"), **args)
