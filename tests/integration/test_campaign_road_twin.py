"""The identification road end to end, as a user takes it, against ``tvist twin-server``:
``tvist plan`` -> each exported excitation program run on the (twin) robot while
``tvist record`` records it -> ``tvist identify`` -> ``tvist fit-map`` -> ``tvist run`` of
the demo's Q1 -> Q2 with the map.

Every step is a ``tvist`` subprocess; the programs go to the robot's script port as
``nc ROBOT 30002 < PROGRAM`` sends them. The plan is small (every 9th pose and the move's
two poses: 8 poses at the server's 5 kg, 3 s excitations, approach moves at 1.5 rad/s) to
keep the test short.
"""

from __future__ import annotations

import json
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from tvist.experiments.motions import DT_S, motion_by_name
from tvist.live import residual_vibration
from twin_server_fixture import (
    HOST,
    PAYLOAD_COM_M,
    PAYLOAD_KG,
    first_undisturbed_run,
    read_line,
    stop_process,
    twin_server,
)

pytest.importorskip("rtde_receive")

#: The script port a program is sent to (the secondary interface).
SCRIPT_PORT = 30002
DASHBOARD_PORT = 29999
#: Polls of the dashboard's program state, 0.05 s apart: bounds a program's run (a 3 s
#: excitation and its approach take ~6 s of simulated time; a loaded machine slips).
MAX_POLLS = 2400


def _tvist(*args: str) -> subprocess.CompletedProcess:
    done = subprocess.run(
        [sys.executable, "-m", "tvist.cli", *args], capture_output=True, text=True, timeout=600
    )
    assert done.returncode == 0, f"tvist {' '.join(args)}:\n{done.stdout}{done.stderr}"
    return done


def _dashboard(command: str) -> str:
    with socket.create_connection((HOST, DASHBOARD_PORT), timeout=10) as sock:
        reader = sock.makefile("rb")
        reader.readline()  # greeting
        sock.sendall(command.encode() + b"\n")
        return reader.readline().decode().strip()


def _run_while_recording(program: str, log) -> None:
    """``tvist record`` from before the program is sent until it has stopped, then Ctrl-C."""
    record = subprocess.Popen(
        [sys.executable, "-m", "tvist.cli", "record", "--robot-ip", HOST, "--out", str(log)],
        stdout=subprocess.PIPE,
        text=True,
    )
    try:
        assert read_line(record, "tvist record").startswith("recording"), (
            "tvist record did not start"
        )
        with socket.create_connection((HOST, SCRIPT_PORT), timeout=10) as sock:
            sock.sendall(program.encode())
        for state in ("PLAYING", "STOPPED"):  # it started, then it ended
            for _ in range(MAX_POLLS):
                if _dashboard("programState").startswith(state):
                    break
                time.sleep(0.05)
            else:
                pytest.fail(f"{log.name}: the program never reached {state}")
        time.sleep(0.5)  # the last ringing
    finally:
        stop_process(record, signal.SIGINT, "tvist record")
    assert record.returncode == 0


def _timestamp_steps(log) -> np.ndarray:
    """The steps between consecutive timestamps of a ur_rtde CSV log, s (read raw)."""
    t = np.loadtxt(log, delimiter=",", skiprows=1, usecols=0)
    return np.diff(t)


@pytest.mark.slow
def test_plan_record_identify_fit_run_on_the_twin(tmp_path) -> None:
    plan, logs = tmp_path / "plan", tmp_path / "logs"
    logs.mkdir()
    motion = motion_by_name("Q1->Q2")
    move = tmp_path / "q1q2.csv"
    np.savetxt(move, motion.reference(0.0, DT_S).q, delimiter=",", fmt="%.12f")
    # The user covers the poses of the move the map is for, besides the plan's own (Q2 has
    # Q1's inertias: the plan takes one of the two; no workspace poses, to keep it short; one
    # pose of the 7 at 90°, where the base identification is flagged).
    cover = tmp_path / "my_poses.csv"
    np.savetxt(cover, [motion.q_start, motion.q_end], delimiter=",", fmt="%.12f")
    com = [str(v) for v in PAYLOAD_COM_M]
    _tvist(
        *("plan", "--payloads", str(PAYLOAD_KG), "--payload-com", *com, "--every", "8"),
        *("--cover", str(cover), "--no-workspace-cover", "--duration", "3"),
        *("--out", str(plan)),
        *("--approach-speed", "1.5", "--approach-accel", "3.0"),
    )
    programs = sorted(plan.glob("*.script"))
    assert len(programs) == 24  # 7 + 1 poses, base, shoulder and elbow (the default --excite)
    with twin_server():
        for program in programs:
            _run_while_recording(program.read_text(), logs / f"{program.stem}.csv")
        poses, dynmap = tmp_path / "poses.jsonl", tmp_path / "map.json"
        # The payload of each log: the controller's, which tvist record recorded.
        _tvist("identify", str(logs), "--out", str(poses), "--workers", "2")
        assert {json.loads(line)["payload_kg"] for line in poses.read_text().splitlines()} == {
            PAYLOAD_KG
        }
        _tvist("fit-map", str(poses), "--out", str(dynmap))

        def run(name: str, *flags: str) -> tuple[Path, str]:
            log = tmp_path / f"run_{name}.csv"
            done = _tvist(
                "run",
                str(move),
                "--robot-ip",
                HOST,
                "--log",
                str(log),
                "--tail",
                "5",
                *flags,
            )
            return log, done.stdout + done.stderr

        unshaped_log, _ = run("unshaped", "--unshaped")
        unshaped = residual_vibration(unshaped_log)

        # A run whose servo loop woke too late is run again (first_undisturbed_run says why).
        def run_shaped(attempt: int) -> tuple[tuple[Path, float], str]:
            log, output = run(f"map{attempt}", "--map", str(dynmap))
            # With a map, the payload is the controller's (the server's 5 kg).
            assert f"payload {PAYLOAD_KG:g} kg" in output and "from the controller" in output
            return (log, residual_vibration(log)), output

        (shaped_log, shaped), output = first_undisturbed_run(
            run_shaped, lambda result: result[1] <= 0.05 * unshaped
        )
    # The identified map must do what the paper's map does on the twin: >= 95 % less
    # residual vibration than the unshaped move (offline, with the twin run directly, the
    # same plan's map gives 99.5 %).
    assert shaped <= 0.05 * unshaped, (shaped, unshaped, output)
    # Every log, the excitations' and the runs', has every 2 ms sample once.
    for log in [*sorted(logs.glob("*.csv")), unshaped_log, shaped_log]:
        steps = _timestamp_steps(log)
        np.testing.assert_allclose(steps, DT_S, atol=1e-6, err_msg=str(log))
