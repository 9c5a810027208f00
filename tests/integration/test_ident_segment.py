"""``tvist identify`` on a log that holds more than the excitation: the approach move to the
pose before it and a rest after it (what recording around an excitation program gives)."""

from __future__ import annotations

import json

import numpy as np
import pytest

from tvist.cli import main
from tvist.ident.excitation import random_excitation
from tvist.ident.logs import Record, read_rtde_csv
from tvist.ident.segment import excitation_segment
from tvist.robots import params
from tvist.sim import Twin
from tvist.trajectory import PAPER_POSES, trapezoid

#: The UR5e's control period, s (its robot data).
UR5E_DT_S = params("ur5e").control_period_s

#: The pose of the excitation, and the pose the arm comes from (the stretched Q1).
Q_POSE = np.array([0.0, -1.9, 1.6, -1.3, -1.57, 0.4])
Q_FROM = np.array(PAPER_POSES["Q1"], dtype=float)
#: The approach of ``to_urscript``'s program: movej at 0.3 rad/s, 0.5 rad/s².
APPROACH_SPEED_RAD_S, APPROACH_ACCEL_RAD_S2 = 0.3, 0.5


def _log_with_approach(
    joint: int, seed: int, folder, q_from: np.ndarray = Q_FROM
) -> tuple[str, Twin, int, int]:
    """Approach, the excitation of ``joint`` (its 0.5 s standstill first), 2 s of rest: the
    twin (5 kg, accelerometer noise) run on it, written as ur_rtde CSV."""
    twin = Twin("ur5e", payload_kg=5.0, payload_com_m=(0.0, 0.0, 0.05), accel_noise_std=0.05)
    approach = trapezoid(
        q_from, Q_POSE, APPROACH_SPEED_RAD_S, APPROACH_ACCEL_RAD_S2, UR5E_DT_S, t_pre_s=0.3
    )
    excitation = random_excitation(Q_POSE, joint, seed=seed, duration_s=4.0, dt_s=UR5E_DT_S)
    rest = np.tile(excitation.q[-1], (1000, 1))
    q_ref = np.vstack([approach.q, excitation.q[1:], rest])
    record = Record.from_rtde_fields(twin.run(q_ref, noise_seed=seed))
    path = record.to_csv(folder / f"joint{joint}.csv", fmt="ur_rtde")
    return str(path), twin, len(approach.q), len(excitation.q) - 1


@pytest.mark.parametrize("joint", [0, 1])
def test_identify_finds_the_excitation_after_an_approach_move(joint, tmp_path, capsys):
    path, twin, n_approach, n_excitation = _log_with_approach(joint, 3 + joint, tmp_path)
    assert main(["identify", path, "--payload-kg", "5", "--json"]) == 0
    fit = json.loads(capsys.readouterr().out)
    wn_true, zeta_true = twin.modes(Q_POSE)[joint]
    assert fit["joint"] == joint
    assert "wn_rad_s" in fit, fit  # not "no ringing above noise"
    # The campaign's acceptance for a local fit: ω_n within 3 %; ζ within 15 % (the local
    # fit's two-mode damping accuracy on the twin, tests/unit/test_ident_local_fit.py).
    assert fit["wn_rad_s"] == pytest.approx(wn_true, rel=0.03)
    assert fit["zeta"] == pytest.approx(zeta_true, rel=0.15)
    # The segment starts where the approach has ended and stops at most MAX_REST_S after
    # the excitation's last sample, in the rest that follows.
    segment = excitation_segment(read_rtde_csv(path))
    assert segment.joint == joint
    assert segment.start >= n_approach - 1
    assert n_approach + n_excitation <= segment.stop <= n_approach + n_excitation + 500


def test_a_long_move_of_the_excited_joint_is_an_approach(tmp_path):
    """An approach that turns the base by 1.2 rad (and the shoulder by 0.01 rad, too little
    to count at that speed) before a base excitation: longer than any move of Algorithm 2
    (two targets within ±10°), so it is left out, and the log's pose is the excitation's."""
    from tvist.ident.pose import pose_of

    q_from = Q_POSE + np.array([-1.2, 0.01, 0.0, 0.0, 0.0, 0.0])
    path, _, n_approach, _ = _log_with_approach(0, 7, tmp_path, q_from=q_from)
    log = read_rtde_csv(path)
    segment = excitation_segment(log)
    assert segment.joint == 0 and segment.start >= n_approach - 1
    # The pose that pairs the log with its shoulder log: the excitation's (the arm sags
    # under gravity by a few mrad on the link side).
    np.testing.assert_allclose(pose_of(segment.of(log)), Q_POSE, atol=5e-3)
