"""RTDE packages on a raw socket for tests, written from UR's RTDE guide with ``struct``
alone (not tvist's wire module, so the tests do not share its assumptions): a package is
``uint16 size, uint8 type, payload``, big-endian, the size counting the 3-byte header."""

from __future__ import annotations

import socket
import struct


def package(kind: int | str, payload: bytes = b"") -> bytes:
    """One package of type ``kind`` (a letter or its code)."""
    kind = ord(kind) if isinstance(kind, str) else kind
    return struct.pack(">HB", 3 + len(payload), kind) + payload


def read_exactly(sock: socket.socket, n: int) -> bytes:
    """``n`` bytes from ``sock``; ConnectionError if the peer closes first."""
    data = b""
    while len(data) < n:
        chunk = sock.recv(n - len(data))
        if not chunk:
            raise ConnectionError("the peer closed the connection")
        data += chunk
    return data


def read_package(sock: socket.socket) -> tuple[int, bytes]:
    """The next package ``(type code, payload)``; ConnectionError if the peer closes."""
    size, kind = struct.unpack(">HB", read_exactly(sock, 3))
    return kind, read_exactly(sock, size - 3)
