"""Nothing a client sends stops the twin server.

A hostile client's numbers (through the unmodified ur_rtde where it lets them through, raw
registers otherwise), recipes, dashboard lines, programs and connections are each answered
as a UR would (protective stop or refusal, with the reason on the dashboard's ``get last
error`` and in the log) while every other client goes on: after each case a fresh ur_rtde
client connects, reads advancing timestamps and moves the arm.

One server (the fixture's subprocess) serves the module; each test leaves it released. Limits
come from the robot's parameter file, not from the server.
"""

from __future__ import annotations

import math
import socket
import struct
import subprocess
import threading
import time

import numpy as np
import pytest

from tvist import robots
from twin_server_fixture import (
    HOST,
    REPLY_TIMEOUT_S,
    Commander,
    RawRtde,
    Subscriber,
    assert_serves_clients,
    dashboard,
    twin_server,
    upload_script,
    wait_dashboard,
)

rtde_control = pytest.importorskip("rtde_control")
rtde_receive = pytest.importorskip("rtde_receive")

PARAMS = robots.params("ur5e")
#: The twin's control period: the UR5e's (its robot data), s.
DT_S = robots.params("ur5e").control_period_s
NAN = float("nan")
#: Command ids of ur_rtde's control script.
MOVEJ, SPEEDJ, SERVOJ, SPEED_STOP, SET_PAYLOAD, STOPJ = 1, 9, 11, 15, 17, 34


@pytest.fixture(scope="module")
def server():
    with twin_server() as proc:
        yield proc


def assert_streaming(subscriber: Subscriber, n: int = 100) -> np.ndarray:
    """``n`` more packages arrive, one tick apart or a whole number of ticks (a package the
    subscriber was too slow for is dropped, never repeated), with finite targets."""
    samples = subscriber.wait_for(n)
    t = np.array([s[0] for s in samples])
    ticks = np.diff(t) / DT_S  # timestamps are k * 2 ms: whole numbers to rounding (1e-6)
    assert np.all(ticks >= 1.0 - 1e-6) and np.allclose(ticks, np.round(ticks), atol=1e-6)
    q = np.array([s[1] for s in samples])
    assert np.all(np.isfinite(q))
    return q


@pytest.fixture
def subscriber(server):
    sub = Subscriber()
    sub.wait_for(1)
    yield sub
    sub.close()


@pytest.fixture
def commander(server):
    """The stand-in control script running, its command registers ours (reset afterwards)."""
    upload_script()
    assert wait_dashboard("running", "true") == "Program running: true"
    cmd = Commander()
    yield cmd
    cmd.close()


def _current_target(subscriber: Subscriber) -> np.ndarray:
    return np.array(subscriber.wait_for(1)[-1][1])


# ----------------------------------------------------------------------------- 1. NaN commands


@pytest.mark.slow
@pytest.mark.parametrize("call", ["servoJ time", "speedStop"])
def test_nan_through_ur_rtde_protective_stops_and_the_server_goes_on(
    server, subscriber, call
) -> None:
    """``servoJ(q, 0, 0, nan, 0.1, 300)`` and ``speedStop(nan)`` pass ur_rtde's checks: the
    twin protective-stops (as for a NaN joint target), names the value, and keeps ticking."""
    control = rtde_control.RTDEControlInterface(HOST)
    try:
        q = list(_current_target(subscriber))
        if call == "servoJ time":
            control.servoJ(q, 0.0, 0.0, NAN, 0.1, 300.0)
        else:
            control.speedStop(NAN)
        assert wait_dashboard("safetystatus", "PROTECTIVE") == "Safetystatus: PROTECTIVE_STOP"
        (error,) = dashboard("get last error")
        assert ("servoj: time" if call == "servoJ time" else "stop: deceleration") in error
        assert "not a finite number" in error
        assert_streaming(subscriber)
    finally:
        control.disconnect()
    assert_serves_clients()


