"""The twin's controller: the 2 ms tick that runs the program, the motion and the arm.

Each :meth:`TwinController.tick` runs one pass of the loaded program (ur_rtde's control
script, or a movej/sleep program), advances the joint motion by one tick, moves the twin's
motors to the new target over the tick (:class:`tvist.sim.twin_plant.TwinPlant`) and returns the
RTDE output values measured at the tick's start. Not thread-safe: the server calls it under
its lock.

Nothing a client commands stops the tick: a command's bad number protective-stops the arm or
stops the program (see :mod:`tvist.urserver.motion`), and any other failure inside a tick
protective-stops the arm where the tick started, with the reason in :attr:`last_error` and
the log. The tick goes on publishing; dashboard ``unlock protective stop`` releases the arm.
"""

from __future__ import annotations

import logging
import math
import time

import numpy as np

from tvist.robots import Robot
from tvist.sim import SimulationDiverged, Twin
from tvist.sim.twin import check_payload_mass
from tvist.sim.twin_plant import TwinPlant
from tvist.urserver import variables
from tvist.urserver.control_script import (
    ControlScript,
    Registers,
    is_control_script,
    register_offsets,
)
from tvist.urserver.kinematics import Kinematics, PoseRate
from tvist.urserver.motion import CommandRefused, JointMotion, SafetyViolation
from tvist.urserver.move_path import parse_move_path
from tvist.urserver.move_program import MoveProgram, is_move_program, parse_move_program

log = logging.getLogger("tvist.urserver")

#: RTDE ``runtime_state`` values.
RUNTIME_STOPPED = 1
RUNTIME_PLAYING = 2
#: ``robot_mode`` RUNNING, ``joint_mode`` RUNNING, ``safety_mode`` NORMAL / PROTECTIVE_STOP.
ROBOT_MODE_RUNNING = 7
JOINT_MODE_RUNNING = 253
SAFETY_MODE_NORMAL = 1
SAFETY_MODE_PROTECTIVE_STOP = 3
#: ``robot_status_bits``: bit 0 power on, bit 1 program running.
STATUS_POWER_ON = 1
STATUS_PROGRAM_RUNNING = 2
#: ``safety_status_bits``: bit 0 normal mode, bit 2 protective stopped.
SAFETY_BIT_NORMAL = 1
SAFETY_BIT_PROTECTIVE_STOPPED = 4
#: Deceleration when a program stops while the arm moves (rad/s²).
PROGRAM_STOP_DECEL_RAD_S2 = 4.0


