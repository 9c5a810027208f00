"""``tvist shape``: shape a planned or recorded joint trajectory offline (CSV file or ROS 2 bag).

CSV input: one row per sample or waypoint, joint positions in rad, with or without a header
row (comma- or whitespace-separated). Columns:

- a **time column** named ``time``, ``t``, ``time_s`` or ``time_from_start`` (s) is never
  shaped: the rows are waypoints at those times, resampled to ``--dt-s``
  (:func:`tvist.trajectory.resample`, a C² spline at rest at both ends) and the output has a
  ``time_s`` column; without one, rows are samples every ``--dt-s``. The command says which.
- **joint columns** are matched to the robot by name (UR joint names, or numbered names such
  as ``q0 … q5``); an RTDE log (``target_q_0 …``) is read through its ``target_q`` columns.

ROS 2 bag input (``--bag IN --topic T``, needs ``pip install tvist[ros]``): every
``trajectory_msgs/msg/JointTrajectory`` on the topic is resampled, shaped and written to a new
bag; other topics are copied unchanged (:func:`tvist.trajectory.bags.shape_bag`).

Methods: ``tvist`` (multi-mode FD-TVIST: the output is longer by the shaper delay at the end
pose), ``ztdis`` / ``modified`` (zero added delay, same length; rest padding is kept and only
the motion is compressed). Modes come from ``--modes`` (fixed, ``FREQ_HZ:ZETA,...``) or from
a map (``--map FILE``, paper10 or modal, or ``--paper-map``) with the robot model (``--robot``,
``--payload-kg``, ``--payload-com X Y Z``; without ``--payload-kg`` the map file's payload, if
it names one; otherwise the command stops). The largest distance of the shaped tool path from
the planned one (:func:`tvist.analysis.path_deviation`) is reported for the ``--robot`` model.
Frequencies on the command line are in Hz (``--modes``, the printed modes: undamped natural
frequencies f_n = ω_n / 2π); the Python API takes ω_n in rad/s.

The output is already shaped: run it on a robot with ``tvist run OUT --unshaped`` (shaping it
again would add a second delay and filter the modes twice).
"""

from __future__ import annotations

import argparse
import csv
import io
import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from tvist.cli.args import (
    add_allow_other_robot,
    add_dt_s,
    add_robot_and_payload,
    add_units,
    dt_s_from_args,
    existing_dir,
    existing_file,
    kinematic_robot,
    map_dynamics,
    map_from_args,
    map_payload,
    output_file,
    payload_from_args,
    robot_from_args,
)
from tvist.trajectory.joint_names import joint_order
from tvist.trajectory.shaping import METHODS, shape_samples

__all__ = [
    "METHODS",
    "TIME_COLUMNS",
    "JointFile",
    "ShapedFile",
    "parse_modes",
    "read_joint_csv",
    "read_trajectory_csv",
    "shape_file",
]

#: Header names (case-insensitive) of a time column, s.
TIME_COLUMNS = ("time", "t", "time_s", "time_from_start")


@dataclass(frozen=True)
class ShapedFile:
    """What :func:`shape_file` did: output array, the delay added and the provider's modes."""

    Q: np.ndarray
    added_delay_s: float
    end_modes: list[tuple[float, float]]
    status_counts: dict[str, int]
    alpha: float = float("nan")


@dataclass(frozen=True)
class JointFile:
    """A trajectory file: joint positions, their column names and an optional time column.

    ``Q`` is ``(n_rows, n_joints)`` rad in file column order; ``times_s`` ``(n_rows,)`` or
    ``None``; ``names`` the joint column names (``None`` without a header); ``time_name`` the
    time column's name as written in the file.
    """

    Q: np.ndarray
    names: list[str] | None
    times_s: np.ndarray | None = None
    time_name: str | None = None


def _rows(path: Path) -> list[list[str]]:
    try:
        text = path.read_text(encoding="utf-8-sig")
    except UnicodeDecodeError as e:
        raise ValueError(f"{path}: not a UTF-8 text file (byte {e.start})") from None
    lines = [ln for ln in text.splitlines() if ln.strip() and not ln.lstrip().startswith("#")]
    if not lines:
        raise ValueError(f"{path}: empty file")
    if "," in lines[0]:
        return [[c.strip() for c in row] for row in csv.reader(io.StringIO("\n".join(lines)))]
    return [ln.split() for ln in lines]


