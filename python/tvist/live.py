"""Live moves on a UR through ur_rtde: the shaped 500 Hz servo loop, and RTDE recording.

:func:`run_shaped_move` streams a planned joint trajectory to the robot with ``servoJ`` at the
controller rate, the shaper in the loop (each period: one reference sample in, one shaped
sample out, one ``servoJ``), keeps streaming until the shaped reference has settled at the
end pose, and records the RTDE log meanwhile. Whatever happens (an error, Ctrl-C), it ends
with ``servoStop`` then ``stopScript``: the arm is never left streaming.

:func:`record` records the RTDE fields identification needs while the robot runs a program
of the user's (for example an excitation exported with :func:`tvist.ident.to_urscript`).

The servo loop needs ur_rtde (``pip install 'tvist[robot]'``); the recorder reads the RTDE
stream itself (:class:`RtdeRecorder`). Both work against ``tvist twin-server``.
"""

from __future__ import annotations

import logging
import math
import threading
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

log = logging.getLogger("tvist.live")

#: RTDE fields of the logs (what :func:`tvist.ident.logs.read_rtde_csv` reads, plus actual_qd).
LOG_FIELDS = (
    "timestamp",
    "target_q",
    "target_qd",
    "target_qdd",
    "actual_q",
    "actual_qd",
    "actual_TCP_pose",
    "actual_tool_accelerometer",
)
#: RTDE fields of the payload the controller has been told (``set_payload``, the installation):
#: mass (kg) and centre of gravity (m, flange frame). Recorded when the controller provides
#: them (e-Series 5.5.1 and later), so a log names the payload it was recorded with.
PAYLOAD_FIELDS = ("payload", "payload_cog")
#: servoJ's lookahead time (s): UR's minimum. The shaper has already removed the arm's modes
#: from the reference; a longer lookahead only adds smoothing and lag the shaper does not
#: account for (and, on the arm's time-varying modes, delays the reference further).
SERVO_LOOKAHEAD_S = 0.03
#: servoJ's proportional gain: high enough to follow the shaped reference closely (lag
#: ~1/gain = 1 ms), below UR's maximum 2000 where a real arm starts to sound rough.
SERVO_GAIN = 1000.0
#: Joint deceleration of the final servoStop (rad/s²; the arm is at rest by then).
STOP_DECEL_RAD_S2 = 2.0
#: Speed and acceleration of the approach to the trajectory's first pose.
APPROACH_SPEED_RAD_S = 0.5
APPROACH_ACCEL_RAD_S2 = 0.5
#: FIFO priority of the servo loop's thread where the OS allows it (Linux, privileged):
#: a 500 Hz loop on a busy machine otherwise misses periods.
REALTIME_PRIORITY = 10
#: The shaped reference has settled when it is this close to the end pose (rad).
SETTLED_TOL_RAD = 1e-9
#: How long the RTDE recorder waits for the controller (s): to connect, for a reply, for
#: the next package of a started stream (500 Hz: 2 ms apart).
REPLY_TIMEOUT_S = 5.0


def read_controller_payload(host: str, port: int = 30004):
    """The payload the controller at ``host`` has been told (RTDE ``payload``,
    ``payload_cog``): a :class:`tvist.robots.Payload` (kg; m in the flange frame).

    Raises
    ------
    ValueError
        If the controller does not provide these fields (before e-Series 5.5.1).
    OSError
        If the controller cannot be reached.
    """
    from tvist.robots import Payload

    with RtdeRecorder(host, None, PAYLOAD_FIELDS, frequency_hz=10.0, port=port) as recorder:
        values = recorder.latest
    return Payload(float(values["payload"]), tuple(float(v) for v in values["payload_cog"]))


