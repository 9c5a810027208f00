"""The twin's controller runs the excitation programs ``to_urscript`` writes (movej, sleep),
so that recording while exciting can be tried on the twin; other URScript is refused."""

from __future__ import annotations

import numpy as np
import pytest

from tvist.ident.excitation import random_excitation, to_urscript
from tvist.robots import params
from tvist.sim import Twin
from tvist.trajectory import PAPER_POSES
from tvist.urserver.controller import TwinController

#: The UR5e's control period, s (its robot data).
UR5E_DT_S = params("ur5e").control_period_s

Q_POSE = np.array([0.1, -1.8, 1.5, -1.3, -1.57, 0.0])


@pytest.fixture(scope="module")
def twin() -> Twin:
    return Twin("ur5e", payload_kg=5.0, payload_com_m=(0.0, 0.0, 0.05))


def test_controller_runs_an_exported_excitation(twin) -> None:
    """The program approaches ``q0``, rests, then makes every move of the excitation in
    order; it ends by itself. Each movej blocks until its target stands still, which the
    controller sees two ticks after the last step (velocity, then acceleration back to 0), so
    the excitation takes at most 3 ticks per move longer than its reference."""
    excitation = random_excitation(Q_POSE, 0, seed=5, duration_s=2.0, dt_s=UR5E_DT_S)
    controller = TwinController(twin, np.array(PAPER_POSES["Q1"]))
    program = to_urscript(excitation, approach_speed_rad_s=1.0, approach_accel_rad_s2=2.0)
    # The script ports deliver the definition and the call that follows it separately.
    definition, call = program.rstrip().rsplit("\n", 1)
    assert controller.load_program(definition + "\n") is None
    assert controller.load_program(call) is None
    targets = []
    for _ in range(20_000):  # bounded: the program takes ~3000 ticks
        if not controller.program_running:
            break
        targets.append(controller.tick()["target_q"])
    assert not controller.program_running and controller.last_error is None
    q = np.array(targets)
    others = [j for j in range(6) if j != excitation.joint]
    arrived = int(np.flatnonzero(np.all(np.abs(q - Q_POSE) < 1e-12, axis=1))[0])
    # After the approach only the excited joint moves.
    assert np.all(q[arrived:, others] == Q_POSE[others])
    # It visits every move's target (the program's 6 decimals), in order.
    j = q[arrived:, excitation.joint]
    at = 0
    for move in excitation.moves:
        hits = np.flatnonzero(np.abs(j[at:] - move.q_to_rad) <= 5e-7)
        assert hits.size, move
        at += int(hits[0])
    extra_ticks = len(q) - arrived - 1 - len(excitation.q)
    assert 0 <= extra_ticks <= 3 * len(excitation.moves)


@pytest.mark.parametrize(
    ("program", "named"),
    [
        ("def p():\n  movel(p[0.1, 0.2, 0.3, 0, 0, 0], a=1, v=1)\nend\n", "movel"),
        ("def p():\n  movej([0, 0, 0, 0, 0], a=1, v=1)\nend\n", "movej"),
        ("def p():\n  movej([0, -1.6, 1.6, 0, 0, 0], a=0, v=1)\nend\n", "a, v > 0"),
    ],
)
def test_controller_refuses_other_urscript_before_moving(twin, program, named) -> None:
    controller = TwinController(twin, np.array(PAPER_POSES["Q1"]))
    error = controller.load_program(program)
    assert error is not None and named in error
    assert not controller.program_running
