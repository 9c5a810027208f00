"""The UR twin server: the controller's network interfaces in front of :class:`TwinController`.

Ports (UR's): 30004 RTDE, 29999 dashboard, 30001-30003 the primary, secondary and real-time
script interfaces (programs sent there replace the running one). One thread paces the
controller to the wall clock at its 2 ms tick and publishes RTDE data packages; every client
connection has its own thread. A client's mistake (a malformed package, an unknown variable,
a register another client owns, a dropped connection) is answered or closes that connection
only; the server and the arm go on.

Every resource a client can make the server hold is bounded: simultaneous connections
(:data:`MAX_CLIENTS`), a dashboard line (:data:`DASHBOARD_MAX_LINE_BYTES`), a program on a
script port (:data:`MAX_PROGRAM_BYTES`), recipes per RTDE connection (:data:`MAX_RECIPES`,
ids are one byte) and the variable names of one (:data:`MAX_RECIPE_NAMES_BYTES`), a reply
(one package), the data queued for a subscriber (:data:`SEND_BUFFER_BYTES` in the kernel,
the rest of one package in the server: a subscriber that does not read loses packages, the
clock does not wait for it) and a blocked send (:data:`SEND_TIMEOUT_S`). A connection's
thread and buffers are freed when it closes.
"""

from __future__ import annotations

import logging
import os
import socket
import struct
import threading
import time
from collections.abc import Sequence
from dataclasses import dataclass, field

from tvist import rtde_wire
from tvist.urserver import variables
from tvist.urserver.controller import TwinController

log = logging.getLogger("tvist.urserver")

RTDE_PORT = 30004
DASHBOARD_PORT = 29999
SCRIPT_PORTS = (30001, 30002, 30003)
#: Controller version reported over RTDE (an e-Series, PolyScope 5.11).
CONTROLLER_VERSION = (5, 11, 8, 0)
POLYSCOPE_VERSION = "5.11.8.0"
#: Publishing is capped at the rate of the controller the server reports (e-Series: 500 Hz).
MAX_FREQUENCY_HZ = rtde_wire.output_rate_hz(CONTROLLER_VERSION[0])
#: FIFO priority of the tick thread where the OS allows it (Linux, privileged); the RTDE
#: readers run just below it.
TICK_PRIORITY = 20
#: Time a client has from a tick's output package to the next tick's read of its registers
#: (s), at least. A real controller's tick is never late; this one, in Python on a shared
#: machine, sometimes is, and starting the next tick on the wall-clock deadline anyway would
#: read the registers before a streaming client (servoJ every tick) could answer: the arm
#: would hold the old target for a tick and then jump. A late tick therefore delays the next
#: one and the simulated time slips behind the wall clock instead; the twin's physics and
#: the published timestamps follow the simulated time.
CLIENT_RESPONSE_S = 0.001
#: Pending connections the kernel queues per port before the server accepts them.
LISTEN_BACKLOG = 64
#: Simultaneous client connections over all ports; more are closed at once. Far below the
#: process's file limit, so accepting never runs out of files.
MAX_CLIENTS = 256
#: A send to a client that does not read blocks its connection's thread this long at most
#: (s); then that connection is closed.
SEND_TIMEOUT_S = 10.0
#: The kernel's send queue of a client connection (bytes; Linux doubles it): ~0.1 s of
#: ur_rtde's default recipe at 500 Hz, so a subscriber that stops reading is found out (and
#: costs the tick nothing) within a fraction of a second, not after megabytes.
SEND_BUFFER_BYTES = 1 << 16
#: Longest dashboard command (bytes, newline excluded); a longer line is refused unread.
DASHBOARD_MAX_LINE_BYTES = 4096
#: Largest program a script port buffers (bytes); ur_rtde's control script is 42 kB.
MAX_PROGRAM_BYTES = 1 << 20
#: How long :meth:`TwinServer.close` waits for the tick and the accept loops to end (s);
#: they end within a tick (2 ms) on an idle machine. Client threads end as their
#: connections close, and are not waited for.
CLOSE_TIMEOUT_S = 5.0
#: Recipes per RTDE connection and direction: ids are one byte and 0 marks a failure.
MAX_RECIPES = 255
#: Variable names of one recipe setup (bytes; the limit of UR's RTDE guide).
MAX_RECIPE_NAMES_BYTES = 2048


