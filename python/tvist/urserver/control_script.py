"""ur_rtde's control script, as the twin's controller runs it.

``RTDEControlInterface`` uploads a URScript program (``rtde_control.script`` of ur_rtde) and
then drives it through RTDE registers. This module does, tick by tick, what that program's
main loop does (the twin recognizes the program; it does not interpret URScript):

- ``input_int_register_0`` holds the command id, ``input_int_register_1`` an integer argument
  (``async``), ``input_double_register_0..10`` the numeric arguments, all shifted by the
  register offset the client injected (0, or 24 for the upper range: the only two values
  ur_rtde injects; a program with another is refused).
- ``output_int_register_0`` is the script's state: 1 ready for a command, 2 done with it.
  Real-time commands (servoj, speedj, ...) are processed at once and answered "ready"; every
  other command is processed once (until the client writes command 0 again) and answered
  "done" when it has finished, which for a blocking move is when the move has ended.
- ``output_int_register_2`` reports asynchronous operations (bit 15: running; bits 16-23 a
  write counter, bits 24-30 the operation id).
- Command 255 ends the program.

A command the twin does not implement, or one with an argument outside URScript's range,
stops the program with an error, as a URScript runtime error stops a UR's program: the client
sees the program stop and its call returns ``False``. An argument that is not a finite number
protective-stops the arm (:class:`~tvist.urserver.motion.SafetyViolation`).
"""

from __future__ import annotations

import logging
import re
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from tvist.urserver.motion import CommandRefused, JointMotion, SafetyViolation, finite_value

log = logging.getLogger("tvist.urserver")

#: Command ids of ur_rtde's ``RTDE::RobotCommand::Type`` (the script's ``cmd == N``).
COMMAND_NAMES = {
    0: "NO_CMD",
    1: "MOVEJ",
    2: "MOVEJ_IK",
    3: "MOVEL",
    4: "MOVEL_FK",
    6: "FORCE_MODE",
    7: "FORCE_MODE_STOP",
    8: "ZERO_FT_SENSOR",
    9: "SPEEDJ",
    10: "SPEEDL",
    11: "SERVOJ",
    12: "SERVOC",
    13: "SET_STD_DIGITAL_OUT",
    14: "SET_TOOL_DIGITAL_OUT",
    15: "SPEED_STOP",
    16: "SERVO_STOP",
    17: "SET_PAYLOAD",
    18: "TEACH_MODE",
    19: "END_TEACH_MODE",
    24: "SERVOL",
    25: "TOOL_CONTACT",
    26: "GET_STEPTIME",
    29: "SET_TCP",
    31: "PROTECTIVE_STOP",
    33: "STOPL",
    34: "STOPJ",
    35: "SET_WATCHDOG",
    45: "MOVE_PATH",
    47: "IS_STEADY",
    255: "STOP_SCRIPT",
}
#: Commands the script processes every tick and answers "ready" at once.
REALTIME_COMMANDS = frozenset({24, 11, 9, 10, 6, 25, 26, 27, 38, 58})
SCRIPT_READY = 1
SCRIPT_DONE = 2
STOP_SCRIPT = 255
#: Register offsets ur_rtde injects into the script: 0, or 24 with its upper-range flag.
REGISTER_OFFSETS = (0, 24)


def is_control_script(program: str) -> bool:
    """Whether ``program`` is ur_rtde's control script (by its entry point and main loop)."""
    return "def rtde_control():" in program and "def rtde_cmd():" in program


def register_offsets(program: str) -> tuple[int, int]:
    """``(int_offset, float_offset)`` the client injected into the control script.

    Raises
    ------
    ValueError
        If one is missing or not one of :data:`REGISTER_OFFSETS`.
    """

    def find(name: str) -> int:
        # The client injects the value after the comment that ends the line, so it
        # continues the assignment on the next line.
        match = re.search(rf"global\s+{name}\s*=\s*(?:#[^\n]*\n)?[ \t]*(\S+)", program)
        if match is None:
            raise ValueError(f"control script without a value for {name}")
        text = match.group(1)
        if text not in {str(offset) for offset in REGISTER_OFFSETS}:
            allowed = " or ".join(str(offset) for offset in REGISTER_OFFSETS)
            raise ValueError(f"control script with {name} = {text[:20]!r} (ur_rtde uses {allowed})")
        return int(text)

    return find("reg_offset_int"), find("reg_offset_float")


@dataclass
class Registers:
    """The controller's general-purpose RTDE registers (48 of each kind and direction)."""

    in_int: list[int]
    in_double: list[float]
    out_int: list[int]
    out_double: list[float]

    @classmethod
    def zeros(cls, n: int = 48) -> Registers:
        return cls([0] * n, [0.0] * n, [0] * n, [0.0] * n)


