"""The twin server runs the Cartesian part of ur_rtde (the unmodified client): moveL, speedL,
servoL, stopL, moveJ_IK, moveL_FK, the kinematics services and the TCP offset, the watchdog
and the speed slider; and every public method of ``RTDEControlInterface`` either works or is
refused with its reason (program stopped, reason in the log and on the dashboard).

Expected poses come from pinocchio's model of the rigid arm built from the DH table
(``pinocchio_reference``), not from the twin's kinematics. Poses are compared on the target
(commanded) TCP pose: the actual one includes the flexible arm's static sag under gravity
(millimetres with the fixture's 5 kg payload), which a rigid reference does not have.
"""

from __future__ import annotations

import struct
import time

import numpy as np
import pytest

from pinocchio_reference import pinocchio_model
from tvist import robots
from tvist.robots import Payload
from twin_server_fixture import (
    HOST,
    Commander,
    CurrentReceive,
    RawRtde,
    Subscriber,
    dashboard,
    twin_server,
    upload_script,
    wait_dashboard,
)

rtde_control = pytest.importorskip("rtde_control")
rtde_receive = pytest.importorskip("rtde_receive")
pin = pytest.importorskip("pinocchio")

#: A usual start pose (elbow and wrist bent: away from singularities).
HOME = [0.0, -1.57, 1.57, -1.57, -1.57, 0.0]
#: IK converges to 1e-10 (m, rad); a pose read back through RTDE doubles is exact. 1e-8
#: leaves room for the rotation-vector conversions; far inside the 0.1 mm / 1e-4 rad a UR
#: program expects.
POSE_TOL = 1e-8


@pytest.fixture(scope="module")
def server():
    with twin_server() as proc:
        yield proc


@pytest.fixture(scope="module")
def reference():
    model, frame = pinocchio_model(robots.params("ur5e"), Payload(0.0, (0.0, 0.0, 0.0)))
    return model, frame


def fk(reference, q, tcp=(0.0, 0.0, 0.0, 0.0, 0.0, 0.0)) -> np.ndarray:
    """TCP pose at ``q`` by pinocchio."""
    model, frame = reference
    data = model.createData()
    pin.framesForwardKinematics(model, data, np.asarray(q, dtype=float))
    tcp = np.asarray(tcp, dtype=float)
    placement = data.oMf[frame] * pin.SE3(pin.exp3(tcp[3:]), tcp[:3])
    return np.concatenate([placement.translation, pin.log3(placement.rotation)])


def assert_pose(actual, expected, tol: float = POSE_TOL) -> None:
    """Positions and orientations equal (orientations as rotations, not vectors)."""
    actual, expected = np.asarray(actual), np.asarray(expected)
    np.testing.assert_allclose(actual[:3], expected[:3], atol=tol)
    relative = pin.exp3(actual[3:]) @ pin.exp3(expected[3:]).T
    assert np.linalg.norm(pin.log3(relative)) < tol


@pytest.fixture
def robot(server):
    """A connected client pair at HOME (the server released, the TCP offset zero)."""
    dashboard("stop", "unlock protective stop", host=HOST)
    control = rtde_control.RTDEControlInterface(HOST)
    receive = rtde_receive.RTDEReceiveInterface(HOST)
    try:
        assert control.setTcp([0.0] * 6)
        assert control.moveJ(HOME, 1.5, 4.0)
        # Reads never older than the call (a blocking move has returned on the control
        # connection: the receive stream must show where it ended).
        yield control, CurrentReceive(receive)
    finally:
        if control.isProgramRunning():
            control.stopScript()
        control.disconnect()
        receive.disconnect()


def wait_until(predicate, what: str, polls: int = 2000) -> None:
    """Poll ``predicate`` every 5 ms (a bounded count, failing rather than hanging)."""
    for _ in range(polls):
        if predicate():
            return
        time.sleep(0.005)
    pytest.fail(f"{what} did not happen")


def last_error() -> str:
    return dashboard("get last error", host=HOST)[0]


# ----------------------------------------------------------------------------- motion


