"""Blended paths on the twin server, driven by the unmodified ur_rtde client: ``moveL(path)``
and ``movePath`` with blend radii, as in ur_rtde's own examples (movel_path_with_blend,
move_path_async).

A blend radius ``r`` at a via point means: the TCP leaves the segment arriving there when it
comes within ``r`` of the point and joins the next segment within ``r`` of it, without
stopping. Expected poses come from pinocchio's rigid model (``pinocchio_reference``), not from
the twin's kinematics; the TCP path is the forward kinematics of the target joints the
controller publishes at 500 Hz.
"""

from __future__ import annotations

import time

import numpy as np
import pytest

import test_twin_server_cartesian as cartesian
from test_twin_server_cartesian import HOME, assert_pose, fk
from twin_server_fixture import HOST, Subscriber

# The Cartesian tests' fixtures: the server, a client pair at HOME, the pinocchio model.
server, robot, reference = cartesian.server, cartesian.robot, cartesian.reference

rtde_control = pytest.importorskip("rtde_control")

#: End-pose tolerance a UR program expects (m and rad); the twin's moves end on IK solutions
#: converged to 1e-10, so anything near this bound is a real error.
END_TOL = 1e-4
#: Slowest TCP speed (m/s) accepted through a blend. A stop at the via point reads 0 (the
#: target stands still for at least one 2 ms tick); a blend between segments run at 0.5 m/s
#: turning by <= 90 degrees keeps at least cos(45 deg) of the blend speed, and the blend speed
#: itself is capped only by the segments' accelerations (>= 0.5 m/s² over >= 2 cm: >= 0.14 m/s).
MIN_BLEND_SPEED = 0.05


def _tcp_track(model, samples):
    """``(t, positions (n, 3), speeds (n-1,))`` of the target TCP along ``samples``."""
    t = np.array([s[0] for s in samples])
    keep = np.concatenate([[True], np.diff(t) > 0])  # a repeated package carries no motion
    t = t[keep]
    p = np.array([fk(model, s[1])[:3] for s, k in zip(samples, keep, strict=True) if k])
    speeds = np.linalg.norm(np.diff(p, axis=0), axis=1) / np.diff(t)
    return t, p, speeds


def _assert_blended(p, speeds, via, radius, before, after):
    """The track passes within ``radius`` of ``via`` without stopping in the blend zone, and
    does not go through ``via`` itself (it cuts the corner between ``before`` and ``after``)."""
    dist = np.linalg.norm(p - np.asarray(via), axis=1)
    inside = np.flatnonzero(dist < radius)
    assert inside.size > 0, f"the path never came within {radius} m of {via}"
    # Speeds between consecutive samples that are both in the blend zone.
    zone = [i for i in inside if i + 1 < len(p) and dist[i + 1] < radius]
    assert min(speeds[zone]) > MIN_BLEND_SPEED, "the TCP stopped in the blend zone"
    # A corner (the segments are not parallel) is cut: the closest approach stays away from
    # the via point (by far more than the 1e-6 m a rest-to-rest path reaches it within).
    d_in = np.asarray(via) - np.asarray(before)
    d_out = np.asarray(after) - np.asarray(via)
    cos = d_in @ d_out / np.linalg.norm(d_in) / np.linalg.norm(d_out)
    if cos < 0.99:
        assert dist.min() > 1e-4, "the path went through the via point (no blend)"


def _run(control, call) -> list:
    subscriber = Subscriber(HOST)
    try:
        assert call(control)
        subscriber.wait_for(1)
        return list(subscriber.samples)
    finally:
        subscriber.close()


@pytest.mark.slow
def test_movel_path_with_blend_example(robot, reference):
    """ur_rtde's movel_path_with_blend example: three poses, a 2 cm blend at the second."""
    control, receive = robot
    v, a = 0.5, 0.5
    path = [
        [-0.143, -0.435, 0.20, -0.001, 3.12, 0.04, v, a, 0.0],
        [-0.143, -0.51, 0.21, -0.001, 3.12, 0.04, v, a, 0.02],
        [-0.32, -0.61, 0.31, -0.001, 3.12, 0.04, v, a, 0.0],
    ]
    samples = _run(control, lambda c: c.moveL(path))
    assert_pose(fk(reference, receive.getTargetQ()), path[-1][:6], END_TOL)
    _, p, speeds = _tcp_track(reference, samples)
    # The first pose (r = 0) is reached at rest; the second is blended.
    assert np.linalg.norm(p - path[0][:3], axis=1).min() < 1e-6
    _assert_blended(p, speeds, path[1][:3], 0.02, path[0][:3], path[2][:3])
    assert control.isProgramRunning()


def _example_path():
    """ur_rtde's move_path_async example: moveJ to a pose, two linear moves and a joint move
    each blended with r = 0.099 m (just under half the 0.2 m segments), a joint move back."""
    kind = rtde_control.PathEntry
    v, a, r = 0.5, 4.0, 0.099
    poses = [
        (kind.MoveJ, [-0.140, -0.400, 0.100, 0, 3.14, 0], 0.0),
        (kind.MoveL, [-0.140, -0.400, 0.300, 0, 3.14, 0], r),
        (kind.MoveL, [-0.140, -0.600, 0.300, 0, 3.14, 0], r),
        (kind.MoveJ, [-0.140, -0.600, 0.100, 0, 3.14, 0], r),
        (kind.MoveJ, [-0.140, -0.400, 0.100, 0, 3.14, 0], 0.0),
    ]
    path = rtde_control.Path()
    for move, pose, blend in poses:
        path.addEntry(kind(move, kind.PositionTcpPose, [*pose, v, a, blend]))
    return path, [pose for _, pose, _ in poses]


