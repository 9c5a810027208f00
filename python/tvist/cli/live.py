"""``tvist run`` (a shaped move on a UR, live) and ``tvist record`` (an RTDE log).

``tvist run`` shapes with the payload the controller has been told (RTDE ``payload``,
``payload_cog``) unless ``--payload-kg`` is given, and prints which it used."""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path


def _error(command: str, message: str) -> int:
    print(f"tvist {command}: error: {message}", file=sys.stderr)
    return 2


def _shaper(args: argparse.Namespace, Q):  # noqa: N803 (the move, as elsewhere)
    """The TvShaper of ``--modes`` / ``--map`` / ``--paper-map`` for the move ``Q``, or None
    for ``--unshaped``. A map's payload is ``--payload-kg`` or the controller's (printed); a
    map used outside its identified inertia range is warned here, once, before the arm moves."""
    import tvist
    from tvist.cli.args import (
        dt_s_from_args,
        map_dynamics,
        map_from_args,
        payload_from_args,
        robot_from_args,
    )
    from tvist.cli.shape import parse_modes
    from tvist.maps.mode_choice import set_modes_for_move
    from tvist.maps.paper10 import range_report_of

    n_dof = Q.shape[1]
    if args.unshaped:
        return None
    if args.modes:
        provider = tvist.ConstantModes(parse_modes(args.modes))
    else:
        dynmap = map_from_args(args)
        controller = (
            [(f"the controller at {args.robot_ip}", lambda: _controller_payload(args.robot_ip))]
            if args.robot_ip
            else []
        )
        payload_from_args(args, *controller, needed_for="shaping with a map")
        robot = robot_from_args(args)
        if robot.n_dof != n_dof:
            raise ValueError(f"the file has {n_dof} joints, the {args.robot} has {robot.n_dof}")
        provider = map_dynamics(args, robot, dynmap)
        report = range_report_of(provider, Q)
        if report is not None:
            print(f"tvist run: warning: {report}", file=sys.stderr)
    dt_s = dt_s_from_args(args)
    shaper = tvist.TvShaper(provider, dt_s=dt_s, n_dof=n_dof, shaper=args.shaper)
    # A frequency-ranked modal map shapes the modes this move needs.
    choice = set_modes_for_move(shaper, provider, Q, dt_s)
    if choice is not None:
        print(f"shaping the {choice.n_modes} lowest mode(s) of the modal map for this move")
        if choice.hold_end_pose:
            following, holding = choice.predicted
            print(
                "holding the stop pose's modes over this move: the map predicts "
                f"{100 * holding:.1f} % of the ringing left, against {100 * following:.1f} % "
                "following the pose"
            )
    return shaper


def _learner(args: argparse.Namespace):
    """The :class:`~tvist.learn.MapLearner` of ``--learn`` (None without it), built before the
    arm moves: a paper10 map or a missing payload is refused first. The payload is the one
    shaping uses, else ``--payload-kg``, the controller's or the map's metadata.payload."""
    if not args.learn:
        return None
    from tvist.cli.args import map_payload, payload_from_args, robot_from_args
    from tvist.cli.learn import modal_prior
    from tvist.learn import MapLearner

    prior = modal_prior(args.learn, "--learn")
    if args.payload_kg is None:  # not resolved already by shaping with a map
        payload_from_args(
            args,
            (f"the controller at {args.robot_ip}", lambda: _controller_payload(args.robot_ip)),
            ("the --learn map's metadata.payload", lambda: map_payload(prior)),
            needed_for="learning (--learn)",
        )
    return MapLearner(robot_from_args(args), prior)


def _learn_from_run(learner, map_path: Path, log_path: Path) -> None:
    """Observes the run's log; writes the learned map (with its provenance, as ``tvist
    learn``) over ``map_path`` only if the learner updated it, the previous file kept as
    ``map_path.bak``. Prints one line on what it did."""
    import shutil

    obs = learner.observe(log_path)
    verdict = "used" if obs.accepted else "rejected"
    if not obs.map_updated:
        print(f"learn: {map_path} unchanged, the log {verdict}: {obs.reason}")
        return
    backup = map_path.with_name(map_path.name + ".bak")
    shutil.copyfile(map_path, backup)
    learner.learned_map().save(map_path)
    print(f"learn: {map_path} updated (previous map in {backup}), the log {verdict}: {obs.reason}")


