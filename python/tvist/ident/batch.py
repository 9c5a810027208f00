"""Batch identification: many excitation logs → one pose record per pose (JSON lines).

1. Every log is read (:func:`~tvist.ident.logs.read_rtde_csv`, skipped samples resampled),
   cut to its excitation and its excited joint found
   (:func:`~tvist.ident.segment.excitation_segment`: approach moves and rests around the
   excitation are left out), and its pose taken from ``actual_q``
   (:func:`~tvist.ident.pose.pose_of`).
2. The logs of the same pose (base, shoulder, elbow, wrist 1: one of each at most) are
   grouped (:func:`group_logs`): their starting poses (the measured joint angles before the
   first move) agree.
3. Each group (or a lone log) is identified (:func:`~tvist.ident.pose.identify_pose`) into the
   record :func:`~tvist.ident.map_fit.fit_map` reads: the base and shoulder logs give the
   ``modes`` entries, every log its ``ringing`` entries.
4. Modes that jump against their neighbouring poses are flagged
   (:func:`~tvist.ident.pose_checks.flag_jumps`).

Both passes run in parallel worker processes.
"""

from __future__ import annotations

import errno
import glob
import os
import warnings
from collections.abc import Callable, Iterable, Sequence
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from tvist.ident.excited import EXCITABLE_JOINTS
from tvist.ident.local_fit import FitOptions
from tvist.ident.logs import Record, read_rtde_csv
from tvist.ident.pose import IDENTIFIED_JOINTS, PoseRecord, identify_pose, pose_of
from tvist.ident.pose_checks import flag_jumps
from tvist.ident.segment import excitation_segment

__all__ = [
    "LoadedLog",
    "PoseLogs",
    "expand_logs",
    "excited_joint",
    "group_logs",
    "identify_logs",
    "load_log",
]

#: The starting poses of two logs of one pose agree to this, rad.
PAIR_TOL_RAD = 0.02


def expand_logs(items: Iterable[str]) -> list[Path]:
    """Files named by ``items``: paths, glob patterns, or directories (their ``*.csv``)."""
    out: list[Path] = []
    for item in items:
        path = Path(item)
        if path.is_dir():
            found = sorted(path.glob("*.csv"))
        elif any(c in item for c in "*?["):
            found = sorted(Path(p) for p in glob.glob(item))
        else:
            if not path.exists():
                raise FileNotFoundError(errno.ENOENT, "No such file or directory", item)
            found = [path]
        if not found:
            raise ValueError(f"{item}: no CSV logs found (give files, globs or folders)")
        out += [p for p in found if p not in out]
    return out


def excited_joint(record: Record) -> int:
    """The joint the log excites (see :func:`~tvist.ident.segment.excitation_segment`)."""
    return excitation_segment(record).joint


@dataclass(frozen=True)
class LoadedLog:
    """A log read for batch identification."""

    path: Path
    record: Record
    joint: int
    pose: np.ndarray
    warnings: tuple[str, ...] = ()