def control_interface(robot_ip: str):
    """ur_rtde's ``RTDEControlInterface`` at ``robot_ip``, once the controller has been seen
    to send RTDE data.

    The constructor waits for its first data package with no time limit, and holds the
    interpreter meanwhile (no Ctrl-C, no other thread): a controller that accepts the
    connection but sends nothing would hang the caller for ever. A short recording first
    (:class:`RtdeRecorder`, :data:`REPLY_TIMEOUT_S`) turns that into an error.

    Raises
    ------
    ConnectionError
        No RTDE data from ``robot_ip``, or ur_rtde could not connect (no free control
        interface: another client holds the registers).
    """
    rtde_control = _rtde_control()
    try:
        with RtdeRecorder(robot_ip, None, ("timestamp",), frequency_hz=10.0):
            pass
    except (OSError, ValueError) as exc:
        raise ConnectionError(f"{robot_ip} sends no RTDE data: {exc}") from exc
    try:
        return rtde_control.RTDEControlInterface(robot_ip)
    except RuntimeError as exc:  # ur_rtde reports a failed connection as RuntimeError
        raise ConnectionError(f"cannot take control of {robot_ip}: {exc}") from exc


def _rtde_control():
    try:
        import rtde_control
    except ImportError as exc:  # pragma: no cover - needs the optional dependency
        raise ImportError("a robot needs ur_rtde: pip install 'tvist[robot]' (or ur-rtde)") from exc
    return rtde_control


