"""Robots a mapping campaign runs on: the MuJoCo twin and a real UR through ur_rtde.

A :class:`CampaignRobot` mounts the payload, records one excitation and, on a simulator,
knows the true modes.
"""

from __future__ import annotations

import tempfile
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any, Protocol

import numpy as np

from tvist.ident.excitation import Excitation, to_urscript
from tvist.ident.logs import Record, read_rtde_csv

#: A twin campaign records every true mode up to this frequency (Hz).
TRUE_MODES_MAX_HZ = 60.0

__all__ = [
    "RECORDED_FIELDS",
    "TRUE_MODES_MAX_HZ",
    "CampaignRobot",
    "TwinRobot",
    "URRobot",
    "new_run_folder",
]

#: RTDE fields recorded on a real robot (what :func:`read_rtde_csv` needs, plus the pose).
RECORDED_FIELDS = (
    "timestamp",
    "target_q",
    "target_qd",
    "target_qdd",
    "actual_q",
    "actual_TCP_pose",
    "actual_tool_accelerometer",
)


def new_run_folder(parent: str | Path) -> Path:
    """A new, empty folder ``parent/run-NNN`` (the next free number): each run of a campaign
    keeps its own logs, and no run writes over an earlier one's."""
    parent = Path(parent)
    parent.mkdir(parents=True, exist_ok=True)
    taken = [int(p.name[4:]) for p in parent.glob("run-*") if p.name[4:].isdigit()]
    number = max(taken, default=0) + 1
    while True:
        folder = parent / f"run-{number:03d}"
        try:
            folder.mkdir()
        except FileExistsError:  # another campaign took it meanwhile
            number += 1
            continue
        return folder


class CampaignRobot(Protocol):
    """What the campaign runner needs from a robot (simulated or real)."""

    robot_name: str

    def set_payload(self, payload_kg: float, payload_com_m: Sequence[float]) -> None:
        """Mount (or declare) the payload for the following excitations."""

    def record_excitation(self, excitation: Excitation) -> Record:
        """Move to ``excitation.q0``, run the excitation while logging, return the log."""

    def true_modes(self, q: np.ndarray) -> list[tuple[float, float]] | None:
        """Ground-truth ``[(wn_rad_s, zeta) base, shoulder]`` if known (simulation), else None."""


class TwinRobot:
    """The MuJoCo twin (:class:`tvist.sim.Twin`) as a campaign robot.

    Parameters
    ----------
    robot_name
        Robot of the parameter file.
    accel_noise_std
        White noise on each accelerometer axis, m/s² (the real sensor is noisy).
    seed
        Seed of the accelerometer noise; combined with each excitation's seed (if it has
        one), so each excitation's noise is reproducible on its own.
    variant
        A twin variant of :mod:`tvist.sim.variants` (a named one or ``family:<robot>:<seed>``;
        its robot must be ``robot_name``), or ``None`` for the standard twin.

    Raises
    ------
    ValueError
        An unknown variant, or one of another robot.
    """

    def __init__(
        self,
        robot_name: str = "ur5e",
        accel_noise_std: float = 0.05,
        seed: int = 0,
        variant: str | None = None,
    ):
        self.robot_name = robot_name
        self.accel_noise_std = float(accel_noise_std)
        self.seed = int(seed)
        self.variant = variant
        self._twin_kwargs: dict = {}
        if variant is not None:
            from tvist.sim.variants import variant_robot, variant_twin_kwargs

            self._twin_kwargs = variant_twin_kwargs(variant)
            if variant_robot(variant) != robot_name:
                raise ValueError(
                    f"twin variant {variant!r} is a {variant_robot(variant)}, not a {robot_name}"
                )
        self._twin = None
        self._payload: tuple[float, tuple[float, ...]] | None = None

    def set_payload(self, payload_kg: float, payload_com_m: Sequence[float]) -> None:
        key = (float(payload_kg), tuple(float(v) for v in payload_com_m))
        if key == self._payload:
            return
        from tvist.sim import Twin

        self._twin = Twin(
            self.robot_name,
            payload_kg=key[0],
            payload_com_m=key[1],
            **self._twin_kwargs,
            accel_noise_std=self.accel_noise_std,
            seed=self.seed,
        )
        self._payload = key

    def _require_twin(self):
        if self._twin is None:
            raise RuntimeError("call set_payload() before running excitations")
        return self._twin

    def record_excitation(self, excitation: Excitation) -> Record:
        # The noise of a seeded excitation depends only on (seed, excitation seed), not on
        # which excitations this robot ran before: a pose's result must not depend on the
        # order in which parallel workers happen to pick the poses up.
        noise_seed = None if excitation.seed is None else [self.seed, excitation.seed]
        sim = self._require_twin().run(excitation.q, dt_s=excitation.dt_s, noise_seed=noise_seed)
        return Record.from_rtde_fields(sim)

    def true_modes(self, q: np.ndarray) -> list[tuple[float, float]] | None:
        return self._require_twin().modes(q)

    def all_true_modes(self, q: np.ndarray, max_freq_hz: float = TRUE_MODES_MAX_HZ) -> list:
        """Every vibration mode of the twin at ``q`` up to ``max_freq_hz``, lowest first
        (:class:`tvist.sim.family.TrueMode`)."""
        from tvist.sim.family import modes_of

        return modes_of(self._require_twin(), q, max_freq_hz=max_freq_hz)


