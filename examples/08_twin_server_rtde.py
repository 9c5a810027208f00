"""Drive the flexible twin with the unmodified ur_rtde client, as a real UR.

Starts ``tvist twin-server`` (the simulated UR5e behind UR's RTDE, dashboard and script
ports), connects ur_rtde's receive and control interfaces, makes one moveJ of the base and
reads the tool accelerometer while the arm rings after the stop, then stops the server.
Needs ur-rtde (``pip install 'tvist[robot]'``).

    python examples/08_twin_server_rtde.py
"""

from __future__ import annotations

import os
import select
import subprocess
import sys
import threading
import time

import numpy as np
import rtde_control
import rtde_receive

# A loopback address of this process's own (Linux routes all of 127.0.0.0/8 here), so the
# example never meets a twin server already running on 127.0.0.1. With a robot: its IP.
pid = os.getpid()
HOST = f"127.{1 + (pid >> 16) % 254}.{(pid >> 8) & 255}.{1 + (pid & 255) % 254}"

server = subprocess.Popen(
    [sys.executable, "-m", "tvist.urserver", "--host", HOST, "--payload-kg", "5"],
    stdout=subprocess.PIPE,
    stderr=subprocess.STDOUT,
    text=True,
)
try:
    deadline = time.monotonic() + 60.0  # ~2 s on an idle machine
    line = ""
    while "ready" not in line:  # wait for "twin server ready on ..."
        waiting = select.select([server.stdout], [], [], max(deadline - time.monotonic(), 0.0))
        line = server.stdout.readline() if waiting[0] else ""
        if not line:  # it exited, or stayed silent for 60 s
            sys.exit("the twin server did not start")
    print(line.strip())
    # Keep reading its log, so that the server never blocks on a full pipe.
    threading.Thread(target=server.stdout.read, daemon=True).start()

    receive = rtde_receive.RTDEReceiveInterface(HOST)
    control = rtde_control.RTDEControlInterface(HOST)  # uploads ur_rtde's control script
    q = receive.getActualQ()
    control.moveJ([q[0] + 0.5, *q[1:]], 1.0, 2.0)  # blocks until the target is reached
    samples = []
    for _ in range(100):  # 0.5 s after the stop
        samples.append(receive.getActualToolAccelerometer())  # m/s², flange frame, gravity in
        time.sleep(0.005)
    control.stopScript()
    accel = np.asarray(samples)
    print(f"base moved {receive.getActualQ()[0] - q[0]:.4f} rad")
    print(
        f"accelerometer after the stop: mean {np.linalg.norm(accel.mean(axis=0)):.3f} m/s², "
        f"std {np.linalg.norm(accel.std(axis=0)):.4f} m/s² (the ringing, over 0.5 s)"
    )
    receive.disconnect()
    control.disconnect()
finally:
    server.terminate()
    try:
        server.wait(timeout=10)
    except subprocess.TimeoutExpired:
        server.kill()
        server.wait()
