"""Safety before motion: ``tvist run`` and ``tvist shape`` refuse a trajectory in degrees,
outside the joint limits or faster than the joint speed limits with one line naming the row,
the column and the fix (exit code 2), and nothing moves; ``tvist run`` reports the
controller's own account of a stop and how to recover; ``--dry-run`` describes the move
without a robot.

The robot is the twin server driven over UR's ports; whether it moved is read from its RTDE
stream (``target_q``) by the unmodified ur_rtde client, and its safety state from its
dashboard. The limits the refusals quote come from the robot data file, read here as JSON.
"""

from __future__ import annotations

import json
import socket
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from tvist.trajectory import PAPER_POSES
from twin_server_fixture import HOST, twin_server

rtde_control = pytest.importorskip("rtde_control")
rtde_receive = pytest.importorskip("rtde_receive")

Q1 = np.array(PAPER_POSES["Q1"])
ROBOT_DATA = Path(__file__).parents[2] / "crates/tvist-core/data/ur_e_series.json"
UR5E = json.loads(ROBOT_DATA.read_text())["robots"]["ur5e"]
DT_S = UR5E["control_period_s"]
SPEED_LIMIT_RAD_S = np.array(UR5E["max_velocity_rad_s"])
JOINT_LIMITS_RAD = np.array(UR5E["joint_limits_rad"])


def base_move(q_start, distance_rad: float, peak_speed_rad_s: float) -> np.ndarray:
    """A minimum-jerk move of the base by ``distance_rad`` with the given peak speed
    (closed form: the peak speed of a quintic is 15/8 of the mean), one row per 2 ms, at
    rest for 0.1 s at both ends."""
    duration = 1.875 * abs(distance_rad) / peak_speed_rad_s
    s = np.clip(np.arange(-0.1, duration + 0.1 + DT_S / 2, DT_S) / duration, 0.0, 1.0)
    blend = 10 * s**3 - 15 * s**4 + 6 * s**5
    return np.asarray(q_start) + np.outer(blend * distance_rad, [1, 0, 0, 0, 0, 0])


def write(path: Path, q: np.ndarray) -> Path:
    np.savetxt(path, q, delimiter=",", fmt="%.12f")
    return path


def tvist(*args: str) -> tuple[int, str, list[str]]:
    proc = subprocess.run(
        [sys.executable, "-m", "tvist.cli", *map(str, args)],
        capture_output=True,
        text=True,
        timeout=300,
    )
    return proc.returncode, proc.stdout, proc.stderr.strip().splitlines()


def dashboard(command: str) -> str:
    with socket.create_connection((HOST, 29999), timeout=5) as sock:
        reader = sock.makefile("rb")
        reader.readline()
        sock.sendall(command.encode() + b"\n")
        return reader.readline().decode().strip()


@pytest.fixture(scope="module")
def server():
    with twin_server() as proc:
        yield proc


@pytest.fixture
def receive(server):
    interface = rtde_receive.RTDEReceiveInterface(HOST, 500.0, ["target_q", "actual_q"])
    yield interface
    interface.disconnect()


def assert_refused_and_still(server, log_from, code, out, err, *texts) -> None:
    """One error line holding ``texts``, exit code 2, no motion announced, no protective stop
    (the server's log from line ``log_from`` on)."""
    assert code == 2, (code, out, err)
    assert len(err) == 1 and err[0].startswith("tvist run: error: "), err
    for text in texts:
        assert text in err[0], err
    assert "approach: moveJ" not in out  # refused before announcing any motion
    assert dashboard("safetystatus") == "Safetystatus: NORMAL"
    new_log = server.log_lines[log_from:]
    assert not any("protective stop" in line for line in new_log), new_log


# --------------------------------------------------------------------------- tvist run


@pytest.mark.slow
def test_run_refuses_a_csv_in_degrees_and_nothing_moves(server, receive, tmp_path):
    log_from, before = len(server.log_lines), np.array(receive.getTargetQ())
    move = write(tmp_path / "deg.csv", np.degrees(base_move(before, 0.3, 1.0)))
    code, out, err = tvist("run", move, "--robot-ip", HOST, "--unshaped")
    assert_refused_and_still(
        server,
        log_from,
        code,
        out,
        err,
        f"{move}, row 1, column q1:",
        "look like degrees",
        "--units q=deg",
    )
    np.testing.assert_array_equal(np.array(receive.getTargetQ()), before)


