"""The twin server driven by the unmodified ur_rtde client, over UR's ports on localhost.

One server (5 kg payload, starting at the stretched pose Q1) serves every test of this module;
each test leaves no control script running. Expected values come from a separate
:class:`tvist.sim.Twin` (static equilibrium, rigid kinematics), not from the server's code.
"""

from __future__ import annotations

import re
import signal
import socket
import struct
import subprocess
import sys
import time

import numpy as np
import pytest

from rtde_packages import package, read_package
from tvist.robots import params
from tvist.sim import Twin
from tvist.trajectory import PAPER_POSES
from twin_server_fixture import (
    EXIT_TIMEOUT_S,
    HOST,
    PAYLOAD_COM_M,
    PAYLOAD_KG,
    first_undisturbed_run,
    read_line,
    stop_process,
    twin_server,
)

#: The twin's control period: the UR5e's (its robot data), s.
UR5E_DT_S = params("ur5e").control_period_s

rtde_control = pytest.importorskip("rtde_control")
rtde_receive = pytest.importorskip("rtde_receive")

Q1 = np.array(PAPER_POSES["Q1"])
G_M_S2 = 9.81


@pytest.fixture(scope="module")
def server():
    with twin_server() as proc:
        yield proc


@pytest.fixture(scope="module")
def twin() -> Twin:
    return Twin("ur5e", payload_kg=PAYLOAD_KG, payload_com_m=PAYLOAD_COM_M)


def _control():
    return rtde_control.RTDEControlInterface(HOST)


def _end(control) -> None:
    control.stopScript()
    control.disconnect()


def _rtde_request(sock: socket.socket, kind: str, payload: bytes) -> tuple[int, bytes]:
    """Send one RTDE package and read the next reply package ``(type, payload)``."""
    sock.sendall(package(kind, payload))
    return read_package(sock)


def test_receive_interface_reads_joints_and_accelerometer(server, twin) -> None:
    """ur_rtde's default receive recipe is served; the arm rests at Q1 under gravity.

    At rest the link side sags by the gear deflection under gravity: actual_q equals the
    static equilibrium of an independent twin (Newton solve) to 1e-6 rad (the server's
    sample is its own integration of the settled state: residual motion ~1e-8 rad). The
    accelerometer reads gravity in the flange frame, R^T [0, 0, g], with R from the reported
    TCP pose: to 0.02 m/s² (the deflection tilts the flange by ~1e-3 rad, ~0.01 m/s²).
    """
    receive = rtde_receive.RTDEReceiveInterface(HOST)
    try:
        t0 = receive.getTimestamp()
        time.sleep(0.3)
        q = np.array(receive.getActualQ())
        accel = np.array(receive.getActualToolAccelerometer())
        pose = np.array(receive.getActualTCPPose())
        assert receive.getTimestamp() > t0
        assert np.allclose(receive.getTargetQ(), Q1, atol=1e-12)
    finally:
        receive.disconnect()
    from scipy.spatial.transform import Rotation

    np.testing.assert_allclose(q, twin.equilibrium(Q1), atol=1e-6)
    gravity_in_flange = Rotation.from_rotvec(pose[3:]).as_matrix().T @ [0.0, 0.0, G_M_S2]
    np.testing.assert_allclose(accel, gravity_in_flange, atol=0.02)


def test_unknown_variable_is_not_found(server) -> None:
    """A variable the controller does not have: ur_rtde raises, naming it (UR's NOT_FOUND)."""
    with pytest.raises(RuntimeError, match="no_such_variable"):
        rtde_receive.RTDEReceiveInterface(HOST, 500.0, ["actual_q", "no_such_variable"])
    with socket.create_connection((HOST, 30004), timeout=5) as sock:
        assert _rtde_request(sock, "V", struct.pack(">H", 2)) == (ord("V"), b"\x01")
        kind, reply = _rtde_request(sock, "O", struct.pack(">d", 500.0) + b"actual_q,bogus")
        assert kind == ord("O")
        assert reply[0] == 0  # no recipe
        assert reply[1:] == b"VECTOR6D,NOT_FOUND"
        kind, reply = _rtde_request(sock, "I", b"input_int_register_40,bogus_input")
        assert reply[1:] == b"INT32,NOT_FOUND"