@pytest.mark.slow
@pytest.mark.parametrize(
    "what, cmd, args",
    [
        ("servoj: lookahead_time", SERVOJ, [0.0, 0.0, 0.002, NAN, 300.0]),
        ("servoj: gain", SERVOJ, [0.0, 0.0, 0.002, 0.1, NAN]),
        ("speedj: acceleration", SPEEDJ, [NAN]),
        ("stop: deceleration", STOPJ, [NAN]),
        ("movej: speed", MOVEJ, [math.inf, 1.0]),
        ("set_payload: mass", SET_PAYLOAD, [NAN]),
    ],
)
def test_nan_in_a_command_register_protective_stops(
    server, subscriber, commander, what, cmd, args
) -> None:
    """Numbers ur_rtde would refuse, written straight into the command registers: a value
    that is not finite protective-stops the arm, the reason names it, the clock goes on."""
    q = _current_target(subscriber)
    joint_args = (
        list(q) if cmd in (SERVOJ, MOVEJ) else [0.1, 0, 0, 0, 0, 0] if cmd == SPEEDJ else []
    )
    if cmd == STOPJ:
        commander.command(SPEEDJ, 0.05, 0, 0, 0, 0, 0, 1.0)  # moving, then stopj(nan)
        subscriber.wait_for(20)
    commander.command(cmd, *joint_args, *args)
    assert wait_dashboard("safetystatus", "PROTECTIVE") == "Safetystatus: PROTECTIVE_STOP"
    (error,) = dashboard("get last error")
    assert what in error and "not a finite number" in error
    assert_streaming(subscriber)
    commander.close()
    assert_serves_clients()


@pytest.mark.slow
@pytest.mark.parametrize(
    "what, cmd, args",
    [
        ("servoj: lookahead_time = 5 is outside [0.03, 0.2]", SERVOJ, [0, 0, 0.002, 5.0, 300]),
        ("servoj: gain = 1e+06 is outside [100, 2000]", SERVOJ, [0, 0, 0.002, 0.1, 1e6]),
        ("servoj: time = -1 s must be >= 0", SERVOJ, [0, 0, -1.0, 0.1, 300]),
        ("speedj: acceleration = 0 must be > 0", SPEEDJ, [0.0]),
        ("stop: deceleration = -3 must be > 0", SPEED_STOP, [-3.0]),
    ],
)
def test_out_of_range_command_stops_the_program(
    server, subscriber, commander, what, cmd, args
) -> None:
    """A finite number outside URScript's range is a runtime error: the program stops with
    the reason (no protective stop) and the arm holds."""
    q = _current_target(subscriber)
    joint_args = list(q) if cmd == SERVOJ else [0.0] * 6 if cmd == SPEEDJ else []
    commander.command(cmd, *joint_args, *args)
    assert wait_dashboard("running", "false") == "Program running: false"
    assert dashboard("get last error", "safetystatus") == [
        f"Last error: {what}",
        "Safetystatus: NORMAL",
    ]
    q_after = assert_streaming(subscriber)
    np.testing.assert_array_equal(q_after[-1], q)  # the target never moved
    commander.close()
    assert_serves_clients()


# ----------------------------------------------------------------------------- 2. recipes


@pytest.mark.slow
def test_recipes_past_the_one_byte_id_are_refused_and_publishing_goes_on(
    server, subscriber
) -> None:
    """On a started session, 255 output recipes take ids 1..255; the 256th is refused
    (recipe id 0, a text message) and every subscriber, this one included, goes on."""
    hostile = RawRtde()
    try:
        hostile.version()
        assert hostile.setup_outputs(["timestamp"])[0] == 1
        hostile.start()
        for recipe_id in range(2, 256):
            assert hostile.setup_outputs(["timestamp"])[0] == recipe_id
        assert hostile.setup_outputs(["timestamp"]) == b"\x00"
        assert any(b"at most 255 recipes" in m for m in hostile.messages)
        assert_streaming(subscriber)
        assert struct.unpack(">Bd", hostile.data())[1] > 0.0
        assert hostile.setup_inputs(["input_int_register_47"]) != 0
    finally:
        hostile.close()
    assert_serves_clients()