def test_run_refuses_a_pose_outside_the_joint_limits_and_nothing_moves(server, receive, tmp_path):
    log_from, before = len(server.log_lines), np.array(receive.getTargetQ())
    q = base_move(before, 0.3, 1.0)
    q[:, 2] = JOINT_LIMITS_RAD[2, 1] + 0.2  # the elbow beyond +π, still within ±2π
    move = write(tmp_path / "elbow.csv", q)
    code, out, err = tvist("run", move, "--robot-ip", HOST, "--unshaped")
    limits = f"[{JOINT_LIMITS_RAD[2, 0]:.4g}, {JOINT_LIMITS_RAD[2, 1]:.4g}] rad"
    assert_refused_and_still(
        server, log_from, code, out, err, "row 1, column q2:", f"outside joint 2's limits {limits}"
    )
    np.testing.assert_array_equal(np.array(receive.getTargetQ()), before)


def test_run_refuses_a_move_faster_than_the_speed_limit_and_nothing_moves(
    server, receive, tmp_path
):
    log_from, before = len(server.log_lines), np.array(receive.getTargetQ())
    move = write(tmp_path / "fast.csv", base_move(before, 1.0, 1.2 * SPEED_LIMIT_RAD_S[0]))
    code, out, err = tvist("run", move, "--robot-ip", HOST, "--unshaped")
    assert_refused_and_still(
        server,
        log_from,
        code,
        out,
        err,
        "column q0: joint 0 would move at",
        f"above its limit {SPEED_LIMIT_RAD_S[0]:.4g} rad/s",
        "slow the move down",
    )
    np.testing.assert_array_equal(np.array(receive.getTargetQ()), before)


@pytest.mark.slow
def test_run_reports_a_protective_stop_and_how_to_recover(server, receive, tmp_path):
    """A protective stop (a moveJ beyond the elbow's limit, sent by ur_rtde itself): the run
    refuses to start with the controller's own account and the dashboard commands that
    clear it; once unlocked, the same command runs, announcing the approach move first."""
    bad = receive.getActualQ()
    bad[2] = JOINT_LIMITS_RAD[2, 1] + 0.5
    control = rtde_control.RTDEControlInterface(HOST)
    try:
        assert not control.moveJ(bad, 0.5, 0.5)
    finally:
        control.stopScript()
        control.disconnect()
    assert dashboard("safetystatus") == "Safetystatus: PROTECTIVE_STOP"
    before = np.array(receive.getTargetQ())
    q = base_move(before, 0.1, 0.5)
    move = write(tmp_path / "move.csv", q)
    code, out, err = tvist("run", move, "--robot-ip", HOST, "--unshaped", "--tail", "0.2")
    assert code == 2 and len(err) == 1, (out, err)
    for text in (
        "safety mode PROTECTIVE_STOP",
        "(dashboard: 'Safetystatus: PROTECTIVE_STOP')",
        "'close safety popup' and 'unlock protective stop'",
        "nothing was moved",
    ):
        assert text in err[0], err
    assert "check --robot-ip" not in err[0]
    np.testing.assert_array_equal(np.array(receive.getTargetQ()), before)
    # After a refusal in the middle of a run, the same account is added to the message.
    from tvist.cli.live import _with_controller_reason

    reason = _with_controller_reason(HOST, "the robot refused servoJ at period 7", "")
    assert reason.startswith("the robot refused servoJ at period 7: the controller reports ")
    assert "unlock protective stop" in reason

    assert dashboard("unlock protective stop") == "Protective stop releasing"
    code, out, err = tvist(
        "run", move, "--robot-ip", HOST, "--unshaped", "--tail", "0.2", "--log", tmp_path / "l.csv"
    )
    assert code == 0, (out, err)
    announce = out.index("approach: moveJ to the first row at 0.5 rad/s")
    assert announce < out.index("sent ")  # said before anything was streamed
    # The run ends once the servo target has settled at the last row (1e-9 rad).
    np.testing.assert_allclose(np.array(receive.getTargetQ()), q[-1], atol=1e-6)


