"""The identification road end to end, as a user takes it, against ``tvist twin-server``:
``tvist plan`` -> each exported excitation program run on the (twin) robot while
``tvist record`` records it -> ``tvist identify`` -> ``tvist fit-map`` -> ``tvist run`` of
the demo's Q1 -> Q2 with the map.

Every step is a ``tvist`` subprocess; the programs go to the robot's script port as
``nc ROBOT 30002 < PROGRAM`` sends them. The plan is small (7 poses at the server's 5 kg,
2 s excitations, approach moves at 1 rad/s) to keep the test near two minutes.
"""

from __future__ import annotations

import signal
import socket
import subprocess
import sys
import time

import numpy as np
import pytest

from tvist.demo.motions import motion_by_name
from twin_server_fixture import HOST, PAYLOAD_COM_M, PAYLOAD_KG, twin_server

pytest.importorskip("rtde_receive")

#: The script port a program is sent to (the secondary interface).
SCRIPT_PORT = 30002
DASHBOARD_PORT = 29999
#: Polls of the dashboard's program state, 0.05 s apart: bounds a program's run (a 2 s
#: excitation and its approach take ~5 s of simulated time; a loaded machine slips).
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
        assert record.stdout.readline().startswith("recording"), "tvist record did not start"
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
        record.send_signal(signal.SIGINT)
        record.wait(timeout=60)
        record.stdout.close()
    assert record.returncode == 0


def _timestamp_steps(log) -> np.ndarray:
    """The steps between consecutive timestamps of a ur_rtde CSV log, s (read raw)."""
    t = np.loadtxt(log, delimiter=",", skiprows=1, usecols=0)
    return np.diff(t)


def test_plan_record_identify_fit_run_on_the_twin(tmp_path) -> None:
    plan = tmp_path / "plan"
    logs = tmp_path / "logs"
    logs.mkdir()
    com = [str(v) for v in PAYLOAD_COM_M]
    _tvist(
        "plan",
        "--payloads",
        str(PAYLOAD_KG),
        "--payload-com",
        *com,
        "--every",
        "8",
        "--duration",
        "2",
        "--approach-speed",
        "1.0",
        "--approach-accel",
        "2.0",
        "--out",
        str(plan),
    )
    programs = sorted(plan.glob("*.script"))
    assert len(programs) == 14  # 7 poses, base and shoulder
    move = tmp_path / "q1q2.csv"
    motion = motion_by_name("Q1->Q2")
    np.savetxt(move, motion.reference(0.0).q, delimiter=",", fmt="%.12f")
    with twin_server():
        for program in programs:
            _run_while_recording(program.read_text(), logs / f"{program.stem}.csv")
        _tvist(
            "identify",
            str(logs),
            "--out",
            str(tmp_path / "poses.jsonl"),
            "--payload-kg",
            str(PAYLOAD_KG),
            "--payload-com",
            *com,
            "--workers",
            "2",
        )
        _tvist("fit-map", str(tmp_path / "poses.jsonl"), "--out", str(tmp_path / "map.json"))
        runs = {}
        for name, flags in (
            ("unshaped", ["--unshaped"]),
            ("map", ["--map", str(tmp_path / "map.json")]),
        ):
            log = tmp_path / f"run_{name}.csv"
            # The payload is given as the server's (5 kg, 5 cm beyond the flange).
            payload = ["--payload-kg", str(PAYLOAD_KG), "--payload-com", *com]
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
                *payload,
            )
            runs[name] = (log, done.stdout + done.stderr)
    from tvist.live import residual_vibration

    unshaped = residual_vibration(runs["unshaped"][0])
    shaped = residual_vibration(runs["map"][0])
    # The identified map must do what the paper's map does on the twin: >= 95 % less
    # residual vibration than the unshaped move.
    assert shaped <= 0.05 * unshaped, (shaped, unshaped, runs["map"][1])
    # Every log, the excitations' and the runs', has every 2 ms sample once.
    for log in [*sorted(logs.glob("*.csv")), runs["unshaped"][0], runs["map"][0]]:
        steps = _timestamp_steps(log)
        np.testing.assert_allclose(steps, 0.002, atol=1e-6, err_msg=str(log))