def test_malformed_packages_do_not_crash_the_server(server) -> None:
    """Garbage on the RTDE port ends that connection only; a bad data package is ignored."""
    with socket.create_connection((HOST, 30004), timeout=5) as sock:
        _rtde_request(sock, "V", struct.pack(">H", 2))
        kind, reply = _rtde_request(sock, "I", b"input_double_register_40")
        assert reply[0] == 1
        # A data package of the wrong size, and one for a recipe that does not exist.
        kind, _ = _rtde_request(sock, "U", b"\x01\x00\x00")
        assert kind == ord("M")
        kind, _ = _rtde_request(sock, "U", b"\x07" + bytes(8))
        assert kind == ord("M")
        # An unknown package type.
        kind, _ = _rtde_request(sock, "Z", b"xyz")
        assert kind == ord("M")
        # A header whose size is below the header's own: the stream is lost, the server
        # says so and closes this connection.
        sock.sendall(b"\x00\x01U")
        kind, _ = read_package(sock)
        assert kind == ord("M")
        with pytest.raises(ConnectionError):
            read_package(sock)
    with socket.create_connection((HOST, 29999), timeout=5) as sock:
        sock.sendall(b"\xff\xfe not a command\n")
        reader = sock.makefile("rb")
        assert reader.readline().startswith(b"Connected")
        assert b"could not understand" in reader.readline()
    with socket.create_connection((HOST, 30002), timeout=5) as sock:
        sock.sendall(b"def nonsense():\n  this is not urscript\nend\n")
    receive = rtde_receive.RTDEReceiveInterface(HOST, 500.0, ["actual_q"])
    assert len(receive.getActualQ()) == 6
    receive.disconnect()
    assert server.poll() is None


def test_second_control_client_is_refused(server) -> None:
    """A second RTDEControlInterface gets IN_USE registers (as on a UR); the first goes on."""
    first = _control()
    try:
        with pytest.raises(RuntimeError, match="already in use"):
            _control()
        q = list(Q1)
        q[5] += 0.05
        assert first.moveJ(q, 1.0, 4.0)
        q[5] -= 0.05
        assert first.moveJ(q, 1.0, 4.0)
    finally:
        _end(first)


def test_unsupported_command_fails_loudly(server) -> None:
    """Teach mode is not modelled: the call returns False and the program stops."""
    control = _control()
    try:
        assert control.isProgramRunning()
        assert control.teachMode() is False
        assert not control.isProgramRunning()
    finally:
        _end(control)


_STREAM_AND_DIE = """
import sys, time, rtde_control
c = rtde_control.RTDEControlInterface(sys.argv[7])
q = [float(v) for v in sys.argv[1:7]]
for k in range(250):  # 0.5 s of servoJ moving joint 5, then killed mid-stream
    t = c.initPeriod()
    q[5] += 0.0004
    c.servoJ(q, 0.0, 0.0, 0.002, 0.03, 1000.0)
    c.waitPeriod(t)
print("streaming", flush=True)
while True:
    t = c.initPeriod()
    c.servoJ(q, 0.0, 0.0, 0.002, 0.03, 1000.0)
    c.waitPeriod(t)
"""


@pytest.mark.slow
def test_client_disconnect_mid_stream_holds(server) -> None:
    """The servo client dies: the arm settles at the last servoJ target and holds it."""
    proc = subprocess.Popen(
        [sys.executable, "-c", _STREAM_AND_DIE, *(str(v) for v in Q1), HOST],
        stdout=subprocess.PIPE,
        text=True,
    )
    try:
        assert read_line(proc, "the streaming client").strip() == "streaming"
    finally:
        stop_process(proc, signal.SIGKILL, "the streaming client")
    expected = Q1.copy()
    expected[5] += 250 * 0.0004
    receive = rtde_receive.RTDEReceiveInterface(HOST, 500.0, ["target_q", "target_qd"])
    try:
        # The servo filters (30 ms lookahead, 1 ms gain lag) converge exponentially: 1 s
        # after the last command they are within 0.1 rad * exp(-1 / 0.03) ~ 1e-15 rad.
        time.sleep(1.0)
        first = np.array(receive.getTargetQ())
        time.sleep(0.5)
        second = np.array(receive.getTargetQ())
        speed = np.array(receive.getTargetQd())
    finally:
        receive.disconnect()
    np.testing.assert_allclose(first, expected, atol=1e-9)
    np.testing.assert_allclose(second, first, atol=1e-12)
    assert np.max(np.abs(speed)) < 1e-9
    # The next client takes over (ur_rtde stops the orphaned script and uploads its own).
    control = _control()
    try:
        assert control.moveJ(list(Q1), 1.0, 4.0)
    finally:
        _end(control)


# ----------------------------------------------------------------------------- live loop


def _tvist(*args: str, **kwargs) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "tvist.cli", *args],
        capture_output=True,
        text=True,
        timeout=300,
        **kwargs,
    )