@pytest.mark.slow
def test_movel_ends_at_the_commanded_pose(robot, reference):
    control, receive = robot
    start = fk(reference, receive.getTargetQ())
    target = start.copy()
    target[:3] += [0.08, -0.05, -0.06]
    assert control.moveL(list(target), 0.25, 1.2)
    assert_pose(receive.getTargetTCPPose(), target)
    assert_pose(fk(reference, receive.getTargetQ()), target)
    assert control.isProgramRunning()


def test_movel_to_an_unreachable_pose_is_refused_before_moving(robot):
    control, receive = robot
    q = receive.getTargetQ()
    assert control.moveL([2.0, 0.0, 0.3, 0.0, 3.14, 0.0], 0.25, 1.2) is False
    assert "no solution" in last_error()
    np.testing.assert_array_equal(receive.getTargetQ(), q)  # not a step taken
    assert dashboard("safetystatus", host=HOST) == ["Safetystatus: NORMAL"]


def test_movel_async_reports_progress_and_stopl_stops_on_the_line(robot, reference):
    control, receive = robot
    start = fk(reference, receive.getTargetQ())
    target = start.copy()
    target[:3] += [0.0, 0.25, 0.0]
    assert control.moveL(list(target), 0.1, 0.5, True)
    wait_until(lambda: control.getAsyncOperationProgress() >= 0, "async progress")
    wait_until(lambda: receive.getTargetTCPPose()[1] > start[1] + 0.02, "2 cm of the move")
    control.stopL(1.0)  # returns nothing (void in ur_rtde)
    wait_until(control.isSteady, "the stop")
    end = np.array(receive.getTargetTCPPose())
    assert start[1] + 0.02 < end[1] < target[1] - 0.01  # stopped short, after 2 cm
    # On the line: x, z and the orientation untouched (to IK precision).
    assert_pose([start[0], end[1], start[2], *start[3:]], end)
    assert control.getAsyncOperationProgress() < 0  # finished
    assert control.isProgramRunning()


def test_speedl_moves_the_tcp_in_the_commanded_direction(robot, reference):
    control, receive = robot
    start = np.array(receive.getTargetTCPPose())
    assert control.speedL([0.0, 0.0, 0.05, 0.0, 0.0, 0.0], 0.5, 0.0)
    wait_until(lambda: receive.getTargetTCPPose()[2] > start[2] + 0.01, "1 cm up")
    # Cruising (the 0.1 s ramp is over after 1 cm at 0.05 m/s): the target TCP speed is the
    # commanded one (a difference of exact poses, 1e-9); the measured one the same within
    # the flexible arm's vibration (5 mm/s).
    np.testing.assert_allclose(receive.getTargetTCPSpeed(), [0, 0, 0.05, 0, 0, 0], atol=1e-9)
    np.testing.assert_allclose(receive.getActualTCPSpeed()[:3], [0, 0, 0.05], atol=5e-3)
    assert control.speedStop(1.0)
    wait_until(control.isSteady, "the stop")
    end = np.array(receive.getTargetTCPPose())
    assert end[2] > start[2] + 0.01
    assert_pose([start[0], start[1], end[2], *start[3:]], end)
    assert control.isProgramRunning()


@pytest.mark.slow
def test_servol_tracks_the_pose(robot, reference):
    control, receive = robot
    target = np.array(receive.getTargetTCPPose())
    target[0] -= 0.02
    for _ in range(1000):  # 2 s of 2 ms servo periods
        period = control.initPeriod()
        assert control.servoL(list(target), 0.0, 0.0, 0.002, 0.1, 300)
        control.waitPeriod(period)
    assert control.servoStop(2.0)
    wait_until(control.isSteady, "the stop")
    # servoj's two first-order lags (0.1 s lookahead) settle within the 2 s: e^-20.
    assert_pose(receive.getTargetTCPPose(), target, tol=1e-6)


def test_movej_ik_and_movel_fk(robot, reference):
    control, receive = robot
    target = fk(reference, HOME)
    target[:3] += [0.03, 0.03, 0.03]
    assert control.moveJ_IK(list(target), 1.0, 2.0)
    assert_pose(fk(reference, receive.getTargetQ()), target)
    assert control.moveL_FK(HOME, 0.25, 1.2)
    np.testing.assert_allclose(receive.getTargetQ(), HOME, atol=1e-8)


# ----------------------------------------------------------------------------- kinematics