def _controller_payload(robot_ip: str):
    """The controller's payload, or None if it does not publish one (an old firmware)."""
    from tvist.live import read_controller_payload

    try:
        return read_controller_payload(robot_ip)
    except ValueError:
        return None


def _cmd_run(args: argparse.Namespace) -> int:
    from tvist.cli.shape import read_joint_csv
    from tvist.live import (
        APPROACH_ACCEL_RAD_S2,
        APPROACH_SPEED_RAD_S,
        moving_span,
        residual_vibration,
        run_shaped_move,
    )

    if not (args.unshaped or args.modes or args.map or args.paper_map):
        return _error("run", "give the modes: --map FILE, --paper-map or --modes (or --unshaped)")
    if not (args.dry_run or args.robot_ip):
        return _error(
            "run", "give the robot's address with --robot-ip (or check the move: --dry-run)"
        )
    if args.learn and args.dry_run:
        return _error("run", "--learn learns from the run's log: leave out --dry-run")
    from tvist.cli.args import dt_s_from_args, existing_file, output_file
    from tvist.move_list import is_move_list
    from tvist.units import parse_units, to_si

    try:
        dt_s_from_args(args)
        moves = is_move_list(existing_file(args.move, "move"))
        if moves:
            Q, shaped = _move_list_reference(args)
            shaper = None  # shaped already, in Cartesian space
        else:
            Q, names = read_joint_csv(args.move)
            Q = to_si(Q, "q", parse_units(args.units, ("q",))["q"])
        if not args.dry_run:
            log_path = output_file(args.log or Path(args.move).with_suffix(".rtde.csv"), "--log")
        if not moves:
            shaper = _shaper(args, Q)  # after the files: it may ask the controller
            shaped = _checked_reference(args, Q, names, shaper)
        learner = _learner(args)
    except (OSError, ValueError, RuntimeError) as exc:
        return _error("run", str(exc))
    if args.dry_run:
        return _dry_run(args, Q, shaped)
    try:
        state = _controller_ready(args.robot_ip)
    except (OSError, ValueError) as exc:
        return _error("run", str(exc))
    travel = abs(Q[0] - state.actual_q)
    joint = int(travel.argmax())
    print(
        f"approach: moveJ to the first row at {APPROACH_SPEED_RAD_S:g} rad/s, "
        f"{APPROACH_ACCEL_RAD_S2:g} rad/s² (not shaped, not logged): joint {joint} turns "
        f"{travel[joint]:.3f} rad, the longest way; then {shaped.shape[0]} servoJ periods at "
        f"--dt-s {args.dt_s:g} s. Ctrl-C stops the arm; keep the emergency stop at hand",
        flush=True,
    )
    try:
        result = run_shaped_move(
            args.robot_ip,
            shaped if moves else Q,  # a move list is shaped already (in Cartesian space)
            log_path,
            shaper=shaper,
            dt_s=args.dt_s,
            lookahead_s=args.lookahead,
            gain=args.gain,
            tail_s=args.tail,
        )
    except ConnectionError as exc:
        return _error("run", _with_controller_reason(args.robot_ip, str(exc), "check --robot-ip"))
    except KeyboardInterrupt:
        print("tvist run: interrupted; the arm was stopped (servoStop, stopScript)")
        return 130
    except RuntimeError as exc:
        reason = _with_controller_reason(args.robot_ip, str(exc), "")
        print(f"tvist run: error: {reason}; the arm was stopped (servoStop, stopScript)")
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
        start, end = moving_span(Q)
        _print_settle(result.log_path, (end - start) * args.dt_s)
    if learner is not None:
        try:
            _learn_from_run(learner, Path(args.learn), Path(result.log_path))
        except (OSError, ValueError) as exc:
            return _error("run", f"--learn: {exc}")
    return 0


