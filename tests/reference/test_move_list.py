"""Move lists (:mod:`tvist.move_list`): the planned linear moves against pinocchio's rigid
model, and ``tvist run``'s answers to bad files (one line, exit code 2, the line named)."""

from __future__ import annotations

import numpy as np
import pytest

from pinocchio_reference import pinocchio_model
from tvist import robots
from tvist.cli import main
from tvist.move_list import plan, read_move_list
from tvist.robots import Payload, Robot

pin = pytest.importorskip("pinocchio")

HOME = [0.0, -1.57, 1.57, -1.57, -1.57, 0.0]
START = "movej, " + ", ".join(str(v) for v in HOME) + "\n"


def _flange_poses(Q):  # noqa: N803
    """Flange poses ``[x, y, z, rx, ry, rz]`` of the rows of ``Q`` by pinocchio."""
    model, frame = pinocchio_model(robots.params("ur5e"), Payload(0.0, (0.0, 0.0, 0.0)))
    data = model.createData()
    out = []
    for q in Q:
        pin.framesForwardKinematics(model, data, np.asarray(q, dtype=float))
        placement = data.oMf[frame]
        out.append(np.concatenate([placement.translation, pin.log3(placement.rotation)]))
    return np.array(out)


def test_two_linear_moves_follow_their_lines_with_trapezoidal_speed(tmp_path):
    robot = Robot(robots.params("ur5e"))
    home = _flange_poses([HOME])[0]
    start = home[:3]
    corner, end = start + [0.0, -0.1, 0.0], start + [0.0, -0.1, -0.05]
    rot = ", ".join(repr(float(v)) for v in home[3:])  # the orientation held
    path = tmp_path / "moves.csv"
    path.write_text(
        START
        + f"movel, {corner[0]}, {corner[1]}, {corner[2]}, {rot}, 0.25, 1.2\n"
        + f"movel, {end[0]}, {end[1]}, {end[2]}, {rot}, 0.25, 1.2  # down\n"
    )
    moves = read_move_list(path, 6)
    planned = plan(robot, moves, 0.002, None)
    p = _flange_poses(planned.Q_planned)[:, :3]
    first = np.flatnonzero(np.linalg.norm(p - corner, axis=1) < 1e-9)
    assert first.size, "the corner is reached"
    k = int(first[0])
    for segment, a, b in ((p[: k + 1], start, corner), (p[k:], corner, end)):
        direction = (b - a) / np.linalg.norm(b - a)
        off_line = segment - a - np.outer((segment - a) @ direction, direction)
        assert np.max(np.linalg.norm(off_line, axis=1)) < 1e-8  # IK converges to 1e-10
    # Rest to rest at the corner; peak speed v = 0.25 m/s (10 cm at 1.2 m/s² reaches it).
    speed = np.linalg.norm(np.diff(p, axis=0), axis=1) / 0.002
    assert speed[k - 1] < 1e-2 and speed[k] < 1e-2
    assert abs(speed.max() - 0.25) < 1e-6
    np.testing.assert_allclose(p[-1], end, atol=1e-9)


@pytest.mark.parametrize(
    ("text", "named"),
    [
        ("movel, 0, 0, 0, 0, 0, 0, 0.1, 1\n", "starts with 'movej"),
        ("movej, 0, 0, 0\n", "line 1: movej needs 6 joint angles"),
        (START, "no movel after the start"),
        (START + "movel, 0.4, 0, 0.4, 0, 3.1, 0, 0.1\n", "line 2: expected 'movel"),
        (START + "movel, 0.4, 0, 0.4, 0, 3.1, 0, 0, 1\n", "line 2: the speed v and acc"),
        (START + "movel, 0.4, x, 0.4, 0, 3.1, 0, 0.1, 1\n", "line 2: '0.4,x"),
        (START + "movel, 0.4, nan, 0.4, 0, 3.1, 0, 0.1, 1\n", "line 2: a value that is not fi"),
    ],
)
def test_a_bad_move_list_is_one_line_naming_it(tmp_path, capsys, text, named):
    path = tmp_path / "moves.csv"
    path.write_text(text)
    code = main(["run", str(path), "--modes", "10:0.1", "--dry-run"])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2
    assert len(err) == 1 and err[0].startswith("tvist run: error: ") and named in err[0], err


@pytest.mark.parametrize(
    ("flags", "named"),
    [(["--paper-map"], "give --modes"), (["--modes", "10:0.1", "--units", "q=deg"], "--units")],
)
def test_a_move_list_refuses_what_it_does_not_take(tmp_path, capsys, flags, named):
    path = tmp_path / "moves.csv"
    path.write_text(START + "movel, -0.49, -0.2, 0.49, 2.2214, 2.2214, 0, 0.1, 1\n")
    assert main(["run", str(path), *flags, "--dry-run"]) == 2
    assert named in capsys.readouterr().err
