"""The path ``RTDEControlInterface.movePath`` injects into the control script.

ur_rtde writes a path as URScript into the script's ``exec_move_path()`` (after the line
``# inject move path``) and uploads the script again; command 45 then runs it. Each waypoint
is one line ``movel(p[x,y,z,rx,ry,rz],a=…,v=…,r=…)`` or ``movej([q…],a=…,v=…,r=…)`` (a
``movej`` to a pose ``p[…]`` goes through inverse kinematics), each preceded by
``signal_async_progress(i)``. The twin runs the waypoints as one motion, blending through
those with a radius ``r > 0`` (see :mod:`tvist.urserver.path_motion`); a line it does not
recognize is refused.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass

import numpy as np

_INJECT = "# inject move path"
_NUMBER = r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?"
_MOVE = re.compile(
    rf"^(movel|movej)\((p?)\[((?:\s*{_NUMBER}\s*,){{5}}\s*{_NUMBER}\s*)\],"
    rf"a=({_NUMBER}),v=({_NUMBER}),r=({_NUMBER})\)$"
)
_PROGRESS = re.compile(r"^signal_async_progress\(\d+\)$")


@dataclass(frozen=True)
class Waypoint:
    """One move of a path: ``kind`` ``"movel"`` or ``"movej"``; ``target`` six numbers, a
    pose if ``is_pose`` (m, rad) else joint angles (rad); speed ``v``, acceleration ``a``;
    blend radius ``r`` (m, 0: stop at the waypoint)."""

    kind: str
    target: np.ndarray
    is_pose: bool
    v: float
    a: float
    r: float = 0.0


@dataclass(frozen=True)
class MovePath:
    """The injected path: its waypoints, or why the twin cannot run it (``refusal``)."""

    waypoints: tuple[Waypoint, ...]
    refusal: str | None = None


def parse_move_path(program: str) -> MovePath | None:
    """The path injected into ``program`` (None: none injected)."""
    start = program.find(_INJECT)
    if start < 0:
        return None
    waypoints = []
    for raw in program[start + len(_INJECT) :].splitlines()[1:]:
        line = raw.strip()
        if line == "end":
            break
        if not line or _PROGRESS.match(line):
            continue
        match = _MOVE.match(line)
        if match is None:
            return MovePath((), f"movePath: the twin does not run the path line {line[:80]!r}")
        kind, pose, values, a, v, r = match.groups()
        target = np.array([float(x) for x in values.split(",")])
        numbers = [*target, float(a), float(v), float(r)]
        if not all(math.isfinite(x) for x in numbers):
            return MovePath((), f"movePath: a number that is not finite in {line[:80]!r}")
        if float(r) < 0.0:
            return MovePath((), f"movePath: a negative blend radius in {line[:80]!r}")
        waypoints.append(Waypoint(kind, target, pose == "p", float(v), float(a), float(r)))
    return MovePath(tuple(waypoints))
