"""``tvist robot-file``: the robot file of a URDF chain (what the C API and Python load)."""

from __future__ import annotations

import argparse

from tvist.cli.args import existing_file

__all__ = ["add_robot_file_command"]


def add_robot_file_command(sub: argparse._SubParsersAction) -> None:
    """``tvist robot-file URDF --base-link --tip-link --out``."""
    p = sub.add_parser(
        "robot-file",
        help="write the robot file of a URDF's serial chain (for tvist_shaper_new_map, "
        "tvist.robots.robot_file)",
        description="Read the chain from --base-link to --tip-link of a URDF (revolute and "
        "continuous joints; fixed joints merged; meshes not read), check it, and write the "
        "robot file the core loads: joint origins and axes, link inertials, joint limits.",
    )
    p.add_argument("urdf", metavar="URDF", help="the URDF file")
    p.add_argument("--base-link", required=True, help="the fixed base link (gravity along -z)")
    p.add_argument("--tip-link", required=True, help="the flange link (the payload's frame)")
    p.add_argument("--out", required=True, help="robot file to write (*.json)")
    p.add_argument("--name", help="robot name (default: the URDF's robot name)")
    p.add_argument(
        "--max-payload-kg", type=float, default=0.0, help="rated payload, kg (default 0)"
    )
    p.add_argument(
        "--control-period-s",
        type=float,
        default=None,
        help="period of the arm controller's control loop, s (URDF gives none; default: not "
        "written, and commands run on the robot file then need --dt-s)",
    )
    p.set_defaults(func=_cmd_robot_file)


def _cmd_robot_file(args: argparse.Namespace) -> int:
    from tvist.robots import robot_file, urdf_params, write_robot_file

    urdf = existing_file(args.urdf, "URDF")
    if not str(args.out).endswith(".json"):
        raise ValueError(f"--out {args.out}: a robot file name ends in .json")
    params = urdf_params(
        urdf,
        args.base_link,
        args.tip_link,
        name=args.name,
        max_payload_kg=args.max_payload_kg,
        control_period_s=args.control_period_s,
    )
    write_robot_file(params, args.out)
    checked = robot_file(args.out)  # read back by the core's reader, as the C API does
    print(
        f"wrote {args.out}: {checked.name}, {checked.n_dof} joints, "
        f"{checked.mass_kg.sum():.3f} kg moving"
    )
    return 0