@dataclass
class ServerPorts:
    """The ports to listen on (tests and a second twin on one machine may move them)."""

    rtde: int = RTDE_PORT
    dashboard: int = DASHBOARD_PORT
    script: Sequence[int] = SCRIPT_PORTS

    def all(self) -> list[int]:
        return [self.rtde, self.dashboard, *self.script]


class PortInUse(OSError):
    """A UR port is taken on this host (another twin, URSim, or a robot driver)."""


@dataclass
class _RtdeSession:
    sock: socket.socket
    address: str
    outputs: list[rtde_wire.Recipe] = field(default_factory=list)
    inputs: dict[int, rtde_wire.Recipe] = field(default_factory=dict)
    n_inputs: int = 0
    frequency_hz: float = MAX_FREQUENCY_HZ
    phase: float = 0.0
    started: bool = False
    pending: bytes = b""
    owned: set = field(default_factory=set)
    send_lock: threading.Lock = field(default_factory=threading.Lock)

    def send(self, data: bytes) -> None:
        """Send a reply (blocking), after the rest of a data package the socket did not take
        at once: packages never interleave."""
        with self.send_lock:
            if self.pending:
                self.sock.sendall(self.pending)
                self.pending = b""
            self.sock.sendall(data)

    def ready(self) -> bool:
        """Whether a data package can go out now without blocking the tick: nothing else is
        sending on this connection and the rest of the previous package has left (if the
        client is not reading, this tick's packages are dropped, never queued)."""
        if not self.send_lock.acquire(blocking=False):
            return False  # a reply is being sent: never wait for it
        try:
            if self.pending:
                sent = self.sock.send(self.pending, socket.MSG_DONTWAIT)
                self.pending = self.pending[sent:]
            return not self.pending
        except BlockingIOError:
            return False
        except OSError:
            self.started = False
            return False
        finally:
            self.send_lock.release()

    def publish(self, data: bytes) -> None:
        """Send a data package without blocking the tick (after :meth:`ready`); what the
        socket does not take at once is kept and sent before the next package."""
        if not self.send_lock.acquire(blocking=False):
            return
        try:
            sent = self.sock.send(data, socket.MSG_DONTWAIT)
            self.pending = data[sent:]
        except BlockingIOError:
            pass
        except OSError:
            self.started = False
        finally:
            self.send_lock.release()


