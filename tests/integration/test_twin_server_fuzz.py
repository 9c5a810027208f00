"""A bounded protocol fuzz of the twin server: RTDE, dashboard and script ports.

A fixed seed draws 300 hostile cases in 5 batches: random and mutated RTDE packages (headers,
setups, data packages with NaN, infinities and huge numbers), dashboard lines (known commands
with random arguments, binary garbage, over-long lines, half lines), programs on the script
ports (the control script with random register offsets, truncated and random programs) and
command registers of a running control script written with hostile numbers. After each batch
the server process is alive and a fresh ur_rtde client connects, reads advancing timestamps
and moves the arm (after the dashboard's ``stop`` and ``unlock protective stop``, as an
operator would). 23-24 s on a 2-core machine at a load average of 4, the server's start
included.
"""

from __future__ import annotations

import socket
import struct
import time

import numpy as np
import pytest

from tvist.urserver import variables
from twin_server_fixture import (
    HOST,
    Commander,
    RawRtde,
    assert_serves_clients,
    dashboard,
    twin_server,
    upload_script,
    wait_dashboard,
)

pytest.importorskip("rtde_control")
pytest.importorskip("rtde_receive")

SEED = 20261201
N_BATCHES = 5
CASES_PER_BATCH = 60
#: Numbers a hostile client writes.
HOSTILE = [np.nan, np.inf, -np.inf, 1e300, -1e300, 0.0, -1.0, 1e-300, 2000.0, 7.0]
#: Package types: the protocol's and two it does not have.
KINDS = [ord(c) for c in "VvOISPUMZ\x00"]
#: Command ids of ur_rtde's control script, and ids it does not have.
COMMANDS = [0, 1, 9, 11, 15, 16, 17, 34, 47, 255, 3, 2, 200, -1]
DASHBOARD = [
    "robotmode",
    "safetystatus",
    "safetymode",
    "running",
    "programState",
    "PolyscopeVersion",
    "get last error",
    "stop",
    "play",
    "unlock protective stop",
    "power on",
    "brake release",
    "load ",
    "close popup",
    "is in remote control",
    "quit",
]


def _connect(port: int) -> socket.socket:
    sock = socket.create_connection((HOST, port), timeout=5)
    sock.settimeout(0.02)
    return sock


def _drain(sock: socket.socket) -> None:
    """Read some of what the server answered (whatever it is; a started stream never ends)
    without waiting for more."""
    try:
        for _ in range(8):
            if not sock.recv(65536):
                return
    except OSError:
        pass


def _package(kind: int, payload: bytes) -> bytes:
    return struct.pack(">HB", min(3 + len(payload), 65535), kind) + payload


def _names(rng, pool: list[str]) -> bytes:
    n = int(rng.integers(0, 40))
    names = [str(rng.choice(pool)) if rng.random() < 0.8 else "x" * int(rng.integers(1, 300))]
    names += [str(rng.choice(pool)) for _ in range(n)]
    return ",".join(names).encode()


def _rtde_case(rng) -> None:
    with _connect(30004) as sock:
        if rng.random() < 0.7:  # a proper start, so that the later packages are parsed
            sock.sendall(_package(ord("V"), struct.pack(">H", 2)))
        for _ in range(int(rng.integers(1, 8))):
            what = rng.random()
            if what < 0.2:
                frequency = float(rng.choice([*HOSTILE, 125.0, 500.0, 499.9]))
                payload = struct.pack(">d", frequency) + _names(rng, list(variables.OUTPUTS))
                sock.sendall(_package(ord("O"), payload))
            elif what < 0.4:
                sock.sendall(_package(ord("I"), _names(rng, list(variables.INPUTS))))
            elif what < 0.6:
                values = rng.choice(HOSTILE, size=int(rng.integers(0, 20)))
                payload = bytes([int(rng.integers(0, 4))]) + struct.pack(
                    f">{len(values)}d", *values
                )
                sock.sendall(_package(ord("U"), payload))
            elif what < 0.75:
                sock.sendall(_package(ord(rng.choice(list("SPv"))), b""))
            elif what < 0.9:
                kind = int(rng.choice(KINDS))
                sock.sendall(_package(kind, rng.bytes(int(rng.integers(0, 3000)))))
            else:  # a header that lies about its size, then whatever
                size, kind = int(rng.integers(0, 65536)), int(rng.choice(KINDS))
                sock.sendall(struct.pack(">HB", size, kind))
                sock.sendall(rng.bytes(int(rng.integers(0, 100))))
                break
        _drain(sock)


