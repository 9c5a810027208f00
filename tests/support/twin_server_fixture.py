"""Start ``tvist twin-server`` as a subprocess on UR's fixed ports, for tests; raw clients
(RTDE, dashboard, script port) for what the unmodified ur_rtde client cannot send.

The server listens on a loopback address of its own test process (``127.x.y.z`` from the
process id; Linux routes the whole of ``127.0.0.0/8`` to this machine), so that test runs in
parallel on one machine, the pytest-xdist workers of one run, or a twin server someone left
running on ``127.0.0.1``, do not take each other's ports. UR's ports cannot be moved (ur_rtde
connects to them), the address can; a server that reaches inside the process
(``local_server`` in ``test_twin_server_hardening.py``) takes ports the OS assigns."""

from __future__ import annotations

import contextlib
import os
import select
import socket
import struct
import subprocess
import sys
import threading
import time
from collections.abc import Iterator, Sequence

import pytest

UR_PORTS = (30004, 29999, 30001, 30002, 30003)


def loopback_host(pid: int) -> str:
    """The loopback address of process ``pid``: one per process id (Linux ids are below
    2**22 = 254 * 256 * 64.5, so the second byte stays below 67); never 127.0.0.1, the last
    byte never 0 or 255."""
    rest, last = divmod(pid, 254)
    high, middle = divmod(rest, 256)
    return f"127.{1 + high}.{middle}.{1 + last}"


#: This test process's loopback address.
HOST = loopback_host(os.getpid())
#: The twin the tests' server runs: the demo's 5 kg payload, 5 cm beyond the flange.
PAYLOAD_KG = 5.0
PAYLOAD_COM_M = (0.0, 0.0, 0.05)
#: Generous: the server is up in ~2 s on an idle machine; a loaded CI box is slower.
STARTUP_TIMEOUT_S = 60.0


def check_ports_free() -> None:
    """Fail (not hang) naming the first UR port that something else listens on."""
    for port in UR_PORTS:
        with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as sock:
            sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
            try:
                sock.bind((HOST, port))
            except OSError as exc:
                pytest.fail(
                    f"port {port} on {HOST} is taken ({exc.strerror}): the twin server tests "
                    "need UR's ports 30001-30004 and 29999 there"
                )


@contextlib.contextmanager
def twin_server(*extra: str) -> Iterator[subprocess.Popen]:
    """A running twin server (5 kg payload); stopped (and checked alive) afterwards."""
    check_ports_free()
    args = [sys.executable, "-m", "tvist.urserver", "--host", HOST]
    args += ["--payload-kg", str(PAYLOAD_KG)]
    args += ["--payload-com", *(str(v) for v in PAYLOAD_COM_M), *extra]
    proc = subprocess.Popen(
        args, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, bufsize=1
    )
    try:
        deadline = time.monotonic() + STARTUP_TIMEOUT_S
        line = ""
        while time.monotonic() < deadline:
            # Wait for output without blocking past the deadline (a hung server must fail).
            ready, _, _ = select.select([proc.stdout], [], [], deadline - time.monotonic())
            if not ready:
                break
            line = proc.stdout.readline()
            if "twin server ready" in line or not line:
                break
        if "twin server ready" not in line:
            proc.kill()
            out = proc.stdout.read()
            pytest.fail(f"twin server did not start: {line}{out}")
        # Keep draining the server's log so that it never blocks on a full pipe.
        proc.log_lines = []
        drain = threading.Thread(
            target=lambda: proc.log_lines.extend(iter(proc.stdout.readline, "")), daemon=True
        )
        drain.start()
        yield proc
        assert proc.poll() is None, "the twin server died during the tests"
    finally:
        if proc.poll() is None:
            proc.terminate()
            try:
                proc.wait(timeout=10)
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.wait()
        if proc.stdout is not None:
            proc.stdout.close()


# ----------------------------------------------------------------------------- raw clients

#: The control script as the twin recognizes it (entry point, command loop, the register
#: offsets ur_rtde injects on the line after the comment); a stand-in for ur_rtde's script
#: when a test writes the command registers itself.
CONTROL_SCRIPT = """def rtde_control():
    global reg_offset_float = # float register offset
{float_offset}    global reg_offset_int = # int register offset
{int_offset}
    def rtde_cmd():
        return read_input_integer_register(0 + reg_offset_int)
    end
end
"""