def test_kinematics_services_match_the_reference(robot, reference):
    control, receive = robot
    q = [0.3, -1.2, 1.9, -2.0, -1.3, 0.4]
    tcp = [0.01, -0.02, 0.12, 0.1, 0.2, -0.3]
    assert_pose(control.getForwardKinematics(q, tcp), fk(reference, q, tcp))
    pose = fk(reference, q)
    qnear = [v + 0.05 for v in q]
    solution = control.getInverseKinematics(list(pose), qnear)
    assert_pose(fk(reference, solution), pose)
    np.testing.assert_allclose(solution, q, atol=1e-6)  # the branch nearest qnear
    assert control.getInverseKinematicsHasSolution(list(pose))
    far = [2.0, 0.0, 0.3, 0.0, 3.14, 0.0]  # beyond the UR5e's reach
    assert not control.getInverseKinematicsHasSolution(far)
    assert not control.isPoseWithinSafetyLimits(far)
    assert control.isPoseWithinSafetyLimits(list(pose))
    assert control.isJointsWithinSafetyLimits(q)
    assert not control.isJointsWithinSafetyLimits([7.0, *q[1:]])  # beyond ±2π
    a, b = [0.1, 0.2, 0.3, 0.4, -0.5, 0.6], [0.3, -0.1, 0.2, -0.2, 0.1, 0.7]
    ref = pin.SE3(pin.exp3(np.array(a[3:])), np.array(a[:3])) * pin.SE3(
        pin.exp3(np.array(b[3:])), np.array(b[:3])
    )
    assert_pose(control.poseTrans(a, b), [*ref.translation, *pin.log3(ref.rotation)])
    assert control.isProgramRunning()  # "no solution" answered, not an error


def test_tcp_offset_applies_to_every_pose(robot, reference):
    control, receive = robot
    tcp = [0.0, 0.05, 0.15, 0.0, 0.3, 0.0]
    assert control.setTcp(tcp)
    np.testing.assert_allclose(control.getTCPOffset(), tcp, atol=1e-12)
    q = receive.getTargetQ()
    assert_pose(receive.getTargetTCPPose(), fk(reference, q, tcp))
    # At the actual joints: those of the call's tick and of the read after it differ by the
    # vibration the moveJ left (~1e-4 rad); 1e-3 still tells the offset (0.16 m) apart.
    assert_pose(control.getForwardKinematics(), fk(reference, receive.getActualQ(), tcp), 1e-3)
    actual = np.array(receive.getActualTCPPose())
    assert np.all(np.isfinite(actual))
    # The actual TCP is the measured flange with the offset: within the arm's sag of the
    # target TCP (1.3 mm, 3.3 mrad measured at this pose with the fixture's 5 kg payload;
    # without the offset they would differ by its 0.16 m).
    assert_pose(actual, receive.getTargetTCPPose(), tol=5e-3)
    # A linear move of the TCP (not of the flange) ends with the TCP at the pose.
    target = np.array(receive.getTargetTCPPose())
    target[2] -= 0.05
    assert control.moveL(list(target), 0.25, 1.2)
    assert_pose(fk(reference, receive.getTargetQ(), tcp), target)


def test_realtime_queries_answer_in_the_registers(server, reference):
    """``get_actual_tool_flange_pose`` (58) and ``get_steptime`` (26) are realtime queries:
    ur_rtde reads the output registers right after writing the command, without waiting for
    the controller's answer (its value is the registers' previous content). The twin answers
    within a tick; read here from the registers themselves."""
    dashboard("stop", "unlock protective stop", host=HOST)
    upload_script(host=HOST)
    assert wait_dashboard("running", "true", host=HOST) == "Program running: true"
    commander = Commander(HOST)
    reader = RawRtde(HOST)
    try:
        reader.version()
        names = [
            "input_int_register_0",
            "actual_q",
            *(f"output_double_register_{i}" for i in range(6)),
        ]
        assert b"NOT_FOUND" not in reader.setup_outputs(names)
        reader.start()

        def registers_after(cmd: int) -> tuple[np.ndarray, np.ndarray]:
            commander.command(cmd)
            for _ in range(5000):  # past the packages queued before the command
                values = struct.unpack(">Bi12d", reader.data())
                if values[1] == cmd:
                    break
            else:
                pytest.fail(f"command {cmd} never reached the registers")
            # The command's tick answers it: its package holds the answer.
            values = struct.unpack(">Bi12d", reader.data())
            commander.command(0)
            return np.array(values[2:8]), np.array(values[8:14])

        q, flange = registers_after(58)
        # The flange measured at that tick, without any TCP offset (pinocchio at the
        # measured joints; the flexible arm's flange is where its links put it: 1e-9).
        assert_pose(flange, fk(reference, q), tol=1e-9)
        _, step = registers_after(26)
        assert step[0] == robots.params("ur5e").control_period_s
    finally:
        commander.close()
        reader.close()
        dashboard("stop", host=HOST)