def test_an_output_rate_above_the_reported_controllers_is_refused_with_the_cap(server) -> None:
    """The server reports an e-Series controller (RTDE ``v`` 5.x), whose outputs go at
    500 Hz at most (UR's RTDE guide; a CB3 125 Hz): 500 Hz is granted, 501 Hz refused with
    a failed reply (id 0) and a text message naming the cap, and the connection stays
    usable. The cap here is typed from the guide for the version the client is told."""
    client = RawRtde()
    try:
        client.version()
        major = struct.unpack(">4I", client.request("v"))[0]
        assert major == 5
        cap = 500.0
        assert client.setup_outputs(["timestamp"], frequency_hz=cap + 1.0)[0] == 0
        assert any(b"not in (0, 500] Hz" in m for m in client.messages), client.messages
        assert client.setup_outputs(["timestamp"], frequency_hz=cap)[0] == 1
    finally:
        client.close()


def test_a_setup_whose_reply_exceeds_a_package_is_refused_not_dropped(server) -> None:
    """30,000 unknown names (a 60 kB request) would make a 300 kB reply: the setup is
    refused with a failed reply (id 0) and the connection stays usable."""
    client = RawRtde()
    try:
        client.version()
        assert client.setup_outputs(["x"] * 30000)[0] == 0
        assert client.setup_inputs(["x"] * 30000) == 0
        client.version()
        assert client.setup_outputs(["timestamp"])[0] == 1
    finally:
        client.close()


# ----------------------------------------------------------------------------- 3. resources


def _status(proc) -> dict[str, int]:
    """``VmRSS`` (kB) and ``Threads`` of the server process."""
    fields = {}
    with open(f"/proc/{proc.pid}/status") as status:
        for line in status:
            key, _, value = line.partition(":")
            if key in ("VmRSS", "Threads"):
                fields[key] = int(value.split()[0])
    return fields


def _connect_and_leave(n: int) -> None:
    """``n`` connections in turn on the RTDE, dashboard and script ports, each answered once
    (the script port's is closed without a program), then closed by the client."""
    for i in range(n):
        port = (30004, 29999, 30002)[i % 3]
        with socket.create_connection((HOST, port), timeout=10) as sock:
            if port == 30004:
                sock.sendall(struct.pack(">HBH", 5, ord("V"), 2))
                assert sock.recv(4, socket.MSG_WAITALL) == b"\x00\x04V\x01"
            elif port == 29999:
                reader = sock.makefile("rb")
                reader.readline()
                sock.sendall(b"robotmode\n")
                assert reader.readline() == b"Robotmode: RUNNING\n"
                reader.close()


def _settled_threads(proc, baseline: int) -> int:
    for _ in range(1000):
        threads = _status(proc)["Threads"]
        if threads <= baseline:
            return threads
        time.sleep(0.01)
    return threads


def test_connections_leave_nothing_behind(server) -> None:
    """2,000 connections: the server's threads return to their number before, and its RSS
    grows by less than 1 MB (it grew 4.4 MB when each connection left ~2.2 kB behind; the
    allocator's arenas move by a few hundred kB either way, hence the bound)."""
    _connect_and_leave(300)  # warm up the allocator's pools
    baseline = _status(server)["Threads"]
    assert _settled_threads(server, baseline) <= baseline
    before = _status(server)["VmRSS"]
    _connect_and_leave(2000)
    assert _settled_threads(server, baseline) <= baseline
    growth_kb = _status(server)["VmRSS"] - before
    print(f"\nserver RSS growth over 2,000 connections: {growth_kb} kB")
    assert growth_kb < 1024


