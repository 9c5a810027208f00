"""Poses of a mapping campaign (paper Algorithm 1).

The flange centre is placed at angle ``V`` (seen from the shoulder axis, in the arm's vertical
plane: 0 = horizontal outwards, π/2 = straight up) and distance ``R`` from the shoulder axis,
for ``V ∈ {0, π/4, π/2, 3π/4}`` and 13 values ``R = 0.4 … 0.9`` m, for every payload. In each
pose one wrist joint (3, 4 or 5), chosen at random, is turned to a random angle; the shoulder
and elbow are then solved (elbow up) by numerical inverse kinematics with the robot model's
flange position and Jacobian.

A plan (:func:`plan_poses`) is every ``every``-th of these poses, plus the poses that extend
its range of joint-axis inertias over the whole workspace (:func:`workspace_poses`) and over
the poses the user gives (:func:`user_poses`), added until every one of those lies within
the plan's range (:func:`covering_poses`; a map is identified only over the inertias of its
poses, :mod:`tvist.maps.paper10`), and the poses where the user's moves stop
(:func:`user_poses`), each identified whether or not it extends the range, in the order that
changes the payload least
(:func:`campaign_order`); :func:`plan_shortfall` says why the map fit could not succeed on it,
before anything moves. Each pose's excitations (:func:`pose_excitations`, of the base, the
shoulder and the robot's elbow by default, :func:`~tvist.ident.excited.default_excited_joints`)
follow from its seed.

Algorithm 1's plane and its inverse kinematics are written for a DH arm whose elbow follows
the shoulder (UR). An arm placed as its URDF places it (FR3, iiwa14, ...) has no such plane:
its plan is drawn from its workspace (:func:`workspace_ranges`: every joint within its limits,
flange above the mounting plane), ``ceil(52 / every)`` random poses per payload (keys
``m{payload}kg-R{i}``, as many as Algorithm 1's every-``every``-th), plus the same coverage of
the extreme inertias.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from scipy import optimize

from tvist.ident.excitation import Excitation, random_excitation
from tvist.ident.excited import excited_joints
from tvist.robots import Payload, Robot, params

__all__ = [
    "PAPER_ANGLES_RAD",
    "PAPER_PAYLOADS_KG",
    "PAPER_RADII_M",
    "USER_POSE_ROLES",
    "CampaignPose",
    "campaign_order",
    "campaign_poses",
    "check_user_poses",
    "covered_joints",
    "covering_poses",
    "plan_poses",
    "plan_shortfall",
    "plane_coordinates",
    "pose_excitations",
    "solve_plane_ik",
    "user_poses",
    "workspace_extremes",
    "workspace_poses",
    "workspace_ranges",
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
#: ``wrist_joint`` of a pose the user gave (no wrist joint was turned at random).
GIVEN_POSE = -1
#: The flange must land within this distance of the target, m.
IK_TOLERANCE_M = 1e-6


def covered_joints(robot_name: str) -> tuple[int, ...]:
    """Joints whose axis inertia ``J_j`` (diagonal of the mass matrix) a plan covers: the base
    and the shoulder, which a paper10 map reads (and holds at the bound of its identified
    range outside it), and the robot's elbow
    (:attr:`~tvist.robots.RobotParams.elbow_joint`), whose stiffness a modal map fits. A UR:
    ``(0, 1, 2)``; an FR3 or iiwa14: ``(0, 1, 3)``."""
    elbow = params(robot_name).elbow_joint
    return (0, 1) if elbow is None else (0, 1, elbow)


#: The workspace (:func:`workspace_poses`): shoulder from one horizontal to the other (upper
#: arm at or above the shoulder), elbow from stretched to the demo's folded pose Q3 (150°),
#: wrists anywhere, flange above the mounting plane.
WORKSPACE_SHOULDER_RAD = (-math.pi, 0.0)
WORKSPACE_ELBOW_RAD = (0.0, 5 * math.pi / 6)
#: Random workspace poses from which the default plan's extreme poses are refined.
WORKSPACE_SAMPLES = 2000
#: Streams of the random draws of :func:`workspace_poses` and of the seeds of the plan's
#: workspace poses, apart from the campaign poses' (``[seed, index]``) and the user's
#: (``[seed, 1_000_000 + row]``).
WORKSPACE_STREAM = 2_000_000
_COVERING_STREAM = 3_000_000
#: Stream of the random plan poses of a URDF-placed arm (the pose seeds: ``[seed, row]``).
_RANDOM_PLAN_STREAM = 5_000_000
#: The roles of the user's poses in a plan (:func:`user_poses`): key letter and seed stream
#: (``[seed, stream + row]``).
USER_POSE_ROLES = {"cover": ("C", 1_000_000), "at": ("A", 7_000_000)}
#: A pose whose inertias lie less than this (relative) outside the plan's range counts as
#: covered: angles written with 6 decimals move an inertia by ~1e-8, and a paper10 map's soft
#: clamp bends the inertia it reads by up to 0.9 % near a bound anyway (:mod:`tvist.maps.paper10`).
COVER_TOLERANCE = 1e-3

# --------------------------------------------------------------------------- poses


def _plane_axes(robot: Robot, base_angle_rad: float) -> tuple[np.ndarray, np.ndarray, float]:
    """Outward horizontal unit vector of the arm plane, up vector, shoulder-axis height (m)."""
    # With q = 0 the arm is stretched along -x of the base (UR convention, a_2 < 0).
    reach = np.array([math.cos(base_angle_rad), math.sin(base_angle_rad), 0.0])
    if robot.params.a_m[1] < 0:
        reach = -reach
    return reach, np.array([0.0, 0.0, 1.0]), float(robot.params.d_m[0])


def _shoulder_height_m(placed) -> float:
    """Height (m) of the shoulder (joint 2's origin) above the base of a URDF-placed arm at
    ``q = 0``: joint 1's origin, then joint 2's in link 1's frame."""
    from tvist.robots.rpy import rpy_matrix

    first = rpy_matrix(placed.origin_rpy_rad[0])
    return float((placed.origin_xyz_m[0] + first @ placed.origin_xyz_m[1])[2])


def plane_coordinates(robot: Robot, q: np.ndarray) -> tuple[float, float]:
    """``(V, R)``: angle (rad) and distance (m) of the flange centre from the shoulder axis.

    For a URDF-placed arm, the angle in the vertical plane through the base axis and the
    flange, seen from the shoulder (joint 2's origin), outwards positive."""
    p = robot.flange_pose(q)[:3, 3]
    placed = robot.params.placements
    if placed is not None:
        x, z = math.hypot(p[0], p[1]), float(p[2]) - _shoulder_height_m(placed)
        return math.atan2(z, x), math.hypot(x, z)
    reach, up, height = _plane_axes(robot, float(q[0]))
    x, z = float(p @ reach), float(p @ up - height)
    return math.atan2(z, x), math.hypot(x, z)


def workspace_ranges(robot: Robot) -> np.ndarray:
    """The joint ranges ``(n_dof, 2)`` (rad) of the campaign's workspace: for a DH arm (UR),
    shoulder :data:`WORKSPACE_SHOULDER_RAD`, elbow :data:`WORKSPACE_ELBOW_RAD`, wrists
    ``[-π, π]``; for a URDF-placed arm its joint limits (its maker's limits already keep the
    links apart) narrowed by Algorithm 2's excursion :data:`~tvist.ident.excitation.MAX_DELTA_RAD`
    at each end, so that an excitation stays within them. The base row is not drawn (it stays
    at the plan's base angle)."""
    if robot.params.placements is not None:
        from tvist.ident.excitation import MAX_DELTA_RAD

        margin = np.array([MAX_DELTA_RAD, -MAX_DELTA_RAD])
        return np.array(robot.params.joint_limits_rad, dtype=float) + margin
    ranges = np.tile([-math.pi, math.pi], (robot.n_dof, 1))
    ranges[1], ranges[2] = WORKSPACE_SHOULDER_RAD, WORKSPACE_ELBOW_RAD
    return ranges


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
    if robot.params.placements is not None:
        raise ValueError(
            f"{robot_name}: Algorithm 1's plane poses need a DH arm; plan a URDF-placed arm "
            "from its workspace (plan_poses)"
        )
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


# --------------------------------------------------------------------------- plans


def user_poses(
    robot_name: str,
    q_rows: np.ndarray,
    role: str,
    *,
    payloads_kg: Sequence[float] = PAPER_PAYLOADS_KG,
    payload_com_m: Sequence[float] = (0.0, 0.0, 0.05),
    seed: int = 0,
) -> list[CampaignPose]:
    """The user's poses ``q_rows`` ``(n, n_dof)`` (rad), each with every payload, in their
    ``role`` in a plan (:data:`USER_POSE_ROLES`): ``"cover"``, poses the moves pass through,
    of which a plan takes those that extend its range (keys ``m{payload}kg-C{row}``);
    ``"at"``, poses where the moves stop, every one identified (keys ``m{payload}kg-A{row}``):
    what rings after a stop is the arm's modes at that pose, and a map identified there is
    measured, not interpolated, where it matters most.

    Raises
    ------
    ValueError
        An unknown ``role``, or a row that is not a pose of the robot in rad
        (:func:`check_user_poses`).
    """
    if role not in USER_POSE_ROLES:
        raise ValueError(f"role {role!r}: give one of {', '.join(USER_POSE_ROLES)}")
    key, stream = USER_POSE_ROLES[role]
    q_rows = check_user_poses(robot_name, q_rows)
    return _given_poses(robot_name, q_rows, payloads_kg, payload_com_m, seed, key, stream)


def check_user_poses(robot_name: str, q_rows: np.ndarray) -> np.ndarray:
    """``q_rows`` as an ``(n, n_dof)`` float array of poses of the robot, rad.

    Raises
    ------
    ValueError
        A row that is not ``n_dof`` finite joint angles, looks like degrees or leaves the
        robot's joint limits (naming the row; :func:`tvist.units.check_trajectory`).
    """
    from tvist.units import check_trajectory

    q_rows = np.asarray(q_rows, dtype=float)
    robot = Robot(params(robot_name))
    if q_rows.ndim != 2 or q_rows.shape[1] != robot.n_dof:
        raise ValueError(f"poses must have {robot.n_dof} joint angles per row (rad)")
    for i, q in enumerate(q_rows):
        if not np.all(np.isfinite(q)):
            raise ValueError(f"pose row {i + 1}: not {robot.n_dof} finite joint angles")
    check_trajectory(
        q_rows, None, robot.params, row_label=lambda i: f"row {i + 1}", what="the poses"
    )
    return q_rows


def _given_poses(
    robot_name: str,
    q_rows: np.ndarray,
    payloads_kg: Sequence[float],
    payload_com_m: Sequence[float],
    seed: int,
    key: str,
    stream: int,
) -> list[CampaignPose]:
    """Poses ``q_rows`` with every payload, keys ``m{payload}kg-{key}{row}``, each seeded
    from ``[seed, stream + row]``."""
    robot = Robot(params(robot_name))
    com = tuple(float(v) for v in payload_com_m)
    poses = []
    for payload in payloads_kg:
        for i, q in enumerate(q_rows):
            angle, radius = plane_coordinates(robot, q)
            rng = np.random.default_rng([seed, stream + i])
            poses.append(
                CampaignPose(
                    key=f"m{payload:g}kg-{key}{i}",
                    payload_kg=float(payload),
                    payload_com_m=com,  # type: ignore[arg-type]
                    angle_rad=angle,
                    radius_m=radius,
                    wrist_joint=GIVEN_POSE,
                    q=np.array(q, dtype=float),
                    seed=int(rng.integers(2**31)),
                )
            )
    return poses


def workspace_poses(
    robot_name: str,
    n: int,
    *,
    seed: int = 0,
    stream: int = WORKSPACE_STREAM,
    corners: bool = False,
    base_angle_rad: float = 0.0,
) -> np.ndarray:
    """``n`` random poses ``(n, 6)`` (rad) of the workspace, drawn from ``[seed, stream]``
    (another ``stream`` draws other poses, e.g. to evaluate a map away from the plan's).

    The workspace: shoulder in :data:`WORKSPACE_SHOULDER_RAD`, elbow in
    :data:`WORKSPACE_ELBOW_RAD`, each wrist joint uniform in ``[-π, π]``, uniformly, kept where
    the flange is above the mounting plane (``z > 0`` in the base frame). The base stays at
    ``base_angle_rad``: no mode of the arm depends on it (it turns the arm about the vertical).
    With ``corners`` the workspace's corners come first (``n`` more rows): shoulder at both
    horizontals and upright, elbow stretched and folded, wrists at
    :data:`NOMINAL_WRIST_RAD` -- where the base inertia is largest (stretched out) and
    smallest (stretched up), which random draws approach only slowly.
    """
    if n < 0:
        raise ValueError(f"n must be >= 0, got {n}")
    robot = Robot(params(robot_name))
    ranges = workspace_ranges(robot)
    rows = []
    if corners and robot.params.placements is None:
        for shoulder in (WORKSPACE_SHOULDER_RAD[0], -math.pi / 2, WORKSPACE_SHOULDER_RAD[1]):
            for elbow in WORKSPACE_ELBOW_RAD:
                rows.append([base_angle_rad, shoulder, elbow, *NOMINAL_WRIST_RAD])
        rows = [q for q in rows if robot.flange_pose(np.array(q))[2, 3] > 0.0]
    rng = np.random.default_rng([seed, stream])
    drawn = 0
    while drawn < n:
        batch = max(2 * (n - drawn), 16)
        q = rng.uniform(ranges[1:, 0], ranges[1:, 1], size=(batch, robot.n_dof - 1))
        q = np.hstack([np.full((batch, 1), base_angle_rad), q])
        above = robot.flange_pose_many(q)[:, 2, 3] > 0.0
        for row in q[above][: n - drawn]:
            rows.append(row)
            drawn += 1
    return np.array(rows, dtype=float).reshape(-1, robot.n_dof)


def workspace_extremes(
    robot_name: str,
    payload_kg: float,
    payload_com_m: Sequence[float],
    *,
    joints: Sequence[int] | None = None,
    samples: int = WORKSPACE_SAMPLES,
    seed: int = 0,
) -> np.ndarray:
    """The workspace poses ``(2 len(joints), 6)`` (rad) of the smallest and the largest
    inertia ``J_j`` of each joint in ``joints`` (default :func:`covered_joints`) with the
    payload: the best of ``samples``
    random poses and the corners (:func:`workspace_poses`), refined by a bounded local search
    within the workspace (a refinement that leaves it, flange below the mounting plane, is
    not taken)."""
    robot = Robot(params(robot_name), Payload(payload_kg, tuple(payload_com_m)))
    joints = covered_joints(robot_name) if joints is None else joints
    q = workspace_poses(robot_name, samples, seed=seed, corners=True)
    inertia = robot.joint_inertia_many(q)
    bounds = [tuple(row) for row in workspace_ranges(robot)[1:]]
    out = []
    for joint in joints:
        for sign in (1.0, -1.0):  # smallest, then largest
            start = q[int(np.argmin(sign * inertia[:, joint]))]

            def objective(x: np.ndarray, start=start, joint=joint, sign=sign) -> float:
                pose = np.concatenate([start[:1], x])
                return sign * float(robot.joint_inertia(pose)[joint])

            res = optimize.minimize(objective, start[1:], method="L-BFGS-B", bounds=bounds)
            best = np.concatenate([start[:1], res.x])
            better = res.fun < objective(start[1:])
            out.append(best if better and robot.flange_pose(best)[2, 3] > 0.0 else start)
    return np.array(out)


def covering_poses(
    robot_name: str,
    plan: Sequence[CampaignPose],
    candidates: Sequence[CampaignPose],
    joints: Sequence[int] | None = None,
) -> list[CampaignPose]:
    """The ``candidates`` to add to ``plan`` so that, payload by payload, the inertias
    ``J_j`` (``j`` in ``joints``, default :func:`covered_joints`) of every candidate lie
    within the range of the plan's.

    Greedy: while a candidate lies outside (by more than :data:`COVER_TOLERANCE`), the one
    farthest outside (largest ``|log(J / bound)|`` over the joints) is added, which widens
    the range; so at most two poses per joint and payload are added, the poses at the
    extremes. A candidate's payload
    is its own (candidates of a payload the plan lacks start that payload's range).
    Unreachable poses (``q = None``) neither count nor are added.
    """
    joints = list(covered_joints(robot_name) if joints is None else joints)
    added: list[CampaignPose] = []
    groups: dict[tuple, list[CampaignPose]] = {}
    for pose in candidates:
        if pose.q is not None:
            groups.setdefault((pose.payload_kg, tuple(pose.payload_com_m)), []).append(pose)
    for (mass, com), group in groups.items():
        robot = Robot(params(robot_name), Payload(mass, com))
        inertia = robot.joint_inertia_many(np.array([p.q for p in group]))[:, joints]
        covered = [
            p.q
            for p in plan
            if p.q is not None and (p.payload_kg, tuple(p.payload_com_m)) == (mass, com)
        ]
        if covered:
            have = robot.joint_inertia_many(np.array(covered))[:, joints]
            lo, hi = have.min(axis=0), have.max(axis=0)
        else:  # an empty range: every candidate lies outside it
            lo, hi = np.full(len(joints), np.inf), np.full(len(joints), -np.inf)
        while True:
            with np.errstate(divide="ignore", invalid="ignore"):
                outside = np.maximum(np.log(lo / inertia), np.log(inertia / hi))
            outside = np.max(np.maximum(np.nan_to_num(outside, nan=np.inf), 0.0), axis=1)
            worst = int(np.argmax(outside))
            if outside[worst] <= COVER_TOLERANCE:
                break
            added.append(group[worst])
            lo, hi = np.minimum(lo, inertia[worst]), np.maximum(hi, inertia[worst])
    return added


def campaign_order(poses: Sequence[CampaignPose]) -> list[CampaignPose]:
    """``poses`` payload by payload (lightest first, otherwise in their order): one payload
    change per payload, the fewest a person has to make."""
    return sorted(poses, key=lambda p: p.payload_kg)


def plan_poses(
    robot_name: str = "ur5e",
    *,
    payloads_kg: Sequence[float] = PAPER_PAYLOADS_KG,
    payload_com_m: Sequence[float] = (0.0, 0.0, 0.05),
    every: int = 1,
    seed: int = 0,
    cover_q: np.ndarray | None = None,
    cover_workspace: bool = True,
    workspace_samples: int = WORKSPACE_SAMPLES,
    at_q: np.ndarray | None = None,
) -> list[CampaignPose]:
    """A campaign plan, in :func:`campaign_order`.

    Every ``every``-th pose of :func:`campaign_poses` and, with them, the workspace poses of
    the smallest and largest inertias of :func:`covered_joints` (:func:`workspace_extremes`
    from ``workspace_samples`` random poses, keys ``m{payload}kg-W{i}``) that extend the
    plan's range over the whole workspace (:func:`covering_poses`; not with
    ``cover_workspace=False``); ``every = 0`` takes none of these. Then every ``at_q``
    pose, where the user's moves stop (:func:`user_poses`, keys ``m{payload}kg-A{row}``), and
    the user's ``cover_q`` poses (:func:`user_poses`, keys ``m{payload}kg-C{row}``) that
    extend the range over theirs: afterwards the inertias of every workspace pose and every
    ``cover_q`` pose lie within the plan's, payload by payload.

    Raises
    ------
    ValueError
        ``every < 0``, or an ``at_q`` or ``cover_q`` row that is not a pose of the robot in
        rad (:func:`check_user_poses`).
    """
    if every < 0:
        raise ValueError(f"every must be >= 0, got {every}")
    poses: list[CampaignPose] = []
    if every > 0:
        if params(robot_name).placements is None:
            poses = campaign_poses(
                robot_name, payloads_kg=payloads_kg, payload_com_m=payload_com_m, seed=seed
            )[::every]
        else:
            per_payload = math.ceil(len(PAPER_ANGLES_RAD) * len(PAPER_RADII_M) / every)
            drawn = workspace_poses(robot_name, per_payload, seed=seed, stream=_RANDOM_PLAN_STREAM)
            poses = _given_poses(robot_name, drawn, payloads_kg, payload_com_m, seed, "R", 0)
        workspace = []
        for payload in payloads_kg if cover_workspace else ():
            extremes = workspace_extremes(
                robot_name, payload, payload_com_m, samples=workspace_samples, seed=seed
            )
            workspace += _given_poses(
                robot_name,
                extremes,
                [payload],
                payload_com_m,
                seed=seed,
                key="W",
                stream=_COVERING_STREAM,
            )
        poses += covering_poses(robot_name, poses, workspace)
    given = {"payloads_kg": payloads_kg, "payload_com_m": payload_com_m, "seed": seed}
    if at_q is not None:
        poses += user_poses(robot_name, at_q, "at", **given)
    if cover_q is not None:
        cover = user_poses(robot_name, cover_q, "cover", **given)
        poses += covering_poses(robot_name, poses, cover)
    return campaign_order(poses)


def plan_shortfall(poses: Sequence[CampaignPose]) -> str | None:
    """Why the map fit (:func:`tvist.ident.map_fit.fit_map`) cannot succeed on ``poses``,
    or ``None`` if it can (if every identification succeeds).

    The fit needs :func:`~tvist.ident.map_fit.poses_needed` usable poses per mode, and the
    poses must differ in radius or payload: the shoulder's inertia is set by those two, so
    poses at one radius with one payload cannot tell the map's stiffness terms apart.
    """
    from tvist.ident.map_fit import poses_needed

    reachable = [p for p in poses if p.q is not None]
    needed = poses_needed()
    if len(reachable) < needed:
        return f"{len(reachable)} reachable poses, the map fit needs at least {needed} per mode"
    loads = {(p.payload_kg, round(p.radius_m, 3)) for p in reachable}
    if len(loads) < 2:
        return (
            f"every pose is {reachable[0].radius_m:.3f} m from the shoulder axis with "
            f"{reachable[0].payload_kg:g} kg: the map fit needs poses at two radii or "
            "payloads at least"
        )
    return None


#: Draws from a pose's seed: one excitation seed per joint 0, 1, ..., so a joint's excitation
#: does not depend on which other joints are excited (joints 0 and 1 keep the seeds of the
#: campaigns that excited only them).
_SEED_DRAWS = 6


def pose_excitations(
    pose: CampaignPose,
    duration_s: float = 8.0,
    joints: Sequence[int] | None = None,
    *,
    robot_name: str = "ur5e",
) -> list[Excitation]:
    """The excitations of ``joints`` (default: the base, shoulder and elbow of
    ``robot_name``, :func:`~tvist.ident.excited.default_excited_joints`; checked with
    :func:`~tvist.ident.excited.excited_joints`) at ``pose`` (Algorithm 2),
    lowest joint first, each ``duration_s`` (s) long, sampled at the robot's control period;
    each with an integer seed drawn from the pose's seed (which also seeds a twin's sensor
    noise): joint ``j`` takes the ``j``-th draw, whichever joints are excited."""
    joints = excited_joints(joints, robot_name)
    dt_s = params(robot_name).sample_period_s()
    if pose.q is None:
        raise ValueError(f"pose {pose.key} is unreachable")
    rng = np.random.default_rng(pose.seed)
    seeds = [int(rng.integers(2**63)) for _ in range(_SEED_DRAWS)]
    return [
        random_excitation(pose.q, joint, seed=seeds[joint], duration_s=duration_s, dt_s=dt_s)
        for joint in joints
    ]