class TwinServer:
    """Serve a :class:`TwinController` on UR's ports.

    Parameters
    ----------
    controller
        The simulated controller.
    host
        Address to listen on (``127.0.0.1``: this machine only).
    ports
        Ports to listen on (UR's by default).
    """

    def __init__(
        self, controller: TwinController, host: str = "127.0.0.1", ports: ServerPorts | None = None
    ) -> None:
        self.controller = controller
        self.host = host
        self.ports = ports or ServerPorts()
        self._lock = threading.Lock()  # the controller, its registers, the owners
        self._sessions: list[_RtdeSession] = []
        self._owners: dict[str, _RtdeSession] = {}  # input variable -> session owning it
        self._listeners: list[socket.socket] = []
        self._threads: list[threading.Thread] = []  # the tick and the accept loops
        self._clients: set[socket.socket] = set()  # open client connections
        self._clients_lock = threading.Lock()
        self._stop = threading.Event()
        #: Ticks that ran late and delayed the next one (the simulated time slipped).
        self.late_ticks = 0

    # ------------------------------------------------------------------ lifecycle

    def start(self) -> None:
        """Bind every port, then start the tick and the listeners.

        Raises
        ------
        PortInUse
            Naming the first port that is taken (nothing is left listening then).
        """
        handlers = {self.ports.rtde: self._serve_rtde, self.ports.dashboard: self._serve_dashboard}
        for port in self.ports.script:
            handlers[port] = self._serve_script
        for port in self.ports.all():
            sock = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
            sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
            try:
                sock.bind((self.host, port))
            except OSError as exc:
                sock.close()
                self.close()
                raise PortInUse(
                    f"port {port} on {self.host} is in use ({exc.strerror}); stop whatever "
                    "listens there (another twin server, URSim, a robot driver)"
                ) from None
            sock.listen(LISTEN_BACKLOG)
            self._listeners.append(sock)
        for sock in self._listeners:
            port = sock.getsockname()[1]
            self._spawn(self._accept_loop, sock, handlers[port], name=f"accept-{port}")
        self._spawn(self._tick_loop, name="tick")

    def _spawn(self, target, *args, name: str) -> None:
        thread = threading.Thread(target=target, args=args, name=name, daemon=True)
        thread.start()
        self._threads.append(thread)

    def close(self) -> None:
        """Stop ticking, close every socket and wait (:data:`CLOSE_TIMEOUT_S` at most) for
        the tick and the accept loops to end; a second call does nothing more."""
        self._stop.set()
        for sock in self._listeners:
            _close(sock)  # the shutdown wakes its accept loop (a close alone does not)
        with self._clients_lock:
            clients = list(self._clients)
        for conn in clients:
            _close(conn)
        deadline = time.monotonic() + CLOSE_TIMEOUT_S
        for thread in self._threads:
            if thread is not threading.current_thread():
                thread.join(max(deadline - time.monotonic(), 0.0))
        stuck = [t.name for t in self._threads if t.is_alive()]
        if stuck:
            log.warning("still running %g s after close: %s", CLOSE_TIMEOUT_S, ", ".join(stuck))

    def serve_forever(self) -> None:
        """Block until :meth:`close` (or Ctrl-C)."""
        try:
            while not self._stop.wait(0.5):
                pass
        finally:
            self.close()

    # ------------------------------------------------------------------ tick

    def _tick_loop(self) -> None:
        if not _realtime(TICK_PRIORITY):
            log.info("the tick runs without real-time priority (not permitted here)")
        dt = self.controller.dt_s
        deadline = time.perf_counter()
        failing = False  # the previous tick failed (a streak of failures is logged once)
        while not self._stop.is_set():
            try:
                self._tick(dt)
                failing = False
            except Exception as exc:  # the tick must survive anything
                if not failing:
                    log.exception("tick failed")
                failing = True
                with self._lock:
                    self.controller.fault(f"server fault: {exc!r}")
            published = time.perf_counter()
            deadline, late = next_tick_deadline(deadline, published, dt)
            self.late_ticks += late
            time.sleep(max(deadline - published, 0.0))

    def _tick(self, dt: float) -> None:
        """One controller tick and its data packages."""
        with self._lock:
            values = self.controller.tick()
            sessions = [s for s in self._sessions if s.started]
        packed: dict[tuple, bytes] = {}  # one packing per recipe, however many subscribers
        for session in sessions:
            session.phase += session.frequency_hz * dt
            if session.phase < 1.0 - 1e-9:
                continue
            session.phase -= 1.0
            if not session.ready():
                continue  # a subscriber that does not read costs no packing
            for recipe in session.outputs:
                try:
                    data = packed.get(recipe.key)
                    if data is None:
                        data = packed[recipe.key] = recipe.pack(values)
                except Exception:  # a recipe that cannot be packed ends its stream only
                    log.exception("RTDE %s: output recipe %d", session.address, recipe.recipe_id)
                    session.started = False
                    break
                session.publish(data)

    # ------------------------------------------------------------------ accepting

    def _accept_loop(self, listener: socket.socket, handler) -> None:
        port = listener.getsockname()[1]
        while not self._stop.is_set():
            try:
                conn, address = listener.accept()
            except OSError as exc:
                if self._stop.is_set():
                    return
                log.error("accept on port %d failed (%s)", port, exc)
                self._stop.wait(0.05)  # e.g. out of files: retry, never give the port up
                continue
            name = f"{address[0]}:{address[1]}"
            with self._clients_lock:
                full = len(self._clients) >= MAX_CLIENTS
                if not full:
                    self._clients.add(conn)
            if full:
                log.warning("%s refused: %d connections are open", name, MAX_CLIENTS)
                _close(conn)
                continue
            try:
                conn.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
                conn.setsockopt(socket.SOL_SOCKET, socket.SO_SNDTIMEO, _timeval(SEND_TIMEOUT_S))
                conn.setsockopt(socket.SOL_SOCKET, socket.SO_SNDBUF, SEND_BUFFER_BYTES)
                # Not kept: the thread ends with its connection and leaves nothing behind.
                threading.Thread(
                    target=self._guard, args=(handler, conn, name), name="client", daemon=True
                ).start()
            except Exception:  # no thread for it (out of resources): refuse this one
                log.exception("client %s refused", name)
                self._forget(conn)

    def _guard(self, handler, conn: socket.socket, address: str) -> None:
        try:
            handler(conn, address)
        except (OSError, ConnectionError):
            pass
        except Exception:  # a client must never take the server down
            log.exception("client %s: handler failed", address)
        finally:
            self._forget(conn)

    def _forget(self, conn: socket.socket) -> None:
        """Close a client connection and drop the server's reference to it."""
        _close(conn)
        with self._clients_lock:
            self._clients.discard(conn)

    # ------------------------------------------------------------------ RTDE

    def _serve_rtde(self, conn: socket.socket, address: str) -> None:
        # A streaming client's commands must reach the registers within the tick they
        # arrive in: the RTDE reader is real-time too (just below the tick).
        _realtime(TICK_PRIORITY - 1)
        session = _RtdeSession(conn, address)
        with self._lock:
            self._sessions.append(session)
        try:
            while not self._stop.is_set():
                header = _recv_exact(conn, rtde_wire.HEADER.size)
                if header is None:
                    return
                size, kind = rtde_wire.HEADER.unpack(header)
                if size < rtde_wire.HEADER.size:
                    # The stream can no longer be split into packages: end this connection.
                    session.send(rtde_wire.text_message(f"malformed package header (size {size})"))
                    log.warning("RTDE %s: malformed package (size %d), closing", address, size)
                    return
                payload = _recv_exact(conn, size - rtde_wire.HEADER.size)
                if payload is None:
                    return
                self._rtde_package(session, kind, payload)
        finally:
            with self._lock:
                self._sessions.remove(session)
                for name in session.owned:
                    self._owners.pop(name, None)

    def _rtde_package(self, session: _RtdeSession, kind: int, payload: bytes) -> None:
        if kind == rtde_wire.REQUEST_PROTOCOL_VERSION:
            ok = len(payload) == 2 and struct.unpack(">H", payload)[0] == rtde_wire.PROTOCOL_VERSION
            session.send(rtde_wire.package(kind, bytes([int(ok)])))
        elif kind == rtde_wire.GET_URCONTROL_VERSION:
            session.send(rtde_wire.package(kind, struct.pack(">IIII", *CONTROLLER_VERSION)))
        elif kind == rtde_wire.CONTROL_PACKAGE_SETUP_OUTPUTS:
            session.send(_setup_reply(session, kind, self._setup_outputs(session, payload)))
        elif kind == rtde_wire.CONTROL_PACKAGE_SETUP_INPUTS:
            session.send(_setup_reply(session, kind, self._setup_inputs(session, payload)))
        elif kind == rtde_wire.CONTROL_PACKAGE_START:
            ok = bool(session.outputs) or bool(session.inputs)
            # First package at the next tick, then one every 1 / frequency.
            session.phase = 1.0 - session.frequency_hz * self.controller.dt_s
            # The reply goes out before the first data package: ur_rtde reads exactly one
            # package as the reply, and a data package read in its place leaves it waiting
            # for a start it never sees.
            session.send(rtde_wire.package(kind, bytes([int(ok)])))
            session.started = ok
        elif kind == rtde_wire.CONTROL_PACKAGE_PAUSE:
            session.started = False
            session.send(rtde_wire.package(kind, b"\x01"))
        elif kind == rtde_wire.DATA_PACKAGE:
            self._data_package(session, payload)
        else:
            session.send(rtde_wire.text_message(f"unknown package type {kind}"))

    def _setup_outputs(self, session: _RtdeSession, payload: bytes) -> bytes:
        if len(payload) < 8:
            return b"\x00" + b"NOT_FOUND"
        refusal = _recipe_refusal(len(session.outputs), len(payload) - 8)
        if refusal:
            session.send(rtde_wire.text_message(refusal))
            return b"\x00"
        frequency = struct.unpack(">d", payload[:8])[0]
        names = rtde_wire.split_names(payload[8:])
        types = [variables.OUTPUTS.get(n, "NOT_FOUND") for n in names]
        valid = bool(names) and "NOT_FOUND" not in types and 0.0 < frequency <= MAX_FREQUENCY_HZ
        if not 0.0 < frequency <= MAX_FREQUENCY_HZ:
            refusal = f"output frequency {frequency:g} Hz not in (0, {MAX_FREQUENCY_HZ:g}] Hz"
            session.send(rtde_wire.text_message(refusal))
        recipe_id = len(session.outputs) + 1 if valid else 0
        if valid:
            session.outputs.append(rtde_wire.Recipe(recipe_id, names, types))
            session.frequency_hz = frequency
        return bytes([recipe_id]) + ",".join(types).encode()

    def _setup_inputs(self, session: _RtdeSession, payload: bytes) -> bytes:
        refusal = _recipe_refusal(len(session.inputs), len(payload))
        if refusal:
            session.send(rtde_wire.text_message(refusal))
            return b"\x00"
        names = rtde_wire.split_names(payload)
        with self._lock:
            types = []
            for name in names:
                owner = self._owners.get(name)
                if name not in variables.INPUTS:
                    types.append("NOT_FOUND")
                elif owner is not None and owner is not session:
                    types.append("IN_USE")
                else:
                    types.append(variables.INPUTS[name])
            valid = bool(names) and all(t in rtde_wire.TYPE_FORMATS for t in types)
            unknown = [n for n, t in zip(names, types, strict=True) if t == "NOT_FOUND"]
            if unknown:
                message = (
                    f"input recipe refused: the twin does not model {', '.join(unknown)[:200]} "
                    "(it has no I/O; its inputs are the registers and the speed slider)"
                )
                # Logged only: a client reads the setup reply next, not a text message.
                log.warning("%s", message)
            # Every request takes the next id, refused or not: ur_rtde numbers its recipes by
            # the order it asks for them (its I/O interface asks for the I/O the twin refuses
            # before the speed slider). Ids stop at 255 (one byte; 0 is "refused").
            recipe_id = 0
            if session.n_inputs < 255:
                session.n_inputs += 1
                recipe_id = session.n_inputs if valid else 0
            if recipe_id:
                session.inputs[recipe_id] = rtde_wire.Recipe(recipe_id, names, types)
                for name in names:
                    self._owners[name] = session
                    session.owned.add(name)
        return bytes([recipe_id]) + ",".join(types).encode()

    def _data_package(self, session: _RtdeSession, payload: bytes) -> None:
        recipe = session.inputs.get(payload[0]) if payload else None
        if recipe is None:
            session.send(rtde_wire.text_message("data package for an unknown input recipe ignored"))
            return
        try:
            values = recipe.unpack(payload)
        except (ValueError, struct.error) as exc:
            session.send(rtde_wire.text_message(f"malformed data package ignored: {exc}"))
            return
        regs = self.controller.registers
        with self._lock:
            for name, value in values.items():
                if name.startswith("input_int_register_"):
                    regs.in_int[int(name.rsplit("_", 1)[1])] = int(value)
                elif name.startswith("input_double_register_"):
                    regs.in_double[int(name.rsplit("_", 1)[1])] = float(value)
            self.controller.client_wrote(values)
            if int(values.get("speed_slider_mask", 0)) & 1:
                refusal = self.controller.set_speed_slider(values.get("speed_slider_fraction"))
                if refusal:
                    log.error("%s", refusal)
                    session.send(rtde_wire.text_message(refusal))

    # ------------------------------------------------------------------ dashboard

    def _serve_dashboard(self, conn: socket.socket, address: str) -> None:
        conn.sendall(b"Connected: Universal Robots Dashboard Server\n")
        limit = DASHBOARD_MAX_LINE_BYTES + 1  # with the newline
        with conn.makefile("rb") as reader:
            while True:
                raw = reader.readline(limit)
                if not raw:
                    return
                if not raw.endswith(b"\n") and len(raw) == limit:
                    while raw and not raw.endswith(b"\n"):  # skip the rest, unbuffered
                        raw = reader.readline(limit)
                    log.warning("dashboard %s: a line over %d bytes refused", address, limit - 1)
                    reply = f"could not understand: a command longer than {limit - 1} bytes"
                    conn.sendall(reply.encode() + b"\n")
                    continue
                command = raw.decode(errors="replace").strip()
                if not command:
                    continue
                reply, close = self._dashboard_reply(command)
                conn.sendall(reply.encode() + b"\n")
                if close:
                    return

    def _dashboard_reply(self, command: str) -> tuple[str, bool]:
        c = self.controller
        lower = command.lower()
        with self._lock:
            running = c.program_running
            if lower == "polyscopeversion":
                return f"URSoftware {POLYSCOPE_VERSION} (twin)", False
            if lower == "get serial number":
                return "0", False
            if lower == "get robot model":
                return c.twin.params.name.upper().rstrip("E"), False
            if lower == "is in remote control":
                return "true", False
            if lower == "robotmode":
                return "Robotmode: RUNNING", False
            if lower == "safetymode":
                return f"Safetymode: {'PROTECTIVE_STOP' if c.protective_stop else 'NORMAL'}", False
            if lower == "safetystatus":
                status = "PROTECTIVE_STOP" if c.protective_stop else "NORMAL"
                return f"Safetystatus: {status}", False
            if lower == "get last error":  # the twin's own: what a UR shows in a popup
                return f"Last error: {c.last_error or 'none'}", False
            if lower == "running":
                return f"Program running: {'true' if running else 'false'}", False
            if lower == "programstate":
                return ("PLAYING " + c.program_name) if running else "STOPPED <unnamed>", False
            if lower == "get loaded program":
                return "No program loaded", False
            if lower == "isprogramsaved":
                return "false <unnamed>", False
            if lower == "stop":
                # A UR answers "Stopped" with no program running too (ur_rtde relies on it
                # right after stopScript).
                c.stop_program()
                return "Stopped", False
            if lower == "unlock protective stop":
                if c.unlock_protective_stop():
                    return "Protective stop releasing", False
                return "Failed to execute: unlock protective stop (the robot is not stopped)", False
            if lower in ("power on", "brake release", "close popup", "close safety popup"):
                replies = {
                    "power on": "Powering on",
                    "brake release": "Brake releasing",
                    "close popup": "closing popup",
                    "close safety popup": "closing safety popup",
                }
                return replies[lower], False
            if lower.startswith("load "):
                return f"File not found: {command[5:]}", False
            if lower == "play":
                return "Failed to execute: play", False
            if lower == "quit":
                return "Disconnected", True
        return f"could not understand: '{command}'", False

    # ------------------------------------------------------------------ script ports

    def _serve_script(self, conn: socket.socket, address: str) -> None:
        buffer = ""
        while not self._stop.is_set():
            data = conn.recv(65536)
            if not data:
                return
            buffer += data.decode(errors="replace")
            if len(buffer) > MAX_PROGRAM_BYTES:
                log.error("script port %s: a program over %d bytes, closing", address, len(buffer))
                return
            while True:
                program, buffer = _split_program(buffer)
                if program is None:
                    break
                with self._lock:
                    error = self.controller.load_program(program)
                if error:
                    log.error("script port %s: %s", address, error)