def control_inputs(offset: int = 0) -> list[str]:
    """ur_rtde's input registers of the control script: command, async flag, 11 arguments."""
    ints = [f"input_int_register_{offset + i}" for i in range(2)]
    return ints + [f"input_double_register_{offset + i}" for i in range(11)]


def upload_script(host: str = HOST, float_offset: int | str = 0, int_offset: int | str = 0) -> None:
    """Send :data:`CONTROL_SCRIPT` to the secondary script port (the twin runs it)."""
    program = CONTROL_SCRIPT.format(float_offset=float_offset, int_offset=int_offset)
    with socket.create_connection((host, 30002), timeout=5) as sock:
        sock.sendall(program.encode())


class RawRtde:
    """An RTDE client on a raw socket: every package a test wants, well-formed or not."""

    def __init__(
        self, host: str = HOST, port: int = 30004, timeout_s: float = 10.0, rcvbuf: int = 0
    ) -> None:
        self.sock = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
        if rcvbuf:  # before connecting: the window the server sees
            self.sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, rcvbuf)
        self.sock.settimeout(timeout_s)
        self.sock.connect((host, port))
        self.messages: list[bytes] = []  # text messages received (payloads)

    def send(self, kind: int | str, payload: bytes = b"") -> None:
        kind = ord(kind) if isinstance(kind, str) else kind
        self.sock.sendall(struct.pack(">HB", 3 + len(payload), kind) + payload)

    def read(self) -> tuple[int, bytes]:
        """The next package ``(type, payload)``; ConnectionError if the server closed."""
        size, kind = struct.unpack(">HB", self._exact(3))
        return kind, self._exact(size - 3)

    def _exact(self, n: int) -> bytes:
        data = b""
        while len(data) < n:
            chunk = self.sock.recv(n - len(data))
            if not chunk:
                raise ConnectionError("the server closed the connection")
            data += chunk
        return data

    def request(self, kind: str, payload: bytes = b"") -> bytes:
        """Send a package and return the payload of the reply of the same type (text
        messages on the way are kept in :attr:`messages`, data packages skipped)."""
        self.send(kind, payload)
        while True:
            got, body = self.read()
            if got == ord(kind):
                return body
            if got == ord("M"):
                self.messages.append(body)

    def version(self) -> None:
        assert self.request("V", struct.pack(">H", 2)) == b"\x01"

    def setup_outputs(self, names: Sequence[str], frequency_hz: float = 500.0) -> bytes:
        return self.request("O", struct.pack(">d", frequency_hz) + ",".join(names).encode())

    def setup_inputs(self, names: Sequence[str]) -> int:
        """The input recipe's id (0: refused)."""
        return self.request("I", ",".join(names).encode())[0]

    def start(self) -> None:
        assert self.request("S") == b"\x01"

    def data(self) -> bytes:
        """The payload of the next data package."""
        while True:
            kind, body = self.read()
            if kind == ord("U"):
                return body

    def close(self) -> None:
        self.sock.close()


class Commander(RawRtde):
    """Writes ur_rtde's command registers of a running :data:`CONTROL_SCRIPT` directly (those
    of register ``offset``: 0, or 24 for the upper range)."""

    def __init__(self, host: str = HOST, offset: int = 0) -> None:
        super().__init__(host)
        self.version()
        self.recipe = self.setup_inputs(control_inputs(offset))
        assert self.recipe != 0, "the command registers are taken"
        self.start()

    def command(self, cmd: int, *args: float, flag: int = 0) -> None:
        values = [*args] + [0.0] * (11 - len(args))
        self.send("U", struct.pack(">Bii11d", self.recipe, cmd, flag, *values))

    def close(self) -> None:
        """Leave "no command" in the registers (the next script must not find one) and
        release them; a second call does nothing."""
        if self.sock.fileno() >= 0:
            self.command(0)
            super().close()


