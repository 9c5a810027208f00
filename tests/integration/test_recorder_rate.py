"""The recorder asks a controller for its own RTDE rate unless told one: a CB-series
controller (software 3.x) publishes at most 125 Hz and refuses a 500 Hz recipe, an e-Series
(5.x) publishes 500 Hz.

The controller here is a scripted peer on a loopback socket, written from UR's RTDE guide
(``tests/support/rtde_packages.py``, not tvist's wire module): it answers the protocol and
version requests, refuses an output recipe above its rate (recipe id 0, as a controller
does), and then streams data packages of one DOUBLE, the controller time."""

from __future__ import annotations

import socket
import struct
import threading

import pytest

from rtde_packages import package, read_package

#: (version reply, highest output rate in Hz) of the two controller generations.
CB3 = ((3, 15, 8, 106339), 125.0)
E_SERIES = ((5, 11, 8, 0), 500.0)


class ScriptedController:
    """One RTDE client served on a loopback port; ``asked_hz`` is the rate of each output
    setup it was asked for, ``version_asked`` whether the client asked its version."""

    def __init__(
        self, version: tuple[int, ...], max_rate_hz: float, *, refuse_start: bool = False
    ) -> None:
        self.version, self.max_rate_hz, self.refuse_start = version, max_rate_hz, refuse_start
        self.closed_by_client = threading.Event()
        self.asked_hz: list[float] = []
        self.version_asked = False
        self._listener = socket.create_server(("127.0.0.1", 0))
        self.port = self._listener.getsockname()[1]
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._serve, daemon=True)
        self._thread.start()

    def _serve(self) -> None:
        conn, _ = self._listener.accept()
        conn.settimeout(5.0)
        try:
            while not self._stop.is_set():
                try:
                    code, payload = read_package(conn)
                except ConnectionError:
                    self.closed_by_client.set()
                    return
                kind = chr(code)
                if kind == "V":
                    conn.sendall(package("V", b"\x01"))
                elif kind == "v":
                    self.version_asked = True
                    conn.sendall(package("v", struct.pack(">IIII", *self.version)))
                elif kind == "O":
                    rate = struct.unpack(">d", payload[:8])[0]
                    self.asked_hz.append(rate)
                    names = payload[8:].decode().split(",")
                    recipe = 1 if rate <= self.max_rate_hz else 0
                    types = ",".join("DOUBLE" for _ in names)
                    conn.sendall(package("O", bytes([recipe]) + types.encode()))
                elif kind == "S" and self.refuse_start:
                    conn.sendall(package("S", b"\x00"))
                elif kind == "S":
                    conn.sendall(package("S", b"\x01"))
                    self._stream(conn, 1.0 / self.asked_hz[-1])
                    return
        finally:
            conn.close()

    def _stream(self, conn: socket.socket, period_s: float) -> None:
        k = 0
        while not self._stop.wait(0.001):
            k += 1
            try:
                conn.sendall(package("U", b"\x01" + struct.pack(">d", k * period_s)))
            except OSError:
                return

    def close(self) -> None:
        self._stop.set()
        self._listener.close()
        self._thread.join(5.0)


@pytest.mark.parametrize("generation", [CB3, E_SERIES], ids=["cb3", "e-series"])
def test_the_recorder_asks_the_controllers_own_rate(generation, tmp_path) -> None:
    from tvist.live import RtdeRecorder

    controller = ScriptedController(*generation)
    try:
        with RtdeRecorder(
            "127.0.0.1", tmp_path / "log.csv", ["timestamp"], port=controller.port
        ) as rec:
            assert rec.frequency_hz == generation[1]
    finally:
        controller.close()
    assert controller.version_asked
    assert controller.asked_hz == [generation[1]]


def test_a_rate_given_is_asked_as_is_and_a_cb3_refuses_500_hz(tmp_path) -> None:
    """What the default avoids: 500 Hz asked of a CB3 is refused, naming the rate."""
    from tvist.live import RtdeRecorder

    controller = ScriptedController(*CB3)
    try:
        with pytest.raises(ValueError, match="at 500 Hz"):
            RtdeRecorder(
                "127.0.0.1", tmp_path / "log.csv", ["timestamp"], 500.0, port=controller.port
            )
    finally:
        controller.close()
    assert not controller.version_asked
    assert controller.asked_hz == [500.0]


def test_a_refused_start_leaves_no_file_and_no_connection(tmp_path) -> None:
    """The controller grants the recipe but refuses to start: the recorder raises, writes no
    CSV (not even a header) and closes its connection before raising."""
    from tvist.live import RtdeRecorder

    controller = ScriptedController(*E_SERIES, refuse_start=True)
    recorder = None
    try:
        with pytest.raises(ValueError, match="refused to start"):
            recorder = RtdeRecorder(
                "127.0.0.1", tmp_path / "log.csv", ["timestamp"], port=controller.port
            )
        # The recorder is still referenced by the traceback here: only an explicit close
        # ends the connection now.
        assert controller.closed_by_client.wait(2.0)
    finally:
        controller.close()
    assert recorder is None
    assert not (tmp_path / "log.csv").exists()