def _print_settle(log_path: Path, move_s: float) -> None:
    """Time to settled of the logged move, beside the move's own duration (the limit)."""
    from tvist.ident import read_rtde_csv
    from tvist.live import settle_times

    record = read_rtde_csv(log_path)
    times = settle_times(record.t_s, record.target_q, record.tool_accel)
    text = ", ".join(
        f"{band:g} m/s² after {t:.3f} s"
        if math.isfinite(t)
        else f"{band:g} m/s² not within the log"
        for band, t in times.items()
    )
    print(
        f"settled (tool acceleration, from the move's start): {text}; "
        f"the move itself {move_s:.3f} s"
    )


def _checked_reference(args: argparse.Namespace, Q, names, shaper):  # noqa: N803
    """The shaped reference ``tvist run`` would stream, after checking the file's rows and
    the shaped periods against the ``--robot`` model's units, joint limits and speed limits."""

    from tvist.cli.args import dt_s_from_args
    from tvist.live import shaped_reference
    from tvist.robots import params
    from tvist.units import check_trajectory

    dt_s_from_args(args)
    robot = params(args.robot)
    if Q.shape[1] != robot.n_dof:
        raise ValueError(
            f"{args.move}: {Q.shape[1]} joint columns, the {args.robot} has {robot.n_dof} "
            "(choose the robot with --robot)"
        )
    first = 2 if names else 1  # file rows as read_joint_csv counts them
    check_trajectory(
        Q, args.dt_s, robot, columns=names, row_label=lambda i: f"row {i + first}", what=args.move
    )
    shaped = shaped_reference(Q, shaper, args.dt_s)
    check_trajectory(
        shaped,
        args.dt_s,
        robot,
        columns=names,
        row_label=lambda i: f"period {i} (t = {i * args.dt_s:.3f} s)",
        what="the shaped reference",
    )
    return shaped


def _move_list_reference(args: argparse.Namespace):
    """``(planned, streamed)`` joint references of a move list (:mod:`tvist.move_list`),
    shaped in Cartesian space with ``--modes`` (or not, ``--unshaped``), checked against the
    ``--robot`` model's limits; prints the streamed path's deviation from the commanded
    lines."""
    from tvist.cli.args import dt_s_from_args, kinematic_robot
    from tvist.cli.shape import parse_modes
    from tvist.move_list import plan, read_move_list
    from tvist.units import check_trajectory

    dt_s_from_args(args)
    if args.map or args.paper_map:
        raise ValueError(
            "a move list is shaped in Cartesian space with fixed modes: give --modes "
            "(or --unshaped)"
        )
    if args.units is not None:
        raise ValueError("a move list is in SI units (m, rad, m/s, m/s²): leave out --units")
    robot = kinematic_robot(args)
    moves = read_move_list(args.move, robot.n_dof)
    modes = None if args.unshaped else parse_modes(args.modes)
    planned = plan(robot, moves, args.dt_s, modes, shaper=args.shaper)
    check_trajectory(
        planned.Q,
        args.dt_s,
        robot.params,
        row_label=lambda i: f"period {i} (t = {i * args.dt_s:.3f} s)",
        what="the move list's reference",
    )
    print(
        f"move list: {len(moves.moves)} linear move{'s' if len(moves.moves) != 1 else ''}, "
        f"{'shaped in Cartesian space' if modes else 'unshaped'}; path deviation "
        f"(flange, from the commanded lines): {planned.deviation_m * 1e3:.3f} mm"
    )
    return planned.Q_planned, planned.Q


def _controller_ready(robot_ip: str):
    """The controller's state, if the arm can move; ``ValueError`` with the controller's own
    account and the recovery if it cannot, ``OSError`` if it cannot be reached."""
    from tvist.controller_state import read_state

    try:
        state = read_state(robot_ip)
    except OSError as exc:
        raise OSError(
            f"cannot reach the controller at {robot_ip}: {exc} (check --robot-ip)"
        ) from None
    if not state.can_move:
        raise ValueError(
            f"the controller at {robot_ip} cannot move the arm: {state.describe()}; to recover, "
            f"{state.recovery()}; nothing was moved"
        )
    return state


