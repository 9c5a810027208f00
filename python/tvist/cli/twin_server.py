"""``tvist twin-server``: serve the flexible twin on UR's ports."""

from __future__ import annotations

import argparse
import logging
import os
import sys


def _cmd_twin_server(args: argparse.Namespace) -> int:
    from tvist.urserver.log_writer import LogWriter

    # The log goes to stderr from a thread of its own: a log call inside the server never
    # waits for the output (a full pipe would stop the server's clock).
    to_stderr = logging.StreamHandler()
    to_stderr.setFormatter(logging.Formatter("twin-server: %(levelname)s: %(message)s"))
    writer = LogWriter(to_stderr)
    code = 1
    try:
        code = _serve(args)
    finally:
        if not writer.close():
            # The log's output is blocked (a pipe nobody reads): a normal exit would wait for
            # it for ever (logging's shutdown flushes every handler). The server is closed.
            os._exit(code)
    return code


def _serve(args: argparse.Namespace) -> int:
    from tvist.cli.args import DEFAULT_PAYLOAD_COM_M
    from tvist.sim.flex import NoTwinError
    from tvist.urserver import PortInUse, start_twin_server

    # Client threads hand the interpreter to the 2 ms tick quickly (default 5 ms).
    sys.setswitchinterval(0.0005)
    try:
        server = start_twin_server(
            args.robot,
            args.payload_kg,
            args.payload_com or DEFAULT_PAYLOAD_COM_M,
            host=args.host,
            q0=args.q0,
            accel_noise_std=args.accel_noise,
        )
    except PortInUse as exc:
        print(f"tvist twin-server: error: {exc}", file=sys.stderr)
        return 2
    except NoTwinError as exc:
        print(f"tvist twin-server: error: --robot {args.robot}: {exc}", file=sys.stderr)
        return 2
    except ValueError as exc:
        print(f"tvist twin-server: error: {exc}", file=sys.stderr)
        return 2
    ports = ", ".join(str(p) for p in server.ports.all())
    com = " ".join(f"{v:g}" for v in (args.payload_com or DEFAULT_PAYLOAD_COM_M))
    print(
        f"twin server ready on {args.host}: ports {ports}, {args.robot} with a "
        f"{args.payload_kg:g} kg payload at {com} m (--payload-kg) (Ctrl-C stops it)",
        flush=True,
    )
    try:
        server.serve_forever()
    except KeyboardInterrupt:
        pass
    finally:
        server.close()
    return 0


def add_twin_server_command(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "twin-server",
        help="serve the flexible twin on UR's RTDE, dashboard and script ports (for ur_rtde)",
    )
    add_arguments(p)


def add_arguments(p: argparse.ArgumentParser) -> None:
    """The twin server's options (shared by ``tvist twin-server`` and
    ``python -m tvist.urserver``)."""
    from tvist.cli.args import add_robot_and_payload

    add_robot_and_payload(
        p,
        "payload mounted on the simulated arm",
        payload_from="default 0: none",
        payload_default=0.0,
    )
    p.add_argument("--host", default="127.0.0.1", help="address to listen on (default 127.0.0.1)")
    p.add_argument(
        "--q0",
        type=float,
        nargs=6,
        default=None,
        metavar="Q",
        help="initial joint angles, rad (default the stretched pose Q1)",
    )
    p.add_argument(
        "--accel-noise",
        type=float,
        default=0.0,
        help="white noise on each accelerometer axis, m/s² (default 0)",
    )
    p.set_defaults(func=_cmd_twin_server)


def main(argv: list[str] | None = None) -> int:
    """``python -m tvist.urserver``: the twin server without loading the rest of the CLI."""
    parser = argparse.ArgumentParser(
        prog="python -m tvist.urserver", description="Serve the flexible twin on UR's ports."
    )
    add_arguments(parser)
    return _cmd_twin_server(parser.parse_args(argv))
