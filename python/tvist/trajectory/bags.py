"""Shaping the ``trajectory_msgs/msg/JointTrajectory`` messages of a ROS 2 bag.

Uses the ``rosbags`` library (``pip install tvist[ros]``; no ROS installation). Every
JointTrajectory on the chosen topic is resampled to the control grid, shaped
(:func:`~tvist.trajectory.shape_waypoints`) and written to a new bag as a message with one
point per control period (positions and velocities); all other messages are copied byte for
byte. Both storage formats of ROS 2 bags, sqlite3 and MCAP, are read, and the output uses the
input's format.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from tvist.trajectory.joint_names import joint_order
from tvist.trajectory.shaping import shape_waypoints
from tvist.units import check_trajectory

__all__ = ["JOINT_TRAJECTORY", "ShapedMessage", "shape_bag"]

#: The message type that is shaped.
JOINT_TRAJECTORY = "trajectory_msgs/msg/JointTrajectory"


@dataclass(frozen=True)
class ShapedMessage:
    """One shaped message: bag time stamp (ns), waypoints in, points out, and the shaping."""

    timestamp_ns: int
    n_waypoints: int
    n_points: int
    added_delay_s: float
    alpha: float
    matched: str
    path_deviation_m: float | None = None


def _rosbags():
    try:
        from rosbags.rosbag2 import Reader, StoragePlugin, Writer
        from rosbags.typesys import Stores, get_typestore
    except ImportError:
        raise ValueError(
            "reading ROS 2 bags needs the rosbags library: pip install 'tvist[ros]'"
        ) from None
    return Reader, Writer, StoragePlugin, get_typestore(Stores.ROS2_HUMBLE)


def _duration_s(d: Any) -> float:
    return float(d.sec) + 1e-9 * float(d.nanosec)


def _duration(typestore, t_s: float):
    Duration = typestore.types["builtin_interfaces/msg/Duration"]
    ns = int(round(t_s * 1e9))
    return Duration(sec=ns // 1_000_000_000, nanosec=ns % 1_000_000_000)


def _waypoint_array(points, field: str, n_joints: int) -> np.ndarray | None:
    rows = [np.asarray(getattr(p, field), dtype=float) for p in points]
    if all(r.size == 0 for r in rows):
        return None
    if any(r.shape != (n_joints,) for r in rows):
        raise ValueError(
            f"JointTrajectory: every point must have {n_joints} {field} (or none at all)"
        )
    return np.vstack(rows)


def _shape_message(msg, typestore, dt_s: float, dynamics, n_dof: int | None, robot, **kwargs):
    names = list(msg.joint_names)
    if not msg.points:
        raise ValueError("JointTrajectory without points")
    n_joints = len(names)
    order, how = joint_order(names, n_dof if n_dof is not None else n_joints)
    times = np.array([_duration_s(p.time_from_start) for p in msg.points])
    arrays = {f: _waypoint_array(msg.points, f, n_joints) for f in ("positions", "velocities")}
    arrays["accelerations"] = (
        _waypoint_array(msg.points, "accelerations", n_joints)
        if arrays["velocities"] is not None
        else None
    )
    if arrays["positions"] is None:
        raise ValueError("JointTrajectory points without positions")
    ordered = {k: (None if v is None else v[:, order]) for k, v in arrays.items()}
    limits = None if robot is None else robot.params
    columns = [names[i] for i in order]
    check_trajectory(
        ordered["positions"], None, limits, columns=columns, row_label=lambda i: f"point {i}"
    )
    shaped = shape_waypoints(
        times,
        ordered["positions"],
        dt_s,
        dynamics,
        velocities=ordered["velocities"],
        accelerations=ordered["accelerations"],
        **kwargs,
    )
    check_trajectory(
        shaped.q,
        dt_s,
        limits,
        columns=columns,
        row_label=lambda i: f"shaped point {i}",
        what="the shaped trajectory",
    )
    deviation = None
    if robot is not None:
        from tvist.analysis.path import path_deviation

        deviation = path_deviation(robot, shaped.planned, shaped.q).max_m
    inverse = np.argsort(order)
    Point = typestore.types["trajectory_msgs/msg/JointTrajectoryPoint"]
    empty = np.zeros(0)
    points = [
        Point(
            positions=np.ascontiguousarray(shaped.q[k, inverse]),
            velocities=np.ascontiguousarray(shaped.qd[k, inverse]),
            accelerations=empty,
            effort=empty,
            time_from_start=_duration(typestore, float(shaped.t_s[k])),
        )
        for k in range(shaped.t_s.shape[0])
    ]
    out = type(msg)(header=msg.header, joint_names=names, points=points)
    info = (len(msg.points), len(points), shaped.added_delay_s, shaped.alpha, how, deviation)
    return out, info


def shape_bag(
    in_path: str | Path,
    out_path: str | Path,
    topic: str,
    dt_s: float,
    dynamics: Any,
    *,
    robot=None,
    n_dof: int | None = None,
    **kwargs: Any,
) -> list[ShapedMessage]:
    """Shape every JointTrajectory on ``topic`` of the bag ``in_path`` into ``out_path``.

    Parameters
    ----------
    in_path
        ROS 2 bag directory (sqlite3 or MCAP storage).
    out_path
        New bag directory (must not exist); same storage format as the input.
    topic
        Topic of ``trajectory_msgs/msg/JointTrajectory`` messages.
    dt_s
        Control period the trajectories are resampled to, s.
    dynamics
        Modes or provider, as :func:`~tvist.trajectory.shape_waypoints` takes them.
    robot
        Robot model: joints are matched to it by name and the path deviation is reported.
    n_dof
        Joints of the robot when no ``robot`` is given (default: as many as the message has).
    **kwargs
        ``method``, ``shaper``, ``interp``, ``max_delay_s`` of
        :func:`~tvist.trajectory.shape_waypoints`.

    Returns
    -------
    list[ShapedMessage]
        One entry per shaped message, in bag order.

    Raises
    ------
    ValueError
        rosbags missing, ``out_path`` exists, the topic is missing or carries another type,
        or a message that cannot be shaped (the message's bag time stamp is named).
    """
    Reader, Writer, StoragePlugin, typestore = _rosbags()
    in_path, out_path = Path(in_path), Path(out_path)
    if out_path.exists():
        raise ValueError(f"{out_path} exists; choose another output bag (rosbags never overwrites)")
    if robot is not None:
        n_dof = robot.n_dof
    reports: list[ShapedMessage] = []
    with Reader(in_path) as reader:
        topics = {c.topic: c.msgtype for c in reader.connections}
        if topic not in topics:
            raise ValueError(f"{in_path}: no topic {topic!r}; the bag has {sorted(topics)}")
        if topics[topic] != JOINT_TRAJECTORY:
            raise ValueError(
                f"{in_path}: topic {topic!r} carries {topics[topic]}, not {JOINT_TRAJECTORY}"
            )
        mcap = any(p.suffix == ".mcap" for p in in_path.glob("*")) or in_path.suffix == ".mcap"
        plugin = StoragePlugin.MCAP if mcap else StoragePlugin.SQLITE3
        with Writer(out_path, version=Writer.VERSION_LATEST, storage_plugin=plugin) as writer:
            out_conn = {}
            for c in reader.connections:
                kwargs_conn: dict[str, Any] = {
                    "serialization_format": c.ext.serialization_format,
                    "offered_qos_profiles": c.ext.offered_qos_profiles,
                }
                if c.msgdef.data and c.digest:
                    kwargs_conn.update(msgdef=c.msgdef.data, rihs01=c.digest)
                else:
                    kwargs_conn["typestore"] = typestore
                out_conn[c.id] = writer.add_connection(c.topic, c.msgtype, **kwargs_conn)
            for conn, stamp, raw in reader.messages():
                if conn.topic != topic:
                    writer.write(out_conn[conn.id], stamp, raw)
                    continue
                msg = typestore.deserialize_cdr(raw, conn.msgtype)
                try:
                    shaped, info = _shape_message(
                        msg, typestore, dt_s, dynamics, n_dof, robot, **kwargs
                    )
                except ValueError as e:
                    raise ValueError(f"{in_path}: message at {stamp} ns on {topic}: {e}") from None
                raw_out = typestore.serialize_cdr(shaped, conn.msgtype)
                writer.write(out_conn[conn.id], stamp, raw_out)
                reports.append(ShapedMessage(stamp, *info))
    if not reports:
        raise ValueError(f"{in_path}: no messages on {topic!r}")
    return reports
