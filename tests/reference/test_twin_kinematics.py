"""The twin controller's kinematics services against pinocchio (an independent rigid model
built from the DH table, see ``pinocchio_reference``) and the tool-space motions' profiles."""

from __future__ import annotations

import numpy as np
import pytest

import tvist
from pinocchio_reference import pinocchio_model
from tvist.robots import Payload
from tvist.urserver.kinematics import Kinematics, pose_trans
from tvist.urserver.motion import CommandRefused, JointMotion
from tvist.urserver.tool_motion import LinearMove, ToolSpeed

pin = pytest.importorskip("pinocchio")

#: Random poses are drawn in this box of joint angles: the usual working range of an arm
#: (elbow bent away from its singular straight position, wrist 2 away from 0).
Q_LOW = np.array([-np.pi, -2.8, 0.4, -np.pi, 0.4, -np.pi])
Q_HIGH = np.array([np.pi, -0.3, 2.6, np.pi, 2.7, np.pi])


def reference_pose(model, frame, q, tcp=None) -> np.ndarray:
    """``[x, y, z, rx, ry, rz]`` of the flange (then ``tcp`` in it) by pinocchio."""
    data = model.createData()
    pin.framesForwardKinematics(model, data, np.asarray(q, dtype=float))
    placement = data.oMf[frame]
    if tcp is not None:
        placement = placement * pin.SE3(pin.exp3(np.asarray(tcp[3:])), np.asarray(tcp[:3]))
    return np.concatenate([placement.translation, pin.log3(placement.rotation)])


@pytest.fixture(scope="module")
def ur5e():
    robot = tvist.robots.ur5e()
    model, frame = pinocchio_model(robot.params, Payload(0.0, (0.0, 0.0, 0.0)))
    return Kinematics(robot, robot.params.joint_limits_rad), model, frame


def test_forward_kinematics_matches_pinocchio_with_a_tcp(ur5e):
    kin, model, frame = ur5e
    rng = np.random.default_rng(1)
    tcp = np.array([0.02, -0.01, 0.15, 0.3, -0.2, 0.1])
    for _ in range(20):
        q = rng.uniform(Q_LOW, Q_HIGH)
        # Round-off of two 6-joint products of 4x4 transforms: ~1e-15; 1e-12 is generous.
        np.testing.assert_allclose(kin.forward(q), reference_pose(model, frame, q), atol=1e-12)
        np.testing.assert_allclose(
            kin.forward(q, tcp), reference_pose(model, frame, q, tcp), atol=1e-12
        )


def test_pose_trans_matches_pinocchio():
    rng = np.random.default_rng(2)
    for _ in range(20):
        a, b = rng.uniform(-1.0, 1.0, 6), rng.uniform(-1.0, 1.0, 6)
        ref = pin.SE3(pin.exp3(a[3:]), a[:3]) * pin.SE3(pin.exp3(b[3:]), b[:3])
        expected = np.concatenate([ref.translation, pin.log3(ref.rotation)])
        np.testing.assert_allclose(pose_trans(a, b), expected, atol=1e-12)


def test_inverse_kinematics_round_trip_nearest_qnear(ur5e):
    kin, model, frame = ur5e
    kin.set_tcp([0.0, 0.0, 0.1, 0.0, 0.0, 0.0])
    try:
        rng = np.random.default_rng(3)
        for _ in range(20):
            q = rng.uniform(Q_LOW, Q_HIGH)
            pose = reference_pose(model, frame, q, kin.tcp_offset)
            qnear = q + rng.uniform(-0.1, 0.1, 6)
            solution = kin.inverse(pose, qnear)
            # FK(IK(p)) = p: IK converges to 1e-10 (m, rad); 1e-9 leaves room for the
            # rotation-vector conversion near the angle pi.
            np.testing.assert_allclose(
                reference_pose(model, frame, solution, kin.tcp_offset), pose, atol=1e-9
            )
            # qnear within 0.1 rad of q: the solution returned is q's branch, not another
            # of the arm's configurations (those differ by > 0.5 rad in some joint).
            assert np.max(np.abs(solution - q)) < 1e-6
    finally:
        kin.set_tcp(np.zeros(6))


def test_unreachable_pose_has_no_solution(ur5e):
    kin, _, _ = ur5e
    far = [2.0, 0.0, 0.3, 0.0, np.pi, 0.0]  # 2 m away: beyond the UR5e's ~0.85 m reach
    assert not kin.has_solution(far, np.zeros(6))
    with pytest.raises(CommandRefused, match="no solution"):
        kin.inverse(far, np.zeros(6))