# ----------------------------------------------------------------------------- supervision


def test_watchdog_stops_the_program_when_the_client_goes_quiet(robot):
    control, _ = robot
    assert control.setWatchdog(2.0)  # at least every 0.5 s
    for _ in range(100):
        control.kickWatchdog()
        time.sleep(0.005)
    assert control.isProgramRunning()
    wait_until(lambda: not control.isProgramRunning(), "the watchdog's stop")
    assert "watchdog" in last_error()


def test_speed_slider_is_published_as_speed_scaling(robot):
    rtde_io = pytest.importorskip("rtde_io")
    _, receive = robot
    io = rtde_io.RTDEIOInterface(HOST)
    try:
        assert io.setSpeedSlider(0.5)
        wait_until(lambda: receive.getSpeedScaling() == 0.5, "speed scaling 0.5")
        assert receive.getTargetSpeedFraction() == 0.5
    finally:
        io.setSpeedSlider(1.0)
        wait_until(lambda: receive.getSpeedScaling() == 1.0, "speed scaling 1.0")
        io.disconnect()


# ----------------------------------------------------------------------------- every method

ZERO6 = [0.0] * 6

#: Methods the twin refuses: the call, and what the reason names. The program stops (every
#: later call fails until a new interface uploads the script); the reason is logged and
#: answered by the dashboard's ``get last error``.
REFUSED = {
    "forceMode": (lambda c: c.forceMode(ZERO6, [0, 0, 1, 0, 0, 0], ZERO6, 2, [0.1] * 6), "force"),
    "forceModeStop": (lambda c: c.forceModeStop(), "force"),
    "forceModeSetDamping": (lambda c: c.forceModeSetDamping(0.1), "force"),
    "forceModeSetGainScaling": (lambda c: c.forceModeSetGainScaling(0.5), "force"),
    "zeroFtSensor": (lambda c: c.zeroFtSensor(), "force/torque sensor"),
    "enableExternalFtSensor": (lambda c: c.enableExternalFtSensor(True), "force/torque"),
    "ftRtdeInputEnable": (lambda c: c.ftRtdeInputEnable(True), "force/torque"),
    "teachMode": (lambda c: c.teachMode(), "teach mode"),
    "endTeachMode": (lambda c: c.endTeachMode(), "teach mode"),
    "freedriveMode": (lambda c: c.freedriveMode(), "freedrive"),
    "endFreedriveMode": (lambda c: c.endFreedriveMode(), "freedrive"),
    "getFreedriveStatus": (lambda c: c.getFreedriveStatus(), "freedrive"),
    "jogStart": (lambda c: c.jogStart([0.0, 0.0, 0.01, 0.0, 0.0, 0.0]), "jogging"),
    "jogStop": (lambda c: c.jogStop(), "jogging"),
    "moveUntilContact": (lambda c: c.moveUntilContact([0.0, 0.0, -0.01, 0, 0, 0]), "contact"),
    "toolContact": (lambda c: c.toolContact(ZERO6), "contact"),
    "startContactDetection": (lambda c: c.startContactDetection(), "contact"),
    "stopContactDetection": (lambda c: c.stopContactDetection(), "contact"),
    "readContactDetection": (lambda c: c.readContactDetection(), "contact"),
    "getJointTorques": (lambda c: c.getJointTorques(), "torque"),
    "directTorque": (lambda c: c.directTorque(ZERO6), "torque"),
    "setGravity": (lambda c: c.setGravity([0.0, 0.0, 9.82]), "gravity"),
    "setTargetPayload": (lambda c: c.setTargetPayload(1.0, [0, 0, 0.05], ZERO6), "inertia"),
    "getMassMatrix": (lambda c: c.getMassMatrix(), "dynamics"),
    "getCoriolisAndCentrifugalTorques": (lambda c: c.getCoriolisAndCentrifugalTorques(), "dyn"),
    "getTargetJointAccelerations": (lambda c: c.getTargetJointAccelerations(), "dynamics"),
    "getJacobian": (lambda c: c.getJacobian(), "Jacobian"),
    "getJacobianTimeDerivative": (lambda c: c.getJacobianTimeDerivative(), "Jacobian"),
    "getTargetWaypoint": (lambda c: c.getTargetWaypoint(), "waypoint query"),
    "getActualJointPositionsHistory": (lambda c: c.getActualJointPositionsHistory(0), "history"),
    "servoC": (lambda c: c.servoC([-0.4, -0.2, 0.4, 0, 3.1, 0], 0.1, 0.1, 0.0), "servoc"),
}

