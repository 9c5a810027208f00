"""Plain URScript move programs, as the twin's controller runs them.

Besides ur_rtde's control script (:mod:`tvist.urserver.control_script`), the twin runs the
small subset of URScript that :func:`tvist.ident.excitation.to_urscript` writes (the
excitation programs of ``tvist plan``)::

    def NAME():
      # comment
      movej([q0, q1, q2, q3, q4, q5], a=ACCEL, v=SPEED)
      sleep(SECONDS)
    end
    NAME()

``movej`` blocks until the move has ended, as on a UR (a target outside the joint limits
protective-stops the arm, an argument outside URScript's range stops the program, see
:mod:`tvist.urserver.motion`); ``sleep`` waits whole controller ticks. The script ports split
the trailing call ``NAME()`` off the definition; the controller takes it as the start of the
program it has just received. A program with any other statement is refused before it moves
anything, naming the line, so a program the twin would run differently from a UR never
starts.
"""

from __future__ import annotations

import logging
import math
import re
from dataclasses import dataclass

import numpy as np

from tvist.urserver.motion import CommandRefused, JointMotion

log = logging.getLogger("tvist.urserver")

__all__ = ["MoveProgram", "MoveStep", "is_move_program", "parse_move_program"]

_NUMBER = r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?"
_DEF = re.compile(r"def\s+([A-Za-z_]\w*)\s*\(\s*\)\s*:")
_MOVEJ = re.compile(
    rf"movej\(\s*\[((?:\s*{_NUMBER}\s*,){{5}}\s*{_NUMBER}\s*)\]\s*,\s*a\s*=\s*({_NUMBER})\s*,"
    rf"\s*v\s*=\s*({_NUMBER})\s*\)"
)
_SLEEP = re.compile(rf"sleep\(\s*({_NUMBER})\s*\)")


@dataclass(frozen=True)
class MoveStep:
    """One statement: ``movej`` to ``q`` (rad) at ``speed``/``accel``, or ``sleep`` ``wait_s``."""

    q: np.ndarray | None = None
    speed_rad_s: float = 0.0
    accel_rad_s2: float = 0.0
    wait_s: float = 0.0


def is_move_program(program: str) -> bool:
    """Whether ``program`` is a ``def NAME():`` program (not ur_rtde's control script)."""
    first = program.strip().splitlines()[0] if program.strip() else ""
    return _DEF.fullmatch(first.strip()) is not None and "def rtde_control():" not in program


def parse_move_program(program: str) -> tuple[str, list[MoveStep]]:
    """``(name, steps)`` of a move program.

    Raises
    ------
    ValueError
        A statement outside the subset (naming its line), a non-finite or non-positive
        number, or anything but the program's call after its ``end``.
    """
    lines = [line.strip() for line in program.splitlines()]
    lines = [line for line in lines if line and not line.startswith("#")]
    header = _DEF.fullmatch(lines[0]) if lines else None
    if header is None:
        raise ValueError("a move program starts with 'def NAME():'")
    name = header.group(1)
    try:
        end = lines.index("end")
    except ValueError:
        raise ValueError(f"program {name}: no 'end'") from None
    if lines[end + 1 :] not in ([], [f"{name}()"]):
        raise ValueError(f"program {name}: after 'end' the twin runs only '{name}()'")
    steps = []
    for line in lines[1:end]:
        code = line.split("#", 1)[0].strip()
        if not code:
            continue
        if match := _MOVEJ.fullmatch(code):
            q = np.array([float(v) for v in match.group(1).split(",")])
            accel, speed = float(match.group(2)), float(match.group(3))
            if not (np.all(np.isfinite(q)) and accel > 0 and speed > 0):
                raise ValueError(f"program {name}: {code!r}: needs finite q and a, v > 0")
            steps.append(MoveStep(q=q, speed_rad_s=speed, accel_rad_s2=accel))
        elif match := _SLEEP.fullmatch(code):
            wait = float(match.group(1))
            if not (math.isfinite(wait) and wait >= 0):
                raise ValueError(f"program {name}: {code!r}: the wait must be finite and >= 0")
            steps.append(MoveStep(wait_s=wait))
        else:
            raise ValueError(
                f"program {name}: {code[:60]!r} is not run by the twin (it runs movej(q, a=, "
                "v=) and sleep(t) programs, and ur_rtde's control script)"
            )
    return name, steps


class MoveProgram:
    """One run of a move program on the controller's :class:`JointMotion`.

    Has the interface the controller drives a program through: ``running``, ``error``,
    :meth:`tick` (one controller tick) and :meth:`fail`.
    """

    def __init__(self, steps: list[MoveStep], motion: JointMotion, dt_s: float) -> None:
        self._steps = list(steps)
        self._motion = motion
        self._dt_s = float(dt_s)
        self._next = 0
        self._moving = False
        self._sleep_ticks = 0
        self.running = True
        self.error: str | None = None

    def tick(self) -> None:
        """Advance the program by one controller tick (before the motion advances)."""
        if not self.running:
            return
        if self._moving:
            if self._motion.moving:
                return
            self._moving = False
        if self._sleep_ticks > 0:
            self._sleep_ticks -= 1
            if self._sleep_ticks > 0:
                return
        while self._next < len(self._steps):
            step = self._steps[self._next]
            self._next += 1
            if step.q is not None:
                try:
                    self._motion.movej(step.q, step.speed_rad_s, step.accel_rad_s2)
                except CommandRefused as exc:  # a runtime error: the program stops
                    self.fail(str(exc))
                    return
                self._moving = True
                return
            # The program goes on ``wait_s`` (whole ticks) after this tick.
            self._sleep_ticks = int(round(step.wait_s / self._dt_s))
            if self._sleep_ticks > 0:
                return
        self.running = False

    def fail(self, message: str) -> None:
        """Stop the program with a runtime error."""
        self.running = False
        self.error = message
        log.error("program stopped: %s", message)