class RtdeRecorder:
    """Write every RTDE data package of ``fields`` to a CSV, in ur_rtde's log format.

    ur_rtde's ``startFileRecording`` writes the latest received state on a timer of its own,
    so a late or early wake-up repeats or skips samples; this recorder reads the output
    stream package by package in a thread and writes each one (comma-separated, 6
    decimals, vector fields as ``name_0 ..``), so nothing the controller sent is lost.

    Parameters
    ----------
    host
        Robot (or twin server) address.
    path
        CSV to write, or ``None`` to keep only the latest package (:attr:`latest`).
    fields
        RTDE output variables (scalars or vectors of doubles).
    frequency_hz
        Output rate asked of the controller, Hz; None: the controller's own rate, from the
        version it reports (e-Series 500 Hz, CB-series 125 Hz:
        :func:`tvist.rtde_wire.output_rate_hz`).
    port
        RTDE port.
    optional_fields
        More variables, left out (and so not in :attr:`fields`) if the controller does not
        provide them.

    Raises
    ------
    ValueError
        If the controller does not know one of the fields (naming it) or refuses the rate.
    OSError
        If the controller cannot be reached.
    """

    def __init__(
        self,
        host: str,
        path: str | Path,
        fields: Sequence[str] = LOG_FIELDS,
        frequency_hz: float | None = None,
        port: int = 30004,
        optional_fields: Sequence[str] = (),
    ) -> None:
        import socket
        import struct

        from tvist import rtde_wire as rtde

        self._rtde = rtde
        self.path = None if path is None else Path(path)
        self.latest: dict = {}
        self.n_samples = 0
        self._new_sample = threading.Condition()
        self._stop = threading.Event()
        self._sock = socket.create_connection((host, port), timeout=REPLY_TIMEOUT_S)
        self._file = None
        self._thread: threading.Thread | None = None
        try:
            self._sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
            self._buffer = b""
            reply = self._request(rtde.REQUEST_PROTOCOL_VERSION, struct.pack(">H", 2))
            if reply[:1] != b"\x01":
                raise ValueError(f"{host}: the controller refused RTDE protocol version 2")
            if frequency_hz is None:
                version = self._request(rtde.GET_URCONTROL_VERSION, b"")
                if len(version) < 4:
                    raise ValueError(f"{host}: the controller's version reply is malformed")
                frequency_hz = rtde.output_rate_hz(struct.unpack(">I", version[:4])[0])
            fields = [*fields, *optional_fields]
            for _ in range(2):  # the second setup leaves out the optional fields not provided
                names = ",".join(fields).encode()
                reply = self._request(
                    rtde.CONTROL_PACKAGE_SETUP_OUTPUTS, struct.pack(">d", frequency_hz) + names
                )
                types = reply[1:].decode().split(",")
                unknown = [f for f, t in zip(fields, types, strict=False) if t == "NOT_FOUND"]
                if not unknown or not set(unknown) <= set(optional_fields):
                    break
                fields = [f for f in fields if f not in unknown]
            if unknown or reply[0] == 0:
                missing = ", ".join(unknown) or "these fields"
                raise ValueError(
                    f"{host}: the controller does not provide {missing} at {frequency_hz:g} Hz"
                )
            self.fields = tuple(fields)
            self.frequency_hz = float(frequency_hz)  # Hz, as asked of the controller
            self._recipe = rtde.Recipe(reply[0], list(fields), types)
            self._columns = []
            for name, kind in zip(fields, types, strict=True):
                width = rtde.TYPE_WIDTHS.get(kind, 0)
                self._columns += [name] if width == 0 else [f"{name}_{i}" for i in range(width)]
            if self._request(rtde.CONTROL_PACKAGE_START, b"")[:1] != b"\x01":
                raise ValueError(f"{host}: the controller refused to start the output stream")
            # Opened once the stream is granted (a refused recording leaves no file); packages
            # that arrive meanwhile wait in the socket for the thread.
            if self.path is not None:
                self.path.parent.mkdir(parents=True, exist_ok=True)
                self._file = self.path.open("w")
                self._file.write(",".join(self._columns) + "\n")
            self._first = threading.Event()
            self._thread = threading.Thread(target=self._run, name="rtde-recorder", daemon=True)
            self._thread.start()
            if not self._first.wait(REPLY_TIMEOUT_S):
                raise OSError(f"{host}: no RTDE data within {REPLY_TIMEOUT_S:g} s")
        except BaseException:  # nothing left open: the socket, the file, the thread
            self.stop()
            raise

    def _read_package(self) -> tuple[int, bytes]:
        header = self._rtde.HEADER
        while True:
            if len(self._buffer) >= header.size:
                size, kind = header.unpack_from(self._buffer)
                if size < header.size:
                    raise OSError("malformed RTDE package from the controller")
                if len(self._buffer) >= size:
                    payload = self._buffer[header.size : size]
                    self._buffer = self._buffer[size:]
                    return kind, payload
            chunk = self._sock.recv(65536)
            if not chunk:
                raise OSError("the controller closed the RTDE connection")
            self._buffer += chunk

    def _request(self, kind: int, payload: bytes) -> bytes:
        """Send a package and return the payload of the controller's reply of the same type
        (other packages on the way skipped).

        Raises
        ------
        OSError
            If the reply has not come within :data:`REPLY_TIMEOUT_S` (each read of the socket
            also gives up after that long without any data).
        """
        self._sock.sendall(self._rtde.package(kind, payload))
        deadline = time.monotonic() + REPLY_TIMEOUT_S
        while time.monotonic() < deadline:
            got, reply = self._read_package()
            if got == kind:
                return reply
        raise OSError(f"no reply to RTDE request {kind} within {REPLY_TIMEOUT_S:g} s")

    def wait_newer(self, n_samples: int, timeout_s: float = 1.0) -> int:
        """Block until more than ``n_samples`` packages have arrived; the new count.

        Raises
        ------
        TimeoutError
            If none arrives within ``timeout_s``.
        """
        with self._new_sample:
            if not self._new_sample.wait_for(lambda: self.n_samples > n_samples, timeout_s):
                raise TimeoutError(f"no RTDE data package within {timeout_s:g} s")
            return self.n_samples

    def wait_controller_time(self, seconds: float, timeout_s: float = 1.0) -> None:
        """Block until the controller's clock has advanced by ``seconds``: that many seconds'
        worth of data packages at the recording rate (rounded up to a whole package).

        A wall-clock sleep is the same on a real controller, whose tick is never late; a twin
        server whose ticks run late lets its simulated time slip behind the wall clock, and a
        sleep there records less than ``seconds`` of the arm.

        Raises
        ------
        TimeoutError
            If no package arrives within ``timeout_s`` (the stream stopped).
        """
        with self._new_sample:
            count = self.n_samples
        target = count + math.ceil(seconds * self.frequency_hz - 1e-9)
        while count < target:
            count = self.wait_newer(count, timeout_s)

    def _run(self) -> None:
        data_kind = self._rtde.DATA_PACKAGE
        # Real-time where allowed: a client clocked by these packages must see them on time.
        _realtime_priority()  # nothing to restore: the thread ends with the recording
        try:
            while not self._stop.is_set():
                kind, payload = self._read_package()
                if kind != data_kind or payload[:1] != bytes([self._recipe.recipe_id]):
                    continue
                values = self._recipe.unpack(payload)
                if self._file is not None:
                    row = []
                    for name in self._recipe.names:
                        value = values[name]
                        row.extend(value if isinstance(value, list) else [value])
                    self._file.write(",".join(f"{float(v):.6f}" for v in row) + "\n")
                with self._new_sample:
                    self.latest = values
                    self.n_samples += 1
                    self._new_sample.notify_all()
                self._first.set()
        except TimeoutError:
            if not self._stop.is_set():
                log.error("RTDE recording ended: no data for %g s", REPLY_TIMEOUT_S)
        except OSError:
            if not self._stop.is_set():
                log.error("RTDE recording ended: the connection was lost")

    def stop(self) -> Path | None:
        """Stop reading, close the connection and the file; the file's path."""
        self._stop.set()
        try:
            self._sock.shutdown(2)
        except OSError:
            pass
        if self._thread is not None:
            self._thread.join(timeout=5.0)
        self._sock.close()
        if self._file is not None:
            self._file.close()
        return self.path

    def __enter__(self) -> RtdeRecorder:
        return self

    def __exit__(self, *exc) -> None:
        self.stop()


