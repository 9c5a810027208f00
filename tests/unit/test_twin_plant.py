"""The steppable twin and the twin controller's parts, without sockets (fast)."""

from __future__ import annotations

import numpy as np
import pytest
import ruckig
from scipy.spatial.transform import Rotation

from tvist import robots, rtde_wire
from tvist.sim import Twin
from tvist.sim.plant import rotation_vector
from tvist.sim.twin_plant import TwinPlant
from tvist.trajectory import PAPER_POSES
from tvist.urserver import variables
from tvist.urserver.control_script import ControlScript, Registers
from tvist.urserver.motion import JointMotion, SafetyViolation
from tvist.urserver.server import _split_program

Q1 = np.array(PAPER_POSES["Q1"])
Q2 = np.array(PAPER_POSES["Q2"])
#: The UR5e twin's control period (its robot data), s.
DT_S = robots.params("ur5e").control_period_s


@pytest.fixture(scope="module")
def twin() -> Twin:
    return Twin("ur5e", payload_kg=5.0, payload_com_m=(0.0, 0.0, 0.05))


def _motion(twin: Twin, q0=Q1) -> JointMotion:
    p = twin.params
    return JointMotion(q0, DT_S, p.max_velocity_rad_s, p.joint_limits_rad)


def test_plant_steps_reproduce_twin_run_exactly(twin) -> None:
    """Stepping the rows of a reference through TwinPlant is Twin.run, bit for bit (the same
    integrator, the same operations), except the TCP rotation vector (quaternion route vs
    scipy: 1e-12 rad)."""
    blend = np.clip(np.arange(0.0, 1.2, DT_S) / 0.9, 0.0, 1.0)
    q_ref = Q1 + np.outer(blend**2 * (3.0 - 2.0 * blend), Q2 - Q1)
    record = twin.run(q_ref)
    plant = TwinPlant(twin, q_ref[0])
    samples = [plant.step(q) for q in np.vstack([q_ref[1:], q_ref[-1:]])]
    np.testing.assert_array_equal([s.q_link for s in samples], record.actual_q)
    np.testing.assert_array_equal([s.qd_link for s in samples], record.actual_qd)
    np.testing.assert_array_equal(
        [s.accelerometer for s in samples], record.actual_tool_accelerometer
    )
    np.testing.assert_array_equal([s.q_motor for s in samples], record.target_q)
    np.testing.assert_allclose([s.flange_pose for s in samples], record.actual_TCP_pose, atol=1e-12)


def test_rotation_vector_matches_scipy_at_every_angle() -> None:
    rotations = list(Rotation.random(500, random_state=3).as_matrix())
    for axis in np.eye(3).tolist() + [[1.0, 1.0, 0.0], [0.0, 1.0, -1.0]]:
        axis = np.array(axis) / np.linalg.norm(axis)
        for angle in (0.0, 1e-9, np.pi - 1e-9, np.pi):
            rotations.append(Rotation.from_rotvec(angle * axis).as_matrix())
    for matrix in rotations:
        got = rotation_vector(matrix.ravel())
        # Recompose: the same rotation whatever the sign convention at exactly pi.
        np.testing.assert_allclose(Rotation.from_rotvec(got).as_matrix(), matrix, atol=1e-12)
        assert np.linalg.norm(got) <= np.pi + 1e-12


