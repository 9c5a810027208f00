"""ROS 2 bags: a bag written with rosbags (sqlite3 and MCAP) is shaped by ``tvist shape --bag``
and read back; the shaped messages equal the library's shaping of the same waypoints and the
other topics are copied byte for byte."""

from __future__ import annotations

import numpy as np
import pytest

# rosbags is in the test extra: a missing install fails here instead of skipping.
from rosbags.rosbag2 import Reader, StoragePlugin, Writer
from rosbags.typesys import Stores, get_typestore

import tvist
from tvist.cli import main
from tvist.trajectory import PAPER_POSES, shape_waypoints
from tvist.trajectory.joint_names import UR_JOINT_NAMES

#: The default --dt-s: the --robot's (ur5e) control period, s (its robot data).
DT = tvist.robots.params("ur5e").control_period_s
TS = get_typestore(Stores.ROS2_HUMBLE)
JT = "trajectory_msgs/msg/JointTrajectory"
MODES_ARG = "8:0.2,7:0.3"
MODES = [(2 * np.pi * 8, 0.2), (2 * np.pi * 7, 0.3)]
# The joints in the message's order (as MoveIt may send them): not the robot's order.
MSG_ORDER = [2, 0, 1, 5, 3, 4]


def plan(scale: float):
    """Waypoints Q1 -> (part of the way to) Q3 with velocities, 9 points over 1.8 s: the
    elbow peaks at 2.7 rad/s, within the ur5e's 3.14 rad/s also once shaped (tvist shape
    refuses a shaped trajectory beyond the limit)."""
    q1, q3 = np.asarray(PAPER_POSES["Q1"]), np.asarray(PAPER_POSES["Q3"])
    t = np.linspace(0.0, 1.8, 9) + 0.05  # the first point is not at 0
    s = (t - t[0]) / 1.8
    q = q1 + scale * np.outer(s**3 * (10 - 15 * s + 6 * s**2), q3 - q1)
    v = scale * np.outer((30 * s**2 - 60 * s**3 + 30 * s**4) / 1.8, q3 - q1)
    return t, q, v


