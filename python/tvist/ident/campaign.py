"""Mapping campaign (paper Algorithm 1): poses over the workspace, excitation and local fits.

Poses: the flange centre is placed at angle ``V`` (seen from the shoulder axis, in the arm's
vertical plane: 0 = horizontal outwards, π/2 = straight up) and distance ``R`` from the shoulder
axis, for ``V ∈ {0, π/4, π/2, 3π/4}`` and 13 values ``R = 0.4 … 0.9`` m, for every payload.
In each pose one wrist joint (3, 4 or 5), chosen at random, is turned to a random angle; the
shoulder and elbow are then solved (elbow up) by numerical inverse kinematics with the robot
model's flange position and Jacobian.

In every pose the base and the shoulder are excited in turn (Algorithm 2,
:func:`~tvist.ident.excitation.random_excitation`) and identified
(:func:`~tvist.ident.local_fit.identify_local`).

The runner works over a :class:`CampaignRobot`: :class:`TwinRobot` (the MuJoCo twin) or
:class:`URRobot` (a real UR through ur_rtde). Results are appended per pose to a JSON-lines
file, so an interrupted campaign resumes where it stopped; each line is one pose record in the
format :func:`~tvist.ident.map_fit.fit_map` reads.
"""

from __future__ import annotations

import json
import math
import os
import tempfile
import time
from collections.abc import Callable, Iterable, Sequence
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Protocol

import numpy as np
from scipy import optimize

from tvist.ident.excitation import Excitation, random_excitation, to_urscript
from tvist.ident.local_fit import FitOptions, LocalFit, identify_local
from tvist.ident.logs import Record, read_rtde_csv
from tvist.ident.two_mode import ModeEstimate
from tvist.robots import Payload as _Payload
from tvist.robots import Robot, params

__all__ = [
    "PAPER_ANGLES_RAD",
    "PAPER_PAYLOADS_KG",
    "PAPER_RADII_M",
    "CampaignPose",
    "CampaignRobot",
    "TwinRobot",
    "URRobot",
    "campaign_poses",
    "load_results",
    "plane_coordinates",
    "run_campaign",
    "solve_plane_ik",
]

#: Algorithm 1's angles of the flange seen from the shoulder, rad.
PAPER_ANGLES_RAD: tuple[float, ...] = (0.0, math.pi / 4, math.pi / 2, 3 * math.pi / 4)
#: Algorithm 1's 13 radii from the shoulder axis to the flange centre, 0.4 + k/24 m.
PAPER_RADII_M: tuple[float, ...] = tuple(0.4 + k / 24 for k in range(13))
#: The paper's payloads, kg.
PAPER_PAYLOADS_KG: tuple[float, ...] = (0.0, 1.0, 3.0, 5.0)
#: Wrist joints of which one is turned at random in each pose (Algorithm 1).
WRIST_JOINTS = (3, 4, 5)
#: Wrist angles the random joint is turned away from, rad (the paper's test poses' wrist).
NOMINAL_WRIST_RAD = (-math.pi / 2, 0.0, 0.0)
#: The flange must land within this distance of the target, m.
IK_TOLERANCE_M = 1e-6
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
#: Joints the campaign identifies (base, shoulder).
IDENTIFIED_JOINTS = (0, 1)


# --------------------------------------------------------------------------- poses


def _plane_axes(robot: Robot, base_angle_rad: float) -> tuple[np.ndarray, np.ndarray, float]:
    """Outward horizontal unit vector of the arm plane, up vector, shoulder-axis height (m)."""
    # With q = 0 the arm is stretched along -x of the base (UR convention, a_2 < 0).
    reach = np.array([math.cos(base_angle_rad), math.sin(base_angle_rad), 0.0])
    if robot.params.a_m[1] < 0:
        reach = -reach
    return reach, np.array([0.0, 0.0, 1.0]), float(robot.params.d_m[0])


def plane_coordinates(robot: Robot, q: np.ndarray) -> tuple[float, float]:
    """``(V, R)``: angle (rad) and distance (m) of the flange centre from the shoulder axis."""
    reach, up, height = _plane_axes(robot, float(q[0]))
    p = robot.flange_pose(q)[:3, 3]
    x, z = float(p @ reach), float(p @ up - height)
    return math.atan2(z, x), math.hypot(x, z)