def test_movej_is_the_time_optimal_trapezoid(twin) -> None:
    """movej's duration equals ruckig's time-optimal profile of the leading joint (velocity
    and acceleration limited, jerk ~unlimited): within one tick plus the jerk ramps (~1 ms).
    The path is joint-space linear, ends exactly, and respects v and a."""
    motion = _motion(twin)
    target = Q1 + np.array([0.8, -0.3, 0.2, 0.0, 0.1, 0.0])
    speed, accel = 1.0, 2.0
    motion.movej(target, speed, accel)
    path = [motion.advance()]
    while motion.mode == "movej":
        path.append(motion.advance())
    path = np.array(path)
    otg = ruckig.Ruckig(1)
    inp = ruckig.InputParameter(1)
    inp.current_position, inp.target_position = [0.0], [0.8]
    inp.max_velocity, inp.max_acceleration, inp.max_jerk = [speed], [accel], [1e6]
    trajectory = ruckig.Trajectory(1)
    otg.calculate(inp, trajectory)
    assert len(path) * DT_S == pytest.approx(trajectory.duration, abs=DT_S + 1e-3)
    np.testing.assert_array_equal(path[-1], target)
    moving = [0, 1, 2, 4]
    fraction = (path - Q1)[:, moving] / (target - Q1)[moving]
    np.testing.assert_allclose(fraction, fraction[:, [0]].repeat(4, axis=1), atol=1e-12)
    velocity = np.diff(np.vstack([Q1, path])[:, 0]) / DT_S
    assert np.max(np.abs(velocity)) <= speed + 1e-9
    assert np.max(np.abs(np.diff(velocity))) / DT_S <= accel * (1 + 1e-6) + 1e-6


def test_servoj_lags_a_ramp_by_lookahead_plus_one_over_gain(twin) -> None:
    """A ramp target at v: two first-order lags (T = lookahead, 1/gain) in series lag it by
    v (T + 1/gain) in steady state (continuous time); the exact discretization adds under
    one tick: the lag is checked to 1 % plus v dt."""
    motion = _motion(twin)
    v = 0.5
    lookahead, gain = 0.05, 500.0
    q = Q1.copy()
    for _ in range(1000):
        q[0] += v * DT_S
        motion.servoj(q, DT_S, lookahead, gain)
        motion.advance()
    lag = q[0] - motion.q[0]
    expected = v * (lookahead + 1.0 / gain)
    assert lag == pytest.approx(expected, rel=0.01, abs=v * DT_S)
    for _ in range(1000):  # no new command: the target holds and the arm converges to it
        motion.advance()
    assert motion.q[0] == pytest.approx(q[0], abs=1e-12)


def test_motion_refuses_targets_outside_the_joint_limits(twin) -> None:
    motion = _motion(twin)
    beyond = Q1.copy()
    beyond[2] = 4.0  # the elbow's limit is +-pi
    with pytest.raises(SafetyViolation, match="joint 2"):
        motion.movej(beyond, 1.0, 1.0)
    motion.speedj([3.0, 0, 0, 0, 0, 0], 10.0)  # the base runs into its +2 pi limit
    with pytest.raises(SafetyViolation, match="joint 0"):
        for _ in range(5000):
            motion.advance()


def test_control_script_register_handshake(twin) -> None:
    """ur_rtde's protocol: ready (1), a blocking moveJ answers done (2) once the arm's target
    has stopped, command 0 returns to ready; async moves flag bit 15 of register 2."""
    regs = Registers.zeros()
    motion = _motion(twin)
    payloads = []
    script = ControlScript(regs, motion, 0, 0, lambda m, c: payloads.append((m, c)))
    assert regs.out_int[0] == 1 and regs.out_int[2] & 32768 == 0
    target = Q1 + np.array([0.1, 0, 0, 0, 0, 0])
    regs.in_double[:8] = [*target, 1.0, 2.0]
    regs.in_int[:2] = [1, 0]  # MOVEJ, synchronous
    ticks = 0
    while regs.out_int[0] != 2:
        script.tick()
        motion.advance()
        ticks += 1
        assert ticks < 2000
    np.testing.assert_array_equal(motion.q, target)
    regs.in_int[0] = 0
    script.tick()
    assert regs.out_int[0] == 1
    regs.in_double[:8] = [*Q1, 1.0, 2.0]
    regs.in_int[:2] = [1, 1]  # MOVEJ, async: done at once, progress register running
    script.tick()
    assert regs.out_int[0] == 2 and regs.out_int[2] & 32768
    regs.in_int[0] = 0
    while motion.mode == "movej":
        script.tick()
        motion.advance()
    script.tick()
    assert regs.out_int[2] & 32768 == 0
    regs.in_double[:4] = [2.5, 0.0, 0.0, 0.0]
    regs.in_int[0] = 17  # SET_PAYLOAD with a zero cog keeps the cog
    script.tick()
    assert payloads == [(2.5, None)]
    regs.in_int[0] = 0
    script.tick()
    regs.in_int[0] = 3  # MOVEL: not implemented, the program stops with an error
    script.tick()
    assert not script.running and "MOVEL" in script.error