def read_trajectory_csv(path: str | Path) -> JointFile:
    """Read a joint trajectory CSV (see the module docstring). Errors name the file and row."""
    path = Path(path)
    rows = _rows(path)
    try:
        [float(c) for c in rows[0]]
        header = None
    except ValueError:
        header = rows[0]
    body = rows if header is None else rows[1:]
    width = len(rows[0])
    data = np.empty((len(body), width))
    first_row = 1 if header is None else 2
    for i, row in enumerate(body):
        if len(row) != width:
            raise ValueError(
                f"{path}: row {i + first_row} has {len(row)} fields, the first row {width}"
            )
        try:
            data[i] = [float(c) for c in row]
        except ValueError:
            raise ValueError(f"{path}: row {i + first_row} is not numeric: {row}") from None
    bad = np.flatnonzero(~np.all(np.isfinite(data), axis=1))
    if bad.size:
        raise ValueError(f"{path}: non-finite value in data row {int(bad[0]) + 1}")
    if data.shape[0] < 2:
        raise ValueError(f"{path}: needs at least 2 rows of data, got {data.shape[0]}")
    if header is None:
        return JointFile(data, None)
    if len(set(header)) != len(header):
        dup = next(h for h in header if header.count(h) > 1)
        raise ValueError(f"{path}: column {dup!r} appears more than once")
    if "target_q_0" in header:  # an RTDE log: its commanded joint positions
        cols = [header.index(f"target_q_{j}") for j in range(6) if f"target_q_{j}" in header]
        return JointFile(data[:, cols], [header[c] for c in cols])
    time_cols = [i for i, h in enumerate(header) if h.lower() in TIME_COLUMNS]
    if len(time_cols) > 1:
        raise ValueError(f"{path}: several time columns {[header[i] for i in time_cols]}; keep one")
    joints = [i for i in range(width) if i not in time_cols]
    if not joints:
        raise ValueError(f"{path}: no joint columns besides the time column")
    times = data[:, time_cols[0]] if time_cols else None
    return JointFile(
        data[:, joints],
        [header[i] for i in joints],
        times,
        header[time_cols[0]] if time_cols else None,
    )


def read_joint_csv(path: str | Path) -> tuple[np.ndarray, list[str] | None]:
    """Joint positions ``(n_rows, n_joints)`` and their names (``None`` without a header).

    A time column is not a joint: it is left out (see :func:`read_trajectory_csv`).
    """
    f = read_trajectory_csv(path)
    return f.Q, f.names


def parse_modes(text: str) -> list[tuple[float, float]]:
    """``"8.0:0.26,6.9:0.37"`` (Hz:zeta) -> ``[(wn_rad_s, zeta), ...]``."""
    modes = []
    for item in text.split(","):
        try:
            freq_hz, zeta = (float(v) for v in item.split(":"))
        except ValueError:
            raise ValueError(f"--modes: {item!r} is not FREQ_HZ:ZETA") from None
        modes.append((2.0 * np.pi * freq_hz, zeta))
    return modes


def shape_file(
    Q: np.ndarray,
    dt_s: float,
    method: str,
    *,
    shaper: str = "zv",
    modes: list[tuple[float, float]] | None = None,
    robot=None,
    dynmap=None,
) -> ShapedFile:
    """Shape samples ``Q`` with ``method``: fixed ``modes``, or a ``robot`` with a ``dynmap``."""
    import tvist

    if method not in METHODS:
        raise ValueError(f"unknown method {method!r}; expected one of {METHODS}")
    if (modes is None) == (dynmap is None or robot is None):
        raise ValueError("give either fixed modes or a robot with a dynamic map")
    dynamics = modes if modes is not None else tvist.dynamics_for(robot, dynmap)
    out, added, end_modes, alpha, counts = shape_samples(
        Q, dt_s, dynamics, method=method, shaper=shaper
    )
    return ShapedFile(out, added, end_modes, counts, alpha)


def _robot_and_dynamics(args: argparse.Namespace):
    """The ``--robot`` model and the fixed modes, or the map provider for it with its payload
    (``--payload-kg`` or the map file's, printed; the kinematics of the path deviation do not
    depend on the payload)."""
    if args.modes:
        return kinematic_robot(args), parse_modes(args.modes)
    if not (args.map or args.paper_map):
        raise ValueError("give --modes, --map FILE or --paper-map")
    dynmap = map_from_args(args)
    payload_from_args(
        args, ("the map file", lambda: map_payload(dynmap)), needed_for="shaping with a map"
    )
    robot = robot_from_args(args)
    return robot, map_dynamics(args, robot, dynmap)