def test_dashboard_refuses_an_over_long_line(server) -> None:
    """A 1 MB line is refused in one short reply (not echoed), the next command answered."""
    with socket.create_connection((HOST, 29999), timeout=10) as sock:
        reader = sock.makefile("rb")
        reader.readline()
        sock.sendall(b"x" * (1 << 20) + b"\nrobotmode\n")
        reply = reader.readline()
        assert reply == b"could not understand: a command longer than 4096 bytes\n"
        assert reader.readline() == b"Robotmode: RUNNING\n"
        reader.close()


def test_listen_backlog_queues_64_connections(server) -> None:
    """Every port queues 64 connections the server has not accepted yet (the kernel's view:
    ``ss`` reports a listening socket's backlog in its Send-Q column)."""
    try:
        out = subprocess.run(["ss", "-ltnH"], capture_output=True, text=True, check=True).stdout
    except (FileNotFoundError, subprocess.CalledProcessError):
        pytest.skip("ss (iproute2) is not available")
    backlog = {}
    for line in out.splitlines():
        fields = line.split()
        host, _, port = fields[3].rpartition(":")
        if host == HOST:
            backlog[int(port)] = int(fields[2])
    assert backlog == {port: 64 for port in (29999, 30001, 30002, 30003, 30004)}


@pytest.mark.slow
def test_a_client_that_reads_no_replies_does_not_stop_the_clock(server, subscriber) -> None:
    """A streaming client stops reading and keeps asking for long replies (setups of 1,000
    unknown names at 0 Hz: 10 kB each, no recipe made): the server's send of a reply blocks
    once its socket is full, and the tick, which sends that client's data packages on the
    same connection, must not wait for it: the other subscribers go on."""
    hostile = RawRtde(rcvbuf=4096)
    hostile.version()
    assert hostile.setup_outputs(["timestamp"])[0] == 1
    hostile.start()
    request = struct.pack(">d", 0.0) + b",".join([b"x"] * 1000)
    request = struct.pack(">HB", 3 + len(request), ord("O")) + request

    def flood() -> None:  # blocks once the server stops reading; ends when closed
        try:
            for _ in range(2000):  # 20 MB of replies: more than any socket buffers
                hostile.sock.sendall(request)
        except OSError:
            pass

    flooding = threading.Thread(target=flood, daemon=True)
    flooding.start()
    try:
        assert_streaming(subscriber, 1000)
    finally:
        hostile.sock.shutdown(socket.SHUT_RDWR)
        hostile.close()
        flooding.join(timeout=30)
    assert_serves_clients()


# ----------------------------------------------------------------------------- 4. programs


@pytest.mark.slow
@pytest.mark.parametrize(
    "offsets, name",
    [
        ((40, 0), "reg_offset_float = '40'"),
        ((0, 25), "reg_offset_int = '25'"),
        (("9" * 5000, 0), "reg_offset_float = '99999999999999999999'"),
    ],
)
def test_a_register_offset_ur_rtde_never_injects_is_refused(
    server, subscriber, offsets, name
) -> None:
    """Only 0 and 24 (ur_rtde's lower and upper range) are offsets of the control script:
    another is refused at upload, so a command cannot make the script read a register that
    does not exist (the twin has 48)."""
    upload_script(float_offset=offsets[0], int_offset=offsets[1])
    error = wait_dashboard("get last error", name)
    assert error.startswith(f"Last error: program not run: control script with {name}")
    assert dashboard("running") == ["Program running: false"]
    cmd = Commander()
    try:
        cmd.command(SERVOJ, *_current_target(subscriber), 0, 0, 0.002, 0.1, 300.0)
        assert_streaming(subscriber)
        cmd.command(0)
    finally:
        cmd.close()
    assert_serves_clients()


# ----------------------------------------------------------------------------- 5. motion


