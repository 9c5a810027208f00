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
import signal
import socket
import struct
import subprocess
import sys
import tempfile
import threading
import time
from collections.abc import Callable, Iterator, Sequence
from pathlib import Path
from typing import TypeVar

import pytest

import rtde_packages

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


class ServerLog:
    """The server's output so far, as a list of lines (read from its log file at each use).

    The server writes to a file, not a pipe: a pipe drained by a thread of the test process
    fills whenever ur_rtde holds the interpreter (its constructors do not release it while
    they wait for the server), and a full pipe blocks the server's next log line inside its
    tick: the server would stop, and ur_rtde would wait for it for ever."""

    def __init__(self, path: Path) -> None:
        self.path = path

    def _lines(self) -> list[str]:
        return self.path.read_text(errors="replace").splitlines(keepends=True)

    def __len__(self) -> int:
        return len(self._lines())

    def __getitem__(self, index):
        return self._lines()[index]

    def __iter__(self) -> Iterator[str]:
        return iter(self._lines())


@contextlib.contextmanager
def twin_server(*extra: str) -> Iterator[subprocess.Popen]:
    """A running twin server (5 kg payload); stopped (and checked alive) afterwards. Its
    output is in ``proc.log_lines`` (:class:`ServerLog`)."""
    check_ports_free()
    args = [sys.executable, "-m", "tvist.urserver", "--host", HOST]
    args += ["--payload-kg", str(PAYLOAD_KG)]
    args += ["--payload-com", *(str(v) for v in PAYLOAD_COM_M), *extra]
    with tempfile.TemporaryDirectory(prefix="twin-server-") as folder:
        log_path = Path(folder) / "server.log"
        with log_path.open("wb") as log_file:
            proc = subprocess.Popen(args, stdout=log_file, stderr=subprocess.STDOUT)
        proc.log_lines = ServerLog(log_path)
        try:
            _wait_ready(proc)
            yield proc
            assert proc.poll() is None, "the twin server died during the tests"
        finally:
            stop_process(proc, signal.SIGTERM, "the twin server")


def _wait_ready(proc: subprocess.Popen) -> None:
    """Wait (polls 20 ms apart, :data:`STARTUP_TIMEOUT_S` at most) for the server's ready
    line; fail with its output if it exits or stays silent."""
    for _ in range(int(STARTUP_TIMEOUT_S / 0.02)):
        if any("twin server ready" in line for line in proc.log_lines):
            return
        if proc.poll() is not None:
            break
        time.sleep(0.02)
    state = "exited" if proc.poll() is not None else f"not ready after {STARTUP_TIMEOUT_S:g} s"
    stop_process(proc, signal.SIGKILL, "the twin server")
    pytest.fail(f"the twin server did not start ({state}): {''.join(proc.log_lines)}")


#: How long a process gets to exit after a signal before it is killed (s): the twin server
#: and ``tvist record``/``tvist run`` exit within a second of SIGTERM/SIGINT on an idle
#: machine (``tvist run`` stops the arm first: servoStop, stopScript).
EXIT_TIMEOUT_S = 60.0


def stop_process(
    proc: subprocess.Popen, sig: int, what: str, timeout_s: float = EXIT_TIMEOUT_S
) -> None:
    """Send ``sig`` to ``proc`` (if it still runs) and wait for it to exit; if it does not
    within ``timeout_s``, kill it and fail naming ``what``. Closes its pipes."""
    hung = False
    if proc.poll() is None:
        proc.send_signal(sig)
        try:
            proc.wait(timeout=timeout_s)
        except subprocess.TimeoutExpired:
            hung = True
            proc.kill()
            proc.wait(timeout=timeout_s)  # SIGKILL cannot be ignored
    for stream in (proc.stdin, proc.stdout, proc.stderr):
        if stream is not None:
            stream.close()
    if hung:
        name = signal.Signals(sig).name
        pytest.fail(f"{what} did not exit within {timeout_s:g} s of {name}; killed")


#: How many times a live shaped run is tried while its servo loop is disturbed.
LIVE_RUN_ATTEMPTS = 5
#: What ``tvist run`` prints when its servo loop woke too late and jumped over samples.
LATE_WAKE_WARNING = "woke too late"

Judged = TypeVar("Judged")


