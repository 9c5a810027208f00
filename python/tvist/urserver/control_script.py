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

A command the twin does not implement (:data:`UNMODELLED` names what it does not model: force
mode, contact, freedrive, I/O, ...), or one with an argument outside URScript's range, stops
the program with an error, as a URScript runtime error stops a UR's program: the client
sees the program stop and its call returns ``False``. An argument that is not a finite number
protective-stops the arm (:class:`~tvist.urserver.motion.SafetyViolation`).
"""

from __future__ import annotations

import logging
import re
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from tvist.urserver.kinematics import Kinematics, finite_pose, pose_trans
from tvist.urserver.motion import CommandRefused, JointMotion, SafetyViolation, finite_value
from tvist.urserver.move_path import MovePath
from tvist.urserver.path_motion import PathMotion
from tvist.urserver.tool_motion import LinearMove, ToolSpeed

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
    5: "MOVEC",
    20: "FORCE_MODE_SET_DAMPING",
    21: "FORCE_MODE_SET_GAIN_SCALING",
    23: "SET_STD_ANALOG_OUT",
    27: "GET_ACTUAL_JOINT_POSITIONS_HISTORY",
    28: "GET_TARGET_WAYPOINT",
    30: "GET_INVERSE_KINEMATICS_ARGS",
    36: "IS_POSE_WITHIN_SAFETY_LIMITS",
    37: "IS_JOINTS_WITHIN_SAFETY_LIMITS",
    38: "GET_JOINT_TORQUES",
    39: "POSE_TRANS",
    40: "GET_TCP_OFFSET",
    41: "JOG_START",
    42: "JOG_STOP",
    43: "GET_FORWARD_KINEMATICS_DEFAULT",
    44: "GET_FORWARD_KINEMATICS_ARGS",
    46: "GET_INVERSE_KINEMATICS_DEFAULT",
    51: "MOVE_UNTIL_CONTACT",
    52: "FREEDRIVE_MODE",
    53: "END_FREEDRIVE_MODE",
    54: "GET_FREEDRIVE_STATUS",
    56: "FT_RTDE_INPUT_ENABLE",
    57: "ENABLE_EXTERNAL_FT_SENSOR",
    58: "GET_ACTUAL_TOOL_FLANGE_POSE",
    59: "SET_GRAVITY",
    60: "GET_INVERSE_KINEMATICS_HAS_SOLUTION_DEFAULT",
    61: "GET_INVERSE_KINEMATICS_HAS_SOLUTION_ARGS",
    62: "START_CONTACT_DETECTION",
    63: "STOP_CONTACT_DETECTION",
    64: "READ_CONTACT_DETECTION",
    65: "SET_TARGET_PAYLOAD",
    66: "DIRECT_TORQUE",
    67: "GET_MASS_MATRIX",
    68: "GET_CORIOLIS_AND_CENTRIFUGAL_TORQUES",
    69: "GET_TARGET_JOINT_ACCELERATIONS",
    70: "GET_JACOBIAN",
    71: "GET_JACOBIAN_TIME_DERIVATIVE",
    99: "WATCHDOG",
    255: "STOP_SCRIPT",
}
#: What the twin does not model, by command: such a command stops the program with this
#: reason (never a success without effect, never an invented value).
UNMODELLED = {
    5: "circular moves (movec)",
    6: "force control (force mode)",
    7: "force control (force mode)",
    8: "a force/torque sensor",
    12: "circular servoing (servoc)",
    13: "I/O (digital outputs)",
    14: "I/O (tool digital outputs)",
    18: "teach mode (hand guiding)",
    19: "teach mode (hand guiding)",
    20: "force control (force mode damping)",
    21: "force control (force mode gain scaling)",
    23: "I/O (analog outputs)",
    25: "contact detection (tool_contact)",
    27: "a joint position history",
    28: "the target waypoint query (get_target_waypoint)",
    38: "joint torque measurements",
    41: "jogging",
    42: "jogging",
    51: "contact detection (moveUntilContact)",
    52: "freedrive (hand guiding)",
    53: "freedrive (hand guiding)",
    54: "freedrive (hand guiding)",
    56: "a force/torque sensor",
    57: "a force/torque sensor",
    59: "a gravity direction other than the twin's",
    62: "contact detection",
    63: "contact detection",
    64: "contact detection",
    65: "payload inertia (set_target_payload)",
    66: "direct torque control",
    67: "the controller's dynamics queries",
    68: "the controller's dynamics queries",
    69: "the controller's dynamics queries",
    70: "the controller's Jacobian query",
    71: "the controller's Jacobian query",
}
#: Commands the script processes every tick and answers "ready" at once.
REALTIME_COMMANDS = frozenset({24, 11, 9, 10, 6, 25, 26, 27, 38, 58, 99})
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
    kinematics
        The robot's kinematics with the TCP offset (Cartesian moves and services).
    measured
        ``() -> (actual_q, actual_flange_pose)``, the latest measurement.
    """

    def __init__(
        self,
        registers: Registers,
        motion: JointMotion,
        int_offset: int,
        float_offset: int,
        set_payload: Callable[[float, list[float] | None], None],
        kinematics: Kinematics | None = None,
        measured: Callable[[], tuple[np.ndarray, np.ndarray]] | None = None,
    ) -> None:
        self._regs = registers
        self._motion = motion
        self._int_offset = int_offset
        self._float_offset = float_offset
        self._set_payload = set_payload
        #: The robot's kinematics and TCP (None: no Cartesian services).
        self._kin = kinematics
        #: ``() -> (actual joints, actual flange pose)``, the latest measurement.
        self._measured = measured
        #: RTDE watchdog (``set_watchdog``): longest time (s) the client may leave the command
        #: register unwritten before the program stops (None: no watchdog), and the time
        #: since it was last written.
        self._watchdog_s: float | None = None
        self._quiet_s = 0.0
        #: The path ``movePath`` injected into this program (None: none); the motion of the
        #: path under way (None: none) and the waypoint it heads for (its async progress).
        self.move_path: MovePath | None = None
        self._path: PathMotion | None = None
        self._path_waypoint = 0
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

    def _out_double(self, i: int, value: float) -> None:
        self._regs.out_double[i + self._float_offset] = float(value)

    def _write_doubles(self, values) -> None:
        for i, value in enumerate(values):
            self._out_double(i, value)

    def _pose_args(self, first: int = 0) -> np.ndarray:
        return np.array([self._in_double(first + i) for i in range(6)])

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
        if self._watchdog_s is not None:
            self._quiet_s += self._motion.dt_s
            if self._quiet_s > self._watchdog_s:
                self.fail(
                    f"watchdog: the client wrote no command register for {self._quiet_s:.3f} s "
                    f"(set_watchdog asks for at least {1.0 / self._watchdog_s:g} Hz)"
                )
                return
        if self._path is not None:
            self._path_progress()
        if self._async_move and self._motion.mode not in ("movej", "follow"):
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

    @property
    def command_register(self) -> str:
        """Name of the RTDE input holding the command (the watchdog's register)."""
        return f"input_int_register_{self._int_offset}"

    def command_register_written(self) -> None:
        """The client wrote the command register (an RTDE data package): kicks the watchdog."""
        self._quiet_s = 0.0

    def fail(self, message: str) -> None:
        """Stop the program with a runtime error."""
        self.running = False
        self.error = message
        log.error("control script stopped: %s", message)

    def _process(self, cmd: int) -> None:
        handler = _CARTESIAN_HANDLERS.get(cmd) if self._kin is not None else None
        if handler is None:
            handler = _HANDLERS.get(cmd)
        if handler is None:
            name = COMMAND_NAMES.get(cmd, "unknown")
            if cmd in UNMODELLED:
                # A query answered at once must not leave the last answer (or zeros) in
                # the output registers: NaN says "not measured".
                self._write_doubles([float("nan")] * 6)
                self.fail(
                    f"command {cmd} ({name}) refused: the twin does not model {UNMODELLED[cmd]}"
                )
            else:
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

    # ------------------------------------------------------------------ Cartesian commands

    def _actual_q(self) -> np.ndarray:
        return self._measured()[0] if self._measured is not None else self._motion.q.copy()

    def _start_move(self, start: Callable[[], None]) -> bool:
        """Start a move (``start``), blocking or asynchronous by the async flag."""
        self._stop_async_move()
        start()
        if self._in_int(1) == 1:
            self._async_move = True
            self._write_async_progress(0)
            return False
        return True

    def _movej_ik(self) -> bool:
        pose = finite_pose(self._pose_args(), "movej_ik: pose")
        q = self._kin.inverse(pose, self._motion.q)
        speed, accel = self._in_double(6), self._in_double(7)
        return self._start_move(lambda: self._motion.movej(q, speed, accel))

    def _movel_to(self, pose: np.ndarray) -> bool:
        move = LinearMove(self._kin, self._motion.q, pose, self._in_double(6), self._in_double(7))
        return self._start_move(lambda: self._motion.follow(move))

    def _movel(self) -> bool:
        return self._movel_to(finite_pose(self._pose_args(), "movel: pose"))

    def _movel_fk(self) -> bool:
        q = self._motion.check_target(self._q_args(), "movel_fk")
        return self._movel_to(self._kin.forward(q))

    def _speedl(self) -> bool:
        xd, accel = self._q_args(), self._in_double(6)
        duration = finite_value(self._in_double(7), "speedl: time")
        if duration < 0.0:
            raise CommandRefused(f"speedl: time = {duration:g} s must be >= 0")
        source = self._motion.source if self._motion.mode == "follow" else None
        if isinstance(source, ToolSpeed):
            source.command(xd, accel)
        else:
            self._motion.follow(ToolSpeed(self._kin, self._motion.q, xd, accel))
        return False

    def _servol(self) -> bool:
        pose = finite_pose(self._pose_args(), "servol: pose")
        q = self._kin.inverse(pose, self._motion.q)
        self._motion.servoj(q, self._in_double(8), self._in_double(9), self._in_double(10))
        return False

    def _stopl(self) -> bool:
        self._stop_async_move()
        decel = self._in_double(0)
        source = self._motion.source if self._motion.mode == "follow" else None
        if source is not None:
            source.stop(decel)
        else:
            self._motion.stop(decel)
        return self._in_int(1) != 1

    def _speed_stop(self) -> bool:
        """speedStop / servoStop: a tool-space motion decelerates along its path."""
        if self._motion.mode == "follow":
            self._motion.source.stop(self._in_double(0))
            return True
        return self._stop_motion()

    def _set_tcp(self) -> bool:
        self._kin.set_tcp(self._pose_args())
        return False

    def _get_tcp_offset(self) -> bool:
        self._write_doubles(self._kin.tcp_offset)
        return False

    def _pose_trans(self) -> bool:
        p_from = finite_pose(self._pose_args(0), "pose_trans: p_from")
        p_from_to = finite_pose(self._pose_args(6), "pose_trans: p_from_to")
        self._write_doubles(pose_trans(p_from, p_from_to))
        return False

    def _fk_default(self) -> bool:
        self._write_doubles(self._kin.forward(self._actual_q()))
        return False

    def _fk_args(self) -> bool:
        q = self._q_args()
        if not np.all(np.isfinite(q)):
            raise SafetyViolation("get_forward_kin: q must be 6 finite numbers")
        tcp = finite_pose(self._pose_args(6), "get_forward_kin: tcp_offset")
        self._write_doubles(self._kin.forward(q, tcp))
        return False

    def _ik_default(self) -> bool:
        pose = finite_pose(self._pose_args(), "get_inverse_kin: x")
        self._write_doubles(self._kin.inverse(pose, self._actual_q(), self._motion.q))
        return False

    def _ik_args(self) -> bool:
        pose = finite_pose(self._pose_args(0), "get_inverse_kin: x")
        qnear = finite_pose(self._pose_args(6), "get_inverse_kin: qnear")
        self._write_doubles(self._kin.inverse(pose, qnear))
        return False

    def _ik_has_solution(self, qnear: np.ndarray) -> bool:
        pose = finite_pose(self._pose_args(0), "get_inverse_kin_has_solution: x")
        self._out_int(1, 1 if self._kin.has_solution(pose, qnear) else 0)
        return False

    def _ik_has_solution_default(self) -> bool:
        return self._ik_has_solution(self._actual_q())

    def _ik_has_solution_args(self) -> bool:
        return self._ik_has_solution(finite_pose(self._pose_args(6), "qnear"))

    def _pose_within_limits(self) -> bool:
        pose = finite_pose(self._pose_args(), "is_within_safety_limits: pose")
        self._out_int(1, 1 if self._kin.has_solution(pose, self._actual_q()) else 0)
        return False

    def _joints_within_limits(self) -> bool:
        self._out_int(1, 1 if self._kin.within_limits(self._q_args()) else 0)
        return False

    def _flange_pose(self) -> bool:
        if self._measured is None:
            raise CommandRefused("get_actual_tool_flange_pose: no measurement")
        self._write_doubles(self._measured()[1])
        return False

    def _move_path(self) -> bool:
        path = self.move_path
        if path is None or not path.waypoints:
            raise CommandRefused(path.refusal if path else "movePath: no path in the program")
        self._stop_async_move()
        motion = PathMotion(self._kin, self._motion, self._motion.q, path.waypoints)
        self._motion.follow(motion)
        self._path = motion
        self._path_waypoint = 0
        self._write_async_progress(0)  # the script's signal_async_progress(0)
        if self._in_int(1) == 1:
            self._async_move = True
            return False
        return True

    def _path_progress(self) -> None:
        """The path's ``signal_async_progress(i)`` as it moves on to waypoint ``i``; forget
        the path once it is no longer the motion."""
        if self._motion.mode != "follow" or self._motion.source is not self._path:
            self._path = None
            return
        waypoint = self._path.waypoint
        if waypoint != self._path_waypoint:
            self._path_waypoint = waypoint
            self._write_async_progress(waypoint)

    def _set_watchdog(self) -> bool:
        frequency = finite_value(self._in_double(0), "set_watchdog: minimum frequency")
        if not frequency > 0.0:
            raise CommandRefused(f"set_watchdog: minimum frequency = {frequency:g} Hz must be > 0")
        self._watchdog_s = 1.0 / frequency
        self._quiet_s = 0.0
        return False

    def _kick_watchdog(self) -> bool:
        return False  # the data package that carried it has kicked the watchdog

    def _protective_stop(self) -> bool:
        raise SafetyViolation("protective stop triggered by the program (protective_stop)")

    def _steptime(self) -> bool:
        self._out_double(0, self._motion.dt_s)
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