def _dashboard_case(rng) -> None:
    with _connect(29999) as sock:
        for _ in range(int(rng.integers(1, 6))):
            what = rng.random()
            if what < 0.5:
                line = str(rng.choice(DASHBOARD)).encode()
                if rng.random() < 0.3:
                    line += b" " + rng.bytes(int(rng.integers(0, 50)))
            elif what < 0.8:
                line = rng.bytes(int(rng.integers(0, 200)))
            else:
                line = b"y" * int(rng.integers(4000, 100_000))
            sock.sendall(line + (b"\n" if rng.random() < 0.9 else b""))
        _drain(sock)


def _script_case(rng) -> None:
    port = int(rng.choice([30001, 30002, 30003]))
    what = rng.random()
    if what < 0.4:
        offsets = [rng.choice(["0", "24", "40", "-1", "1e9", "x", "9" * 30]) for _ in range(2)]
        upload_script(float_offset=offsets[0], int_offset=offsets[1])
        return
    with _connect(port) as sock:
        if what < 0.7:
            program = rng.bytes(int(rng.integers(0, 5000)))
        elif what < 0.85:
            program = b"def rtde_control():\n  def rtde_cmd():\n" + rng.bytes(100)  # no end
        else:
            program = b"sec s():\n  textmsg(1)\nend\nmovej([0,0,0,0,0,0])\nstopj(2)\n"
        sock.sendall(program)
        _drain(sock)


def _target_q() -> np.ndarray:
    client = RawRtde()
    try:
        client.version()
        client.setup_outputs(["target_q"])
        client.start()
        return np.array(struct.unpack(">B6d", client.data())[1:])
    finally:
        client.close()


def _register_case(rng) -> None:
    """The control script runs; hostile numbers go into its command registers."""
    offset = int(rng.choice([0, 24]))
    dashboard("unlock protective stop")
    upload_script(float_offset=offset, int_offset=offset)
    if "true" not in wait_dashboard("running", "true", max_wait_s=2.0):
        return
    q = _target_q()
    commander = Commander(offset=offset)
    try:
        for _ in range(int(rng.integers(1, 5))):
            cmd = int(rng.choice(COMMANDS))
            args = rng.choice(HOSTILE, size=11)
            if rng.random() < 0.5:  # a plausible target, so that some commands move
                args[:6] = q + rng.normal(0.0, 0.05, 6)
            if rng.random() < 0.5:  # plausible speeds and servo parameters
                args[6:11] = [0.5, 1.0, 0.008, 0.1, 300.0]
            commander.command(cmd, *args, flag=int(rng.integers(0, 2)))
            time.sleep(0.004)  # two ticks
    finally:
        commander.close()


CASES = [_rtde_case, _dashboard_case, _script_case, _register_case]


@pytest.fixture(scope="module")
def server():
    with twin_server() as proc:
        yield proc


@pytest.mark.slow
def test_fuzzed_clients_never_stop_the_server(server) -> None:
    """Every case is drawn from its own seed (the same cases whatever the timing); the
    server's log holds no traceback afterwards (nothing failed unexpectedly, even caught)."""
    kinds = np.random.default_rng(SEED).choice(
        len(CASES), size=N_BATCHES * CASES_PER_BATCH, p=[0.4, 0.25, 0.2, 0.15]
    )
    counts = dict.fromkeys((case.__name__ for case in CASES), 0)
    for i, kind in enumerate(kinds):
        case = CASES[int(kind)]
        counts[case.__name__] += 1
        try:
            case(np.random.default_rng([SEED, i]))
        except OSError:
            pass  # the server may close a hostile connection at any point
        if (i + 1) % CASES_PER_BATCH == 0:
            assert server.poll() is None, f"the server died by case {i}"
            assert_serves_clients()
    print(f"\nfuzz cases: {counts}")
    tracebacks = [line for line in server.log_lines if "Traceback" in line]
    assert not tracebacks, "".join(server.log_lines)[-5000:]