def solve_plane_ik(
    robot: Robot, angle_rad: float, radius_m: float, q_fixed: np.ndarray
) -> np.ndarray | None:
    """Shoulder and elbow angles that put the flange centre at ``(V, R)``, elbow up.

    ``q_fixed`` gives the base and wrist angles (its entries 1 and 2 are ignored). Returns
    the full pose, or ``None`` if the point is out of reach with this wrist.
    """
    reach, up, height = _plane_axes(robot, float(q_fixed[0]))
    target = np.array([radius_m * math.cos(angle_rad), radius_m * math.sin(angle_rad)])
    q = np.array(q_fixed, dtype=float)

    def residual(x: np.ndarray) -> np.ndarray:
        q[1:3] = x
        p = robot.flange_pose(q)[:3, 3]
        return np.array([p @ reach, p @ up - height]) - target

    def jacobian(x: np.ndarray) -> np.ndarray:
        q[1:3] = x
        lin = robot.jacobian(q)[:3, 1:3]
        return np.vstack([reach @ lin, up @ lin])

    # Elbow up: shoulder in (-π, 0), elbow bent in (0, π) away from its straight singularity.
    lower, upper = [-math.pi, 0.05], [0.0, math.pi - 0.05]
    best = None
    for start in ([-math.pi / 2, math.pi / 2], [-math.pi / 4, 1.0], [-3 * math.pi / 4, 2.0]):
        res = optimize.least_squares(
            residual, start, jac=jacobian, bounds=(lower, upper), xtol=1e-14, ftol=1e-14
        )
        if best is None or res.cost < best.cost:
            best = res
    assert best is not None
    if np.max(np.abs(best.fun)) > IK_TOLERANCE_M:
        return None
    q[1:3] = best.x
    return q.copy()


@dataclass(frozen=True)
class CampaignPose:
    """One pose of the campaign.

    Attributes
    ----------
    key
        Unique, stable name (used to resume).
    payload_kg, payload_com_m
        Payload in this pose.
    angle_rad, radius_m
        Target ``(V, R)`` of the flange centre.
    wrist_joint
        The wrist joint that was turned at random.
    q
        Joint angles, rad, shape (6,); ``None`` if unreachable.
    seed
        Seed of this pose's random draws (wrist and excitations).
    """

    key: str
    payload_kg: float
    payload_com_m: tuple[float, float, float]
    angle_rad: float
    radius_m: float
    wrist_joint: int
    q: np.ndarray | None
    seed: int


def campaign_poses(
    robot_name: str = "ur5e",
    *,
    payloads_kg: Sequence[float] = PAPER_PAYLOADS_KG,
    payload_com_m: Sequence[float] = (0.0, 0.0, 0.05),
    angles_rad: Sequence[float] = PAPER_ANGLES_RAD,
    radii_m: Sequence[float] = PAPER_RADII_M,
    base_angle_rad: float = 0.0,
    seed: int = 0,
    max_wrist_draws: int = 50,
) -> list[CampaignPose]:
    """The poses of Algorithm 1 (208 for the defaults), payload by payload.

    For each pose a wrist joint and angle are drawn (from a generator seeded by ``seed`` and
    the pose index, so one pose does not depend on the others); if the point is out of reach
    with that wrist, another wrist is drawn, up to ``max_wrist_draws`` times, after which the
    pose is kept with ``q = None``.
    """
    com = tuple(float(v) for v in payload_com_m)
    if len(com) != 3:
        raise ValueError(f"payload_com_m must have 3 values, got {payload_com_m!r}")
    robot = Robot(params(robot_name))  # kinematics only: the payload does not matter here
    poses = []
    index = 0
    for payload in payloads_kg:
        for iv, angle in enumerate(angles_rad):
            for ir, radius in enumerate(radii_m):
                rng = np.random.default_rng([seed, index])
                q = None
                wrist = WRIST_JOINTS[0]
                for _ in range(max_wrist_draws):
                    wrist = int(rng.choice(WRIST_JOINTS))
                    q_fixed = np.array([base_angle_rad, 0.0, 0.0, *NOMINAL_WRIST_RAD])
                    q_fixed[wrist] = rng.uniform(-math.pi, math.pi)
                    q = solve_plane_ik(robot, angle, radius, q_fixed)
                    if q is not None:
                        break
                poses.append(
                    CampaignPose(
                        key=f"m{payload:g}kg-V{iv}-R{ir}",
                        payload_kg=float(payload),
                        payload_com_m=com,  # type: ignore[arg-type]
                        angle_rad=float(angle),
                        radius_m=float(radius),
                        wrist_joint=wrist,
                        q=q,
                        seed=int(rng.integers(2**31)),
                    )
                )
                index += 1
    return poses