def load_log(
    path: Path,
    drop_nan: bool = False,
    resample: bool = True,
    repair: tuple[str, ...] = (),
    units: str | None = None,
) -> LoadedLog:
    """Read ``path`` (declared ``units``, see :func:`~tvist.ident.logs.read_rtde_csv`), cut
    it to its excitation and find its excited joint and pose (warnings are kept, not shown)."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        record = read_rtde_csv(
            path, repair=repair or None, drop_nan=drop_nan, resample=resample, units=units
        )
    segment = excitation_segment(record)
    record = segment.of(record)
    return LoadedLog(
        path=Path(path),
        record=record,
        joint=segment.joint,
        pose=pose_of(record),
        warnings=tuple(str(w.message) for w in caught),
    )


@dataclass(frozen=True)
class PoseLogs:
    """Logs of one pose, by excited joint (base and/or shoulder, and further joints' logs);
    a joint without a log is missing."""

    logs: dict[int, LoadedLog]

    @property
    def base(self) -> LoadedLog | None:
        return self.logs.get(0)

    @property
    def shoulder(self) -> LoadedLog | None:
        return self.logs.get(1)

    @property
    def others(self) -> dict[int, LoadedLog]:
        """The logs of joints other than base and shoulder (elbow, wrist 1), by joint."""
        return {j: log for j, log in self.logs.items() if j not in IDENTIFIED_JOINTS}

    @property
    def key(self) -> str:
        return "+".join(self.logs[j].path.stem for j in sorted(self.logs))


def _distance(a: LoadedLog, b: LoadedLog) -> float:
    """Largest difference of the two logs' starting poses (rad)."""
    return float(np.max(np.abs(a.pose - b.pose)))


def group_logs(logs: Sequence[LoadedLog]) -> tuple[list[PoseLogs], list[LoadedLog]]:
    """Group the logs of the same pose: at most one log per joint, every two of a group's
    starting poses within :data:`PAIR_TOL_RAD` (closest pairs joined first).

    Returns the groups (including lone logs), in the order of their first log in ``logs``,
    and the logs that excite a joint that is not identified (outside
    :data:`~tvist.ident.excited.EXCITABLE_JOINTS`).
    """
    usable = [log for log in logs if log.joint in EXCITABLE_JOINTS]
    others = [log for log in logs if log.joint not in EXCITABLE_JOINTS]
    group_of = list(range(len(usable)))
    members: dict[int, list[int]] = {i: [i] for i in range(len(usable))}
    candidates = sorted(
        (d, i, k)
        for i in range(len(usable))
        for k in range(i + 1, len(usable))
        if usable[i].joint != usable[k].joint
        and (d := _distance(usable[i], usable[k])) <= PAIR_TOL_RAD
    )
    for _, i, k in candidates:
        a, b = group_of[i], group_of[k]
        if a == b:
            continue
        joints_a = {usable[n].joint for n in members[a]}
        if joints_a & {usable[n].joint for n in members[b]}:
            continue
        if any(
            _distance(usable[m], usable[n]) > PAIR_TOL_RAD for m in members[a] for n in members[b]
        ):
            continue
        for n in members[b]:
            group_of[n] = a
        members[a] += members.pop(b)
    groups = [
        PoseLogs({usable[n].joint: usable[n] for n in sorted(members[g])})
        for g in sorted(members, key=lambda g: min(members[g]))
    ]
    return groups, others


@dataclass(frozen=True)
class _Job:
    robot_name: str
    payload_kg: float | None  # None: each log's own (its payload columns)
    payload_com_m: tuple[float, float, float]
    accel_frame: str
    options: FitOptions
    separate_modes: bool


def _pose_payload(group: PoseLogs, job: _Job):
    """The pose's payload: the job's, or the one its logs name (they must agree)."""
    from tvist.ident.logs import log_payload
    from tvist.robots import Payload

    if job.payload_kg is not None:
        return Payload(job.payload_kg, job.payload_com_m)
    logs = [group.logs[j] for j in sorted(group.logs)]
    payloads = [log_payload(log.path) for log in logs]
    for log, payload in zip(logs, payloads, strict=True):
        if payload is None:
            raise ValueError(f"{log.path}: no payload columns; give the payload explicitly")
    first = payloads[0]
    for log, payload in zip(logs[1:], payloads[1:], strict=True):
        if payload.mass_kg != first.mass_kg or not np.array_equal(payload.com_m, first.com_m):
            raise ValueError(
                f"{logs[0].path} and {log.path} start at one pose but name different payloads "
                f"({first.mass_kg:g} and {payload.mass_kg:g} kg)"
            )
    return first


def _identify_pose(group: PoseLogs, job: _Job) -> dict[str, Any]:
    from tvist.robots import Robot, params

    try:
        payload = _pose_payload(group, job)
    except ValueError as exc:
        return {"key": group.key, "error": str(exc)}
    robot = Robot(params(job.robot_name), payload)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # reported when the logs were read
        result: PoseRecord = identify_pose(
            None if group.base is None else group.base.record,
            None if group.shoulder is None else group.shoulder.record,
            robot,
            key=group.key,
            options=job.options,
            separate_modes=job.separate_modes,
            accel_frame=job.accel_frame,
            other_records={j: log.record for j, log in group.others.items()},
        )
    record = result.to_dict()
    record["logs"] = {str(j): str(group.logs[j].path) for j in sorted(group.logs)}
    return record


def _load_safely(
    path: Path, drop_nan: bool, resample: bool, repair: tuple[str, ...], units: str | None
) -> LoadedLog | str:
    try:
        return load_log(path, drop_nan, resample, repair, units)
    except (ValueError, OSError) as exc:
        return f"{path}: {exc}"


def identify_logs(
    paths: Sequence[Path],
    *,
    robot_name: str = "ur5e",
    payload_kg: float | None = None,
    payload_com_m: Sequence[float] | None = None,
    accel_frame: str = "flange",
    options: FitOptions | None = None,
    separate_modes: bool = True,
    drop_nan: bool = False,
    resample: bool = True,
    repair: tuple[str, ...] = (),
    units: str | None = None,
    workers: int | None = None,
    on_message: Callable[[str], None] = lambda _: None,
    progress: bool = False,
) -> list[dict[str, Any]]:
    """Identify every pose in ``paths``; one record (:class:`PoseRecord` dict) per pose.

    The payload is ``payload_kg`` at ``payload_com_m`` (default 5 cm beyond the flange) for
    every log, or with ``payload_kg=None`` the one each log names (its payload columns, written
    by ``tvist record`` and ``tvist run``); a pose whose logs name none gets an ``error``.
    ``on_message`` receives the log warnings and the logs that were skipped (one line each).
    ``units`` declares the logs' units where they are not SI (``"q=deg,acc=g"``).
    ``workers`` processes (default: the number of CPUs) run the reading and the fits.
    """
    job = _Job(
        robot_name=robot_name,
        payload_kg=None if payload_kg is None else float(payload_kg),
        payload_com_m=tuple(  # type: ignore[arg-type]
            float(v) for v in (payload_com_m or (0.0, 0.0, 0.05))
        ),
        accel_frame=accel_frame,
        options=options or FitOptions(),
        separate_modes=separate_modes,
    )
    n_workers = max(1, int(workers or os.cpu_count() or 1))
    bar = _Bar(len(paths), progress)
    try:
        with ProcessPoolExecutor(max_workers=n_workers) as pool:
            loaded: list[LoadedLog] = []
            futures = [
                pool.submit(_load_safely, p, drop_nan, resample, tuple(repair), units)
                for p in paths
            ]
            for future in futures:
                item = future.result()
                bar.advance("read")
                if isinstance(item, str):
                    on_message(f"skipped {item}")
                    continue
                for text in item.warnings:
                    on_message(text)
                loaded.append(item)
            groups, others = group_logs(loaded)
            names = ", ".join(str(j) for j in EXCITABLE_JOINTS)
            for log in others:
                on_message(f"skipped {log.path}: it excites joint {log.joint}, not one of {names}")
            bar.restart(len(groups))
            results = []
            for future in [pool.submit(_identify_pose, group, job) for group in groups]:
                results.append(future.result())
                bar.advance("identified")
    finally:
        bar.close()
    return flag_jumps(results, robot_name)


class _Bar:
    """A rich progress bar over reading and identifying (inert when disabled)."""

    def __init__(self, total: int, enabled: bool) -> None:
        self._progress = None
        if not enabled:
            return
        from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn

        self._progress = Progress(
            TextColumn("identify {task.fields[stage]}"), BarColumn(), MofNCompleteColumn()
        )
        self._task = self._progress.add_task("logs", total=total, stage="reading")
        self._progress.start()

    def advance(self, stage: str) -> None:
        if self._progress is not None:
            self._progress.update(self._task, advance=1)

    def restart(self, total: int) -> None:
        if self._progress is not None:
            self._progress.reset(self._task, total=total, stage="poses")

    def close(self) -> None:
        if self._progress is not None:
            self._progress.stop()