def first_undisturbed_run(
    run: Callable[[int], tuple[Judged, str]],
    good: Callable[[Judged], bool],
    attempts: int = LIVE_RUN_ATTEMPTS,
) -> tuple[Judged, str]:
    """``run(attempt)`` (a live ``tvist run``: its result and its output) until it is
    ``good`` or its servo loop was undisturbed; that result and output are judged.

    The client's servo loop and the server's tick are processes on a shared machine: a loop
    that woke too late jumps over samples (``tvist run`` warns, :data:`LATE_WAKE_WARNING`),
    and the jumps excite the arm, so such a run measures the machine, not the shaping. An
    undisturbed run is judged at once, good or bad. If all ``attempts`` runs were disturbed
    and none was good, nothing was measured: the test is skipped with that reason rather
    than failed on the machine's load."""
    for attempt in range(attempts):
        result, output = run(attempt)
        if good(result) or LATE_WAKE_WARNING not in output:
            return result, output
    pytest.skip(
        f"every one of {attempts} live runs had its servo loop wake too late (a loaded "
        f"machine): nothing was measured. Last run: {output.strip()[-300:]}"
    )


#: How long a line a test waits for from a child process's output may take (s).
LINE_TIMEOUT_S = 60.0


def read_line(proc: subprocess.Popen, what: str, timeout_s: float = LINE_TIMEOUT_S) -> str:
    """The next line of ``proc``'s stdout (a text pipe the child writes whole lines to, each
    flushed); fail naming ``what`` if none comes within ``timeout_s`` (the child is killed)."""
    ready, _, _ = select.select([proc.stdout], [], [], timeout_s)
    if not ready:
        proc.kill()
        proc.wait(timeout=timeout_s)
        pytest.fail(f"no line from {what} within {timeout_s:g} s")
    return proc.stdout.readline()


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


#: How long a raw client waits for a reply or a data package (s); each read of the socket
#: gives up sooner (the socket's own time-out) if nothing at all arrives.
REPLY_TIMEOUT_S = 30.0


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
        self.sock.sendall(rtde_packages.package(kind, payload))

    def read(self) -> tuple[int, bytes]:
        """The next package ``(type, payload)``; ConnectionError if the server closed."""
        return rtde_packages.read_package(self.sock)

    def request(self, kind: str, payload: bytes = b"", timeout_s: float = REPLY_TIMEOUT_S) -> bytes:
        """Send a package and return the payload of the reply of the same type (text
        messages on the way are kept in :attr:`messages`, data packages skipped); fail if
        it has not come within ``timeout_s`` (data packages alone keep every read short)."""
        self.send(kind, payload)
        deadline = time.monotonic() + timeout_s
        while time.monotonic() < deadline:
            got, body = self.read()
            if got == ord(kind):
                return body
            if got == ord("M"):
                self.messages.append(body)
        pytest.fail(f"no reply of type {kind!r} from the server within {timeout_s:g} s")

    def version(self) -> None:
        assert self.request("V", struct.pack(">H", 2)) == b"\x01"

    def setup_outputs(self, names: Sequence[str], frequency_hz: float = 500.0) -> bytes:
        return self.request("O", struct.pack(">d", frequency_hz) + ",".join(names).encode())

    def setup_inputs(self, names: Sequence[str]) -> int:
        """The input recipe's id (0: refused)."""
        return self.request("I", ",".join(names).encode())[0]

    def start(self) -> None:
        assert self.request("S") == b"\x01"

    def data(self, timeout_s: float = REPLY_TIMEOUT_S) -> bytes:
        """The payload of the next data package; fail if none comes within ``timeout_s``."""
        deadline = time.monotonic() + timeout_s
        while time.monotonic() < deadline:
            kind, body = self.read()
            if kind == ord("U"):
                return body
        pytest.fail(f"no data package from the server within {timeout_s:g} s")

    def close(self) -> None:
        """Close the connection; a thread blocked reading it returns at once (a plain close
        from another thread would leave it blocked until the socket's time-out)."""
        with contextlib.suppress(OSError):
            self.sock.shutdown(socket.SHUT_RDWR)
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
        except (OSError, ConnectionError, struct.error, pytest.fail.Exception):
            return  # closed, or the stream stopped: wait_for reports the shortfall

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
