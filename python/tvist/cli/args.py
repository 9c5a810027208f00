"""Command-line options shared by every ``tvist`` command that needs a robot and its payload,
so ``--robot``, ``--payload-kg`` and ``--payload-com X Y Z`` mean the same everywhere, and the
payload is never a silent default: it is given, or read from a named source (the controller,
the map file, the log), and the command prints which; otherwise it stops naming the flag."""

from __future__ import annotations

import argparse
import sys
import warnings
from collections.abc import Callable
from pathlib import Path
from typing import TextIO

#: Payload centre of mass in the flange frame with ``--payload-kg`` alone, m (the paper's 5 cm
#: beyond the flange).
DEFAULT_PAYLOAD_COM_M = (0.0, 0.0, 0.05)

#: A named place a payload may come from: ``(description, finder)``; the finder returns a
#: :class:`tvist.robots.Payload` or ``None`` when that place has none.
PayloadSource = tuple[str, Callable[[], object]]


def add_robot_and_payload(
    p: argparse.ArgumentParser,
    payload_help: str = "payload mass",
    *,
    payload_from: str = "required",
    payload_default: float | None = None,
) -> None:
    """``--robot NAME``, ``--payload-kg M`` and ``--payload-com X Y Z``.

    ``payload_from`` says in the help where the payload comes from without ``--payload-kg``
    (``"default: read from the controller"``); ``payload_default`` is for the twin server only,
    whose payload is the physical one it simulates.
    """
    p.add_argument("--robot", default="ur5e", help="robot model (default ur5e)")
    p.add_argument(
        "--payload-kg",
        type=float,
        default=payload_default,
        help=f"{payload_help}, kg ({payload_from})",
    )
    p.add_argument(
        "--payload-com",
        type=float,
        nargs=3,
        default=None,
        metavar=("X", "Y", "Z"),
        help="payload centre of mass in the flange frame, m (default: with --payload-kg "
        "0 0 0.05, otherwise that of the payload's source)",
    )


def payload_from_args(
    args: argparse.Namespace,
    *sources: PayloadSource,
    needed_for: str,
    out: TextIO | None = None,
):
    """The payload: ``--payload-kg`` (with ``--payload-com``, default
    :data:`DEFAULT_PAYLOAD_COM_M`), else the first of ``sources`` that has one (its centre of
    mass replaced by ``--payload-com`` if given). Printed to ``out`` (default stdout) with
    where it came from, and stored back in ``args.payload_kg``/``args.payload_com``.

    Raises
    ------
    ValueError
        No payload anywhere: one line naming what needs it, where it was looked for and the
        flag.
    """
    from tvist.robots import Payload

    com = None if args.payload_com is None else tuple(args.payload_com)
    if args.payload_kg is not None:
        payload = Payload(args.payload_kg, com or DEFAULT_PAYLOAD_COM_M)
        source = "--payload-kg" + (", --payload-com" if com else ", default centre of mass")
    else:
        for name, find in sources:
            payload = find()
            if payload is not None:
                source = name
                break
        else:
            looked = f" (none in {' or '.join(name for name, _ in sources)})" if sources else ""
            raise ValueError(
                f"no payload: {needed_for} needs the payload mass{looked}; give --payload-kg KG "
                "(and --payload-com X Y Z, m in the flange frame)"
            )
        if com is not None:
            payload = Payload(payload.mass_kg, com)
            source += ", centre of mass from --payload-com"
    args.payload_kg, args.payload_com = payload.mass_kg, tuple(float(v) for v in payload.com_m)
    com_text = " ".join(f"{v:g}" for v in args.payload_com)
    print(
        f"payload {payload.mass_kg:g} kg, centre of mass {com_text} m (flange frame), "
        f"from {source}",
        file=out or sys.stdout,
    )
    return payload


def map_payload(dynmap) -> object:
    """The payload a map file names (``metadata.payload``), or ``None``."""
    from tvist.robots import Payload

    entry = (dynmap.metadata or {}).get("payload")
    if not entry:
        return None
    return Payload(entry["mass_kg"], tuple(entry["com_m"]), entry.get("inertia_kg_m2"))


