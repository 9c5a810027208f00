"""``tvist plan``: a campaign plan for one's own robot (poses, excitation programs, time),
and the plan options ``tvist campaign`` shares with it."""

from __future__ import annotations

import argparse
import math

import numpy as np

from tvist.cli.args import DEFAULT_PAYLOAD_COM_M, existing_file
from tvist.ident.excited import excited_joints

__all__ = [
    "add_plan_command",
    "add_plan_options",
    "checked_plan",
    "coverage_text",
    "excited_from_args",
]


def add_plan_options(p: argparse.ArgumentParser) -> None:
    """``--robot``, ``--payloads``, ``--payload-com``, ``--every``, ``--seed``, ``--cover``,
    ``--at``, ``--no-workspace-cover``, ``--duration``, ``--excite``: which poses and excitations a
    campaign runs."""
    p.add_argument("--robot", default="ur5e", help="robot model (default ur5e)")
    p.add_argument(
        "--payloads",
        type=float,
        nargs="+",
        default=[0.0, 1.0, 3.0, 5.0],
        help="payloads, kg (default 0 1 3 5)",
    )
    p.add_argument(
        "--payload-com",
        type=float,
        nargs=3,
        default=DEFAULT_PAYLOAD_COM_M,
        metavar=("X", "Y", "Z"),
        help="payload centre of mass in the flange frame, m (default 0 0 0.05)",
    )
    p.add_argument(
        "--every",
        type=int,
        default=1,
        help="keep every N-th of Algorithm 1's poses (52 per payload, counted over all "
        "payloads), plus the poses that cover the inertias of the workspace (0: none of "
        "these, only the --at poses and poses covering the --cover poses; default 1)",
    )
    p.add_argument(
        "--seed", type=int, default=0, help="seed of wrists, excitations, noise (default 0)"
    )
    p.add_argument(
        "--cover",
        metavar="POSES.csv",
        help="poses your moves will pass through (a CSV: 6 comma-separated joint angles, rad, "
        "per row; header optional): the plan adds poses until their inertias lie within the "
        "plan's, with every payload",
    )
    p.add_argument(
        "--at",
        metavar="POSES.csv",
        help="poses where your moves stop (a CSV like --cover's): each is identified too, "
        "with every payload, so the map is measured where what it shapes rings",
    )
    p.add_argument(
        "--no-workspace-cover",
        action="store_true",
        help="do not add the poses that cover the workspace's inertias (a few poses only: "
        "a map of them is held at the bounds of their range elsewhere)",
    )
    p.add_argument(
        "--duration", type=float, default=8.0, help="excitation length per joint, s (default 8)"
    )
    p.add_argument(
        "--excite",
        default=None,
        metavar="JOINTS",
        help="joints excited at every pose, comma-separated: 0 base and 1 shoulder (always), "
        "on a UR 2 elbow, 3 wrist 1 (default: base, shoulder and the robot's elbow, 0,1,2 on "
        "a UR, 0,1,3 on an FR3 or iiwa14: the elbow log rings the elbow-dominated mode for "
        "the modal fit)",
    )


def excited_from_args(args: argparse.Namespace) -> tuple[int, ...]:
    """The joints of ``--excite`` (:func:`tvist.ident.excited.excited_joints`); without it,
    the default of ``--robot`` (:func:`tvist.ident.excited.default_excited_joints`).

    Raises
    ------
    ValueError
        Not comma-separated joint numbers, or joints a campaign cannot excite; one line
        naming the value (an unknown ``--robot``: naming that).
    """
    try:
        default = excited_joints(None, args.robot)
    except ValueError as exc:
        raise ValueError(f"--robot {args.robot}: {exc}") from None
    if args.excite is None:
        return default
    cells = [c.strip() for c in str(args.excite).split(",")]
    try:
        return excited_joints([int(c) for c in cells])
    except ValueError as exc:
        detail = str(exc) if all(_is_int(c) for c in cells) else "not joint numbers"
        example = ",".join(str(j) for j in default)
        raise ValueError(f"--excite {args.excite}: {detail} (e.g. --excite {example})") from None


def _is_int(text: str) -> bool:
    try:
        int(text)
    except ValueError:
        return False
    return True


def checked_plan(args: argparse.Namespace, require_fittable: bool = True) -> list:
    """The poses of the plan options, payload by payload.

    Raises
    ------
    ValueError
        ``--every`` below 1, a bad ``--cover`` or ``--at`` file, or (with
        ``require_fittable``) a plan the map fit cannot succeed on, with the reason and the
        flags that change it.
    """
    from tvist.ident.pose_plan import plan_poses, plan_shortfall

    if args.every < 0 or (args.every == 0 and not (args.cover or args.at)):
        raise ValueError(f"--every {args.every}: give 1 or more (0 only with --cover or --at)")
    if not (math.isfinite(args.duration) and args.duration > 0):
        raise ValueError(f"--duration {args.duration}: give a length > 0 s")
    cover_q = _read_poses(args.cover, "--cover", args.robot) if args.cover else None
    at_q = _read_poses(args.at, "--at", args.robot) if args.at else None
    poses = plan_poses(
        args.robot,
        payloads_kg=args.payloads,
        payload_com_m=args.payload_com,
        every=args.every,
        seed=args.seed,
        cover_q=cover_q,
        cover_workspace=not args.no_workspace_cover,
        at_q=at_q,
    )
    shortfall = plan_shortfall(poses) if require_fittable else None
    if shortfall:
        raise ValueError(
            f"this plan cannot give a map: {shortfall} (lower --every, or add poses with "
            "--cover or --at or payloads with --payloads)"
        )
    return poses