@dataclass(frozen=True)
class LiveRun:
    """What :func:`run_shaped_move` did.

    Attributes
    ----------
    log_path
        The RTDE log (ur_rtde's CSV format).
    stream_start_s, stream_end_s
        Controller timestamps (s, the log's ``timestamp``) of the first and the last servoJ.
    n_commands
        servoJ commands sent (one per period).
    n_skipped
        Periods the servo loop woke too late for: their samples were stepped through the
        shaper but never sent, so the robot's target jumped over them (0 on a loop that kept
        up; a jump excites the arm's modes).
    reference_end_s
        Controller time at which the unshaped reference ended (s).
    final_q
        Joint angles read at the end (rad), ``(n_dof,)``.
    """

    log_path: Path
    stream_start_s: float
    stream_end_s: float
    n_commands: int
    n_skipped: int
    reference_end_s: float
    final_q: np.ndarray


def run_shaped_move(
    robot_ip: str,
    Q: np.ndarray,  # noqa: N803 (the paper's Q)
    log_path: str | Path,
    *,
    shaper=None,
    dt_s: float,
    lookahead_s: float = SERVO_LOOKAHEAD_S,
    gain: float = SERVO_GAIN,
    tail_s: float = 3.0,
    max_settle_s: float = 5.0,
) -> LiveRun:
    """Run the joint trajectory ``Q`` on the robot with ``servoJ``, shaped live.

    Parameters
    ----------
    robot_ip
        Robot (or twin server) address.
    Q
        Joint reference (rad), one row per control period, ``(n_samples, n_dof)``.
    log_path
        Where to write the RTDE log (the approach move is not in it).
    shaper
        A :class:`tvist.TvShaper` (reset to ``Q[0]`` here) or ``None`` to stream ``Q`` as is.
    dt_s
        Control period (s): the controller's (the robot's ``control_period_s``, 0.002 on
        the e-Series).
    lookahead_s, gain
        servoJ's lookahead time (s) and gain; see :data:`SERVO_LOOKAHEAD_S`, :data:`SERVO_GAIN`.
    tail_s
        Recording after the last command (s): the arm holds the end pose meanwhile.
    max_settle_s
        Give up (``RuntimeError``) if the shaped reference has not settled this long after
        the reference's end.

    Raises
    ------
    ValueError
        Malformed ``Q``.
    ConnectionError
        No controller (or no free control interface) at ``robot_ip``.
    RuntimeError
        The robot refused a command or the shaper did not settle; the arm was stopped.
    """
    q_ref = np.asarray(Q, dtype=float)
    if q_ref.ndim != 2 or q_ref.shape[0] < 2 or not np.all(np.isfinite(q_ref)):
        raise ValueError("Q must be a finite array (n_samples >= 2, n_dof)")
    _rtde_control()  # ImportError before anything else if ur_rtde is missing
    path = Path(log_path)
    # Real-time from before ur_rtde starts its receive thread, which inherits the policy: at
    # normal priority that thread could be kept off the CPU while the real-time servo loop
    # waits for the state it holds (servoJ reads it), and the loop would miss ticks.
    previous = _realtime_priority()
    try:
        control = control_interface(robot_ip)
    except ConnectionError:
        _restore_priority(previous)
        raise
    try:
        if not control.moveJ(list(q_ref[0]), APPROACH_SPEED_RAD_S, APPROACH_ACCEL_RAD_S2):
            raise RuntimeError("the robot refused the approach moveJ to the first pose")
        time.sleep(0.5)  # let the approach's vibration pass before the log starts
        if shaper is not None:
            shaper.reset(q_ref[0].copy())
        with RtdeRecorder(
            robot_ip, path, LOG_FIELDS, 1.0 / dt_s, optional_fields=PAYLOAD_FIELDS
        ) as recorder:
            run = _stream(control, recorder, q_ref, shaper, dt_s, lookahead_s, gain, max_settle_s)
            recorder.wait_controller_time(tail_s)
            final_q = np.array(recorder.latest["actual_q"])
    finally:
        safe_stop(control)
        _restore_priority(previous)
    return LiveRun(path, *run, final_q)


