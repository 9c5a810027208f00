"""``tvist plan``: a campaign plan for one's own robot (poses, excitation programs, time),
and the plan options ``tvist campaign`` shares with it."""

from __future__ import annotations

import argparse
import math

import numpy as np

from tvist.cli.args import DEFAULT_PAYLOAD_COM_M, existing_file

__all__ = ["add_plan_command", "add_plan_options", "checked_plan"]


def add_plan_options(p: argparse.ArgumentParser) -> None:
    """``--robot``, ``--payloads``, ``--payload-com``, ``--every``, ``--seed``, ``--cover``,
    ``--duration``: which poses and excitations a campaign runs."""
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
        "payloads; 0: none, only the --cover poses; default 1)",
    )
    p.add_argument(
        "--seed", type=int, default=0, help="seed of wrists, excitations, noise (default 0)"
    )
    p.add_argument(
        "--cover",
        metavar="POSES.csv",
        help="also your own poses: a CSV of 6 joint angles (rad) per row, each run with "
        "every payload",
    )
    p.add_argument(
        "--duration", type=float, default=8.0, help="excitation length per joint, s (default 8)"
    )


def checked_plan(args: argparse.Namespace, require_fittable: bool = True) -> list:
    """The poses of the plan options, payload by payload.

    Raises
    ------
    ValueError
        ``--every`` below 1, a bad ``--cover`` file, or (with ``require_fittable``) a plan
        the map fit cannot succeed on, with the reason and the flags that change it.
    """
    from tvist.ident.pose_plan import plan_poses, plan_shortfall

    if args.every < 0 or (args.every == 0 and not args.cover):
        raise ValueError(f"--every {args.every}: give 1 or more (0 only with --cover)")
    if not (math.isfinite(args.duration) and args.duration > 0):
        raise ValueError(f"--duration {args.duration}: give a length > 0 s")
    cover_q = _read_poses(args.cover) if args.cover else None
    try:
        poses = plan_poses(
            args.robot,
            payloads_kg=args.payloads,
            payload_com_m=args.payload_com,
            every=args.every,
            seed=args.seed,
            cover_q=cover_q,
        )
    except ValueError as exc:
        if cover_q is None:
            raise
        raise ValueError(f"--cover {args.cover}: {exc}") from None
    shortfall = plan_shortfall(poses) if require_fittable else None
    if shortfall:
        raise ValueError(
            f"this plan cannot give a map: {shortfall} (lower --every, or add poses with "
            "--cover or payloads with --payloads)"
        )
    return poses


def _read_poses(path: str) -> np.ndarray:
    """``--cover``: joint angles (rad), one pose per row, comma-separated, an optional
    header line."""
    text = existing_file(path, "--cover").read_text().splitlines()
    rows = [line for line in text if line.strip()]
    if rows and not rows[0].lstrip()[:1].isdigit() and rows[0].lstrip()[:1] not in "+-.":
        rows = rows[1:]  # a header
    try:
        q = np.array([[float(v) for v in line.split(",")] for line in rows], ndmin=2)
    except ValueError:
        raise ValueError(f"--cover {path}: not comma-separated numbers") from None
    if q.size == 0 or q.ndim != 2:
        raise ValueError(f"--cover {path}: one pose per row (joint angles, rad)")
    return q


def _cmd_plan(args: argparse.Namespace) -> int:
    from tvist.ident.campaign_plan import write_plan

    for flag, value in (
        ("--approach-speed", args.approach_speed),
        ("--approach-accel", args.approach_accel),
    ):
        if not (math.isfinite(value) and value > 0):
            raise ValueError(f"{flag} {value}: give a value > 0")
    poses = checked_plan(args)
    summary = write_plan(
        poses,
        args.out,
        robot_name=args.robot,
        duration_s=args.duration,
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
        "--cover poses) payload by payload, check that the map fit can succeed on them, and "
        "write each base and shoulder excitation (Algorithm 2) as a URScript program and as "
        "a trajectory CSV, with plan.json listing them in order.",
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
