"""Command-line options shared by every ``tvist`` command that needs a robot and its payload,
so ``--robot``, ``--payload-kg`` and ``--payload-com X Y Z`` mean the same everywhere."""

from __future__ import annotations

import argparse
from pathlib import Path

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


def existing_file(path: str | Path, flag: str) -> Path:
    """``path`` if it is a file; otherwise ``ValueError`` naming ``flag`` (``"--map"``, or a
    positional argument's name), which the CLI reports on one line."""
    path = Path(path)
    if not path.is_file():
        what = "is a directory, not a file" if path.is_dir() else "no such file"
        raise ValueError(f"{flag} {path}: {what}")
    return path


def existing_dir(path: str | Path, flag: str) -> Path:
    """``path`` if it is a directory; otherwise ``ValueError`` naming ``flag``."""
    path = Path(path)
    if not path.is_dir():
        what = "is a file, not a directory" if path.exists() else "no such directory"
        raise ValueError(f"{flag} {path}: {what}")
    return path


def output_file(path: str | Path, flag: str) -> Path:
    """``path``, with its directory created if missing (as the campaign and the recorder do),
    checked before any work is done: ``ValueError`` naming ``flag`` if it is a directory or
    its directory cannot be made."""
    path = Path(path)
    if path.is_dir():
        raise ValueError(f"{flag} {path}: is a directory, give a file name")
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise ValueError(f"{flag} {path}: cannot make its directory ({exc.strerror})") from None
    return path


def map_from_args(args: argparse.Namespace):
    """The map of ``--paper-map`` or ``--map FILE`` (either kind, by the file's ``kind``)."""
    import tvist

    if args.paper_map:
        return tvist.DynamicMap.paper_ur5e()
    return tvist.load_map(existing_file(args.map, "--map"))


def add_units(p: argparse.ArgumentParser, quantities: tuple[str, ...]) -> None:
    """``--units q=deg,...``: the input's units where they are not SI (converted on reading)."""
    from tvist.units import units_help

    p.add_argument("--units", default=None, metavar="Q=UNIT,...", help=units_help(quantities))