def test_linear_move_is_straight_trapezoidal_and_arrives(ur5e):
    kin, _, _ = ur5e
    q0 = np.array([0.0, -1.57, 1.57, -1.57, -1.57, 0.0])
    start = kin.forward(q0)
    target = start + np.array([0.10, -0.05, -0.08, 0.0, 0.0, 0.0])
    # 0.1 rad about tool x: less than the 0.137 m way, so the position leads at v.
    target[3:] = pose_trans(start, [0, 0, 0, 0.1, 0.0, 0.0])[3:]
    v, a, dt = 0.25, 1.2, 0.002
    move = LinearMove(kin, q0, target, v, a)
    q, positions = q0.copy(), [start[:3]]
    for _ in range(5000):
        q_next = move.next_q(q, dt)
        if q_next is None:
            break
        q = q_next
        positions.append(kin.forward(q)[:3])
    else:
        pytest.fail("the move did not end")
    positions = np.array(positions)
    # Arrives exactly (IK converged to 1e-10).
    np.testing.assert_allclose(kin.forward(q), target, atol=1e-9)
    # Every point on the line from start to target (to IK precision).
    line = (target[:3] - start[:3]) / np.linalg.norm(target[:3] - start[:3])
    rel = positions - start[:3]
    off_line = rel - np.outer(rel @ line, line)
    assert np.max(np.linalg.norm(off_line, axis=1)) < 1e-9
    # Speed within v; acceleration within a (finite differences of the 2 ms samples; the
    # profile's corners make one sample's difference up to a*dt off, hence the margins).
    speed = np.linalg.norm(np.diff(positions, axis=0), axis=1) / dt
    assert speed.max() <= v * (1 + 1e-9)
    assert speed.max() > 0.99 * v  # 0.14 m at 0.25 m/s and 1.2 m/s² cruises at v
    assert np.max(np.abs(np.diff(speed))) / dt <= a * 1.01


def test_tool_speed_moves_along_the_commanded_direction_and_stops(ur5e):
    kin, _, _ = ur5e
    q0 = np.array([0.0, -1.57, 1.57, -1.57, -1.57, 0.0])
    start = kin.forward(q0)
    speed = ToolSpeed(kin, q0, [0.0, 0.05, 0.0, 0.0, 0.0, 0.0], 0.5)
    q = q0.copy()
    for _ in range(500):  # 1 s
        q = speed.next_q(q, 0.002)
    speed.stop(0.5)
    for _ in range(1000):
        q_next = speed.next_q(q, 0.002)
        if q_next is None:
            break
        q = q_next
    else:
        pytest.fail("speedl did not stop")
    moved = kin.forward(q) - start
    # 0.05 m/s after a 0.1 s ramp at 0.5 m/s², 1 s, then 0.1 s of deceleration:
    # 0.5*0.05*0.1 + 0.05*0.9 + 0.5*0.05*0.1 = 0.05 m, along y only.
    assert moved[1] == pytest.approx(0.05, abs=1e-6)
    np.testing.assert_allclose(moved[[0, 2, 3, 4, 5]], 0.0, atol=1e-9)


def test_speed_slider_slows_a_move_in_proportion(ur5e):
    kin, _, _ = ur5e
    robot = kin.robot
    q0 = np.array([0.0, -1.57, 1.57, -1.57, -1.57, 0.0])
    target = kin.forward(q0) + np.array([0.05, 0.0, 0.0, 0.0, 0.0, 0.0])

    def ticks(scale: float) -> int:
        motion = JointMotion(
            q0, 0.002, robot.params.max_velocity_rad_s, robot.params.joint_limits_rad
        )
        motion.time_scale = scale
        motion.follow(LinearMove(kin, q0, target, 0.25, 1.2))
        for n in range(20000):
            motion.advance()
            if not motion.moving:
                return n
        pytest.fail("the move did not end")

    # Half speed: twice the ticks (to the tick the last sample rounds to).
    assert abs(ticks(0.5) - 2 * ticks(1.0)) <= 2


def test_rotation_matrix_matches_pinocchio_at_every_angle():
    from tvist.urserver.kinematics import rotation_matrix

    rng = np.random.default_rng(4)
    vectors = [*rng.normal(size=(50, 3)) * 2.0, *rng.normal(size=(20, 3)) * 1e-9, np.zeros(3)]
    for v in vectors:
        # Round-off of the sums of products: a few ulps of 1.
        np.testing.assert_allclose(rotation_matrix(v), pin.exp3(v), atol=1e-14)