def _stream(control, recorder, q_ref, shaper, dt_s, lookahead_s, gain, max_settle_s):
    """The servo loop; ``(start_s, end_s, n_commands, n_skipped, reference_end_s)`` (times in
    controller time, s).

    The loop is clocked by the controller: it waits for each RTDE data package (one per
    controller tick), then sends the sample due at that package's timestamp, so every
    command reaches the controller early in the tick it is meant for. If the loop wakes late
    it steps the shaper over the missed samples (counted in ``n_skipped``) and sends the one
    due now: the move is never stretched in time, but the reference jumps.
    """
    n = q_ref.shape[0]
    end = q_ref[-1]
    limit = n + int(np.ceil(max_settle_s / dt_s))
    count = recorder.wait_newer(recorder.n_samples)
    start_s = float(recorder.latest["timestamp"])
    k = -1  # last sample stepped through the shaper
    sent = skipped = 0
    while True:
        now_s = float(recorder.latest["timestamp"])
        due = max(k + 1, int(round((now_s - start_s) / dt_s)))
        skipped += due - k - 1
        while k < due:
            k += 1
            row = q_ref[min(k, n - 1)]
            # ur_rtde takes lists; TvShaper.step takes a float64 array.
            q = row if shaper is None else shaper.step(row)
        if not control.servoJ([float(v) for v in q], 0.0, 0.0, dt_s, lookahead_s, gain):
            raise RuntimeError(f"the robot refused servoJ at period {k}")
        sent += 1
        if _settled(k, n, q, end, limit, max_settle_s):
            break
        count = recorder.wait_newer(count)
    reference_end_s = start_s + (n - 1) * dt_s
    end_s = float(recorder.latest["timestamp"])
    return start_s, end_s, sent, skipped, reference_end_s