def _recipe_refusal(n_recipes: int, names_bytes: int) -> str | None:
    """Why a recipe setup is refused (None: it is not), given the connection's recipes so
    far and the size of the variable names asked for."""
    if n_recipes >= MAX_RECIPES:
        return f"recipe refused: a connection has at most {MAX_RECIPES} recipes"
    if names_bytes > MAX_RECIPE_NAMES_BYTES:
        return (
            f"recipe refused: {names_bytes} bytes of variable names "
            f"(at most {MAX_RECIPE_NAMES_BYTES})"
        )
    return None


def _setup_reply(session: _RtdeSession, kind: int, reply: bytes) -> bytes:
    """The setup reply package, or a failed one (recipe id 0) if it would not fit in one."""
    if rtde_wire.HEADER.size + len(reply) > rtde_wire.MAX_PACKAGE_BYTES:
        session.send(rtde_wire.text_message("recipe refused: its reply does not fit in a package"))
        return rtde_wire.package(kind, b"\x00")
    return rtde_wire.package(kind, reply)


def _split_program(buffer: str) -> tuple[str | None, str]:
    """The first complete program or statement in ``buffer`` and the rest.

    A program runs from ``def name():`` / ``sec name():`` to an ``end`` at the start of a line;
    anything else is one statement per line.
    """
    stripped = buffer.lstrip()
    if not stripped:
        return None, ""
    if stripped.startswith(("def ", "sec ")):
        lines = stripped.split("\n")
        for i, line in enumerate(lines[1:], start=1):
            if line.rstrip() == "end" and i < len(lines) - 1:
                return "\n".join(lines[: i + 1]) + "\n", "\n".join(lines[i + 1 :])
        return None, buffer
    if "\n" not in stripped:
        return None, buffer
    line, rest = stripped.split("\n", 1)
    return line, rest