def test_movej_speed_and_acceleration_are_clipped_to_the_joint_limits(
    server, subscriber, commander
) -> None:
    """moveJ at 1e300 rad/s and rad/s² (raw registers): the move runs at the robot's speed
    limits (parameter file), no joint faster than its limit between two packages, and ends
    at the target without a protective stop. The limit is checked to 1e-9 relative (the
    profile's rounding)."""
    q0 = _current_target(subscriber)
    target = q0 + np.array([0.5, -0.2, 0.0, 0.0, 0.0, 0.0])
    start = len(subscriber.samples)
    commander.command(MOVEJ, *target, 1e300, 1e300)
    for _ in range(3000):
        if subscriber.samples and np.array_equal(subscriber.samples[-1][1], target):
            break
        subscriber.wait_for(1)
    samples = subscriber.samples[start:]
    t = np.array([s[0] for s in samples])
    q = np.array([s[1] for s in samples])
    np.testing.assert_array_equal(q[-1], target)
    speed = np.abs(np.diff(q, axis=0)) / np.diff(t)[:, None]
    assert np.all(speed <= PARAMS.max_velocity_rad_s * (1 + 1e-9))
    # The leading joint reached its limit (the clip, not a slower profile).
    assert np.max(speed[:, 0]) == pytest.approx(PARAMS.max_velocity_rad_s[0], rel=1e-9)
    assert dashboard("safetystatus") == ["Safetystatus: NORMAL"]
    commander.command(0)
    subscriber.wait_for(5)  # the script has seen "no command" before the next one
    commander.command(MOVEJ, *q0, 1.0, 4.0)  # back
    for _ in range(3000):
        if np.array_equal(subscriber.wait_for(1)[-1][1], q0):
            break
    np.testing.assert_array_equal(subscriber.samples[-1][1], q0)


@pytest.mark.slow
@pytest.mark.parametrize(
    "mass, cog, safety, error",
    [
        (NAN, [0.0, 0.0, 0.0], "PROTECTIVE_STOP", "set_payload: mass is nan"),
        (-1e9, [0.0, 0.0, 0.0], "NORMAL", "set_payload: mass = -1e+09 is outside [0, 7.5] kg"),
        (1.0, [1e9, 0.0, 0.0], "NORMAL", "set_payload: centre of gravity 1e+09 m"),
    ],
)
def test_set_payload_refuses_what_no_arm_carries(server, mass, cog, safety, error) -> None:
    """``setPayload`` through ur_rtde: a NaN mass protective-stops, a negative one or a
    centre of gravity beyond the arm's reach is refused; the call returns False and the
    published payload is the one declared before."""
    receive = rtde_receive.RTDEReceiveInterface(HOST, 500.0, ["timestamp", "payload"])
    control = rtde_control.RTDEControlInterface(HOST)
    try:
        before = receive.getPayload()
        assert control.setPayload(mass, cog) is False
        assert dashboard("safetystatus") == [f"Safetystatus: {safety}"]
        (reply,) = dashboard("get last error")
        assert reply.startswith(f"Last error: {error}")
        t0 = receive.getTimestamp()
        for _ in range(1000):
            if receive.getTimestamp() > t0 + 0.1:
                break
            time.sleep(0.01)
        assert receive.getPayload() == before
    finally:
        control.disconnect()
        receive.disconnect()
    assert_serves_clients()


# ----------------------------------------------------------------------------- 6. the tick


def _free_ports(n: int) -> list[int]:
    sockets = [socket.socket() for _ in range(n)]
    for sock in sockets:
        sock.bind((HOST, 0))
    ports = [sock.getsockname()[1] for sock in sockets]
    for sock in sockets:
        sock.close()
    return ports