def _settled(k: int, n: int, q: np.ndarray, end: np.ndarray, limit: int, max_settle_s: float):
    """True once sample ``k`` is past the reference's last (``n - 1``) and the shaped sample
    ``q`` is at the end pose; ``RuntimeError`` past sample ``limit``."""
    if k >= n - 1 and float(np.max(np.abs(q - end))) <= SETTLED_TOL_RAD:
        return True
    if k >= limit:
        raise RuntimeError(
            f"the shaped reference has not settled {max_settle_s:g} s after the move's end"
        )
    return False


def shaped_reference(
    Q: np.ndarray,  # noqa: N803 (the paper's Q)
    shaper,
    dt_s: float,
    max_settle_s: float = 5.0,
) -> np.ndarray:
    """The joint reference :func:`run_shaped_move` streams, computed offline, one row per
    control period: ``Q`` stepped through ``shaper`` (reset to ``Q[0]``) until the shaped
    reference has settled at the end pose, or ``Q`` itself without a shaper. The servo loop
    takes the same steps, so a run that skips no period sends exactly these rows.

    Raises
    ------
    RuntimeError
        If the shaped reference has not settled ``max_settle_s`` after the reference's end.
    """
    q_ref = np.asarray(Q, dtype=float)
    if shaper is None:
        return q_ref.copy()
    n, end = q_ref.shape[0], q_ref[-1]
    limit = n + int(np.ceil(max_settle_s / dt_s))
    shaper.reset(q_ref[0].copy())
    rows = []
    for k in range(limit + 1):
        q = np.array(shaper.step(q_ref[min(k, n - 1)]), dtype=float)
        rows.append(q)
        if _settled(k, n, q, end, limit, max_settle_s):
            break
    return np.array(rows)


def _realtime_priority():
    """Raise this thread to real-time FIFO scheduling if allowed; the policy to restore."""
    import os

    try:
        previous = (os.sched_getscheduler(0), os.sched_getparam(0))
        os.sched_setscheduler(0, os.SCHED_FIFO, os.sched_param(REALTIME_PRIORITY))
        return previous
    except (AttributeError, OSError):  # not Linux, or not permitted: run as a normal thread
        return None


def _restore_priority(previous) -> None:
    import os

    if previous is not None:
        try:
            os.sched_setscheduler(0, previous[0], previous[1])
        except OSError:
            log.warning("could not restore the thread's scheduling policy")


def safe_stop(control) -> None:
    """``servoStop`` then ``stopScript``, each attempted even if the other fails."""
    try:
        control.servoStop(STOP_DECEL_RAD_S2)
    except Exception:  # the connection may be gone: still try to end the script
        log.exception("servoStop failed")
    finally:
        try:
            control.stopScript()
        except Exception:
            log.exception("stopScript failed")
        try:
            control.disconnect()
        except Exception:
            log.exception("disconnect failed")


def record(
    robot_ip: str,
    out: str | Path,
    *,
    frequency_hz: float | None = None,
    duration_s: float | None = None,
    stop: threading.Event | None = None,
    fields: Sequence[str] = LOG_FIELDS,
    on_start: Callable[[RtdeRecorder], object] | None = None,
    optional_fields: Sequence[str] = PAYLOAD_FIELDS,
) -> Path:
    """Record RTDE ``fields`` (and ``optional_fields`` the controller provides: by default
    the payload, so the log names it) to ``out`` until ``duration_s`` passes, ``stop`` is set
    or Ctrl-C.

    ``frequency_hz`` is the output rate asked of the controller (None: the controller's own,
    :class:`RtdeRecorder`); ``on_start`` is called with the recorder once the first sample
    has arrived.

    Every data package is written as it arrives (:class:`RtdeRecorder`); stopping closes the
    file after the last one, so an interrupt loses nothing that was received.
    """
    stop = stop or threading.Event()
    deadline = None if duration_s is None else time.monotonic() + duration_s
    recorder = RtdeRecorder(robot_ip, out, fields, frequency_hz, optional_fields=optional_fields)
    if on_start is not None:
        on_start(recorder)
    try:
        while not stop.is_set():
            if deadline is not None and time.monotonic() >= deadline:
                break
            stop.wait(0.05)
    finally:
        recorder.stop()
    return recorder.path