def next_tick_deadline(deadline_s: float, published_s: float, dt_s: float) -> tuple[float, bool]:
    """When the tick after the one due at ``deadline_s`` starts (wall clock, s), given that
    this tick's output went out at ``published_s``: one period later, or
    :data:`CLIENT_RESPONSE_S` after the output if that is later (then ``True``: this tick ran
    late and the simulated time slips)."""
    earliest = published_s + CLIENT_RESPONSE_S
    following = deadline_s + dt_s
    return (earliest, True) if following < earliest else (following, False)


def _realtime(priority: int) -> bool:
    """Put the calling thread under FIFO real-time scheduling; False where not permitted."""
    try:
        os.sched_setscheduler(0, os.SCHED_FIFO, os.sched_param(priority))
    except (AttributeError, OSError):
        return False
    return True


def _timeval(seconds: float) -> bytes:
    """A ``struct timeval`` for the socket time-out options."""
    return struct.pack("ll", int(seconds), int((seconds % 1.0) * 1e6))


def _recv_exact(conn: socket.socket, n: int) -> bytes | None:
    chunks = []
    while n > 0:
        chunk = conn.recv(n)
        if not chunk:
            return None
        chunks.append(chunk)
        n -= len(chunk)
    return b"".join(chunks)


def _close(sock: socket.socket) -> None:
    try:
        sock.shutdown(socket.SHUT_RDWR)
    except OSError:
        pass
    try:
        sock.close()
    except OSError:
        pass
