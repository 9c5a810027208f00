"""Start ``tvist twin-server`` as a subprocess on UR's fixed ports, for tests.

The server listens on a loopback address of its own test session (``127.x.y.z`` from the
process id; Linux routes the whole of ``127.0.0.0/8`` to this machine), so that test runs in
parallel on one machine, or a twin server someone left running on ``127.0.0.1``, do not take
each other's ports."""

from __future__ import annotations

import contextlib
import os
import select
import socket
import subprocess
import sys
import threading
import time
from collections.abc import Iterator

import pytest

UR_PORTS = (30004, 29999, 30001, 30002, 30003)
_PID = os.getpid()
#: This session's loopback address (never 127.0.0.1; the last byte never 0 or 255).
HOST = f"127.{1 + (_PID >> 16) % 254}.{(_PID >> 8) & 255}.{1 + (_PID & 255) % 254}"
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