def _describe_modes(end_modes: list[tuple[float, float]]) -> str:
    """Modes as the command line takes them: undamped natural frequency f_n (Hz) and ζ."""
    return ", ".join(f"f_n {w / (2 * np.pi):.2f} Hz / ζ {z:.3f}" for w, z in end_modes)


def _cmd_shape_csv(args: argparse.Namespace, robot, dynamics) -> int:
    from tvist.analysis.path import path_deviation
    from tvist.trajectory import resample
    from tvist.units import UNITS, check_trajectory, parse_units

    f = read_trajectory_csv(existing_file(args.input, "input"))
    output_file(args.out, "--out")
    unit = parse_units(args.units, ("q",))["q"]
    factor = UNITS["q"][unit]  # the output is written in the input's unit
    n_joints = f.Q.shape[1]
    uses_map = not args.modes
    if uses_map and n_joints != robot.n_dof:
        raise ValueError(
            f"the file has {n_joints} joint columns, the {args.robot} has {robot.n_dof} "
            "(choose the robot with --robot)"
        )
    order, how = list(range(n_joints)), "in file order"
    if f.names is not None and n_joints == robot.n_dof:
        order, how = joint_order(f.names, robot.n_dof)
    print(f"joint columns matched {how}" + (f": {[f.names[i] for i in order]}" if f.names else ""))
    Q = f.Q[:, order] * factor
    limits = robot.params if n_joints == robot.n_dof else None
    joint_names = None if f.names is None else [f.names[i] for i in order]
    first = 1 if f.names is None else 2  # file rows as read_trajectory_csv counts them
    check_trajectory(
        Q,
        None if f.times_s is not None else args.dt_s,
        limits,
        columns=joint_names,
        row_label=lambda i: f"row {i + first}",
        what=str(args.input),
    )
    if f.times_s is not None:
        t, Q = resample(f.times_s, Q, args.dt_s)
        print(
            f"time column {f.time_name!r}: {f.Q.shape[0]} waypoints over "
            f"{f.times_s[-1] - f.times_s[0]:.4g} s resampled to --dt-s {args.dt_s:g} s "
            f"({Q.shape[0]} samples, C² spline at rest at both ends)"
        )
    else:
        t = None
        print(
            f"no time column (time, t, time_s or time_from_start): rows taken as samples "
            f"every --dt-s {args.dt_s:g} s"
        )
        check_trajectory(
            Q,
            args.dt_s,
            limits,
            columns=joint_names,
            row_label=lambda i: f"sample {i} (t = {t[i]:.4g} s)",
            what="the resampled waypoints",
        )
    shaped_q, added, end_modes, alpha, counts = shape_samples(
        Q, args.dt_s, dynamics, method=args.method, shaper=args.shaper
    )
    check_trajectory(
        shaped_q,
        args.dt_s,
        limits,
        columns=joint_names,
        row_label=lambda i: f"output row {i + first}",
        what=f"the {args.method}-shaped trajectory",
    )
    if unit != "rad":
        print(f"--units q={unit}: the joint columns are read and written in {unit}")
    inverse = np.argsort(order)
    columns = shaped_q[:, inverse] / factor
    names = None if f.names is None else list(f.names)
    if t is not None:
        t_out = t[0] + args.dt_s * np.arange(shaped_q.shape[0])
        columns = np.column_stack([t_out, columns])
        names = ["time_s"] + (names or [f"q{j}" for j in range(n_joints)])
    np.savetxt(
        args.out,
        columns,
        delimiter=",",
        fmt="%.9f",
        header=",".join(names) if names else "",
        comments="",
    )
    extra = f", alpha {alpha:.4f}" if np.isfinite(alpha) else ""
    print(f"{args.method}: modes at the end pose {_describe_modes(end_modes)}{extra}")
    print(f"wrote {shaped_q.shape[0]} samples to {args.out} (+{added * 1e3:.0f} ms)")
    if n_joints == robot.n_dof:
        planned = np.vstack([Q, np.repeat(Q[-1:], shaped_q.shape[0] - Q.shape[0], axis=0)])
        dev = path_deviation(robot, planned, shaped_q)
        print(
            f"path deviation ({args.robot} flange): {dev.max_m * 1e3:.3f} mm at "
            f"{100 * dev.path_fraction:.0f} % of the planned path"
        )
    else:
        print(
            f"path deviation: not computed (the file has {n_joints} joints, the {args.robot} "
            f"{robot.n_dof}; choose the robot with --robot)"
        )
    if any(counts.values()):
        print(f"status counts: {counts}")
    return 0