@pytest.fixture
def local_server():
    """A twin server in this process (tests that reach inside it), on free ports of HOST;
    only raw clients talk to it (ur_rtde's calls hold the interpreter while they wait)."""
    from tvist.sim import Twin
    from tvist.trajectory import PAPER_POSES
    from tvist.urserver import ServerPorts, TwinServer
    from tvist.urserver.controller import TwinController

    ports = _free_ports(5)
    twin = Twin("ur5e", payload_kg=5.0, payload_com_m=(0.0, 0.0, 0.05))
    controller = TwinController(twin, np.array(PAPER_POSES["Q1"]))
    local = TwinServer(controller, host=HOST, ports=ServerPorts(ports[0], ports[1], ports[2:]))
    local.start()
    yield local
    local.close()


@pytest.mark.parametrize("part", ["motion", "outputs"])
def test_a_fault_in_the_tick_protective_stops_and_the_tick_goes_on(local_server, part) -> None:
    """An exception inside the tick (the motion, inside the controller's step; the outputs,
    after it) protective-stops the arm with the reason; packages keep coming and ``unlock
    protective stop`` releases the arm."""
    controller = local_server.controller
    dash = local_server.ports.dashboard
    sub = Subscriber(HOST, port=local_server.ports.rtde)
    owner, name = (controller.motion, "advance") if part == "motion" else (controller, "_outputs")
    original = getattr(owner, name)
    faults = []

    def fail_once(*args):
        if not faults:
            faults.append(name)
            raise RuntimeError(f"injected fault in {name}")
        return original(*args)

    try:
        sub.wait_for(10)
        setattr(owner, name, fail_once)
        reply = wait_dashboard("safetystatus", "PROTECTIVE", port=dash)
        assert reply == "Safetystatus: PROTECTIVE_STOP"
        (error,) = dashboard("get last error", port=dash)
        assert f"injected fault in {name}" in error
        assert_streaming(sub)
        assert dashboard("unlock protective stop", "safetystatus", port=dash) == [
            "Protective stop releasing",
            "Safetystatus: NORMAL",
        ]
        assert_streaming(sub)
    finally:
        vars(owner).pop(name, None)
        sub.close()


def test_subscribers_that_do_not_read_cost_the_tick_no_packing(local_server, monkeypatch) -> None:
    """50 subscribers stop reading (each with a recipe of its own): once their sockets are
    full the tick drops their packages without packing them, so it packs one package per
    tick, the reading subscriber's, not 51 (which made the simulated clock run at 72 % of
    the wall clock)."""
    from tvist import rtde_wire
    from tvist.urserver import variables

    packed = [0]
    pack = rtde_wire.Recipe.pack

    def counting_pack(self, values):
        packed[0] += 1
        return pack(self, values)

    monkeypatch.setattr(rtde_wire.Recipe, "pack", counting_pack)
    names = [n for n in variables.OUTPUTS if not n.startswith(("input_", "output_"))]
    stalled = []
    try:
        for i in range(50):
            client = RawRtde(HOST, local_server.ports.rtde, rcvbuf=4096)
            client.version()
            assert client.setup_outputs(names[i:] + names[:i])[0] == 1  # no two alike
            client.start()
            stalled.append(client)
        sub = Subscriber(HOST, port=local_server.ports.rtde)
        sub.wait_for(500)  # the stalled sockets fill within ~100 packages (~1 kB each)
        start, n0 = packed[0], len(sub.samples)
        samples = sub.wait_for(500)
        packings = packed[0] - start
        ticks = round((samples[-1][0] - sub.samples[n0 - 1][0]) / DT_S)
        print(f"\n{packings} packings in {ticks} ticks with 50 stalled subscribers")
        assert packings < 2 * ticks
        sub.close()
    finally:
        for client in stalled:
            client.close()


# ----------------------------------------------------------------------------- 7. timestamps