def robot_from_args(args: argparse.Namespace):
    """The :class:`tvist.robots.Robot` named by ``--robot`` with the payload of
    ``--payload-kg/--payload-com`` (resolved by :func:`payload_from_args`)."""
    import tvist

    if args.payload_kg is None:
        raise ValueError("no payload: give --payload-kg KG (and --payload-com X Y Z)")
    return tvist.robots.Robot(
        tvist.robots.params(args.robot),
        tvist.robots.Payload(args.payload_kg, tuple(args.payload_com or DEFAULT_PAYLOAD_COM_M)),
    )


def kinematic_robot(args: argparse.Namespace):
    """The ``--robot`` model for kinematics only (flange path, joint names): its payload, the
    given one or none, does not change them."""
    import tvist

    if args.payload_kg is not None:
        return robot_from_args(args)
    return tvist.robots.Robot(tvist.robots.params(args.robot))


class DeprecatedAlias(argparse.Action):
    """Stores like ``store`` and warns when the option is spelled with a deprecated name
    (``deprecated``: the old option strings; the first option string is the current name)."""

    def __init__(self, option_strings, dest, deprecated: tuple[str, ...] = (), **kwargs):
        super().__init__(option_strings, dest, **kwargs)
        self.deprecated = deprecated

    def __call__(self, parser, namespace, values, option_string=None):
        if option_string in self.deprecated:
            warnings.warn(
                f"{option_string} is deprecated, use {self.option_strings[0]}",
                FutureWarning,
                stacklevel=2,
            )
        setattr(namespace, self.dest, values)


def add_dt_s(
    p: argparse.ArgumentParser,
    what: str = "control period",
    default: str = "the --robot's control period (control_period_s of its robot data)",
) -> None:
    """``--dt-s`` (s; ``--dt`` is its deprecated spelling). Its default, ``None``, is resolved
    by :func:`dt_s_from_args`; ``default`` says in the help what it means."""
    p.add_argument(
        "--dt-s",
        "--dt",
        dest="dt_s",
        type=float,
        default=None,
        action=DeprecatedAlias,
        deprecated=("--dt",),
        help=f"{what}, s (default: {default}; --dt is a deprecated spelling)",
    )


def dt_s_from_args(args: argparse.Namespace, robot: str | None = None) -> float:
    """``--dt-s``, else the control period of ``robot`` (default: ``--robot``), stored back
    in ``args.dt_s``.

    Raises
    ------
    ValueError
        ``--dt-s`` is not a time > 0, or it is not given and the robot's data states no
        control period: one line naming ``--dt-s``.
    """
    import math

    from tvist.robots import params

    if args.dt_s is None:
        name = args.robot if robot is None else robot
        period = params(name).control_period_s
        if period is None:
            raise ValueError(
                f"the {name} has no control period in its robot data: give --dt-s S "
                "(the controller's sample period, s)"
            )
        args.dt_s = period
    if not (math.isfinite(args.dt_s) and args.dt_s > 0):
        raise ValueError(f"--dt-s must be > 0; got {args.dt_s}")
    return args.dt_s


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


def add_allow_other_robot(p: argparse.ArgumentParser) -> None:
    """``--allow-other-robot``: use a map identified on another robot (with a warning)."""
    p.add_argument(
        "--allow-other-robot",
        action="store_true",
        help="use a map identified on another robot than --robot (its modes are then only "
        "an estimate; a warning says so)",
    )


def map_dynamics(args: argparse.Namespace, robot, dynmap):
    """``tvist.dynamics_for(robot, dynmap)``; a map of another robot is refused naming
    ``--allow-other-robot``, or used with a warning when that flag is given."""
    import tvist

    allow = bool(getattr(args, "allow_other_robot", False))
    other = dynmap.robot is not None and dynmap.robot != args.robot
    if other and not allow:
        raise ValueError(
            f"the map was identified on {dynmap.robot}, not on {args.robot} (--robot); "
            "--allow-other-robot uses it anyway"
        )
    if other:
        warnings.warn(
            f"--allow-other-robot: a map identified on {dynmap.robot} shapes the {args.robot}; "
            "its modes are an estimate for this robot",
            UserWarning,
            stacklevel=2,
        )
    return tvist.dynamics_for(robot, dynmap, allow_other_robot=allow)


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