#: Realtime commands the client sends without waiting for the controller: it returns True
#: (or the registers' previous content) before the twin refuses them; the refusal shows in
#: the stopped program, the next call failing, the log and the dashboard.
NO_WAIT = {
    "forceMode", "servoC", "toolContact", "getJointTorques", "getActualJointPositionsHistory",
    "directTorque",
}  # fmt: skip

#: Methods that work; each is exercised (with its effect checked) by the test named.
WORKS = {
    "moveJ": "robot fixture, assert_serves_clients",
    "moveJ_IK": "test_movej_ik_and_movel_fk",
    "moveL": "test_movel_ends_at_the_commanded_pose",
    "moveL_FK": "test_movej_ik_and_movel_fk",
    "movePath": "test_move_path_runs_its_waypoints, test_twin_server_blends.py",
    "speedJ": "test_twin_server.py",
    "speedL": "test_speedl_moves_the_tcp_in_the_commanded_direction",
    "speedStop": "test_speedl_moves_the_tcp_in_the_commanded_direction",
    "servoJ": "test_twin_server.py",
    "servoL": "test_servol_tracks_the_pose",
    "servoStop": "test_servol_tracks_the_pose",
    "stopJ": "test_twin_server_hardening.py",
    "stopL": "test_movel_async_reports_progress_and_stopl_stops_on_the_line",
    "setPayload": "test_twin_server_hardening.py",
    "setTcp": "test_tcp_offset_applies_to_every_pose",
    "getTCPOffset": "test_tcp_offset_applies_to_every_pose",
    "getActualToolFlangePose": "test_realtime_queries_answer_in_the_registers",
    "getForwardKinematics": "test_kinematics_services_match_the_reference",
    "getInverseKinematics": "test_kinematics_services_match_the_reference",
    "getInverseKinematicsHasSolution": "test_kinematics_services_match_the_reference",
    "poseTrans": "test_kinematics_services_match_the_reference",
    "isPoseWithinSafetyLimits": "test_kinematics_services_match_the_reference",
    "isJointsWithinSafetyLimits": "test_kinematics_services_match_the_reference",
    "isSteady": "test_movel_async_reports_progress_and_stopl_stops_on_the_line",
    "getAsyncOperationProgress": "test_movel_async_reports_progress_and_stopl_stops_on_the_line",
    "setWatchdog": "test_watchdog_stops_the_program_when_the_client_goes_quiet",
    "kickWatchdog": "test_watchdog_stops_the_program_when_the_client_goes_quiet",
    "triggerProtectiveStop": "test_every_control_method_works_or_is_refused",
    "getStepTime": "test_realtime_queries_answer_in_the_registers",
}

#: Methods of the client alone (connection, timing, script upload) or that only read the
#: state the other tests check: no controller command of their own.
CLIENT_SIDE = {
    "disconnect", "reconnect", "isConnected", "isProgramRunning", "initPeriod", "waitPeriod",
    "getRobotStatus", "stopScript", "reuploadScript", "getAsyncOperationProgressEx",
    "setCustomScriptFile", "sendCustomScript", "sendCustomScriptFile",
    "sendCustomScriptFunction", "setExternalForceTorque",
}  # fmt: skip