def _with_controller_reason(robot_ip: str, message: str, otherwise: str) -> str:
    """``message`` with the controller's account of a stop and how to recover, if it reports
    one; else with ``otherwise`` (a hint) in parentheses."""
    from tvist.controller_state import read_state

    try:
        state = read_state(robot_ip)
    except (OSError, ValueError):
        state = None
    if state is not None and not state.can_move:
        return (
            f"{message}: the controller reports {state.describe()}; to recover, {state.recovery()}"
        )
    return f"{message} ({otherwise})" if otherwise else message


def _dry_run(args: argparse.Namespace, Q, shaped) -> int:  # noqa: N803
    """Print (and with ``--plot`` plot) what ``tvist run`` would stream; move nothing."""
    import numpy as np

    from tvist.analysis.path import path_deviation
    from tvist.cli.args import kinematic_robot
    from tvist.live import APPROACH_SPEED_RAD_S
    from tvist.units import joint_peaks

    robot = kinematic_robot(args)  # speed limits and the flange path: no payload needed
    dt = args.dt_s
    print(f"dry run of {args.move}: nothing is sent to a robot")
    print(
        f"the run would first move to row 1 with moveJ at {APPROACH_SPEED_RAD_S:g} rad/s, then "
        f"stream {shaped.shape[0]} servoJ periods ({shaped.shape[0] * dt:.3f} s; the file's "
        f"{Q.shape[0]} rows {'unshaped' if args.unshaped else 'shaped'}, "
        f"+{(shaped.shape[0] - Q.shape[0]) * dt * 1e3:.0f} ms)"
    )
    peaks = joint_peaks(shaped, dt)
    limits = robot.params.max_velocity_rad_s
    print("joint  peak speed / limit, rad/s    peak acceleration, rad/s²   peak jerk, rad/s³")
    for j in range(shaped.shape[1]):
        speed, share = peaks["speed"][j], 100 * peaks["speed"][j] / limits[j]
        print(
            f"  {j}    {speed:7.3f} / {limits[j]:.3f} ({share:3.0f} %)"
            f"    {peaks['acceleration'][j]:12.3f}              {peaks['jerk'][j]:12.1f}"
        )
    print(
        f"the {args.robot} model has speed limits only: judge the acceleration and jerk "
        "against your arm and payload"
    )
    planned = np.vstack([Q, np.repeat(Q[-1:], max(shaped.shape[0] - Q.shape[0], 0), axis=0)])
    dev = path_deviation(robot, planned, shaped)
    print(
        f"path deviation ({args.robot} flange): {dev.max_m * 1e3:.3f} mm at "
        f"{100 * dev.path_fraction:.0f} % of the planned path"
    )
    if args.plot:
        from tvist.cli.args import output_file

        plot = output_file(args.plot, "--plot")
        print(f"plot written to {_plot_reference(plot, Q, shaped, dt, limits)}")
    return 0


