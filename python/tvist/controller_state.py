"""What a UR controller says about itself, and how to get its arm moving again.

:func:`read_state` reads the robot and safety modes and the joint angles over RTDE, and asks
the dashboard server (port 29999) for its safety status, as a user would on the pendant.
:meth:`ControllerState.recovery` says what to do about a stop, in the dashboard's commands.
``tvist run`` reads the state before it moves (and refuses to start on a stopped arm) and
after a refusal (to report the controller's own reason instead of a guess).

The mode numbers are those of UR's RTDE guide (``robot_mode``, ``safety_mode``).
"""

from __future__ import annotations

import os
import socket
from dataclasses import dataclass

import numpy as np

__all__ = ["ROBOT_MODES", "SAFETY_MODES", "ControllerState", "dashboard_query", "read_state"]

#: RTDE ``safety_mode`` values.
SAFETY_MODES = {
    1: "NORMAL",
    2: "REDUCED",
    3: "PROTECTIVE_STOP",
    4: "RECOVERY",
    5: "SAFEGUARD_STOP",
    6: "SYSTEM_EMERGENCY_STOP",
    7: "ROBOT_EMERGENCY_STOP",
    8: "VIOLATION",
    9: "FAULT",
    10: "VALIDATE_JOINT_ID",
    11: "UNDEFINED_SAFETY_MODE",
    12: "AUTOMATIC_MODE_SAFEGUARD_STOP",
    13: "SYSTEM_THREE_POSITION_ENABLING_STOP",
}
#: RTDE ``robot_mode`` values.
ROBOT_MODES = {
    -1: "NO_CONTROLLER",
    0: "DISCONNECTED",
    1: "CONFIRM_SAFETY",
    2: "BOOTING",
    3: "POWER_OFF",
    4: "POWER_ON",
    5: "IDLE",
    6: "BACKDRIVE",
    7: "RUNNING",
    8: "UPDATING_FIRMWARE",
}
#: Safety modes in which the arm may move, and the robot mode it must be in.
MOVING_SAFETY_MODES = ("NORMAL", "REDUCED")
RUNNING = "RUNNING"

_UNLOCK = (
    "remove its cause (the pendant's popup and the controller log name it), then on the "
    "dashboard (port 29999) 'close safety popup' and 'unlock protective stop', or unlock it "
    "on the pendant"
)
_POWER_ON = "power it on and release the brakes: dashboard 'power on', then 'brake release'"
_RELEASE = (
    "release the emergency stop, then dashboard 'close safety popup', 'power on' and "
    "'brake release'"
)
_RESTART = "dashboard 'restart safety', then 'power on' and 'brake release'"
_SAFEGUARD = "close the safeguard (a safety input is open), then continue"
#: What to do in each stopped safety mode.
_SAFETY_RECOVERY = {
    "PROTECTIVE_STOP": _UNLOCK,
    "SAFEGUARD_STOP": _SAFEGUARD,
    "AUTOMATIC_MODE_SAFEGUARD_STOP": _SAFEGUARD,
    "SYSTEM_EMERGENCY_STOP": _RELEASE,
    "ROBOT_EMERGENCY_STOP": _RELEASE,
    "VIOLATION": _RESTART,
    "FAULT": _RESTART,
    "RECOVERY": "the arm is beyond a safety limit: move it back inside on the pendant",
}


@dataclass(frozen=True)
class ControllerState:
    """The controller's own account of the arm.

    Attributes
    ----------
    robot_mode, safety_mode
        Names from :data:`ROBOT_MODES` and :data:`SAFETY_MODES` (``"UNKNOWN(n)"`` otherwise).
    actual_q
        Joint angles, rad, ``(6,)``.
    dashboard
        The dashboard's answer to ``safetystatus`` (``safetymode`` on a CB-series), or
        ``None`` if it did not answer.
    """

    robot_mode: str
    safety_mode: str
    actual_q: np.ndarray
    dashboard: str | None = None

    @property
    def can_move(self) -> bool:
        """True if the arm is powered, released and not stopped."""
        return self.robot_mode == RUNNING and self.safety_mode in MOVING_SAFETY_MODES

    def describe(self) -> str:
        """``safety mode PROTECTIVE_STOP, robot mode RUNNING (dashboard: ...)``."""
        text = f"safety mode {self.safety_mode}, robot mode {self.robot_mode}"
        return text + (f" (dashboard: {self.dashboard!r})" if self.dashboard else "")

    def recovery(self) -> str:
        """What to do so that the arm can move ("" if it can)."""
        if self.safety_mode not in MOVING_SAFETY_MODES:
            return _SAFETY_RECOVERY.get(self.safety_mode, "see the pendant")
        if self.robot_mode != RUNNING:
            return _POWER_ON
        return ""


def read_state(host: str, port: int = 30004) -> ControllerState:
    """The controller's robot and safety modes, joint angles and dashboard safety status.

    Raises
    ------
    OSError
        If the controller's RTDE interface cannot be reached (or sends nothing within 5 s).
    """
    from tvist.live import RtdeRecorder

    fields = ("robot_mode", "safety_mode", "actual_q")
    with RtdeRecorder(host, os.devnull, fields, frequency_hz=125.0, port=port) as rtde:
        values = rtde.latest
    robot = int(values["robot_mode"])
    safety = int(values["safety_mode"])
    return ControllerState(
        robot_mode=ROBOT_MODES.get(robot, f"UNKNOWN({robot})"),
        safety_mode=SAFETY_MODES.get(safety, f"UNKNOWN({safety})"),
        actual_q=np.array(values["actual_q"], dtype=float),
        dashboard=_dashboard_safety(host),
    )


def _dashboard_safety(host: str) -> str | None:
    """``safetystatus`` (e-Series), else ``safetymode`` (CB-series); None if no answer."""
    for command in ("safetystatus", "safetymode"):
        answer = dashboard_query(host, command)
        if answer is None:
            return None
        if not answer.lower().startswith("could not understand"):
            return answer
    return None


def dashboard_query(host: str, command: str, port: int = 29999, timeout_s: float = 2.0):
    """The dashboard server's one-line answer to ``command``, or None if it cannot be reached."""
    try:
        with socket.create_connection((host, port), timeout=timeout_s) as sock:
            reader = sock.makefile("rb")
            reader.readline()  # "Connected: Universal Robots Dashboard Server"
            sock.sendall(command.encode() + b"\n")
            return reader.readline().decode(errors="replace").strip() or None
    except OSError:
        return None