def _path(blend: float = 0.0, poses=None, q_end=HOME):
    """moveL through ``poses`` (the second with the blend radius ``blend``), then moveJ to
    ``q_end`` (joints); 0.25 m/s, 1.2 m/s²; 1 rad/s, 2 rad/s²."""
    poses = poses or [[-0.45, -0.15, 0.45, 0.0, 3.1, 0.0], [-0.40, -0.25, 0.40, 0.0, 3.1, 0.0]]
    path = rtde_control.Path()
    entry, kind = rtde_control.PathEntry, rtde_control.PathEntry
    for i, pose in enumerate(poses):
        r = blend if i == 1 else 0.0
        path.addEntry(entry(kind.MoveL, kind.PositionTcpPose, [*pose, 0.25, 1.2, r]))
    path.addEntry(entry(kind.MoveJ, kind.PositionJoints, [*q_end, 1.0, 2.0, 0.0]))
    return path


@pytest.mark.slow
def test_move_path_runs_its_waypoints(robot, reference):
    control, receive = robot
    start = fk(reference, HOME)
    poses = [list(start + [0.05, 0.0, -0.05, 0, 0, 0]), list(start + [0.0, 0.08, 0.0, 0, 0, 0])]
    q_end = [0.2, -1.4, 1.4, -1.6, -1.5, 0.1]
    # Blocking: the call returns with the arm at the last waypoint, having stopped at each
    # linear one on the way (rest-to-rest moves end exactly there; ur_rtde writes the path's
    # numbers with 6 significant digits, so the waypoint run is within 5e-7 m of the one
    # given: 1e-6).
    subscriber = Subscriber(HOST)
    try:
        assert control.movePath(_path(0.0, poses, q_end), False)
        samples = subscriber.wait_for(1)
    finally:
        subscriber.close()
    np.testing.assert_allclose(receive.getTargetQ(), q_end, atol=1e-9)
    visited = np.array([fk(reference, q)[:3] for _, q in subscriber.samples])
    for pose in poses:
        assert np.min(np.linalg.norm(visited - np.array(pose[:3]), axis=1)) < 1e-6
    del samples
    # Asynchronous: progress counts the waypoints, then the path ends.
    assert control.moveJ(HOME, 1.5, 4.0)
    assert control.movePath(_path(0.0, poses, q_end), True)
    seen = set()
    for _ in range(4000):
        progress = control.getAsyncOperationProgress()
        if progress < 0 and seen:
            break
        if progress >= 0:
            seen.add(progress)
        time.sleep(0.005)
    assert seen == {0, 1, 2}
    np.testing.assert_allclose(receive.getTargetQ(), q_end, atol=1e-9)
    assert control.isProgramRunning()


@pytest.mark.slow
def test_every_control_method_works_or_is_refused(server):
    public = {
        name
        for name in dir(rtde_control.RTDEControlInterface)
        if not name.startswith("_")
        and not name[0].isupper()
        and callable(getattr(rtde_control.RTDEControlInterface, name))
    }
    listed = set(REFUSED) | set(WORKS) | CLIENT_SIDE
    assert public - listed == set(), "methods without an expected outcome"
    assert listed - public == set(), "the table names methods the client does not have"

    dashboard("stop", "unlock protective stop", host=HOST)
    for name, (call, reason) in REFUSED.items():
        control = rtde_control.RTDEControlInterface(HOST)
        try:
            assert control.isProgramRunning()
            try:
                result = call(control)
            except RuntimeError:
                result = None  # the client raises "did not succeed": a refusal it surfaces
            wait_until(lambda c=control: not c.isProgramRunning(), f"{name}: program stop")
            error = last_error()
            assert "does not model" in error and reason in error, (name, error)
            if name not in NO_WAIT:
                assert result is not True, f"{name} returned True"
            assert control.moveJ(HOME) is False  # the next call fails: the program stopped
            # Refused without moving the arm or protective-stopping it.
            assert dashboard("safetystatus", host=HOST) == ["Safetystatus: NORMAL"], name
        finally:
            control.disconnect()

    control = rtde_control.RTDEControlInterface(HOST)
    try:
        assert control.triggerProtectiveStop() is False  # the program stops with the arm
        assert dashboard("safetystatus", host=HOST) == ["Safetystatus: PROTECTIVE_STOP"]
        assert "protective stop triggered by the program" in last_error()
    finally:
        control.disconnect()
        dashboard("stop", "unlock protective stop", host=HOST)