def trajectory_msg(t, q, v):
    Header = TS.types["std_msgs/msg/Header"]
    Time = TS.types["builtin_interfaces/msg/Time"]
    Duration = TS.types["builtin_interfaces/msg/Duration"]
    Point = TS.types["trajectory_msgs/msg/JointTrajectoryPoint"]
    points = []
    for tk, qk, vk in zip(t, q, v, strict=True):
        ns = int(round(tk * 1e9))
        points.append(
            Point(
                positions=qk[MSG_ORDER].copy(),
                velocities=vk[MSG_ORDER].copy(),
                accelerations=np.zeros(0),
                effort=np.zeros(0),
                time_from_start=Duration(sec=ns // 10**9, nanosec=ns % 10**9),
            )
        )
    return TS.types[JT](
        header=Header(stamp=Time(sec=12, nanosec=34), frame_id="base"),
        joint_names=["ur5e_" + UR_JOINT_NAMES[j] for j in MSG_ORDER],
        points=points,
    )


def write_bag(path, plugin):
    String = TS.types["std_msgs/msg/String"]
    with Writer(path, version=9, storage_plugin=plugin) as w:
        traj = w.add_connection("/joint_trajectory", JT, typestore=TS)
        note = w.add_connection("/note", "std_msgs/msg/String", typestore=TS)
        w.write(note, 1_000, TS.serialize_cdr(String(data="before"), "std_msgs/msg/String"))
        for k, scale in enumerate((1.0, 0.5)):
            w.write(traj, 2_000 + k, TS.serialize_cdr(trajectory_msg(*plan(scale)), JT))
        w.write(note, 5_000, TS.serialize_cdr(String(data="after"), "std_msgs/msg/String"))


def read_bag(path):
    with Reader(path) as r:
        return [(c.topic, stamp, raw) for c, stamp, raw in r.messages()]


@pytest.mark.parametrize("plugin", [StoragePlugin.SQLITE3, StoragePlugin.MCAP])
def test_bag_round_trip(tmp_path, plugin, capsys):
    src, dst = tmp_path / "in", tmp_path / "out"
    write_bag(src, plugin)
    args = ["shape", "--bag", str(src), "--topic", "/joint_trajectory", "--out", str(dst)]
    assert main([*args, "--modes", MODES_ARG]) == 0
    said = capsys.readouterr().out
    assert said.count("waypoints ->") == 2 and "matched by UR joint name" in said
    before, after = read_bag(src), read_bag(dst)
    assert [(t, s) for t, s, _ in after] == [(t, s) for t, s, _ in before]
    suffix = ".mcap" if plugin == StoragePlugin.MCAP else ".db3"
    assert any(p.suffix == suffix for p in dst.iterdir())
    for (topic, _, raw_in), (_, _, raw_out), scale in zip(
        before, after, (None, 1.0, 0.5, None), strict=True
    ):
        if topic == "/note":
            assert raw_out == raw_in  # copied unchanged
            continue
        msg_in = TS.deserialize_cdr(raw_in, JT)
        msg = TS.deserialize_cdr(raw_out, JT)
        assert msg.joint_names == msg_in.joint_names
        assert (msg.header.stamp.sec, msg.header.frame_id) == (12, "base")
        t_wp, q, v = plan(scale)
        ref = shape_waypoints(t_wp, q, DT, MODES, velocities=v)
        stamps = [p.time_from_start for p in msg.points]
        times = np.array([d.sec + 1e-9 * d.nanosec for d in stamps])
        positions = np.array([p.positions for p in msg.points])
        velocities = np.array([p.velocities for p in msg.points])
        # Time stamps are whole nanoseconds: within 0.5 ns of the grid starting at 0.05 s.
        np.testing.assert_allclose(times, ref.t_s, rtol=0, atol=6e-10)
        assert times[0] == pytest.approx(0.05, abs=1e-9)
        # Positions in the message's joint order, equal to the library's result. The message
        # carries whole-nanosecond waypoint times, so the grid shifts by < 0.5 ns: at most
        # 3 rad/s x 0.5 ns = 1.5e-9 rad (measured 1.3e-15, the times happen to be exact).
        np.testing.assert_allclose(positions, ref.q[:, MSG_ORDER], rtol=0, atol=1e-8)
        np.testing.assert_allclose(velocities, ref.qd[:, MSG_ORDER], rtol=0, atol=1e-6)
        # The shaped trajectory ends at the last waypoint's pose.
        np.testing.assert_allclose(positions[-1], q[-1][MSG_ORDER], atol=1e-12)
        assert ref.added_delay_s > sum(tvist.shaper("zv", w, z).duration_s for w, z in MODES)


def test_bag_errors_name_the_problem(tmp_path, capsys):
    src = tmp_path / "in"
    write_bag(src, StoragePlugin.SQLITE3)
    base = ["shape", "--bag", str(src), "--modes", MODES_ARG]
    cases = [
        (["--topic", "/nope", "--out", str(tmp_path / "o1")], "no topic '/nope'"),
        (["--topic", "/note", "--out", str(tmp_path / "o2")], "carries std_msgs/msg/String"),
        (["--topic", "/joint_trajectory", "--out", str(src)], "exists"),
        (["--out", str(tmp_path / "o3")], "--topic"),
    ]
    for extra, message in cases:
        assert main([*base, *extra]) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and err[0].startswith("tvist shape: error: "), err
        assert message in err[0]


def test_zero_delay_method_in_a_bag_ends_at_the_last_waypoint(tmp_path):
    src, dst = tmp_path / "in", tmp_path / "out"
    write_bag(src, StoragePlugin.MCAP)
    args = ["shape", "--bag", str(src), "--topic", "/joint_trajectory", "--out", str(dst)]
    assert main([*args, "--modes", MODES_ARG, "--method", "modified"]) == 0
    shaped = [TS.deserialize_cdr(raw, JT) for topic, _, raw in read_bag(dst) if topic != "/note"]
    for msg, scale in zip(shaped, (1.0, 0.5), strict=True):
        t_wp, q, v = plan(scale)
        ref = shape_waypoints(t_wp, q, DT, MODES, velocities=v, method="modified")
        positions = np.array([p.positions for p in msg.points])
        np.testing.assert_allclose(positions, ref.q[:, MSG_ORDER], rtol=0, atol=1e-8)
        last = msg.points[-1].time_from_start
        assert last.sec + 1e-9 * last.nanosec == pytest.approx(t_wp[-1], abs=1e-9)


def test_a_bag_in_degrees_or_beyond_the_limits_is_refused(tmp_path, capsys):
    """Positions in degrees (ROS uses rad), or a point beyond the elbow's limit on the ur5e
    (π rad), are refused naming the message, the point and the joint."""
    t, q, v = plan(1.0)
    elbow_beyond = q.copy()
    elbow_beyond[4, 2] = 3.5
    cases = [
        (np.degrees(q), np.degrees(v), "point 0, column ur5e_shoulder_lift_joint: -180"),
        (elbow_beyond, v, "point 4, column ur5e_elbow_joint: 3.5 rad is outside joint 2's"),
    ]
    for k, (positions, velocities, message) in enumerate(cases):
        src = tmp_path / f"in{k}"
        with Writer(src, version=9, storage_plugin=StoragePlugin.SQLITE3) as w:
            conn = w.add_connection("/joint_trajectory", JT, typestore=TS)
            w.write(conn, 2_000, TS.serialize_cdr(trajectory_msg(t, positions, velocities), JT))
        args = ["shape", "--bag", str(src), "--topic", "/joint_trajectory", "--modes", MODES_ARG]
        assert main([*args, "--out", str(tmp_path / f"out{k}")]) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and "message at 2000 ns on /joint_trajectory" in err[0], err
        assert message in err[0], err