class Subscriber:
    """A raw RTDE subscriber that collects ``(timestamp, target_q)`` of every data package
    in a thread (fields: ``timestamp``, ``target_q``)."""

    def __init__(self, host: str = HOST, frequency_hz: float = 500.0, port: int = 30004) -> None:
        self.client = RawRtde(host, port)
        self.client.version()
        reply = self.client.setup_outputs(["timestamp", "target_q"], frequency_hz)
        assert reply[0] != 0, reply
        self.client.start()
        self.samples: list[tuple[float, tuple[float, ...]]] = []
        self._thread = threading.Thread(target=self._run, daemon=True)
        self._thread.start()

    def _run(self) -> None:
        try:
            while True:
                body = self.client.data()
                values = struct.unpack(">B7d", body)
                self.samples.append((values[1], values[2:]))
        except (OSError, ConnectionError, struct.error):
            return

    def wait_for(self, n: int, max_wait_s: float = 30.0) -> list:
        """At least ``n`` more samples than now (fails, not hangs, if they do not come)."""
        start = len(self.samples)
        for _ in range(int(max_wait_s / 0.01)):
            if len(self.samples) >= start + n:
                return self.samples[start:]
            time.sleep(0.01)
        pytest.fail(f"only {len(self.samples) - start} of {n} data packages arrived")

    def close(self) -> None:
        self.client.close()
        self._thread.join(timeout=10)


def server_timestamp(host: str = HOST) -> float:
    """The twin controller's clock now, s: the timestamp of the first data package of a fresh
    RTDE connection."""
    client = RawRtde(host)
    try:
        client.version()
        assert client.setup_outputs(["timestamp"])[0] != 0
        client.start()
        return struct.unpack(">Bd", client.data())[1]
    finally:
        client.close()


class CurrentReceive:
    """An ``rtde_receive.RTDEReceiveInterface`` whose reads are never older than the call.

    ur_rtde's receive thread takes the data stream in the background; on a busy machine (two
    test workers on two cores) its latest package can lag a blocking ``moveL`` that has
    already returned on the control connection, and a read right after it would see the arm
    still on its way. Each ``get...``/``is...`` call first waits (polls 1 ms apart, a bounded
    count) until the interface's stream has reached the server's clock at the call."""

    def __init__(self, receive, host: str = HOST, max_wait_s: float = 30.0) -> None:
        self._receive, self._host, self._max_wait_s = receive, host, max_wait_s

    def catch_up(self) -> None:
        now = server_timestamp(self._host)
        for _ in range(int(self._max_wait_s / 0.001)):
            if self._receive.getTimestamp() >= now:
                return
            time.sleep(0.001)
        pytest.fail(f"ur_rtde's receive stream did not reach the server's time {now} s")

    def __getattr__(self, name: str):
        attr = getattr(self._receive, name)
        if not name.startswith(("get", "is")) or name == "getTimestamp":
            return attr

        def current(*args):
            self.catch_up()
            return attr(*args)

        return current


def assert_serves_clients(host: str = HOST) -> None:
    """Release the arm as an operator would (dashboard ``stop``, ``unlock protective
    stop``); then a fresh ur_rtde client connects, reads advancing timestamps and moves the
    wrist (0.05 rad towards the middle of its range and back)."""
    import rtde_control
    import rtde_receive

    dashboard("stop", "unlock protective stop", host=host)
    assert dashboard("safetystatus", host=host) == ["Safetystatus: NORMAL"]
    probe = Subscriber(host)  # fails (ur_rtde would wait forever) if no data comes
    try:
        probe.wait_for(10)
    finally:
        probe.close()
    receive = rtde_receive.RTDEReceiveInterface(host, 500.0, ["timestamp", "target_q"])
    try:
        control = rtde_control.RTDEControlInterface(host)
        try:
            t0 = receive.getTimestamp()
            q = receive.getTargetQ()
            step = -0.05 if q[5] > 0.0 else 0.05
            q[5] += step
            assert control.moveJ(q, 1.0, 4.0)
            q[5] -= step
            assert control.moveJ(q, 1.0, 4.0)
            assert receive.getTimestamp() > t0
        finally:
            control.stopScript()
            control.disconnect()
    finally:
        receive.disconnect()


def dashboard(*commands: str, host: str = HOST, port: int = 29999) -> list[str]:
    """The dashboard's replies to ``commands`` (one connection)."""
    with socket.create_connection((host, port), timeout=10) as sock:
        reader = sock.makefile("rb")
        reader.readline()  # the greeting
        replies = []
        for command in commands:
            sock.sendall(command.encode() + b"\n")
            replies.append(reader.readline().decode().strip())
        reader.close()
        return replies


def wait_dashboard(
    command: str, expected: str, host: str = HOST, port: int = 29999, max_wait_s: float = 30.0
) -> str:
    """Poll a dashboard command until its reply contains ``expected``; the last reply."""
    reply = ""
    for _ in range(int(max_wait_s / 0.02)):
        (reply,) = dashboard(command, host=host, port=port)
        if expected in reply:
            return reply
        time.sleep(0.02)
    return reply
