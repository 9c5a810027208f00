"""``tvist run`` with a move list (a start ``movej`` and ``movel`` rows): the linear move is
shaped in Cartesian space and streamed to the twin server through servoJ.

The same 20 cm line at 0.5 m/s, 2 m/s² runs unshaped and shaped with the twin's true modes at
the end pose (from a separate :class:`tvist.sim.Twin`, not from the server). Expected poses
come from pinocchio's rigid model, not from tvist's kinematics.
"""

from __future__ import annotations

import re

import numpy as np
import pytest

from pinocchio_reference import pinocchio_model
from test_twin_server import _residual_rms, _tvist
from tvist import robots
from tvist.robots import Payload
from tvist.sim import Twin
from twin_server_fixture import (
    HOST,
    PAYLOAD_COM_M,
    PAYLOAD_KG,
    first_undisturbed_run,
    twin_server,
)

pin = pytest.importorskip("pinocchio")
pytest.importorskip("rtde_control")

HOME = np.array([0.0, -1.57, 1.57, -1.57, -1.57, 0.0])
#: The line: 20 cm along -y of the base, orientation held.
DISPLACEMENT_M = np.array([0.0, -0.2, 0.0])


@pytest.fixture(scope="module")
def server():
    with twin_server() as proc:
        yield proc


def _flange(q) -> np.ndarray:
    """Flange pose ``[x, y, z, rx, ry, rz]`` at ``q`` by pinocchio."""
    model, frame = pinocchio_model(robots.params("ur5e"), Payload(0.0, (0.0, 0.0, 0.0)))
    data = model.createData()
    pin.framesForwardKinematics(model, data, np.asarray(q, dtype=float))
    placement = data.oMf[frame]
    return np.concatenate([placement.translation, pin.log3(placement.rotation)])


@pytest.mark.slow
def test_move_list_runs_shaped_with_far_less_residual_vibration(server, tmp_path):
    start = _flange(HOME)
    end = start.copy()
    end[:3] += DISPLACEMENT_M
    program = tmp_path / "line.csv"
    program.write_text(
        "# a user's Cartesian program\n"
        f"movej, {', '.join(f'{v:.12f}' for v in HOME)}\n"
        f"movel, {', '.join(f'{v:.12f}' for v in end)}, 0.5, 2.0\n"
    )
    twin = Twin("ur5e", payload_kg=PAYLOAD_KG, payload_com_m=PAYLOAD_COM_M)
    # The end joints, for the modes only: Newton on pinocchio's model from HOME.
    model, frame = pinocchio_model(twin.params, Payload(0.0, (0.0, 0.0, 0.0)))
    data, q_end = model.createData(), HOME.copy()
    for _ in range(50):
        pin.framesForwardKinematics(model, data, q_end)
        error = np.concatenate([end[:3] - data.oMf[frame].translation, np.zeros(3)])
        jac = pin.computeFrameJacobian(model, data, q_end, frame, pin.LOCAL_WORLD_ALIGNED)
        q_end = q_end + np.linalg.pinv(jac) @ error
    modes = ",".join(f"{wn / (2 * np.pi):.6f}:{zeta:.6f}" for wn, zeta in twin.modes(q_end))

    def run(name: str, *extra: str):
        log = tmp_path / f"{name}.csv"
        done = _tvist(
            "run", str(program), "--robot-ip", HOST, "--log", str(log), "--tail", "5", *extra
        )
        assert done.returncode == 0, done.stdout + done.stderr
        return _residual_rms(log), done.stdout + done.stderr

    (unshaped, _, _), _ = run("unshaped", "--unshaped")
    # A run whose servo loop woke too late is run again (first_undisturbed_run says why).
    (shaped, target_end, _), output = first_undisturbed_run(
        lambda attempt: run(f"shaped{attempt}", "--modes", modes),
        lambda result: result[0] <= 0.05 * unshaped,
    )
    print(f"residual vibration: unshaped {unshaped:.3e}, shaped {shaped:.3e} m/s²")
    assert shaped <= 0.05 * unshaped, (shaped, unshaped, output)
    # The arm ends on the commanded pose (0.1 mm, 1e-4 rad: what a UR program expects).
    reached = _flange(target_end)
    np.testing.assert_allclose(reached[:3], end[:3], atol=1e-4)
    relative = pin.exp3(reached[3:]) @ pin.exp3(end[3:]).T
    assert np.linalg.norm(pin.log3(relative)) < 1e-4
    # The path deviation is reported; shaping in TCP space keeps a single line straight (the
    # shaped points are weighted sums of points of the line): well under 0.01 mm.
    match = re.search(r"path deviation \(flange, from the commanded lines\): ([0-9.]+) mm", output)
    assert match, output
    assert float(match.group(1)) < 0.01