@pytest.mark.slow
def test_dry_run_describes_the_move_without_a_robot(tmp_path):
    """No --robot-ip: the peak speed printed is the file's (computed here by differences),
    with the model's limit; a plot is written; a file in degrees is refused all the same."""
    q = base_move(Q1, 0.8, 1.5)
    move = write(tmp_path / "move.csv", q)
    plot = tmp_path / "plot.png"
    code, out, err = tvist("run", move, "--dry-run", "--unshaped", "--plot", plot)
    assert code == 0, err
    peak = np.max(np.abs(np.diff(q[:, 0]))) / DT_S
    assert f"  0    {peak:7.3f} / {SPEED_LIMIT_RAD_S[0]:.3f}" in out, out
    assert "nothing is sent to a robot" in out and "path deviation (ur5e flange)" in out
    assert "moveJ at 0.5 rad/s" in out
    assert plot.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and plot.stat().st_size > 10_000

    code, out, err = tvist(
        "run", write(tmp_path / "d.csv", np.degrees(q)), "--dry-run", "--unshaped"
    )
    assert code == 2 and len(err) == 1 and "look like degrees" in err[0], err
    code, out, err = tvist("run", move, "--unshaped")
    assert code == 2 and "--robot-ip" in err[0], err


# --------------------------------------------------------------------------- tvist shape


def test_shape_refuses_degrees_and_limits_and_writes_nothing(tmp_path):
    q = base_move(Q1, 0.8, 1.5)
    out = tmp_path / "out.csv"
    cases = [
        (np.degrees(q), ["row 1, column q1:", "look like degrees", "--units q=deg"]),
        (q + [0, 0, 3.5, 0, 0, 0], ["row 1, column q2:", "outside joint 2's limits"]),
    ]
    for data, texts in cases:
        code, _, err = tvist(
            "shape", write(tmp_path / "in.csv", data), "--modes", "8:0.1", "--out", out
        )
        assert code == 2 and len(err) == 1, err
        for text in texts:
            assert text in err[0], err
        assert not out.exists()


@pytest.mark.slow
def test_shape_refuses_an_output_the_zero_delay_method_made_too_fast(tmp_path):
    """A move at 98 % of the base's speed limit: the input passes; ZTDIS compresses the
    motion in time (alpha < 1), which pushes the shaped speed over the limit."""
    move = write(tmp_path / "in.csv", base_move(Q1, 1.0, 0.98 * SPEED_LIMIT_RAD_S[0]))
    out = tmp_path / "out.csv"
    code, _, err = tvist("shape", move, "--modes", "8:0.1", "--method", "ztdis", "--out", out)
    assert code == 2 and len(err) == 1, err
    assert "the ztdis-shaped trajectory, output row" in err[0] and "above its limit" in err[0]
    assert not out.exists()
    assert tvist("shape", move, "--modes", "8:0.1", "--out", out)[0] == 0  # FD-TVIST: slower


def test_shape_reads_and_writes_declared_degrees(tmp_path):
    q = base_move(Q1, 0.8, 1.5)
    rad, deg = tmp_path / "rad_out.csv", tmp_path / "deg_out.csv"
    assert tvist("shape", write(tmp_path / "r.csv", q), "--modes", "8:0.1", "--out", rad)[0] == 0
    code, stdout, err = tvist(
        "shape",
        write(tmp_path / "d.csv", np.degrees(q)),
        "--modes",
        "8:0.1",
        "--out",
        deg,
        "--units",
        "q=deg",
    )
    assert code == 0, err
    assert "read and written in deg" in stdout
    # The degrees input is written with 12 decimals (rounding 5e-13 deg), the outputs with 9.
    np.testing.assert_allclose(
        np.loadtxt(deg, delimiter=","), np.degrees(np.loadtxt(rad, delimiter=",")), atol=2e-7
    )