# --------------------------------------------------------------------------- robots


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
    """

    def __init__(self, robot_name: str = "ur5e", accel_noise_std: float = 0.05, seed: int = 0):
        self.robot_name = robot_name
        self.accel_noise_std = float(accel_noise_std)
        self.seed = int(seed)
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


class URRobot:
    """A real UR e-Series arm through ur_rtde (``pip install ur-rtde``), imported lazily.

    Each excitation: ``moveJ`` to the start pose, start RTDE file recording at 500 Hz, stand
    still, run every bang-coast-bang move as ``moveJ(q, speed, acceleration)`` followed by the
    wait, stop recording and read the log back with :func:`read_rtde_csv`.

    Make sure the workspace is clear: the campaign moves the arm through the whole workspace
    and jerks the base and shoulder. Payload changes are manual: :meth:`set_payload` declares
    the payload to the controller and, if ``confirm`` is given, calls it to let the operator
    mount it first.

    Parameters
    ----------
    ip
        Robot address.
    robot_name
        Parameter-file name of the model (for the kinematics used in identification).
    log_dir
        Folder for the RTDE logs (kept for inspection); default a temporary folder.
    frequency_hz
        RTDE recording frequency (e-Series: 500 Hz).
    confirm
        Called with a message before each payload change (e.g. ``input``); None to skip.
    """

    def __init__(
        self,
        ip: str,
        robot_name: str = "ur5e",
        *,
        log_dir: str | Path | None = None,
        frequency_hz: float = 500.0,
        confirm: Callable[[str], Any] | None = input,
    ) -> None:
        try:
            import rtde_control
            import rtde_receive
        except ImportError as exc:  # pragma: no cover - needs the optional dependency
            raise ImportError(
                "a real robot needs ur_rtde: pip install 'tvist[robot]' (or ur-rtde)"
            ) from exc
        self.robot_name = robot_name
        self._control = rtde_control.RTDEControlInterface(ip)
        self._receive = rtde_receive.RTDEReceiveInterface(ip, frequency_hz)
        self._log_dir = Path(log_dir or tempfile.mkdtemp(prefix="tvist-campaign-"))
        self._log_dir.mkdir(parents=True, exist_ok=True)
        self._confirm = confirm
        self._count = 0

    def set_payload(self, payload_kg: float, payload_com_m: Sequence[float]) -> None:
        if self._confirm is not None:
            self._confirm(
                f"Mount a {payload_kg:g} kg payload (centre of mass {list(payload_com_m)} m in "
                "the flange frame), then press Enter"
            )
        self._control.setPayload(float(payload_kg), [float(v) for v in payload_com_m])

    def record_excitation(self, excitation: Excitation) -> Record:
        c = self._control
        c.moveJ(list(excitation.q0), 0.5, 0.5)
        # The receive connection may still be a few packages behind the control connection
        # that reported the move done: let it catch up so the log starts at rest.
        time.sleep(0.1)
        path = self._log_dir / f"excitation_{self._count:04d}_joint{excitation.joint}.csv"
        self._count += 1
        self._receive.startFileRecording(str(path), list(RECORDED_FIELDS))
        try:
            time.sleep(excitation.standstill_s)
            q = np.array(excitation.q0, dtype=float)
            for move in excitation.moves:
                q[excitation.joint] = move.q_to_rad
                c.moveJ(list(q), move.speed_rad_s, move.accel_rad_s2)
                time.sleep(move.wait_s)
        finally:
            self._receive.stopFileRecording()
        return read_rtde_csv(path, resample=True)

    def true_modes(self, q: np.ndarray) -> list[tuple[float, float]] | None:
        return None

    def urscript(self, excitation: Excitation) -> str:
        """The same excitation as a URScript program (to run from the pendant instead)."""
        return to_urscript(excitation)


# --------------------------------------------------------------------------- running


@dataclass
class _Settings:
    robot_name: str
    accel_noise_std: float
    noise_seed: int
    duration_s: float
    options: FitOptions = field(default_factory=FitOptions)
    separate_modes: bool = True


def identify_pose(robot: CampaignRobot, pose: CampaignPose, settings: _Settings) -> dict:
    """Excite and identify base and shoulder at one pose; the JSON-lines record of it."""
    record: dict[str, Any] = {
        "key": pose.key,
        "payload_kg": pose.payload_kg,
        "payload_com_m": list(pose.payload_com_m),
        "angle_rad": pose.angle_rad,
        "radius_m": pose.radius_m,
        "wrist_joint": pose.wrist_joint,
        "q": None if pose.q is None else [float(v) for v in pose.q],
        "modes": [],
        "error": None,
    }
    if pose.q is None:
        record["error"] = "unreachable"
        return record
    model = Robot(params(robot.robot_name), _Payload(pose.payload_kg, pose.payload_com_m))
    record["inertia_kg_m2"] = model.joint_inertia(pose.q).tolist()
    record["gravity_torque_nm"] = model.gravity_torque(pose.q).tolist()
    robot.set_payload(pose.payload_kg, pose.payload_com_m)
    rng = np.random.default_rng(pose.seed)
    fits: dict[int, LocalFit] = {}
    for joint in IDENTIFIED_JOINTS:
        # An integer seed per excitation (recorded in it) also seeds a twin's sensor noise.
        excitation = random_excitation(
            pose.q, joint, seed=int(rng.integers(2**63)), duration_s=settings.duration_s
        )
        try:
            log = robot.record_excitation(excitation)
            fits[joint] = identify_local(
                log,
                joint,
                model,
                options=settings.options,
                two_modes=settings.separate_modes and joint == 0,
            )
            record["modes"].append(fits[joint].to_dict())
        except (ValueError, RuntimeError) as exc:
            record["modes"].append({"joint": joint, "error": str(exc)})
    if settings.separate_modes and 0 in fits and 1 in fits:
        record["modes"][0] = _separated_base_mode(fits[0], fits[1], settings.options)
    truth = robot.true_modes(pose.q)
    if truth is not None:
        record["true_modes"] = [
            {"joint": j, "wn_rad_s": wn, "zeta": zeta}
            for j, (wn, zeta) in zip(IDENTIFIED_JOINTS, truth, strict=True)
        ]
    return record


def _separated_base_mode(base: LocalFit, shoulder: LocalFit, options: FitOptions) -> dict:
    """The base record, with the base mode separated from the shoulder mode where needed.

    The base excitation may ring the shoulder mode too (strongly where the base mode is
    heavily damped, the paper's Fig. 22 situation). From the two-mode fit of the base log:

    - if its dominant component (largest share of the response) is not at the shoulder
      frequency identified from the shoulder excitation (within :data:`SAME_MODE_RATIO`),
      it is the base mode (the single-mode fit if the other component is no real mode);
    - if the dominant component is at the shoulder frequency, the base mode is the other
      component when that one is significant and well determined; with less than
      :data:`CLEAR_SHARE` of the response it is flagged low-confidence (it is still the best
      estimate of the base mode: the single-mode value would be the shoulder mode's);
    - otherwise the base and shoulder modes cannot be told apart (hidden or coincident
      modes): the single-mode fit is kept, flagged.

    The single-mode result is kept under ``apparent`` whenever it is replaced.
    """
    entry = base.to_dict()
    entry["method"] = "single-mode"
    split = base.two_mode
    if split is None or shoulder.low_confidence:
        return entry
    limit = math.log(SAME_MODE_RATIO)

    def shoulder_like(m: ModeEstimate) -> bool:
        return abs(math.log(m.wn_rad_s / shoulder.wn_rad_s)) < limit

    dominant, other = sorted(split.modes, key=lambda m: -m.energy_share)
    reasons = [r for r in base.reasons if not r.startswith(("uncertain", "overdamped"))]
    if not shoulder_like(dominant):
        # Even a weak second mode biases the single-mode fit, so the two-mode value is used
        # unless the second component is no mode at all (overdamped or unresolved).
        if other.zeta >= 0.9 or not other.wn_se_rad_s < 0.5 * other.wn_rad_s:
            return entry
        chosen = dominant
    elif split.significant and other.wn_se_rad_s <= options.max_wn_rel_se * 5 * other.wn_rad_s:
        chosen = other
        if other.energy_share < CLEAR_SHARE:
            reasons.append(
                f"base mode weak next to the shoulder mode ({100 * other.energy_share:.0f} % "
                "of the response)"
            )
    else:
        entry.update(
            low_confidence=True,
            reasons=[
                *base.reasons,
                "base excitation rings at the shoulder frequency: the base mode is hidden "
                "behind (or coincides with) the shoulder mode",
            ],
        )
        return entry
    if chosen.wn_se_rad_s > options.max_wn_rel_se * chosen.wn_rad_s:
        reasons.append(
            f"uncertain frequency: standard error {100 * chosen.wn_se_rad_s / chosen.wn_rad_s:.2f}"
            " % of ω_n (two-mode fit)"
        )
    entry.update(
        wn_rad_s=chosen.wn_rad_s,
        zeta=chosen.zeta,
        wn_se_rad_s=chosen.wn_se_rad_s,
        zeta_se=chosen.zeta_se,
        k_a=None,
        k_b=None,
        k_c=2.0 * chosen.zeta * chosen.wn_rad_s,
        k_d=chosen.wn_rad_s**2,
        method="two-mode",
        apparent={"wn_rad_s": base.wn_rad_s, "zeta": base.zeta},
        reasons=reasons,
        low_confidence=bool(reasons),
    )
    return entry


#: Modes closer than this frequency ratio are taken for the same mode (twice the 1 % accuracy
#: of a local fit, plus margin).
SAME_MODE_RATIO = 1.03
#: A base component with less than this share of the response is flagged low-confidence.
CLEAR_SHARE = 0.3


#: One twin per worker process and payload (building a MuJoCo model takes a while).
_WORKER_ROBOT: TwinRobot | None = None


def _twin_worker(pose: CampaignPose, settings: _Settings) -> dict:
    global _WORKER_ROBOT
    if _WORKER_ROBOT is None:
        _WORKER_ROBOT = TwinRobot(
            settings.robot_name, settings.accel_noise_std, seed=settings.noise_seed
        )
    return identify_pose(_WORKER_ROBOT, pose, settings)


def load_results(path: str | Path) -> list[dict]:
    """Pose records of a campaign results file (JSON lines); a torn last line is ignored."""
    path = Path(path)
    if not path.exists():
        return []
    out = []
    lines = path.read_text(encoding="utf-8").splitlines()
    for i, line in enumerate(lines):
        if not line.strip():
            continue
        try:
            out.append(json.loads(line))
        except json.JSONDecodeError:
            if i == len(lines) - 1:  # interrupted while writing: that pose reruns
                continue
            raise ValueError(f"{path}: line {i + 1} is not valid JSON") from None
    return out


def _append(path: Path, record: dict) -> None:
    with path.open("a", encoding="utf-8") as fh:
        fh.write(json.dumps(record) + "\n")
        fh.flush()
        os.fsync(fh.fileno())


def _repair_tail(path: Path) -> None:
    """Drop a torn last line so appended records start on a fresh line."""
    if not path.exists():
        return
    text = path.read_text(encoding="utf-8")
    if text and not text.endswith("\n"):
        path.write_text(text[: text.rfind("\n") + 1], encoding="utf-8")


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
) -> list[dict]:
    """Run (or resume) a campaign and return every pose record in ``results_path``.

    Parameters
    ----------
    poses
        From :func:`campaign_poses` (or a subset).
    results_path
        JSON-lines file; poses already in it are skipped, new ones are appended as they
        finish.
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
    """
    path = Path(results_path)
    path.parent.mkdir(parents=True, exist_ok=True)
    _repair_tail(path)
    done = {r["key"] for r in load_results(path)}
    todo = [p for p in poses if p.key not in done]
    settings = _Settings(
        robot_name=robot_name if robot is None else robot.robot_name,
        accel_noise_std=accel_noise_std,
        noise_seed=noise_seed,
        duration_s=duration_s,
        options=options or FitOptions(),
        separate_modes=separate_modes,
    )
    bar = _Progress(len(todo), len(done)) if progress and todo else None
    try:
        if robot is not None or workers <= 1:
            runner = robot or TwinRobot(robot_name, accel_noise_std, seed=noise_seed)
            # Payload by payload keeps manual payload changes on a real robot to a minimum.
            for pose in sorted(todo, key=lambda p: p.payload_kg):
                _append(path, identify_pose(runner, pose, settings))
                if bar is not None:
                    bar.advance(pose.key)
        else:
            with ProcessPoolExecutor(max_workers=workers) as pool:
                futures = {pool.submit(_twin_worker, p, settings): p for p in todo}
                for future in as_completed(futures):
                    _append(path, future.result())
                    if bar is not None:
                        bar.advance(futures[future].key)
    finally:
        if bar is not None:
            bar.close()
    return load_results(path)


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
