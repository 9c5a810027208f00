"""The ``tvist`` command line: one module per group of commands (``demo``, ``ident``,
``learn``, ``shape``, ``live``, ``plan``, ``twin_server``, ``robot_file``; shared options in
``args``), each registering its subparsers through an ``add_*_command`` listed in
``COMMANDS``. Heavy imports happen inside the command that needs them. :func:`main` turns
user errors into one line and exit code 2."""

from __future__ import annotations

import argparse
import sys
import warnings

from tvist.cli.demo import add_demo_command, add_zero_delay_command
from tvist.cli.ident import (
    add_campaign_command,
    add_fit_map_command,
    add_identify_command,
    add_sensitivity_command,
)
from tvist.cli.learn import add_learn_command
from tvist.cli.live import add_record_command, add_run_command
from tvist.cli.plan import add_plan_command
from tvist.cli.robot_file import add_robot_file_command
from tvist.cli.shape import add_shape_command
from tvist.cli.twin_server import add_twin_server_command

#: (name, adder) pairs; an adder registers one subparser and sets ``func``.
COMMANDS = [("demo", add_demo_command), ("zero-delay", add_zero_delay_command)]
COMMANDS += [
    ("plan", add_plan_command),
    ("campaign", add_campaign_command),
    ("identify", add_identify_command),
    ("fit-map", add_fit_map_command),
    ("sensitivity", add_sensitivity_command),
    ("learn", add_learn_command),
    ("shape", add_shape_command),
]
COMMANDS += [
    ("twin-server", add_twin_server_command),
    ("run", add_run_command),
    ("record", add_record_command),
    ("robot-file", add_robot_file_command),
]


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="tvist",
        description="Vibration suppression for robot arms: shaping, identification, the "
        "simulated twin and reports. Frequencies are in Hz on the command line (undamped "
        "natural frequencies), rad/s in the Python API; times in s.",
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
    """Run one command; user errors print ``tvist <command>: error: ...`` and return 2, and
    warnings ``tvist <command>: warning: ...`` (one line each)."""
    argv = list(sys.argv[1:] if argv is None else argv)
    debug = "--debug" in argv
    with warnings.catch_warnings():
        where = ["tvist"]
        warnings.showwarning = lambda message, *_, **__: print(
            f"{where[0]}: warning: {message}", file=sys.stderr
        )
        args = build_parser().parse_args([a for a in argv if a != "--debug"])
        where[0] = f"tvist {args.command}"
        return _run(args, where[0], debug)


def _run(args: argparse.Namespace, where: str, debug: bool) -> int:
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