def _plot_reference(path: Path, Q, shaped, dt: float, limits) -> Path:  # noqa: N803
    """Joint positions (planned and shaped) and the shaped joint speeds against the limits."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np

    t_plan, t_shaped = dt * np.arange(Q.shape[0]), dt * np.arange(shaped.shape[0])
    speed = np.diff(shaped, axis=0) / dt
    fig, (top, bottom) = plt.subplots(2, 1, sharex=True, figsize=(8, 6))
    for j in range(shaped.shape[1]):
        (line,) = top.plot(t_shaped, shaped[:, j], label=f"joint {j}")
        top.plot(t_plan, Q[:, j], "--", color=line.get_color(), linewidth=0.8)
        bottom.plot(t_shaped[1:], speed[:, j], color=line.get_color())
        bottom.axhline(limits[j], color=line.get_color(), linestyle=":", linewidth=0.8)
        bottom.axhline(-limits[j], color=line.get_color(), linestyle=":", linewidth=0.8)
    top.set_ylabel("position, rad (dashed: planned)")
    bottom.set_ylabel("speed, rad/s (dotted: limits)")
    bottom.set_xlabel("time, s")
    top.legend(loc="best", fontsize="small")
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)
    return path


def _cmd_record(args: argparse.Namespace) -> int:
    from tvist.cli.args import output_file
    from tvist.live import record

    def started(recorder) -> None:
        print(
            f"recording {args.robot_ip} at {recorder.frequency_hz:g} Hz to {args.out}; "
            "Ctrl-C stops",
            flush=True,
        )

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
    from tvist.cli.args import add_allow_other_robot, add_robot_and_payload

    add_robot_and_payload(
        p,
        "payload mass for a map",
        payload_from="default: the controller's, read over RTDE (payload, payload_cog)",
    )
    add_allow_other_robot(p)


def add_run_command(sub: argparse._SubParsersAction) -> None:
    from tvist.cli.args import add_dt_s, add_units
    from tvist.live import SERVO_GAIN, SERVO_LOOKAHEAD_S

    p = sub.add_parser(
        "run",
        help="run a joint trajectory CSV on a UR with servoJ every control period, shaped live",
        description="Move to the CSV's first row with moveJ (0.5 rad/s, unshaped), then "
        "stream the rows with servoJ, shaped live by --map/--paper-map/--modes. A file "
        "written by 'tvist shape' is shaped already: run it with --unshaped. Frequencies "
        "are in Hz on the command line, rad/s in the Python API.",
    )
    p.add_argument(
        "move",
        help="CSV of joint positions (rad), one row per control period; or a move list "
        "(first row 'movej, q…', then 'movel, x, y, z, rx, ry, rz, v, a' rows), shaped in "
        "Cartesian space with --modes",
    )
    p.add_argument("--robot-ip", help="robot (or twin server) address (not with --dry-run)")
    modes = p.add_mutually_exclusive_group()
    modes.add_argument("--map", help="map file, paper10 or modal (tvist fit-map)")
    modes.add_argument("--paper-map", action="store_true", help="the paper's UR5e map")
    modes.add_argument(
        "--modes",
        help="fixed modes FREQ_HZ:ZETA,...: undamped natural frequency in Hz (not rad/s), "
        "damping ratio",
    )
    modes.add_argument(
        "--unshaped",
        action="store_true",
        help="stream the rows as they are (for a file 'tvist shape' has shaped already)",
    )
    p.add_argument("--shaper", default="zv", help="shaper per mode: zv, zvd, ei (default zv)")
    _add_payload(p)
    p.add_argument("--log", help="RTDE log to write (default MOVE.rtde.csv)")
    add_dt_s(p)
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
    p.add_argument(
        "--dry-run",
        action="store_true",
        help="check and describe the shaped reference (peak speed, acceleration, jerk, path "
        "deviation) without connecting to a robot",
    )
    p.add_argument("--plot", metavar="PNG", help="with --dry-run: plot the shaped reference here")
    p.add_argument(
        "--learn",
        metavar="MAP",
        help="after the move, learn from its log (as 'tvist learn') and update this modal map "
        "file if the learner accepts an update (the previous file kept as MAP.bak)",
    )
    add_units(p, ("q",))
    p.set_defaults(func=_cmd_run)


def add_record_command(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("record", help="record the RTDE fields identification needs (until Ctrl-C)")
    p.add_argument("--robot-ip", required=True, help="robot (or twin server) address")
    p.add_argument("--out", required=True, help="CSV to write (ur_rtde's format)")
    p.add_argument(
        "--frequency",
        type=float,
        default=None,
        help="RTDE output rate, Hz (default: the controller's, from the version it reports: "
        "500 on the e-Series, 125 on the CB-series)",
    )
    p.add_argument("--duration", type=float, default=None, help="stop after this many s")
    p.set_defaults(func=_cmd_record)