def coverage_text(poses: list, args: argparse.Namespace) -> str:
    """What the plan added to cover inertias: workspace poses, ``--at`` and ``--cover``
    poses (counted by their keys' role letters, :data:`~tvist.ident.pose_plan.USER_POSE_ROLES`)."""
    from tvist.ident.pose_plan import USER_POSE_ROLES, covered_joints

    def count(role: str) -> int:
        return sum(f"-{USER_POSE_ROLES[role][0]}" in p.key for p in poses)

    joints = ", ".join(f"J_{j}" for j in covered_joints(args.robot))
    if args.no_workspace_cover or args.every == 0:
        text = f"the workspace's {joints} not covered (--no-workspace-cover or --every 0)"
    else:
        workspace = sum("-W" in p.key for p in poses)
        text = f"{workspace} poses added so that {joints} cover the workspace's"
    if args.at:
        text += f"; {count('at')} poses at the --at poses"
    if args.cover:
        text += f"; {count('cover')} of the --cover poses (the others lie within the plan's range)"
    return text


def _read_poses(path: str, flag: str, robot_name: str) -> np.ndarray:
    """The poses file of ``flag`` (``--cover``, ``--at``): one pose per row, the robot's
    joint angles in rad, comma-separated, an optional header line (a first line that does not
    start with a number). Refused on one line naming the flag, the file and the row: a value
    that is not a number, a row of another length, angles that are not a pose of the robot
    in rad (:func:`tvist.ident.pose_plan.check_user_poses`)."""
    from tvist.ident.pose_plan import check_user_poses
    from tvist.robots import params

    n_dof = params(robot_name).n_dof
    lines = existing_file(path, flag).read_text(errors="replace").splitlines()
    rows = [(n, line) for n, line in enumerate(lines, start=1) if line.strip()]
    if rows and rows[0][1].lstrip()[:1] not in "0123456789+-.":
        rows = rows[1:]  # a header
    if not rows:
        raise ValueError(f"{flag} {path}: no poses (one pose per row: {n_dof} joint angles, rad)")
    q = []
    for n, line in rows:
        cells = [c.strip() for c in line.split(",")]
        try:
            q.append([float(c) for c in cells])
        except ValueError:
            bad = next(c for c in cells if not _is_number(c))
            raise ValueError(
                f"{flag} {path}: line {n}: {bad[:20]!r} is not a number ({n_dof} "
                "comma-separated joint angles, rad, per row)"
            ) from None
        if len(cells) != n_dof:
            raise ValueError(
                f"{flag} {path}: line {n} has {len(cells)} values: a pose of the {robot_name} "
                f"is {n_dof} comma-separated joint angles (rad)"
            )
    try:
        return check_user_poses(robot_name, np.array(q, dtype=float))
    except ValueError as exc:
        raise ValueError(f"{flag} {path}: {exc}") from None


def _is_number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def _cmd_plan(args: argparse.Namespace) -> int:
    from tvist.ident.campaign_plan import write_plan

    for flag, value in (
        ("--approach-speed", args.approach_speed),
        ("--approach-accel", args.approach_accel),
    ):
        if not (math.isfinite(value) and value > 0):
            raise ValueError(f"{flag} {value}: give a value > 0")
    joints = excited_from_args(args)
    poses = checked_plan(args)
    summary = write_plan(
        poses,
        args.out,
        robot_name=args.robot,
        duration_s=args.duration,
        joints=joints,
        approach_speed_rad_s=args.approach_speed,
        approach_accel_rad_s2=args.approach_accel,
    )
    payloads = ", ".join(f"{m:g} kg" for m in summary.payloads_kg)
    print(
        f"{summary.n_excitations} excitation programs at {summary.n_poses} poses in {args.out} "
        f"(list: {summary.path})"
    )
    if summary.unreachable:
        print(f"  left out, out of reach: {', '.join(summary.unreachable)}")
    print(f"  {coverage_text(poses, args)}")
    print(f"  payloads in this order, one change each: {payloads}")
    print(
        f"  the robot will be busy {summary.busy_s / 60:.1f} min ({summary.excitation_s:.0f} s "
        f"exciting, {summary.approach_s:.0f} s moving between poses at "
        f"{args.approach_speed:g} rad/s), plus the move to the first pose and the payload "
        "changes"
    )
    print(
        "  run each NNN_*.script on the robot while 'tvist record' records it, then "
        "'tvist identify LOGS --out poses.jsonl' and 'tvist fit-map poses.jsonl'"
    )
    return 0


def add_plan_command(sub: argparse._SubParsersAction) -> None:
    """``tvist plan``: write a campaign plan for one's own robot."""
    from tvist.ident.campaign_plan import APPROACH_ACCEL_RAD_S2, APPROACH_SPEED_RAD_S

    p = sub.add_parser(
        "plan",
        help="write a campaign plan: poses, excitation programs (URScript, CSV), time",
        description="Choose the campaign poses (paper Algorithm 1, every --every-th, plus "
        "--at and --cover poses) payload by payload, check that the map fit can succeed on "
        "them, and write each excitation (of the --excite joints) (Algorithm 2) as a URScript "
        "program and as a trajectory CSV, with plan.json listing them in order.",
    )
    add_plan_options(p)
    p.add_argument("--out", default="out/plan", help="folder to write (default out/plan)")
    p.add_argument(
        "--approach-speed",
        type=float,
        default=APPROACH_SPEED_RAD_S,
        help=f"speed of each program's move to its pose, rad/s (default {APPROACH_SPEED_RAD_S})",
    )
    p.add_argument(
        "--approach-accel",
        type=float,
        default=APPROACH_ACCEL_RAD_S2,
        help="acceleration of each program's move to its pose, rad/s² "
        f"(default {APPROACH_ACCEL_RAD_S2})",
    )
    p.set_defaults(func=_cmd_plan)