@pytest.mark.slow
def test_a_campaign_log_has_every_package_once(server, tmp_path) -> None:
    """A campaign's excitation recorded from the twin server (~5 s): the log's timestamp
    advances by exactly one 2 ms period per row, none repeated or skipped (ur_rtde's file
    recorder, on a timer of its own, repeated and skipped 3-14 % of them). The timestamps
    are k * 2 ms written with 6 decimals: compared to 1e-9 s."""
    from tvist.ident.campaign_robots import URRobot
    from tvist.ident.excitation import random_excitation

    receive = rtde_receive.RTDEReceiveInterface(HOST, 500.0, ["target_q"])
    q0 = np.array(receive.getTargetQ())
    receive.disconnect()
    excitation = random_excitation(q0, 0, seed=3, duration_s=4.0, dt_s=DT_S, max_delta_rad=0.05)
    robot = URRobot(HOST, log_dir=tmp_path, confirm=None)
    try:
        robot.record_excitation(excitation)
    finally:
        robot.close()
    (log,) = tmp_path.glob("excitation_*.csv")
    t = np.genfromtxt(log, delimiter=",", names=True)["timestamp"]
    assert t[-1] - t[0] >= 4.5
    np.testing.assert_allclose(np.diff(t), DT_S, rtol=0, atol=1e-9)


def test_a_recorder_waits_on_the_controllers_clock(server, tmp_path) -> None:
    """``wait_controller_time(0.5)`` at 125 Hz returns once the stream's timestamp has
    advanced by 0.5 s: at least that (the start is read before the call), and at most a few
    packages more (0.1 s: the test thread may be scheduled late). A wall-clock sleep would
    record less on a twin whose ticks run late; counting packages at the wrong rate (500 Hz
    for a 125 Hz stream) would wait 2 s."""
    from tvist.live import RtdeRecorder

    with RtdeRecorder(HOST, tmp_path / "log.csv", ["timestamp"], 125.0) as recorder:
        start = recorder.latest["timestamp"]
        recorder.wait_controller_time(0.5)
        elapsed = recorder.latest["timestamp"] - start
    assert 0.5 - 1e-9 <= elapsed <= 0.6


def test_a_recording_below_500_hz_is_evenly_spaced_from_its_first_package(server, tmp_path) -> None:
    """At 125 Hz every package is 4 ticks after the previous one, the first two included
    (the first interval was 3 ticks)."""
    from tvist.live import RtdeRecorder

    with RtdeRecorder(HOST, tmp_path / "log.csv", ["timestamp"], 125.0) as recorder:
        count = 0
        while count < 30:
            count = recorder.wait_newer(count, timeout_s=10.0)
    t = np.genfromtxt(recorder.path, delimiter=",", names=True)["timestamp"]
    np.testing.assert_allclose(np.diff(t), 4 * DT_S, rtol=0, atol=1e-9)


def test_a_reply_never_splits_a_data_package(server) -> None:
    """A subscriber that reads slowly gets part of a data package now and the rest later;
    a reply sent meanwhile must wait for that rest: the stream stays a sequence of whole
    packages (each reply to the version request is its own ``V`` package saying yes)."""
    client = RawRtde(rcvbuf=4096)
    try:
        client.version()
        names = ["timestamp", "actual_q", "actual_qd", "target_q", "target_qd", "actual_TCP_pose"]
        assert client.setup_outputs(names * 4)[0] == 1  # 1 kB packages
        client.start()
        for _ in range(20):  # fill the socket (a partial package left over), then ask
            time.sleep(0.02)
            client.send("V", struct.pack(">H", 2))
        replies = 0
        deadline = time.monotonic() + REPLY_TIMEOUT_S  # data packages alone never end it
        while replies < 20:
            if time.monotonic() > deadline:
                pytest.fail(f"{replies} of 20 replies within {REPLY_TIMEOUT_S:g} s")
            kind, body = client.read()
            assert kind in (ord("U"), ord("V")), f"stream out of step: package type {kind}"
            if kind == ord("V"):
                assert body == b"\x01"
                replies += 1
            else:
                assert len(body) == 1 + 4 * (8 + 5 * 48)
    finally:
        client.close()