def residual_vibration(log_path: str | Path, window_s: float = 1.0) -> float:
    """Residual vibration of a logged move (m/s²): the RMS over ``window_s`` after the servo
    target came to rest of the accelerometer's deviation from its value at rest.

    The target is at rest from the first sample after which it stays within 1e-7 rad of its
    final value; the rest value is the accelerometer's mean over the last 0.2 s of the log.

    Raises
    ------
    ValueError
        If the log does not extend ``window_s`` + 0.2 s beyond the move.
    """
    from tvist.ident.logs import read_rtde_csv

    record = read_rtde_csv(log_path)
    t, target, accel = record.t_s, record.target_q, record.tool_accel
    away = np.flatnonzero(np.max(np.abs(target - target[-1]), axis=1) > 1e-7)
    t_rest = t[away[-1] + 1] if away.size else t[0]
    if t[-1] < t_rest + window_s + 0.2:
        raise ValueError(f"{log_path}: the log ends less than {window_s + 0.2:g} s after the move")
    rest = accel[t >= t[-1] - 0.2].mean(axis=0)
    window = (t >= t_rest) & (t < t_rest + window_s)
    deviation = np.linalg.norm(accel[window] - rest, axis=1)
    return float(np.sqrt(np.mean(deviation**2)))


def moving_span(q: np.ndarray) -> tuple[int, int]:
    """Sample indices ``(start, end)`` of the move in joint positions ``q`` (rad,
    ``(n, n_dof)``): the last sample at the first row's position, and the first sample at the
    last row's, each within 1e-7 rad; ``(end - start) * dt`` is the move's own duration.

    Raises
    ------
    ValueError
        If ``q`` never moves.
    """
    q = np.asarray(q, dtype=float)
    left = np.flatnonzero(np.max(np.abs(q - q[0]), axis=1) > 1e-7)
    if left.size == 0:
        raise ValueError("the servo target never moves: no move to settle")
    arriving = np.flatnonzero(np.max(np.abs(q - q[-1]), axis=1) > 1e-7)
    return max(int(left[0]) - 1, 0), int(arriving[-1]) + 1


def settle_times(
    t_s: np.ndarray, target_q: np.ndarray, accel: np.ndarray, rest_window_s: float = 0.2
) -> dict[float, float]:
    """Time to settled of a logged move, s from the move's start, per band of
    :data:`tvist.analysis.SETTLE_BANDS_M_S2` (``math.inf``: not settled within the log).

    The move starts at the first sample whose servo target ``target_q`` (rad,
    ``(n, n_dof)``) is more than 1e-7 rad from the first one. The tool acceleration ``accel``
    (m/s², ``(n, 3)``) is taken relative to its mean over the log's last ``rest_window_s``
    (gravity at the end pose, the arm at rest), and has settled once it stays inside the band
    for :data:`tvist.analysis.SETTLE_HOLD_S` or longer.
    """
    from tvist.analysis import SETTLE_BANDS_M_S2, SETTLE_HOLD_S, settling_time

    t, target, acc = np.asarray(t_s, float), np.asarray(target_q, float), np.asarray(accel, float)
    start, _ = moving_span(target)
    t_start = t[start]
    dynamic = acc - acc[t >= t[-1] - rest_window_s].mean(axis=0)
    return {
        band: settling_time(t, dynamic, t_start, band, hold_s=SETTLE_HOLD_S)
        for band in SETTLE_BANDS_M_S2
    }