@pytest.mark.slow
def test_move_path_async_example(robot, reference):
    control, receive = robot
    path, poses = _example_path()
    samples = _run(control, lambda c: c.movePath(path, False))
    assert_pose(fk(reference, receive.getTargetQ()), poses[-1], END_TOL)
    _, p, speeds = _tcp_track(reference, samples)
    positions = [np.array(pose[:3]) for pose in poses]
    for i in (1, 2, 3):
        _assert_blended(p, speeds, positions[i], 0.099, positions[i - 1], positions[i + 1])

    # Asynchronous: the progress counts the waypoints, then the path ends.
    assert control.moveJ(HOME, 1.5, 4.0)
    assert control.movePath(path, True)
    seen = []
    for _ in range(4000):
        progress = control.getAsyncOperationProgress()
        if progress < 0 and seen:
            break
        if progress >= 0 and (not seen or seen[-1] != progress):
            seen.append(progress)
        time.sleep(0.005)
    assert seen == [0, 1, 2, 3, 4]
    assert_pose(fk(reference, receive.getTargetQ()), poses[-1], END_TOL)
    assert control.isProgramRunning()


# Fast although above the slow criterion: the cheapest test of the server's blended paths
# (tvist.urserver.move_path, path_motion; docs/test-quality.md).
def test_overlapping_blends_are_shrunk_to_half_a_segment(robot, reference):
    """Blends of 5 cm on 6 cm segments would overlap: each is reduced to half its shorter
    neighbouring segment (3 cm), so the path still passes both via points without stopping
    and within 3 cm of each."""
    control, receive = robot
    start = fk(reference, HOME)
    rot = list(start[3:])
    v, a = 0.25, 1.2
    corners = [start[:3] + d for d in ([0.06, 0, 0], [0.06, 0.06, 0], [0.0, 0.06, 0])]
    path = [[*c, *rot, v, a, 0.05 if i < 2 else 0.0] for i, c in enumerate(corners)]
    samples = _run(control, lambda c: c.moveL(path))
    assert_pose(fk(reference, receive.getTargetQ()), path[-1][:6], END_TOL)
    _, p, speeds = _tcp_track(reference, samples)
    points = [start[:3], *corners]
    for i in (1, 2):
        _assert_blended(p, speeds, points[i], 0.03 + 1e-6, points[i - 1], points[i + 1])

    # Outside the reduced zones the TCP is on the segments (the blends start 3 cm from the
    # corners, not 5 cm): within 1e-6 m (IK converges to 1e-10; the poses ur_rtde writes
    # with 6 significant digits move the corners by < 5e-7 m).
    def off_path(x):
        gaps = []
        for a, b in zip(points[:-1], points[1:], strict=True):
            u = np.clip((x - a) @ (b - a) / ((b - a) @ (b - a)), 0.0, 1.0)
            gaps.append(np.linalg.norm(x - a - u * (b - a)))
        return min(gaps)

    outside = [x for x in p if min(np.linalg.norm(x - c) for c in corners[:2]) > 0.03 + 1e-4]
    assert max(off_path(x) for x in outside) < 1e-6


@pytest.mark.slow
def test_stopl_stops_a_blended_path_on_its_way(robot, reference):
    """stopL during an asynchronous blended path: the arm decelerates along the path and
    rests short of the end; the program keeps running and takes the next command."""
    control, receive = robot
    path, poses = _example_path()
    assert control.movePath(path, True)
    for _ in range(4000):  # until the path is past its first (joint) move
        if control.getAsyncOperationProgress() >= 2:
            break
        time.sleep(0.005)
    else:
        pytest.fail("the path did not reach its third waypoint")
    control.stopL(2.0)  # blocking (the binding returns nothing)
    assert control.getAsyncOperationProgress() < 0  # the path has ended
    q = np.array(receive.getTargetQ())
    time.sleep(0.1)
    np.testing.assert_array_equal(receive.getTargetQ(), q)  # at rest
    # Stopped between the waypoints it had reached and the end, not at the end.
    assert np.linalg.norm(fk(reference, q)[:3] - np.array(poses[-1][:3])) > 0.05
    assert control.isProgramRunning()
    assert control.moveJ(HOME, 1.5, 4.0)


@pytest.mark.slow
def test_movej_path_with_blend(robot, reference):
    """moveJ with a list of joint targets (ur_rtde sends it as a path of movej): the middle
    one blended with r = 5 cm, in joint space."""
    control, receive = robot
    v, a = 1.0, 2.0
    targets = [
        [0.3, -1.4, 1.4, -1.57, -1.57, 0.0],
        [0.3, -1.2, 1.8, -2.1, -1.57, 0.2],
        [-0.2, -1.3, 1.6, -1.8, -1.4, 0.0],
    ]
    path = [[*targets[0], v, a, 0.0], [*targets[1], v, a, 0.05], [*targets[2], v, a, 0.0]]
    samples = _run(control, lambda c: c.moveJ(path))
    np.testing.assert_allclose(receive.getTargetQ(), targets[-1], atol=1e-9)
    _, p, speeds = _tcp_track(reference, samples)
    corners = [fk(reference, q)[:3] for q in targets]
    _assert_blended(p, speeds, corners[1], 0.05, corners[0], corners[2])
