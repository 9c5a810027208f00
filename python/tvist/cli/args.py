"""Command-line options shared by every ``tvist`` command that needs a robot and its payload,
so ``--robot``, ``--payload-kg`` and ``--payload-com X Y Z`` mean the same everywhere."""

from __future__ import annotations

import argparse

#: Default payload centre of mass in the flange frame, m (the paper's 5 cm beyond the flange).
DEFAULT_PAYLOAD_COM_M = (0.0, 0.0, 0.05)


def add_robot_and_payload(p: argparse.ArgumentParser, payload_help: str = "payload mass") -> None:
    """``--robot NAME``, ``--payload-kg M`` and ``--payload-com X Y Z``."""
    p.add_argument("--robot", default="ur5e", help="robot model (default ur5e)")
    p.add_argument("--payload-kg", type=float, default=0.0, help=f"{payload_help}, kg (default 0)")
    p.add_argument(
        "--payload-com",
        type=float,
        nargs=3,
        default=DEFAULT_PAYLOAD_COM_M,
        metavar=("X", "Y", "Z"),
        help="payload centre of mass in the flange frame, m (default 0 0 0.05)",
    )


def robot_from_args(args: argparse.Namespace):
    """The :class:`tvist.robots.Robot` named by ``--robot`` with ``--payload-kg/--payload-com``."""
    import tvist

    return tvist.robots.Robot(
        tvist.robots.params(args.robot),
        tvist.robots.Payload(args.payload_kg, tuple(args.payload_com)),
    )


def map_from_args(args: argparse.Namespace):
    """The map of ``--paper-map`` or ``--map FILE`` (either kind, by the file's ``kind``)."""
    import tvist

    return tvist.DynamicMap.paper_ur5e() if args.paper_map else tvist.load_map(args.map)