def _residual_rms(path) -> tuple[float, np.ndarray, np.ndarray]:
    """RMS of the accelerometer's deviation from its final rest value over the first second
    after the servo target came to rest; also the final target and actual joint angles.

    The target is at rest from the first sample after which it stays within 1e-7 rad of its
    final value (the servo filters approach it exponentially).
    """
    from tvist.ident import read_rtde_csv

    record = read_rtde_csv(path)
    t, target, accel = record.t_s, record.target_q, record.tool_accel
    assert np.allclose(np.diff(t), UR5E_DT_S, atol=1e-9), "the log lost samples"
    away = np.flatnonzero(np.max(np.abs(target - target[-1]), axis=1) > 1e-7)
    t_rest = t[away[-1] + 1]
    window = (t >= t_rest) & (t < t_rest + 1.0)
    assert t[-1] >= t_rest + 1.5, "the log must run on 1.5 s after the move"
    rest = accel[t >= t_rest + 1.3].mean(axis=0)
    deviation = np.linalg.norm(accel[window] - rest, axis=1)
    return float(np.sqrt(np.mean(deviation**2))), target[-1], record.actual_q[-1]


@pytest.mark.slow
def test_run_shaped_move_cuts_residual_vibration(server, twin, tmp_path) -> None:
    """``tvist run`` Q1 -> Q2 through servoJ, unshaped and shaped with the twin's true modes.

    The ZV shaper on the end pose's two modes (from the twin's modal analysis, not from the
    server) must cut the residual vibration by >= 90 %; the arm ends where the servo was
    sent: target within 1e-4 rad of Q2 and the link side at the twin's static equilibrium
    there within 1e-4 rad.
    """
    from tvist.experiments.motions import DT_S, motion_by_name

    motion = motion_by_name("Q1->Q2")
    move = tmp_path / "q1q2.csv"
    np.savetxt(move, motion.reference(0.0, DT_S).q, delimiter=",", fmt="%.12f")
    modes = ",".join(f"{wn / (2 * np.pi):.6f}:{zeta:.6f}" for wn, zeta in twin.modes(motion.q_end))

    def run(name: str, *extra: str) -> tuple[tuple[float, np.ndarray, np.ndarray], str]:
        log = tmp_path / f"{name}.csv"
        # --tail 5: the server slips simulated time after a late tick, so under load the
        # default 3 s of wall-clock recording after the last command can hold less than the
        # 1.5 s of simulated rest that _residual_rms needs after the target settles.
        done = _tvist(
            "run", str(move), "--robot-ip", HOST, "--log", str(log), "--tail", "5", *extra
        )
        assert done.returncode == 0, done.stdout + done.stderr
        return _residual_rms(log), done.stdout + done.stderr

    (unshaped, _, _), unshaped_output = run("unshaped", "--unshaped")
    # A run whose servo loop woke too late is run again (first_undisturbed_run says why).
    (shaped, target_end, actual_end), output = first_undisturbed_run(
        lambda attempt: run(f"shaped{attempt}", "--modes", modes),
        lambda result: result[0] <= 0.1 * unshaped,
    )
    assert shaped <= 0.1 * unshaped, (shaped, unshaped, output)
    np.testing.assert_allclose(target_end, motion.q_end, atol=1e-4)
    np.testing.assert_allclose(actual_end, twin.equilibrium(motion.q_end), atol=1e-4)
    # Time to settled, reported from each log: the shaped move is still sooner than the
    # unshaped one (on the twin 1.91 s against 2.08 s at 0.05 m/s²), and never before the
    # move itself ends.
    settled = re.compile(r"0\.05 m/s² after ([0-9.]+) s.*the move itself ([0-9.]+) s")
    (unshaped_s, move_s), (shaped_s, _) = (
        map(float, settled.search(text).groups()) for text in (unshaped_output, output)
    )
    assert move_s < shaped_s < unshaped_s, (unshaped_output, output)


@pytest.mark.slow
def test_run_interrupted_stops_the_arm(server, tmp_path) -> None:
    """Ctrl-C during ``tvist run``: servoStop then stopScript; the program ends, the arm
    comes to rest and the command reports the interruption."""
    receive = rtde_receive.RTDEReceiveInterface(HOST, 500.0, ["target_q", "target_qd"])
    proc = None
    try:
        start = np.array(receive.getTargetQ())
        blend = np.clip(np.arange(0.0, 3.0, 0.002) / 3.0, 0.0, 1.0)
        move = start + np.outer(blend**2 * (3.0 - 2.0 * blend), [-0.5, 0, 0, 0, 0, 0])
        path = tmp_path / "move.csv"
        np.savetxt(path, move, delimiter=",", fmt="%.12f")
        proc = subprocess.Popen(
            [sys.executable, "-m", "tvist.cli", "run", str(path), "--robot-ip", HOST]
            + ["--unshaped", "--log", str(tmp_path / "log.csv")],
            stdout=subprocess.PIPE,
            text=True,
        )
        deadline = time.monotonic() + 60.0
        while abs(receive.getTargetQd()[0]) < 0.05 and time.monotonic() < deadline:
            time.sleep(0.01)
        assert abs(receive.getTargetQd()[0]) >= 0.05, "the streamed move never started"
        proc.send_signal(signal.SIGINT)
        try:
            out, _ = proc.communicate(timeout=EXIT_TIMEOUT_S)
        except subprocess.TimeoutExpired:
            stop_process(proc, signal.SIGKILL, "tvist run")
            pytest.fail(f"tvist run did not exit within {EXIT_TIMEOUT_S:g} s of Ctrl-C")
        assert proc.returncode == 130 and "interrupted" in out
        time.sleep(0.5)
        assert np.all(np.array(receive.getTargetQd()) == 0.0)
        stopped_at = np.array(receive.getTargetQ())[0]
        assert move[-1, 0] < stopped_at < start[0]  # stopped on the way
    finally:
        if proc is not None:  # a failure above leaves it streaming: stop it as a user would
            stop_process(proc, signal.SIGINT, "tvist run")
        receive.disconnect()
    with socket.create_connection((HOST, 29999), timeout=5) as sock:
        reader = sock.makefile("rb")
        reader.readline()
        sock.sendall(b"running\n")
        assert reader.readline().strip() == b"Program running: false"


