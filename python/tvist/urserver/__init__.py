"""A UR e-Series controller in front of the flexible MuJoCo twin, for the unmodified ur_rtde.

``tvist twin-server`` serves RTDE (30004), the dashboard (29999) and the script ports
(30001-30003) on localhost; ``RTDEReceiveInterface`` and ``RTDEControlInterface`` connect to
it as to a robot, and the arm they move vibrates like the real one.

Examples
--------
>>> from tvist.urserver import start_twin_server
>>> server = start_twin_server(payload_kg=5.0)  # doctest: +SKIP
>>> import rtde_receive
>>> rtde_receive.RTDEReceiveInterface("127.0.0.1").getActualQ()  # doctest: +SKIP
>>> server.close()  # doctest: +SKIP
"""

from __future__ import annotations

from collections.abc import Sequence

from tvist.urserver.server import PortInUse, ServerPorts, TwinServer

__all__ = ["PortInUse", "ServerPorts", "TwinServer", "start_twin_server"]


def start_twin_server(
    robot: str = "ur5e",
    payload_kg: float = 0.0,
    payload_com_m: Sequence[float] = (0.0, 0.0, 0.0),
    *,
    host: str = "127.0.0.1",
    q0: Sequence[float] | None = None,
    accel_noise_std: float = 0.0,
    ports: ServerPorts | None = None,
) -> TwinServer:
    """Build the twin and its controller and start serving (returns once listening).

    Parameters
    ----------
    robot
        Robot of the parameter file.
    payload_kg, payload_com_m
        The payload mounted on the flange (kg, m in the flange frame).
    host
        Address to listen on.
    q0
        Initial joint angles (rad); default the stretched pose Q1.
    accel_noise_std
        White noise on each accelerometer axis (m/s²).
    ports
        Ports (UR's by default).

    Raises
    ------
    ValueError
        Unknown robot or impossible payload / pose.
    PortInUse
        A port is taken.
    """
    import numpy as np

    from tvist.sim import Twin
    from tvist.urserver.controller import TwinController, initial_pose

    twin = Twin(
        robot, payload_kg=payload_kg, payload_com_m=payload_com_m, accel_noise_std=accel_noise_std
    )
    start = initial_pose(twin) if q0 is None else np.asarray(q0, dtype=float)
    server = TwinServer(TwinController(twin, start), host=host, ports=ports)
    server.start()
    return server