class TwinController:
    """The simulated controller of a UR e-Series arm.

    Parameters
    ----------
    twin
        The flexible twin (robot and physical payload).
    q0
        Initial joint angles (rad).
    dt_s
        Controller tick (s); ``None``: the robot's control period
        (:attr:`~tvist.robots.RobotParams.control_period_s`, 0.002 on the e-Series).
    """

    def __init__(self, twin: Twin, q0, dt_s: float | None = None) -> None:
        self.twin = twin
        self.dt_s = float(twin.params.sample_period_s(dt_s))
        self.plant = TwinPlant(twin, q0, self.dt_s)
        params = twin.params
        self.motion = JointMotion(
            self.plant.q_motor, self.dt_s, params.max_velocity_rad_s, params.joint_limits_rad
        )
        #: The robot's kinematics and the TCP offset (``set_tcp``), shared by every program.
        self.kinematics = Kinematics(Robot(params), params.joint_limits_rad)
        self._actual_q = self.plant.q_motor
        self._actual_speed = PoseRate()
        self._target_speed = PoseRate()
        self._actual_flange = self.kinematics.forward(self._actual_q, np.zeros(6))
        self.registers = Registers.zeros(variables.N_REGISTERS)
        self.script: ControlScript | MoveProgram | None = None
        self.program_name = ""
        self.protective_stop = False
        self.payload_kg = float(twin.payload.mass_kg)
        self.payload_cog_m = [float(v) for v in twin.payload.com_m]
        #: A declared payload's centre of gravity lies within the arm's reach of the flange
        #: (m): farther out it is no payload the arm could carry.
        self.payload_cog_limit_m = float(np.sum(np.abs(params.a_m)) + np.sum(np.abs(params.d_m)))
        #: Why the last protective stop or program stop happened (None: none yet).
        self.last_error: str | None = None
        self._execution_ms = 0.0
        self._q_prev = self.plant.q_motor
        self._started = time.monotonic()

    # ------------------------------------------------------------------ programs

    @property
    def program_running(self) -> bool:
        return self.script is not None and self.script.running

    def load_program(self, program: str) -> str | None:
        """Run a URScript program received on a script port; an error message if refused.

        A program replaces the running one, as on a UR. The call ``NAME()`` that follows a
        move program's definition (the script ports receive it as a statement of its own)
        runs that program, which already runs.
        """
        if isinstance(self.script, MoveProgram) and program.strip() == f"{self.program_name}()":
            return None
        self.stop_program()
        if self.protective_stop:
            return "the robot is protective-stopped: unlock it first (dashboard)"
        if is_move_program(program):
            return self._load_move_program(program)
        if not is_control_script(program):
            first = program.strip().splitlines()[0] if program.strip() else ""
            return (
                f"program {first[:60]!r} not run: the twin runs ur_rtde's control script "
                "(RTDEControlInterface) and movej/sleep programs, not arbitrary URScript"
            )
        try:
            int_offset, float_offset = register_offsets(program)
        except ValueError as exc:
            self.last_error = f"program not run: {exc}"
            return self.last_error
        self.script = ControlScript(
            self.registers,
            self.motion,
            int_offset,
            float_offset,
            self._set_payload,
            kinematics=self.kinematics,
            measured=lambda: (self._actual_q.copy(), self._actual_flange.copy()),
        )
        self.script.move_path = parse_move_path(program)
        self.program_name = "rtde_control"
        log.info("control script started (register offsets %d/%d)", int_offset, float_offset)
        return None

    def _load_move_program(self, program: str) -> str | None:
        """Start a movej/sleep program (:mod:`tvist.urserver.move_program`); an error
        message if it is outside that subset (then nothing moves)."""
        try:
            name, steps = parse_move_program(program)
        except ValueError as exc:
            self.last_error = f"program not run: {exc}"
            return self.last_error
        self.script = MoveProgram(steps, self.motion, self.dt_s)
        self.program_name = name
        log.info("program %s started (%d statements)", name, len(steps))
        return None

    def client_wrote(self, names) -> None:
        """An RTDE data package wrote the inputs ``names`` (kicks the program's watchdog when
        it holds the command register)."""
        script = self.script
        if (
            isinstance(script, ControlScript)
            and script.running
            and script.command_register in names
        ):
            script.command_register_written()

    def set_speed_slider(self, fraction) -> str | None:
        """The speed slider: every move's time runs at ``fraction`` (0..1) of real time, as
        the speed scaling published; the reason if refused (not a number in [0, 1])."""
        try:
            value = float(fraction)
        except (TypeError, ValueError):
            value = math.nan
        if not 0.0 <= value <= 1.0:
            return f"speed slider fraction {fraction!r} refused: it must be in [0, 1]"
        self.motion.time_scale = value
        return None

    def stop_program(self) -> None:
        """Stop the running program (dashboard ``stop``): the arm decelerates to rest."""
        if self.script is not None and self.script.running:
            self.script.running = False
        self._on_program_end()

    def _on_program_end(self) -> None:
        if self.script is not None:
            if self.script.error:
                self.last_error = self.script.error
            self.script = None
        if self.motion.mode not in ("hold", "stop"):
            self.motion.stop(PROGRAM_STOP_DECEL_RAD_S2)

    def unlock_protective_stop(self) -> bool:
        """Clear a protective stop; False if there is none."""
        if not self.protective_stop:
            return False
        self.protective_stop = False
        return True

    def _set_payload(self, mass_kg: float, cog_m: list[float] | None) -> None:
        """A controller's set_payload declares the payload (the physical one is the twin's).

        Raises
        ------
        CommandRefused
            A mass the twin could not carry or a centre of gravity beyond the arm's reach.
        """
        try:
            mass = check_payload_mass(self.twin.params, mass_kg, "set_payload: mass")
        except ValueError as exc:
            raise CommandRefused(str(exc)) from None
        if cog_m is not None:
            distance = float(np.linalg.norm(cog_m))
            if not distance <= self.payload_cog_limit_m:
                raise CommandRefused(
                    f"set_payload: centre of gravity {distance:g} m from the flange, beyond "
                    f"the arm's reach {self.payload_cog_limit_m:g} m"
                )
            self.payload_cog_m = [float(v) for v in cog_m]
        self.payload_kg = mass

    # ------------------------------------------------------------------ tick

    def tick(self) -> dict:
        """Advance one controller tick; the RTDE output values at the tick's start."""
        t0 = time.perf_counter()
        q_start = self.motion.q.copy()
        qd_start, qdd_start = self.motion.qd.copy(), self.motion.qdd.copy()
        try:
            self._run_program()
            q_next = self.motion.advance()
        except SafetyViolation as exc:
            self._protective_stop(str(exc))
            q_next = self.motion.q.copy()
        except Exception as exc:  # a fault of the twin's own must not end the tick
            log.exception("controller fault")
            self.motion.hold_at(q_start)
            self._protective_stop(f"controller fault: {exc!r}")
            q_next = q_start
        sample = self._step_plant(q_start, q_next)
        self._actual_q, self._actual_flange = sample.q_link, sample.flange_pose
        values = self._outputs(sample, q_start, qd_start, qdd_start)
        self._execution_ms = (time.perf_counter() - t0) * 1e3
        return values

    def _run_program(self) -> None:
        script = self.script
        if script is None or not script.running:
            return
        try:
            script.tick()
        finally:
            if not script.running:
                self._on_program_end()

    def _step_plant(self, q_start: np.ndarray, q_next: np.ndarray):
        """Step the twin to ``q_next``; if it fails, restart it at rest at ``q_start`` (a
        finite pose within the limits: the motion's invariant) and protective-stop."""
        try:
            return self.plant.step(q_next)
        except Exception as exc:
            if isinstance(exc, SimulationDiverged):
                reason = str(exc)
            else:
                log.exception("twin step failed")
                reason = f"twin step failed: {exc!r}"
            log.error("%s: the twin restarts at rest", reason)
            self.plant = TwinPlant(self.twin, q_start, self.dt_s)
            self.motion.hold_at(q_start)
            self._protective_stop(reason)
            return self.plant.step(q_start)

    def fault(self, reason: str) -> None:
        """Protective-stop for a failure outside :meth:`tick` (the server's own)."""
        self._protective_stop(reason)

    def _protective_stop(self, reason: str) -> None:
        log.error("protective stop: %s", reason)
        self.protective_stop = True
        self.last_error = reason
        if self.script is not None and self.script.running:
            self.script.fail(reason)
        self.script = None
        self.motion.hold()

    def _outputs(self, sample, q, qd, qdd) -> dict:
        regs = self.registers
        running = self.program_running
        actual_tcp = self.kinematics.flange_to_tcp(sample.flange_pose)
        target_tcp = self.kinematics.forward(q)
        nan6 = [math.nan] * 6
        values = {
            "timestamp": sample.time_s,
            "target_q": q.tolist(),
            "target_qd": qd.tolist(),
            "target_qdd": qdd.tolist(),
            "actual_q": sample.q_link.tolist(),
            "actual_qd": sample.qd_link.tolist(),
            "actual_TCP_pose": actual_tcp.tolist(),
            "target_TCP_pose": target_tcp.tolist(),
            "actual_TCP_speed": self._actual_speed.velocity(actual_tcp, sample.time_s).tolist(),
            "target_TCP_speed": self._target_speed.velocity(target_tcp, sample.time_s).tolist(),
            "actual_tool_accelerometer": sample.accelerometer.tolist(),
            "actual_execution_time": self._execution_ms,
            "robot_mode": ROBOT_MODE_RUNNING,
            "joint_mode": [JOINT_MODE_RUNNING] * 6,
            "safety_mode": SAFETY_MODE_PROTECTIVE_STOP
            if self.protective_stop
            else SAFETY_MODE_NORMAL,
            "speed_scaling": self.motion.time_scale,
            "target_speed_fraction": self.motion.time_scale,
            "actual_digital_input_bits": 0,
            "actual_digital_output_bits": 0,
            "standard_analog_output0": 0.0,
            "standard_analog_output1": 0.0,
            "runtime_state": RUNTIME_PLAYING if running else RUNTIME_STOPPED,
            "robot_status_bits": STATUS_POWER_ON | (STATUS_PROGRAM_RUNNING if running else 0),
            "safety_status_bits": SAFETY_BIT_PROTECTIVE_STOPPED
            if self.protective_stop
            else SAFETY_BIT_NORMAL,
            "payload": self.payload_kg,
            "payload_cog": list(self.payload_cog_m),
            "payload_inertia": [0.0] * 6,
            "output_bit_registers0_to_31": 0,
            "output_bit_registers32_to_63": 0,
            "input_bit_registers0_to_31": 0,
            "input_bit_registers32_to_63": 0,
        }
        values["safety_status"] = values["safety_mode"]
        for name in variables.UNMEASURED_OUTPUTS:
            values[name] = nan6 if variables.OUTPUTS[name] == "VECTOR6D" else math.nan
        for i in range(variables.N_REGISTERS):
            values[f"output_int_register_{i}"] = regs.out_int[i]
            values[f"output_double_register_{i}"] = regs.out_double[i]
            values[f"input_int_register_{i}"] = regs.in_int[i]
            values[f"input_double_register_{i}"] = regs.in_double[i]
        return values


def initial_pose(twin: Twin) -> np.ndarray:
    """The pose the twin starts in: the paper's stretched pose Q1 (arm horizontal)."""
    from tvist.trajectory import PAPER_POSES

    return np.array(PAPER_POSES["Q1"], dtype=float)