@pytest.mark.slow
def test_record_keeps_every_sample_until_interrupted(server, tmp_path) -> None:
    """``tvist record`` writes every 2 ms sample, a moveJ included, and stops on Ctrl-C."""
    from tvist.ident import read_rtde_csv

    out = tmp_path / "log.csv"
    proc = subprocess.Popen(
        [sys.executable, "-m", "tvist.cli", "record", "--robot-ip", HOST, "--out", str(out)],
        stdout=subprocess.PIPE,
        text=True,
    )
    control = _control()
    receive = rtde_receive.RTDEReceiveInterface(HOST, 500.0, ["target_q"])
    start = receive.getTargetQ()
    receive.disconnect()
    try:
        assert read_line(proc, "tvist record").startswith("recording")
        time.sleep(0.3)
        q = list(start)
        q[0] -= 0.2
        assert control.moveJ(q, 1.0, 2.0)
        assert control.moveJ(start, 1.0, 2.0)
        time.sleep(0.3)
    finally:
        _end(control)
        stop_process(proc, signal.SIGINT, "tvist record")
    assert proc.returncode == 0
    record = read_rtde_csv(out)
    np.testing.assert_allclose(np.diff(record.t_s), UR5E_DT_S, atol=1e-9)
    # The log has ur_rtde's 6 decimals.
    assert np.min(record.target_q[:, 0]) == pytest.approx(start[0] - 0.2, abs=1e-6)
    assert record.n_samples > 500


@pytest.mark.slow
def test_campaign_through_ur_rtde_finds_the_twins_modes(server, twin, tmp_path) -> None:
    """``tvist campaign --robot-ip`` on one pose (the server's 5 kg payload): base and
    shoulder frequencies within 3 % of the twin's modal analysis at the pose."""
    import json

    out = tmp_path / "campaign.jsonl"
    args = ["campaign", "--robot-ip", HOST, "--payloads", str(PAYLOAD_KG), "--every", "52"]
    args += ["--no-fit-check", "--no-workspace-cover"]  # one pose: modes, no map
    args += ["--payload-com", *(str(v) for v in PAYLOAD_COM_M), "--out", str(out)]
    # The campaign asks the operator to mount the payload: answer with Enter.
    done = _tvist(*args, input="\n" * 4)
    assert done.returncode == 0, done.stdout + done.stderr
    (record,) = [json.loads(line) for line in out.read_text().splitlines()]
    truth = twin.modes(np.array(record["q"]))
    for joint in (0, 1):
        fit = next(m for m in record["modes"] if m["joint"] == joint)
        assert fit["wn_rad_s"] == pytest.approx(truth[joint][0], rel=0.03), (joint, fit, truth)


def test_a_late_tick_leaves_clients_time_to_answer() -> None:
    """The tick schedule (pure: no clock): on time, ticks are one period apart; a tick whose
    output went out late delays the next one to ``CLIENT_RESPONSE_S`` after that output, so
    a client streaming servoJ still answers before the registers are read (catching up on the
    wall clock instead would read them at once and hold the old target for a tick)."""
    from tvist.urserver.server import CLIENT_RESPONSE_S, next_tick_deadline

    dt = 0.002
    # On time: output 0.4 ms into the tick, next tick one period after this one's deadline.
    assert next_tick_deadline(10.0, 10.0004, dt) == (10.0 + dt, False)
    # Exactly the response time left: still on schedule.
    assert next_tick_deadline(10.0, 10.0 + dt - CLIENT_RESPONSE_S, dt) == (10.0 + dt, False)
    # Output 1.5 ms late into the next period (and 5 ms late): the schedule slips.
    for published in (10.0035, 10.007):
        deadline, late = next_tick_deadline(10.0, published, dt)
        assert late and deadline == published + CLIENT_RESPONSE_S