def _cmd_shape_bag(args: argparse.Namespace, robot, dynamics) -> int:
    from tvist.trajectory.bags import shape_bag

    if not args.topic:
        raise ValueError("--bag needs --topic (the JointTrajectory topic, e.g. /joint_trajectory)")
    reports = shape_bag(
        existing_dir(args.bag, "--bag"),
        args.out,
        args.topic,
        args.dt_s,
        dynamics,
        robot=robot,
        method=args.method,
        shaper=args.shaper,
    )
    for r in reports:
        extra = f", alpha {r.alpha:.4f}" if np.isfinite(r.alpha) else ""
        print(
            f"{args.topic} @ {r.timestamp_ns} ns: {r.n_waypoints} waypoints -> {r.n_points} "
            f"points at --dt-s {args.dt_s:g} s (+{r.added_delay_s * 1e3:.0f} ms{extra}), joints "
            f"matched {r.matched}, path deviation {r.path_deviation_m * 1e3:.3f} mm"
        )
    print(f"wrote {args.out} ({len(reports)} shaped messages, other topics copied)")
    return 0


def _cmd_shape(args: argparse.Namespace) -> int:
    if (args.input is None) == (args.bag is None):
        raise ValueError("give a CSV file or --bag BAG (one of them)")
    dt_s_from_args(args)
    if args.bag is None:  # the files first, then the payload (which may come from the map)
        existing_file(args.input, "input")
        output_file(args.out, "--out")
    else:
        existing_dir(args.bag, "--bag")
    import warnings

    from tvist.maps.paper10 import MapRangeWarning

    robot, dynamics = _robot_and_dynamics(args)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", MapRangeWarning)
        if args.bag is not None:
            code = _cmd_shape_bag(args, robot, dynamics)
        else:
            code = _cmd_shape_csv(args, robot, dynamics)
    ranges = [w for w in caught if issubclass(w.category, MapRangeWarning)]
    if ranges:  # once per run, however many trajectories (bag messages) were shaped
        more = f" (and in {len(ranges) - 1} more trajectories)" if len(ranges) > 1 else ""
        print(f"tvist shape: warning: {ranges[0].message}{more}", file=sys.stderr)
    for w in caught:
        if not issubclass(w.category, MapRangeWarning):
            warnings.showwarning(w.message, w.category, w.filename, w.lineno)
    return code


def add_shape_command(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "shape",
        help="shape a joint trajectory (CSV, with or without times, or a ROS 2 bag)",
        description="Shape a joint trajectory offline. Frequencies are in Hz on the command "
        "line (undamped natural frequencies), rad/s in the Python API. The output is "
        "shaped already: run it with 'tvist run OUT --robot-ip IP --unshaped'.",
    )
    p.add_argument(
        "input",
        nargs="?",
        help="CSV of joint positions (rad); a time/t/time_s/time_from_start column marks "
        "waypoints to resample",
    )
    p.add_argument("--bag", help="ROS 2 bag directory to shape instead of a CSV (tvist[ros])")
    p.add_argument("--topic", help="JointTrajectory topic of --bag (e.g. /joint_trajectory)")
    p.add_argument("--out", required=True, help="output CSV (or bag directory with --bag)")
    add_dt_s(p)
    p.add_argument("--method", choices=METHODS, default="tvist", help="default tvist")
    p.add_argument("--shaper", default="zv", help="registry shaper name (default zv)")
    source = p.add_mutually_exclusive_group()
    source.add_argument(
        "--modes",
        help="fixed modes FREQ_HZ:ZETA,...: undamped natural frequency in Hz (not rad/s), "
        "damping ratio",
    )
    source.add_argument(
        "--map", help="map file, paper10 or modal (tvist fit-map, DynamicMap/ModalMap.save)"
    )
    source.add_argument("--paper-map", action="store_true", help="the paper's UR5e map")
    add_allow_other_robot(p)
    add_robot_and_payload(p, payload_from="with a map: required unless the map file names one")
    add_units(p, ("q",))
    p.set_defaults(func=_cmd_shape)
