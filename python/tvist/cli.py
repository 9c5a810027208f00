"""The ``tvist`` command line. Each subcommand lives in its own ``_cmd_*`` function and is
registered in ``COMMANDS``; heavy imports happen inside the command that needs them."""

from __future__ import annotations

import argparse
import sys

from tvist.ident.cli import (
    add_campaign_command,
    add_fit_map_command,
    add_identify_command,
    add_sensitivity_command,
)
from tvist.live_cli import add_record_command, add_run_command
from tvist.shape_command import METHODS as SHAPING_METHODS
from tvist.shape_command import add_shape_command
from tvist.urserver.cli import add_twin_server_command


def _cmd_demo(args: argparse.Namespace) -> int:
    if args.experiment == "flexible-payload":
        from tvist.demo.flexible_payload import run_from_args

        return run_from_args(args)
    if args.linear:
        from tvist.demo.linear import run_linear_demo

        run_linear_demo(out_dir=args.out or "out/demo-linear", quick=args.quick)
        return 0
    from tvist import DynamicMap
    from tvist.demo import default_methods, fd_tvist_map, run_demo

    chosen = set(args.method or SHAPING_METHODS)
    methods = default_methods()
    for i, path in enumerate(args.map or []):
        methods.append(
            fd_tvist_map(f"fd-tvist-map-{i + 1}", f"FD-TVIST ZV, map {path}", DynamicMap.load(path))
        )
    methods = [m for m in methods if _demo_row_method(m.key) in chosen | {"unshaped"}]
    run_demo(
        out_dir=args.out or "out/demo",
        quick=args.quick,
        methods=methods,
        identify=args.identify and "tvist" in chosen,
    )
    return 0


def _demo_row_method(key: str) -> str:
    """Which ``--method`` a demo row belongs to (``"unshaped"`` for the baseline)."""
    if key.startswith(("fd-tvist", "fixed-")):  # fixed shapers: FD-TVIST's baselines
        return "tvist"
    return {"zero-delay-ztdis": "ztdis", "zero-delay-modified": "mztdis"}.get(key, "unshaped")


def _add_demo(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "demo", help="the paper's UR5e experiment on the simulated arm: table, figures, report"
    )
    p.add_argument("--out", default=None, help="output folder (default out/demo)")
    p.add_argument("--quick", action="store_true", help="shortened run (used by the tests)")
    p.add_argument(
        "--map",
        action="append",
        metavar="FILE",
        help="add an FD-TVIST row driven by this dynamic map file (repeatable)",
    )
    p.add_argument(
        "--method",
        action="append",
        choices=SHAPING_METHODS,
        help="shaping method rows to run (repeatable; default all): tvist = FD-TVIST, "
        "ztdis = zero-time-delay IS, mztdis = modified ZTDIS",
    )
    p.add_argument(
        "--identify",
        action=argparse.BooleanOptionalAction,
        default=True,
        help="identify a map on the twin first (reduced mapping campaign, 20-60 s, cached in "
        "the output folder) and add its row (default); --no-identify skips it",
    )
    p.add_argument(
        "--linear",
        action="store_true",
        help="run the small two-mode linear-plant example instead (default out/demo-linear)",
    )
    p.add_argument(
        "--experiment",
        choices=("ur5e-motions", "flexible-payload"),
        default="ur5e-motions",
        help="ur5e-motions: the FD-TVIST paper's three test motions (default); "
        "flexible-payload: the zero-delay paper's experiment, a flexible payload on the twin "
        "moved rapidly along X (default out/demo-payload)",
    )
    p.add_argument(
        "--payload-hz",
        type=float,
        default=2.55,
        help="flexible-payload: natural frequency of the payload mount, Hz (default 2.55)",
    )
    p.add_argument(
        "--payload-zeta",
        type=float,
        default=0.04,
        help="flexible-payload: damping ratio of the payload mount (default 0.04)",
    )
    p.set_defaults(func=_cmd_demo)


def _cmd_zero_delay(args: argparse.Namespace) -> int:
    from tvist.ztdis_benchmark import run_from_args

    return run_from_args(args)


def _add_zero_delay(sub: argparse._SubParsersAction) -> None:
    from tvist.ztdis_benchmark import add_arguments

    p = sub.add_parser(
        "zero-delay",
        help="benchmark unshaped / IS / ZTDIS / modified ZTDIS on the 2.55 Hz payload",
    )
    add_arguments(p)
    p.set_defaults(func=_cmd_zero_delay)


#: (name, adder) pairs; an adder registers one subparser and sets ``func``.
COMMANDS = [("demo", _add_demo), ("zero-delay", _add_zero_delay)]
COMMANDS += [
    ("campaign", add_campaign_command),
    ("identify", add_identify_command),
    ("fit-map", add_fit_map_command),
    ("sensitivity", add_sensitivity_command),
    ("shape", add_shape_command),
]
COMMANDS += [
    ("twin-server", add_twin_server_command),
    ("run", add_run_command),
    ("record", add_record_command),
]


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="tvist",
        description="Vibration suppression for robot arms: shaping, identification, the "
        "simulated twin and reports.",
    )
    parser.add_argument("--version", action="version", version=f"tvist {_version()}")
    parser.add_argument(
        "--debug",
        action="store_true",
        help="show the full traceback of an error (accepted anywhere on the command line)",
    )
    sub = parser.add_subparsers(dest="command", required=True)
    for _, add in COMMANDS:
        add(sub)
    return parser


def _version() -> str:
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("tvist")
    except PackageNotFoundError:
        return "unknown"


#: Exceptions that mean "the input or the environment is wrong", not "tvist is broken": the
#: library raises ``ValueError`` (and its subclasses) for bad input and ``OSError`` for files
#: and connections. They are reported in one line; anything else keeps its traceback.
USER_ERRORS = (ValueError, OSError)


def main(argv: list[str] | None = None) -> int:
    """Run one command; user errors print ``tvist <command>: error: ...`` and return 2."""
    argv = list(sys.argv[1:] if argv is None else argv)
    debug = "--debug" in argv
    args = build_parser().parse_args([a for a in argv if a != "--debug"])
    where = f"tvist {args.command}"
    try:
        return int(args.func(args) or 0)
    except KeyboardInterrupt:
        if debug:
            raise
        print(f"{where}: interrupted", file=sys.stderr)
        return 130
    except USER_ERRORS as exc:
        if debug:
            raise
        print(f"{where}: error: {_one_line(exc)}", file=sys.stderr)
        return 2


def _one_line(exc: BaseException) -> str:
    """The exception's message on one line (file errors keep their path)."""
    if isinstance(exc, OSError) and exc.strerror and exc.filename:
        text = f"{exc.strerror}: {exc.filename}"
    else:
        text = " ".join(str(exc).split()) or type(exc).__name__
    return f"{text} (--debug shows the traceback)"


if __name__ == "__main__":
    sys.exit(main())
