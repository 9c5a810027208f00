"""Mapping campaign runner (paper Algorithm 1): every pose excited, identified and stored.

In every pose of the plan (:mod:`tvist.ident.pose_plan`) the base, the shoulder and the
robot's elbow (the excited joints, :func:`~tvist.ident.excited.default_excited_joints` by
default) are
excited in turn (Algorithm 2, :func:`~tvist.ident.excitation.random_excitation`) on a
campaign robot (:mod:`tvist.ident.campaign_robots`: the MuJoCo twin or a real UR) and
identified (:func:`~tvist.ident.pose.identify_pose`). Each pose record is appended to a
JSON-lines file as it finishes (:mod:`tvist.ident.results_store`), so an interrupted campaign
resumes where it stopped; each line is one pose record in the format
:func:`~tvist.ident.map_fit.fit_map` reads. When the campaign ends, ringing modes that jump
against their neighbouring poses are flagged in the file
(:func:`~tvist.ident.pose_checks.flag_jumps`). On the twin each record lists every true mode
below :data:`~tvist.ident.campaign_robots.TRUE_MODES_MAX_HZ` (:func:`true_modes_entries`).
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

from tvist.ident.campaign_robots import RECORDED_FIELDS, CampaignRobot, TwinRobot, URRobot
from tvist.ident.excited import excited_joints
from tvist.ident.local_fit import FitOptions
from tvist.ident.logs import Record
from tvist.ident.pose import IDENTIFIED_JOINTS, identify_pose
from tvist.ident.pose_checks import flag_jumps
from tvist.ident.pose_plan import (
    PAPER_ANGLES_RAD,
    PAPER_PAYLOADS_KG,
    PAPER_RADII_M,
    CampaignPose,
    campaign_order,
    campaign_poses,
    plane_coordinates,
    pose_excitations,
    solve_plane_ik,
)
from tvist.ident.results_store import ResultsStore, fingerprint, load_results
from tvist.robots import Payload as _Payload
from tvist.robots import Robot, params

__all__ = [
    "IDENTIFIED_JOINTS",
    "PAPER_ANGLES_RAD",
    "PAPER_PAYLOADS_KG",
    "PAPER_RADII_M",
    "RECORDED_FIELDS",
    "CampaignPose",
    "CampaignRobot",
    "TwinRobot",
    "URRobot",
    "campaign_poses",
    "load_results",
    "plane_coordinates",
    "run_campaign",
    "run_pose",
    "run_variant_campaign",
    "solve_plane_ik",
]


@dataclass
class _Settings:
    robot_name: str
    accel_noise_std: float
    noise_seed: int
    duration_s: float
    options: FitOptions = field(default_factory=FitOptions)
    separate_modes: bool = True
    variant: str | None = None
    joints: tuple[int, ...] | None = None  # None: the robot's default

    def __post_init__(self) -> None:
        self.joints = excited_joints(self.joints, self.robot_name)


def run_pose(robot: CampaignRobot, pose: CampaignPose, settings: _Settings) -> dict:
    """Excite and identify the excited joints (``settings.joints``) at one pose; the
    JSON-lines record of it."""
    plan = {
        "angle_rad": pose.angle_rad,
        "radius_m": pose.radius_m,
        "wrist_joint": pose.wrist_joint,
    }
    if pose.q is None:
        return {
            "key": pose.key,
            "payload_kg": pose.payload_kg,
            "payload_com_m": list(pose.payload_com_m),
            **plan,
            "q": None,
            "modes": [],
            "error": "unreachable",
        }
    model = Robot(params(robot.robot_name), _Payload(pose.payload_kg, pose.payload_com_m))
    robot.set_payload(pose.payload_kg, pose.payload_com_m)
    logs: dict[int, Record | None] = {}
    failed: dict[int, str] = {}
    for excitation in pose_excitations(
        pose, settings.duration_s, settings.joints, robot_name=settings.robot_name
    ):
        joint = excitation.joint
        try:
            logs[joint] = robot.record_excitation(excitation)
        except (ValueError, RuntimeError) as exc:
            logs[joint] = None
            failed[joint] = str(exc)
    result = identify_pose(
        logs[0],
        logs[1],
        model,
        key=pose.key,
        q=pose.q,
        options=settings.options,
        separate_modes=settings.separate_modes,
        other_records={j: log for j, log in logs.items() if j not in IDENTIFIED_JOINTS},
    )
    record = result.to_dict()
    for entry in record["modes"]:
        if entry["joint"] in failed:
            entry["error"] = failed[entry["joint"]]
    record.update(plan)
    truth = robot.true_modes(pose.q)
    if truth is not None:
        every = getattr(robot, "all_true_modes", None)
        record["true_modes"] = true_modes_entries(truth, [] if every is None else every(pose.q))
    return record


def true_modes_entries(
    base_shoulder: list[tuple[float, float]], every: list
) -> list[dict[str, Any]]:
    """The record's ``true_modes``: every true mode (:class:`tvist.sim.family.TrueMode`,
    lowest first) as ``{"freq_hz", "zeta", "joint_shares", "flange_direction", "link_share",
    "wn_rad_s", "joint"}``, where ``joint`` is 0 (1) for the twin's base (shoulder) mode, the
    mode that stores most of its strain energy in that joint (:meth:`tvist.sim.Twin.modes`),
    else ``None``. A base or shoulder mode beyond the listed ones is added with the
    ``joint``, ``wn_rad_s`` and ``zeta`` only."""
    out: list[dict[str, Any]] = [
        {
            "freq_hz": float(m.freq_hz),
            "zeta": float(m.zeta),
            "joint_shares": [float(v) for v in m.joint_shares],
            "flange_direction": [float(v) for v in m.flange_direction],
            "link_share": float(m.link_share),
            "wn_rad_s": 2.0 * math.pi * float(m.freq_hz),
            "joint": None,
        }
        for m in every
    ]
    for joint, (wn, zeta) in zip(IDENTIFIED_JOINTS, base_shoulder, strict=True):
        match = [e for e in out if e["joint"] is None and abs(e["wn_rad_s"] / wn - 1.0) < 1e-6]
        if match:
            match[0]["joint"] = joint
        else:
            out.append({"joint": joint, "wn_rad_s": float(wn), "zeta": float(zeta)})
    return out


#: One twin per worker process and payload (building a MuJoCo model takes a while).
_WORKER_ROBOT: TwinRobot | None = None


def _twin_worker(pose: CampaignPose, settings: _Settings) -> dict:
    global _WORKER_ROBOT
    if _WORKER_ROBOT is None:
        _WORKER_ROBOT = TwinRobot(
            settings.robot_name,
            settings.accel_noise_std,
            seed=settings.noise_seed,
            variant=settings.variant,
        )
    return run_pose(_WORKER_ROBOT, pose, settings)


def run_campaign(
    poses: Iterable[CampaignPose],
    results_path: str | Path,
    *,
    robot: CampaignRobot | None = None,
    robot_name: str = "ur5e",
    workers: int = 1,
    accel_noise_std: float = 0.05,
    noise_seed: int = 0,
    duration_s: float = 8.0,
    options: FitOptions | None = None,
    separate_modes: bool = True,
    progress: bool = True,
    overwrite: bool = False,
    variant: str | None = None,
    joints: tuple[int, ...] | None = None,
) -> list[dict]:
    """Run (or resume) a campaign and return every pose record in ``results_path``.

    Parameters
    ----------
    poses
        From :func:`campaign_poses` (or a subset).
    results_path
        JSON-lines file (:mod:`tvist.ident.results_store`); poses already in it with the
        same settings are skipped, new ones are appended as they finish.
    robot
        A :class:`CampaignRobot` (e.g. :class:`URRobot`), run in this process. ``None`` runs
        the MuJoCo twin, with ``workers`` processes.
    robot_name
        Robot model for the twin and the kinematics.
    workers
        Parallel processes for the twin (ignored for a given ``robot``).
    accel_noise_std, noise_seed
        Twin accelerometer noise, m/s², and its seed.
    duration_s
        Excitation length per joint (Algorithm 2: about 8 s).
    options
        Local-fit settings.
    separate_modes
        Separate the base mode from the shoulder mode with a two-mode fit where the base
        excitation rings both (see :func:`tvist.ident.two_mode.fit_two_modes`); ``False``
        records the paper's single-mode fit only.
    progress
        Show a rich progress bar.
    overwrite
        Empty ``results_path`` first. Without it, a file written with other settings is
        refused (:class:`~tvist.ident.results_store.SettingsMismatch`).
    variant
        Run a twin variant (:data:`tvist.sim.variants.VARIANTS`) instead of the standard
        twin (for a given ``robot``: that robot's ``variant``, if it has one); its records
        are not mixed with the standard twin's in one file.
    joints
        The joints excited at every pose (:func:`~tvist.ident.excited.excited_joints`:
        base and shoulder, and any of elbow and wrist 1); ``None``: the robot's
        (:func:`~tvist.ident.excited.default_excited_joints`). Records of other joints are not
        mixed in one file.

    Raises
    ------
    ValueError
        The file holds records made with other settings, or another campaign is writing it.
    """
    settings = _Settings(
        robot_name=robot_name if robot is None else robot.robot_name,
        accel_noise_std=accel_noise_std,
        noise_seed=noise_seed,
        duration_s=duration_s,
        options=options or FitOptions(),
        separate_modes=separate_modes,
        variant=getattr(robot, "variant", None) if robot is not None else variant,
        joints=excited_joints(joints, robot_name if robot is None else robot.robot_name),
    )
    poses = list(poses)
    coms = sorted({tuple(p.payload_com_m) for p in poses})
    key = fingerprint(
        {
            "robot": settings.robot_name,
            "real_robot": robot is not None and not isinstance(robot, TwinRobot),
            "payload_com_m": coms,
            "noise_seed": noise_seed,
            "accel_noise_std": accel_noise_std,
            "duration_s": duration_s,
            "options": asdict(settings.options),
            "separate_modes": separate_modes,
            # Only when set, so files of the standard twin keep their fingerprint.
            **({"variant": settings.variant} if settings.variant else {}),
            # Only when not base and shoulder alone, so files of the campaigns that excited
            # those only keep their fingerprint.
            **({"excited_joints": settings.joints} if settings.joints != (0, 1) else {}),
        }
    )
    with ResultsStore(results_path, key, overwrite=overwrite) as store:
        todo = [p for p in poses if p.key not in store.done]
        bar = _Progress(len(todo), len(store.done)) if progress and todo else None
        try:
            if robot is not None or workers <= 1:
                runner = robot or TwinRobot(
                    robot_name, accel_noise_std, seed=noise_seed, variant=settings.variant
                )
                # Payload by payload keeps manual payload changes on a real robot to a minimum.
                for pose in campaign_order(todo):
                    store.append(run_pose(runner, pose, settings))
                    if bar is not None:
                        bar.advance(pose.key)
            else:
                pool = ProcessPoolExecutor(max_workers=workers, initializer=_worker_init)
                try:
                    futures = {pool.submit(_twin_worker, p, settings): p for p in todo}
                    for future in as_completed(futures):
                        store.append(future.result())
                        if bar is not None:
                            bar.advance(futures[future].key)
                except BaseException:
                    # Ctrl-C or an error: stop the workers now; finished poses are saved.
                    for process in list(getattr(pool, "_processes", {}).values()):
                        process.terminate()
                    pool.shutdown(wait=False, cancel_futures=True)
                    raise
                pool.shutdown()
        finally:
            if bar is not None:
                bar.close()
        # Parallel workers finish in any order: the file is rewritten in the order a sequential
        # run writes it (campaign_order; records of poses not in this plan last), so the
        # records, and any map fitted from them, are the same to the bit either way.
        rank = {p.key: i for i, p in enumerate(campaign_order(poses))}
        ordered = sorted(store.records, key=lambda r: rank.get(r["key"], len(rank)))
        store.replace_all(flag_jumps(ordered, settings.robot_name))
        return list(store.records)


def _worker_init() -> None:
    """In each worker: leave Ctrl-C to the parent, and die with it (Linux)."""
    import signal

    signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        import ctypes

        pr_set_pdeathsig = 1
        ctypes.CDLL("libc.so.6", use_errno=True).prctl(pr_set_pdeathsig, signal.SIGTERM)
    except (OSError, AttributeError):  # not Linux: workers end when their queue closes
        pass


class _Progress:
    def __init__(self, total: int, already: int) -> None:
        from rich.progress import (
            BarColumn,
            MofNCompleteColumn,
            Progress,
            TextColumn,
            TimeRemainingColumn,
        )

        self._progress = Progress(
            TextColumn("campaign"),
            BarColumn(),
            MofNCompleteColumn(),
            TextColumn("{task.fields[last]}"),
            TimeRemainingColumn(),
        )
        label = f"resumed after {already}" if already else ""
        self._task = self._progress.add_task("poses", total=total, last=label)
        self._progress.start()

    def advance(self, key: str) -> None:
        self._progress.update(self._task, advance=1, last=key)

    def close(self) -> None:
        self._progress.stop()


def run_variant_campaign(
    variant: str,
    results_path: str | Path,
    *,
    every: int = 1,
    part: tuple[int, int] = (0, 1),
    seed: int = 0,
    workers: int = 1,
    progress: bool = False,
) -> list[dict]:
    """Algorithm 1's campaign (every ``every``-th pose) on a twin variant: ``tvist campaign
    --sim --variant NAME --every N``.

    ``part = (i, n)`` runs only poses ``i, i + n, ...`` of those (to split a campaign over
    processes that write separate files).
    """
    from tvist.sim.variants import variant_robot

    robot_name = variant_robot(variant)  # an unknown name is refused here, naming the known ones
    poses = campaign_poses(robot_name, seed=seed)[::every]
    return run_campaign(
        poses[part[0] :: part[1]],
        results_path,
        robot_name=robot_name,
        variant=variant,
        workers=workers,
        noise_seed=seed,
        progress=progress,
    )