class URRobot:
    """A real UR e-Series arm through ur_rtde (``pip install ur-rtde``), imported lazily.

    Each excitation: ``moveJ`` to the start pose, start recording every RTDE package at 500 Hz
    (:class:`tvist.live.RtdeRecorder`; ur_rtde's ``startFileRecording`` writes the latest
    state on a timer of its own, so a late or early wake-up repeats or skips samples), stand
    still, run every bang-coast-bang move as ``moveJ(q, speed, acceleration)`` followed by the
    wait, stop recording and read the log back with :func:`read_rtde_csv`. :meth:`close`
    ends the control script.

    Make sure the workspace is clear: the campaign moves the arm through the whole workspace
    and jerks the base and shoulder. Payload changes are manual: :meth:`set_payload` declares
    the payload to the controller and, when it differs from the one declared before and
    ``confirm`` is given, calls it to let the operator mount it first (once per change, not
    per pose).

    Parameters
    ----------
    ip
        Robot address.
    robot_name
        Parameter-file name of the model (for the kinematics used in identification).
    log_dir
        Folder for the RTDE logs (kept for inspection; see :func:`new_run_folder`); default
        a temporary folder.
    frequency_hz
        RTDE recording frequency, Hz; None: the controller's own rate (e-Series 500 Hz,
        CB-series 125 Hz; :class:`tvist.live.RtdeRecorder`).
    confirm
        Called with a message before each payload change (e.g. ``input``); None to skip.
        End of input (``EOFError``: no terminal to answer) is a ``ValueError``.
    """

    def __init__(
        self,
        ip: str,
        robot_name: str = "ur5e",
        *,
        log_dir: str | Path | None = None,
        frequency_hz: float | None = None,
        confirm: Callable[[str], Any] | None = input,
    ) -> None:
        try:
            import rtde_control  # noqa: F401 (checked here: the error names the extra)
        except ImportError as exc:  # pragma: no cover - needs the optional dependency
            raise ImportError(
                "a real robot needs ur_rtde: pip install 'tvist[robot]' (or ur-rtde)"
            ) from exc
        from tvist.live import control_interface

        self.robot_name = robot_name
        self._control = control_interface(ip)  # ConnectionError, never a hang, if no data
        self._ip = ip
        self._frequency_hz = frequency_hz
        self._log_dir = Path(log_dir or tempfile.mkdtemp(prefix="tvist-campaign-"))
        self._log_dir.mkdir(parents=True, exist_ok=True)
        self._confirm = confirm
        self._count = 0
        self._payload: tuple[float, tuple[float, ...]] | None = None

    def set_payload(self, payload_kg: float, payload_com_m: Sequence[float]) -> None:
        payload = (float(payload_kg), tuple(float(v) for v in payload_com_m))
        if payload == self._payload:
            return
        if self._confirm is not None:
            try:
                self._confirm(
                    f"Mount a {payload_kg:g} kg payload (centre of mass {list(payload[1])} m "
                    "in the flange frame), then press Enter"
                )
            except EOFError:
                raise ValueError(
                    f"no answer to the prompt to mount the {payload_kg:g} kg payload (no "
                    "terminal): mount the payloads in the plan's order and pass --yes"
                ) from None
        self._control.setPayload(payload[0], list(payload[1]))
        self._payload = payload

    def record_excitation(self, excitation: Excitation) -> Record:
        from tvist.live import RtdeRecorder

        c = self._control
        c.moveJ(list(excitation.q0), 0.5, 0.5)
        path = self._log_dir / f"excitation_{self._count:04d}_joint{excitation.joint}.csv"
        self._count += 1
        # The recording starts with the package after the move was reported done: at rest.
        # Waits count the controller's packages, not the wall clock: a twin server whose
        # ticks run late slips behind the wall clock, and a sleep would record less.
        with RtdeRecorder(self._ip, path, RECORDED_FIELDS, self._frequency_hz) as recorder:
            recorder.wait_controller_time(excitation.standstill_s)
            q = np.array(excitation.q0, dtype=float)
            for move in excitation.moves:
                q[excitation.joint] = move.q_to_rad
                c.moveJ(list(q), move.speed_rad_s, move.accel_rad_s2)
                recorder.wait_controller_time(move.wait_s)
        return read_rtde_csv(path, resample=True)

    def close(self) -> None:
        """Stop the control script and disconnect."""
        self._control.stopScript()
        self._control.disconnect()

    def true_modes(self, q: np.ndarray) -> list[tuple[float, float]] | None:
        return None

    def urscript(self, excitation: Excitation) -> str:
        """The same excitation as a URScript program (to run from the pendant instead)."""
        return to_urscript(excitation)