#: The controller's services beyond joint motion: tool-space motion, kinematics, the TCP,
#: paths, the watchdog, the step time, protective stop (a script given the robot's
#: kinematics runs them; one without refuses them as unsupported).
_CARTESIAN_HANDLERS: dict[int, Callable[[ControlScript], bool]] = {
    2: ControlScript._movej_ik,
    3: ControlScript._movel,
    4: ControlScript._movel_fk,
    10: ControlScript._speedl,
    15: ControlScript._speed_stop,
    16: ControlScript._speed_stop,
    24: ControlScript._servol,
    26: ControlScript._steptime,
    35: ControlScript._set_watchdog,
    99: ControlScript._kick_watchdog,
    29: ControlScript._set_tcp,
    45: ControlScript._move_path,
    31: ControlScript._protective_stop,
    30: ControlScript._ik_args,
    33: ControlScript._stopl,
    36: ControlScript._pose_within_limits,
    37: ControlScript._joints_within_limits,
    39: ControlScript._pose_trans,
    40: ControlScript._get_tcp_offset,
    43: ControlScript._fk_default,
    44: ControlScript._fk_args,
    46: ControlScript._ik_default,
    58: ControlScript._flange_pose,
    60: ControlScript._ik_has_solution_default,
    61: ControlScript._ik_has_solution_args,
}
