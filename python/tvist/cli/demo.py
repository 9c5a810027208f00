"""``tvist demo`` and ``tvist zero-delay``: the papers' experiments and the zero-delay benchmark.

Each ``add_*_command(sub)`` registers one subparser and sets ``func``; heavy imports happen
inside the command.
"""

from __future__ import annotations

import argparse

from tvist.cli.shape import METHODS as SHAPING_METHODS

__all__ = ["add_demo_command", "add_zero_delay_command", "demo_row_method"]

#: The arm whose control period ``tvist zero-delay`` samples at without ``--dt-s`` (the
#: benchmark's plant is the payload alone): the UR5e, the arm of the flexible-payload demo.
ZERO_DELAY_ROBOT = "ur5e"


def _cmd_demo(args: argparse.Namespace) -> int:
    if args.robot != "ur5e":
        return _robot_demo(args)
    if args.experiment == "flexible-payload":
        from tvist.experiments.flexible_payload import run_from_args

        return run_from_args(args)
    if args.experiment == "pick-place":
        from tvist.experiments.pick_place import run_from_args as run_pick_place

        return run_pick_place(args)
    if args.linear:
        from tvist.experiments.linear import run_linear_demo

        run_linear_demo(out_dir=args.out or "out/demo-linear", quick=args.quick)
        return 0
    from tvist import ModalMap, load_map
    from tvist.cli.args import existing_file
    from tvist.cli.demo_table import print_table
    from tvist.experiments import default_methods, fd_tvist_map, run_demo
    from tvist.experiments.methods import fd_tvist_modal

    chosen = set(args.method or SHAPING_METHODS)
    methods = default_methods()
    for i, path in enumerate(args.map or []):
        dynmap = load_map(existing_file(path, "--map"))
        row = fd_tvist_modal if isinstance(dynmap, ModalMap) else fd_tvist_map
        methods.append(row(f"fd-tvist-map-{i + 1}", f"FD-TVIST ZV, map {path}", dynmap))
    methods = [m for m in methods if demo_row_method(m.key) in chosen | {"unshaped"}]
    run_demo(
        out_dir=args.out or "out/demo",
        quick=args.quick,
        methods=methods,
        identify=args.identify and "tvist" in chosen,
        show_table=print_table,
    )
    return 0


def _robot_demo(args: argparse.Namespace) -> int:
    """``tvist demo --robot NAME``: the campaign, identification, modal map and the three
    moves on the arm's default twin (:func:`tvist.experiments.generalization.run_variant`); the
    table is printed and written to ``out/demo-NAME/table.md``."""
    from pathlib import Path

    from tvist.experiments.generalization import (
        TABLE_FILE,
        HarnessSettings,
        run_variant,
        table_markdown,
    )
    from tvist.robots import params
    from tvist.sim import default_flex

    params(args.robot)  # an unknown robot: one line naming the known ones
    try:
        default_flex(args.robot)
    except ValueError as exc:
        raise ValueError(f"--robot {args.robot}: {exc}") from None
    out = Path(args.out or f"out/demo-{args.robot}")
    result = run_variant(None, out, HarnessSettings(robot=args.robot))
    table = table_markdown([result])
    (out / TABLE_FILE).write_text(table, encoding="utf-8")
    print(table)
    cpu = result.get("cpu_time_s") or {}
    print("CPU time, s: " + ", ".join(f"{k} {v:.0f}" for k, v in cpu.items()))
    if "error" in result:
        raise ValueError(f"--robot {args.robot}: {result['error']}")
    return 0


def demo_row_method(key: str) -> str:
    """Which ``--method`` a demo row belongs to (``"unshaped"`` for the baseline)."""
    if key.startswith(("fd-tvist", "fixed-")):  # fixed shapers: FD-TVIST's baselines
        return "tvist"
    return key if key in ("ztdis", "modified") else "unshaped"


def add_demo_command(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "demo", help="the paper's UR5e experiment on the simulated arm: table, figures, report"
    )
    p.add_argument("--out", default=None, help="output folder (default out/demo)")
    p.add_argument(
        "--robot",
        default="ur5e",
        help="ur5e: the paper's experiment (default); fr3, iiwa14 (or another arm with a "
        "default twin): identify a modal map on its twin and shape its three test moves "
        "(default out/demo-ROBOT; the other options do not apply)",
    )
    p.add_argument("--quick", action="store_true", help="shortened run (used by the tests)")
    p.add_argument(
        "--map",
        action="append",
        metavar="FILE",
        help="add an FD-TVIST row driven by this map file, paper10 or modal (repeatable)",
    )
    p.add_argument(
        "--method",
        action="append",
        choices=SHAPING_METHODS,
        help="shaping method rows to run (repeatable; default all): tvist = FD-TVIST, "
        "ztdis = zero-time-delay IS, modified = modified ZTDIS",
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
        choices=("ur5e-motions", "flexible-payload", "pick-place"),
        default="ur5e-motions",
        help="ur5e-motions: the FD-TVIST paper's three test motions (default); "
        "flexible-payload: the zero-delay paper's experiment, a flexible payload on the twin "
        "moved rapidly along X (default out/demo-payload); pick-place: a cycle of eight short "
        "fast moves of a cobot cell, cycle time to settled per method (default "
        "out/demo-pick-place)",
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
    return _run_zero_delay(args)


def add_zero_delay_command(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "zero-delay",
        help="benchmark unshaped / IS / ZTDIS / modified ZTDIS on the 2.55 Hz payload",
    )
    _zero_delay_arguments(p)
    p.set_defaults(func=_cmd_zero_delay)


def _zero_delay_arguments(p: argparse.ArgumentParser) -> None:
    """Options of ``tvist zero-delay``."""
    from tvist.cli.args import add_dt_s

    p.add_argument(
        "--reference",
        nargs="+",
        default=["min_jerk", "trapezoid"],
        choices=["min_jerk", "trapezoid"],
        help="reference move(s) (default: both)",
    )
    add_dt_s(p, default=f"the {ZERO_DELAY_ROBOT}'s control period, as in the flexible-payload demo")
    p.add_argument(
        "--rest-s",
        type=float,
        nargs=2,
        default=(0.0, 0.0),
        metavar=("BEFORE", "AFTER"),
        help="pad the move with rest before and after it, s (zero-delay shaping compresses "
        "only the move; default 0 0)",
    )
    p.add_argument("--plot", default=None, help="write the Fig. 13-style plot to this PNG path")


def _run_zero_delay(args: argparse.Namespace) -> int:
    """Run the benchmark as described by the parsed options; print tables."""
    from tvist.cli.args import dt_s_from_args
    from tvist.experiments.ztdis_benchmark import format_table, plot_benchmark, run_benchmark

    dt_s = dt_s_from_args(args, ZERO_DELAY_ROBOT)
    benches = [run_benchmark(ref, dt_s=dt_s, rest_s=tuple(args.rest_s)) for ref in args.reference]
    for bench in benches:
        print(format_table(bench))
        print()
    if args.plot:
        print(f"plot written to {plot_benchmark(benches, args.plot)}")
    return 0
