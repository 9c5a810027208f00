"""``tvist run`` (a shaped move on a UR, live) and ``tvist record`` (an RTDE log)."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path


def _error(command: str, message: str) -> int:
    print(f"tvist {command}: error: {message}", file=sys.stderr)
    return 2


def _shaper(args: argparse.Namespace, Q):  # noqa: N803 (the move, as elsewhere)
    """The TvShaper of ``--modes`` / ``--map`` / ``--paper-map`` for the move ``Q``, or None
    for ``--unshaped``; a map used outside its identified inertia range is warned here, once,
    before the arm moves."""
    import tvist
    from tvist.cli.args import map_from_args, robot_from_args
    from tvist.cli.shape import parse_modes
    from tvist.dynmap import range_report_of

    n_dof = Q.shape[1]
    if args.unshaped:
        return None
    if args.modes:
        provider = tvist.ConstantModes(parse_modes(args.modes))
    else:
        robot = robot_from_args(args)
        if robot.n_dof != n_dof:
            raise ValueError(f"the file has {n_dof} joints, the {args.robot} has {robot.n_dof}")
        provider = tvist.MapDynamics(robot, map_from_args(args))
        report = range_report_of(provider, Q)
        if report is not None:
            print(f"tvist run: warning: {report}", file=sys.stderr)
    return tvist.TvShaper(provider, dt_s=args.dt, n_dof=n_dof, shaper=args.shaper)


def _cmd_run(args: argparse.Namespace) -> int:
    from tvist.cli.shape import read_joint_csv
    from tvist.live import residual_vibration, run_shaped_move

    if not (args.unshaped or args.modes or args.map or args.paper_map):
        return _error("run", "give the modes: --map FILE, --paper-map or --modes (or --unshaped)")
    from tvist.cli.args import existing_file, output_file

    try:
        Q, _ = read_joint_csv(existing_file(args.move, "move"))
        shaper = _shaper(args, Q)
    except (OSError, ValueError) as exc:
        return _error("run", str(exc))
    try:
        log_path = output_file(args.log or Path(args.move).with_suffix(".rtde.csv"), "--log")
    except ValueError as exc:
        return _error("run", str(exc))
    try:
        result = run_shaped_move(
            args.robot_ip,
            Q,
            log_path,
            shaper=shaper,
            dt_s=args.dt,
            lookahead_s=args.lookahead,
            gain=args.gain,
            tail_s=args.tail,
        )
    except ConnectionError as exc:
        return _error("run", f"{exc} (check --robot-ip)")
    except KeyboardInterrupt:
        print("tvist run: interrupted; the arm was stopped (servoStop, stopScript)")
        return 130
    except RuntimeError as exc:
        print(f"tvist run: error: {exc}; the arm was stopped (servoStop, stopScript)")
        return 1
    print(
        f"sent {result.n_commands} servoJ commands over "
        f"{result.stream_end_s - result.stream_start_s:.3f} s; log {result.log_path}"
    )
    if result.n_skipped:
        print(
            f"tvist run: warning: the servo loop woke too late for {result.n_skipped} periods and "
            "the target jumped over their samples (run on a less loaded machine, with "
            "real-time priority: root or CAP_SYS_NICE)",
            file=sys.stderr,
        )
    if args.tail >= 1.2:
        rms = residual_vibration(result.log_path)
        print(f"residual vibration (accelerometer RMS, 1 s after the move): {rms:.2e} m/s²")
    return 0


def _cmd_record(args: argparse.Namespace) -> int:
    from tvist.cli.args import output_file
    from tvist.live import record

    def started() -> None:
        print(f"recording {args.robot_ip} to {args.out}; Ctrl-C stops", flush=True)

    try:
        output_file(args.out, "--out")
    except ValueError as exc:
        return _error("record", str(exc))

    try:
        record(
            args.robot_ip,
            args.out,
            frequency_hz=args.frequency,
            duration_s=args.duration,
            on_start=started,
        )
    except KeyboardInterrupt:
        pass
    except (OSError, ValueError) as exc:
        return _error("record", f"{exc} (check --robot-ip)")
    print(f"wrote {args.out}")
    return 0


def _add_payload(p: argparse.ArgumentParser) -> None:
    from tvist.cli.args import add_robot_and_payload

    add_robot_and_payload(p)


def add_run_command(sub: argparse._SubParsersAction) -> None:
    from tvist.live import SERVO_GAIN, SERVO_LOOKAHEAD_S

    p = sub.add_parser(
        "run", help="run a joint trajectory CSV on a UR with servoJ at 500 Hz, shaped live"
    )
    p.add_argument("move", help="CSV of joint positions (rad), one row per control period")
    p.add_argument("--robot-ip", required=True, help="robot (or twin server) address")
    modes = p.add_mutually_exclusive_group()
    modes.add_argument("--map", help="map file, paper10 or modal (tvist fit-map)")
    modes.add_argument("--paper-map", action="store_true", help="the paper's UR5e map")
    modes.add_argument("--modes", help="fixed modes FREQ_HZ:ZETA,...")
    modes.add_argument("--unshaped", action="store_true", help="stream the reference unshaped")
    p.add_argument("--shaper", default="zv", help="shaper per mode: zv, zvd, ei (default zv)")
    _add_payload(p)
    p.add_argument("--log", help="RTDE log to write (default MOVE.rtde.csv)")
    p.add_argument("--dt", type=float, default=0.002, help="control period, s (default 0.002)")
    p.add_argument(
        "--lookahead",
        type=float,
        default=SERVO_LOOKAHEAD_S,
        help=f"servoJ lookahead time, s (default {SERVO_LOOKAHEAD_S})",
    )
    p.add_argument(
        "--gain", type=float, default=SERVO_GAIN, help=f"servoJ gain (default {SERVO_GAIN:g})"
    )
    p.add_argument(
        "--tail", type=float, default=3.0, help="recording after the last command, s (default 3)"
    )
    p.set_defaults(func=_cmd_run)


def add_record_command(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("record", help="record the RTDE fields identification needs (until Ctrl-C)")
    p.add_argument("--robot-ip", required=True, help="robot (or twin server) address")
    p.add_argument("--out", required=True, help="CSV to write (ur_rtde's format)")
    p.add_argument("--frequency", type=float, default=500.0, help="Hz (default 500)")
    p.add_argument("--duration", type=float, default=None, help="stop after this many s")
    p.set_defaults(func=_cmd_record)