def test_rtde_recipe_round_trip() -> None:
    names = ["timestamp", "actual_q", "robot_mode", "actual_tool_accelerometer"]
    recipe = rtde_wire.Recipe(3, names, [variables.OUTPUTS[n] for n in names])
    values = {
        "timestamp": 1.25,
        "actual_q": [0.1, 0.2, 0.3, 0.4, 0.5, 0.6],
        "robot_mode": 7,
        "actual_tool_accelerometer": [0.0, 0.0, 9.81],
    }
    package = recipe.pack(values)
    size, kind = rtde_wire.HEADER.unpack_from(package)
    assert size == len(package) == 3 + 1 + 8 + 48 + 4 + 24 and kind == ord("U")
    assert recipe.unpack(package[3:]) == values
    with pytest.raises(ValueError, match="expected"):
        recipe.unpack(package[3:-1])


def test_script_port_splits_programs_and_statements() -> None:
    program = "def prog():\n  movej([0,0,0,0,0,0])\n  if x:\n    y()\n  end\nend\n"
    assert _split_program(program + "textmsg(1)\n") == (program, "textmsg(1)\n")
    assert _split_program(program[:-1]) == (None, program[:-1])  # waits for the last newline
    assert _split_program("stopj(2)\nrest") == ("stopj(2)", "rest")


def test_server_names_a_taken_port(twin) -> None:
    """Starting on a taken port fails at once with PortInUse naming it; nothing stays open."""
    import socket

    from tvist.urserver import PortInUse, ServerPorts, TwinServer
    from tvist.urserver.controller import TwinController

    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen(1)
        port = taken.getsockname()[1]
        server = TwinServer(
            TwinController(twin, Q1), ports=ServerPorts(rtde=0, dashboard=port, script=(0,))
        )
        with pytest.raises(PortInUse, match=f"port {port} "):
            server.start()
        assert all(s.fileno() == -1 for s in server._listeners)


def test_motion_lets_no_number_that_is_not_finite_through(twin) -> None:
    """Every number a command takes is checked before any clamp could pass it on: NaN or
    infinite protective-stops (SafetyViolation), a finite one out of URScript's range is
    refused (CommandRefused); either way the motion keeps its finite target."""
    motion = _motion(twin)
    nan, inf = float("nan"), float("inf")
    calls = {
        "servoj: time": lambda: motion.servoj(Q1, nan, 0.1, 300.0),
        "servoj: lookahead_time": lambda: motion.servoj(Q1, 0.002, nan, 300.0),
        "servoj: gain": lambda: motion.servoj(Q1, 0.002, 0.1, inf),
        "speedj: acceleration": lambda: motion.speedj(np.zeros(6), nan),
        "stop: deceleration": lambda: motion.stop(-inf),
        "movej: speed": lambda: motion.movej(Q1, nan, 1.0),
        "movej: acceleration": lambda: motion.movej(Q1, 1.0, inf),
    }
    for what, call in calls.items():
        with pytest.raises(SafetyViolation, match=f"{what} is .*not a finite number"):
            call()
    from tvist.urserver.motion import CommandRefused

    refused = {
        "servoj: lookahead_time = 0.01": lambda: motion.servoj(Q1, 0.002, 0.01, 300.0),
        "servoj: gain = 50": lambda: motion.servoj(Q1, 0.002, 0.1, 50.0),
        "servoj: time = -0.1": lambda: motion.servoj(Q1, -0.1, 0.1, 300.0),
        "speedj: acceleration = 0": lambda: motion.speedj(np.zeros(6), 0.0),
        "movej: speed = -1": lambda: motion.movej(Q1, -1.0, 1.0),
    }
    for what, call in refused.items():
        with pytest.raises(CommandRefused, match=what):
            call()
    for _ in range(10):
        motion.advance()
    np.testing.assert_array_equal(motion.q, Q1)
