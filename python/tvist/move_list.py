"""A moveL command list: a user's Cartesian program, planned as a TCP reference and shaped in
Cartesian space (:mod:`tvist.cartesian`) so that every line stays straight.

File format (CSV, ``#`` starts a comment)::

    movej, q0, q1, q2, q3, q4, q5             # the start: joint angles, rad (first row only)
    movel, x, y, z, rx, ry, rz, v, a          # a linear move to a flange pose
    movel, ...

A ``movel`` pose is the flange's ``p[x, y, z, rx, ry, rz]`` in the base frame (m, rotation
vector in rad; tvist's TCP is the flange), ``v`` its speed (m/s, or rad/s for a pure
rotation) and ``a`` its acceleration (m/s², rad/s²). The start row fixes the inverse
kinematics branch, as a UR program's first ``movej`` does.

Each ``movel`` runs as on a UR's controller (:class:`tvist.urserver.tool_motion.Line`): the
position on the straight line and the orientation slerped about one axis, both by one
rest-to-rest trapezoidal profile in ``v`` and ``a``. The moves follow each other at rest
(no blends).
"""

from __future__ import annotations

import csv
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from tvist.cartesian import _rotvec, joints_from_tcp, shape_cartesian, tcp_path_deviation_m
from tvist.robots import Robot
from tvist.trajectory.scalar_trapezoid import trapezoid_duration, trapezoid_position
from tvist.urserver.kinematics import pose_matrix
from tvist.urserver.tool_motion import Line

__all__ = ["LinearMove", "MoveList", "PlannedMoves", "is_move_list", "plan", "read_move_list"]


@dataclass(frozen=True)
class LinearMove:
    """One ``movel``: flange ``pose`` (m, rad), speed ``v``, acceleration ``a``."""

    pose: np.ndarray
    v: float
    a: float


@dataclass(frozen=True)
class MoveList:
    """The start joints (rad) and the linear moves from there."""

    q_start: np.ndarray
    moves: tuple[LinearMove, ...]


def _rows(path: str | Path) -> list[tuple[int, list[str]]]:
    """``(line number, fields)`` of the file's rows that are not empty or comments."""
    rows = []
    with open(path, newline="") as f:
        for number, line in enumerate(f, start=1):
            text = line.split("#", 1)[0].strip()
            if text:
                rows.append((number, [field.strip() for field in next(csv.reader([text]))]))
    return rows


def is_move_list(path: str | Path) -> bool:
    """Whether the file's first row is a ``movej`` or ``movel`` command (a move list, not a
    joint CSV; :func:`read_move_list` names what is wrong with it)."""
    try:
        rows = _rows(path)
    except (OSError, UnicodeDecodeError, csv.Error):
        return False
    return bool(rows) and rows[0][1][0].lower() in ("movej", "movel")


def _numbers(fields: list[str], where: str) -> list[float]:
    try:
        values = [float(v) for v in fields]
    except ValueError:
        raise ValueError(
            f"{where}: {','.join(fields)!r} holds a value that is not a number"
        ) from None
    if not all(math.isfinite(v) for v in values):
        raise ValueError(f"{where}: a value that is not finite")
    return values


def read_move_list(path: str | Path, n_dof: int) -> MoveList:
    """The move list in ``path`` for an arm of ``n_dof`` joints.

    Raises
    ------
    ValueError
        Naming the line: a first row that is not ``movej`` with ``n_dof`` angles, a later row
        that is not ``movel`` with 8 numbers, ``v`` or ``a`` not > 0, no ``movel`` at all.
    """
    rows = _rows(path)
    if not rows or rows[0][1][0].lower() != "movej":
        raise ValueError(f"{path}: a move list starts with 'movej, q0, …' (the start joints)")
    number, fields = rows[0]
    if len(fields) != n_dof + 1:
        raise ValueError(f"{path} line {number}: movej needs {n_dof} joint angles (rad)")
    q_start = np.array(_numbers(fields[1:], f"{path} line {number}"))
    moves = []
    for number, fields in rows[1:]:
        where = f"{path} line {number}"
        if fields[0].lower() != "movel" or len(fields) != 9:
            raise ValueError(f"{where}: expected 'movel, x, y, z, rx, ry, rz, v, a'")
        values = _numbers(fields[1:], where)
        if not (values[6] > 0 and values[7] > 0):
            raise ValueError(f"{where}: the speed v and acceleration a must be > 0")
        moves.append(LinearMove(np.array(values[:6]), values[6], values[7]))
    if not moves:
        raise ValueError(f"{path}: no movel after the start")
    return MoveList(q_start, tuple(moves))


@dataclass(frozen=True)
class PlannedMoves:
    """A move list as streamed: joint references one row per period (rad).

    Attributes
    ----------
    Q_planned
        The commanded moves (the unshaped reference).
    Q
        The reference to stream: shaped in Cartesian space, or ``Q_planned`` unshaped.
    deviation_m
        Largest distance (m) of the streamed flange path from the commanded lines.
    """

    Q_planned: np.ndarray
    Q: np.ndarray
    deviation_m: float


def _tcp_reference(robot: Robot, moves: MoveList, dt_s: float, rest_s: float):
    """TCP reference ``X`` (see :mod:`tvist.cartesian`) of the moves and ``R_0``."""
    start = robot.flange_pose(moves.q_start)
    r0 = start[:3, :3]
    rows = [np.concatenate([start[:3, 3], np.zeros(3)])]
    for move in moves.moves:
        end = pose_matrix(move.pose)
        line = Line(start, end)
        duration, speed = trapezoid_duration(line.distance, move.v, move.a)
        for k in range(1, int(math.ceil(duration / dt_s)) + 1):
            t = min(k * dt_s, duration)
            s = trapezoid_position(t, speed, move.a, duration, line.distance)
            position, rotation = line.at(s)
            rows.append(np.concatenate([position, _rotvec(rotation @ r0.T)]))
        start = end
    rows.extend([rows[-1]] * int(math.ceil(rest_s / dt_s)))
    return np.array(rows), r0


def plan(
    robot: Robot,
    moves: MoveList,
    dt_s: float,
    modes: list[tuple[float, float]] | None,
    shaper: str = "zv",
) -> PlannedMoves:
    """The moves sampled every ``dt_s`` and, with ``modes`` (``[(wn_rad_s, zeta), ...]``),
    shaped in Cartesian space; the rest after the last move covers the shaper's delay (one
    damped period of the slowest mode bounds every registry shaper's)."""
    periods = [2.0 * math.pi / (wn * math.sqrt(max(1.0 - z * z, 1e-12))) for wn, z in modes or []]
    X, r0 = _tcp_reference(robot, moves, dt_s, max(periods, default=0.0) + 0.1)
    Q_planned = joints_from_tcp(robot, X, r0, moves.q_start)  # noqa: N806
    if not modes:
        return PlannedMoves(Q_planned, Q_planned, 0.0)
    shaped = shape_cartesian(robot, moves.q_start, X, r0, dt_s, modes, shaper=shaper)
    deviation = float(np.max(tcp_path_deviation_m(robot, Q_planned, shaped.Q)))
    return PlannedMoves(Q_planned, shaped.Q, deviation)