class ControlScript:
    """One run of ur_rtde's control script.

    Parameters
    ----------
    registers
        The controller's registers (read and written in place).
    motion
        The joint motion the script commands.
    int_offset, float_offset
        Register offsets injected by the client (0 or 24).
    set_payload
        Called with ``(mass_kg, cog_m or None)`` for ``set_payload`` (``None``: keep the cog).
    """

    def __init__(
        self,
        registers: Registers,
        motion: JointMotion,
        int_offset: int,
        float_offset: int,
        set_payload: Callable[[float, list[float] | None], None],
    ) -> None:
        self._regs = registers
        self._motion = motion
        self._int_offset = int_offset
        self._float_offset = float_offset
        self._set_payload = set_payload
        self.running = True
        self.error: str | None = None
        self._executing_cmd = False
        self._blocked_cmd: int | None = None  # a blocking command waiting for its motion
        self._async_move = False
        self._async_wr_count = 0
        self._async_op_id = 0
        # Program start: reset_async_progress(); signal_ready().
        self._write_async_progress(-1)
        self._out_int(0, SCRIPT_READY)

    # ------------------------------------------------------------------ registers

    def _in_int(self, i: int) -> int:
        return int(self._regs.in_int[i + self._int_offset])

    def _in_double(self, i: int) -> float:
        return float(self._regs.in_double[i + self._float_offset])

    def _out_int(self, i: int, value: int) -> None:
        self._regs.out_int[i + self._int_offset] = int(value)

    def _q_args(self) -> np.ndarray:
        return np.array([self._in_double(i) for i in range(6)])

    def _write_async_progress(self, value: int) -> None:
        """The script's ``write_async_progress_register``: 0 starts, < 0 ends an operation."""
        self._async_wr_count = 0 if self._async_wr_count >= 127 else self._async_wr_count + 1
        if value == 0:
            self._async_op_id = 0 if self._async_op_id >= 127 else self._async_op_id + 1
        reg = self._async_wr_count * 65536 + self._async_op_id * 16777216
        if value >= 0:
            reg += min(value, 32767) + 32768
        self._out_int(2, reg)

    # ------------------------------------------------------------------ main loop

    def tick(self) -> None:
        """One pass of the script's main loop (its ``sync()`` is one controller tick)."""
        if not self.running:
            return
        if self._async_move and self._motion.mode != "movej":
            self._async_move = False
            self._write_async_progress(-1)
        if self._blocked_cmd is not None:
            if self._motion.moving:
                return
            self._blocked_cmd = None
            self._out_int(0, SCRIPT_DONE)
            return
        cmd = self._in_int(0)
        if cmd in REALTIME_COMMANDS:
            self._process(cmd)
            if self.running:
                self._out_int(0, SCRIPT_READY)
        elif cmd == 0:
            self._executing_cmd = False
            self._out_int(0, SCRIPT_READY)
        elif not self._executing_cmd:
            self._executing_cmd = True
            self._process(cmd)

    def fail(self, message: str) -> None:
        """Stop the program with a runtime error."""
        self.running = False
        self.error = message
        log.error("control script stopped: %s", message)

    def _process(self, cmd: int) -> None:
        handler = _HANDLERS.get(cmd)
        if handler is None:
            name = COMMAND_NAMES.get(cmd, "unknown")
            self.fail(f"command {cmd} ({name}) is not supported by the twin")
            return
        try:
            blocking = handler(self)
        except CommandRefused as exc:
            self.fail(str(exc))
            return
        except SafetyViolation as exc:
            self.fail(str(exc))
            raise
        if cmd == STOP_SCRIPT or not self.running:
            return
        if blocking:
            self._blocked_cmd = cmd
        elif cmd not in REALTIME_COMMANDS:
            self._out_int(0, SCRIPT_DONE)

    # ------------------------------------------------------------------ commands
    # Each handler returns True if the script blocks until the motion has ended.

    def _stop_async_move(self) -> None:
        if self._async_move:
            self._async_move = False
            self._write_async_progress(-1)

    def _movej(self) -> bool:
        q = self._q_args()
        speed, accel = self._in_double(6), self._in_double(7)
        self._stop_async_move()
        self._motion.movej(q, speed, accel)
        if self._in_int(1) == 1:
            self._async_move = True
            self._write_async_progress(0)
            return False
        return True

    def _speedj(self) -> bool:
        self._motion.speedj(self._q_args(), self._in_double(6))
        return False

    def _servoj(self) -> bool:
        # The script reads speed (6) and acceleration (7) too, but servoj ignores them.
        self._motion.servoj(
            self._q_args(), self._in_double(8), self._in_double(9), self._in_double(10)
        )
        return False

    def _stop_motion(self) -> bool:
        self._motion.stop(self._in_double(0))
        return True

    def _stopj(self) -> bool:
        self._stop_async_move()
        self._motion.stop(self._in_double(0))
        if self._in_int(1) == 1:
            return False
        return True

    def _set_payload(self) -> bool:
        mass = finite_value(self._in_double(0), "set_payload: mass")
        cog = [finite_value(self._in_double(i), "set_payload: cog") for i in (1, 2, 3)]
        self._set_payload(mass, None if cog == [0.0, 0.0, 0.0] else cog)
        return False

    def _is_steady(self) -> bool:
        self._out_int(1, 0 if self._motion.moving else 1)
        return False

    def _stop_script(self) -> bool:
        self.running = False
        return False


_HANDLERS: dict[int, Callable[[ControlScript], bool]] = {
    1: ControlScript._movej,
    9: ControlScript._speedj,
    11: ControlScript._servoj,
    15: ControlScript._stop_motion,
    16: ControlScript._stop_motion,
    17: ControlScript._set_payload,
    34: ControlScript._stopj,
    47: ControlScript._is_steady,
    255: ControlScript._stop_script,
}
#: Commands of ur_rtde the twin implements (the rest stop the program with an error).
SUPPORTED_COMMANDS = tuple(COMMAND_NAMES.get(c, str(c)) for c in sorted(_HANDLERS))
