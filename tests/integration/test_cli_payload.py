"""The payload is never a silent 0 kg: every command that needs it takes ``--payload-kg`` or a
named source (the controller, the map file, the log's payload columns, the pose records) and
prints which; with none it stops in one line naming the flag, exit code 2, and nothing moves.

The controller cases run against ``tvist twin-server`` (5 kg, 5 cm beyond the flange)."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import tvist
from tvist.cli import main
from tvist.ident.excitation import random_excitation
from tvist.ident.logs import PAYLOAD_COLUMNS, Record, log_payload
from tvist.robots import params
from tvist.sim import Twin
from twin_server_fixture import HOST, PAYLOAD_COM_M, PAYLOAD_KG, twin_server

#: The UR5e's control period, s (its robot data).
UR5E_DT_S = params("ur5e").control_period_s

Q0 = np.array([0.3, -1.7, 1.4, -1.2, 1.57, 0.0])
#: The excited twin's payload (kg; m in the flange frame), not the twin server's.
LOG_PAYLOAD_KG, LOG_PAYLOAD_COM_M = 3.0, (0.0, 0.0, 0.05)


def _tvist(*argv: str) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "tvist.cli", *argv], capture_output=True, text=True, timeout=300
    )


def _one_error_line(done: subprocess.CompletedProcess, command: str) -> str:
    assert done.returncode == 2, done.stdout + done.stderr
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1, done.stderr
    assert lines[0].startswith(f"tvist {command}: error: ")
    assert "Traceback" not in done.stderr
    return lines[0]


@pytest.fixture(scope="module")
def logs(tmp_path_factory) -> dict[str, Path]:
    """A shoulder excitation of the twin (3 kg) as a log without payload columns and as one
    with them (what ``tvist record`` writes from a controller that publishes the payload)."""
    twin = Twin(
        "ur5e",
        payload_kg=LOG_PAYLOAD_KG,
        payload_com_m=LOG_PAYLOAD_COM_M,
        accel_noise_std=0.05,
    )
    record = Record.from_rtde_fields(twin.run(random_excitation(Q0, 1, seed=2, dt_s=UR5E_DT_S).q))
    folder = tmp_path_factory.mktemp("logs")
    plain = record.to_csv(folder / "plain.csv")
    text = plain.read_text().splitlines()
    payload = ",".join(f"{v:.6f}" for v in (LOG_PAYLOAD_KG, *LOG_PAYLOAD_COM_M))
    named = folder / "named.csv"
    named.write_text(
        "\n".join(
            [text[0] + "," + ",".join(PAYLOAD_COLUMNS)] + [row + "," + payload for row in text[1:]]
        )
        + "\n"
    )
    return {"plain": plain, "named": named}


# --------------------------------------------------------------------------- tvist shape


def test_shape_with_a_map_and_no_payload_stops_naming_the_flag(move_csv, tmp_path):
    out = tmp_path / "o.csv"
    done = _tvist("shape", str(move_csv), "--out", str(out), "--paper-map")
    line = _one_error_line(done, "shape")
    assert "no payload" in line and "--payload-kg" in line and "map file" in line
    assert not out.exists()


def test_shape_takes_the_payload_a_map_file_names(move_csv, tmp_path, capsys):
    # A map file whose metadata names its payload shapes exactly as that payload given as
    # flags, and says where the payload came from.
    payload = tvist.robots.Payload(5.0, (0.0, 0.0, 0.05))
    paper = tvist.DynamicMap.paper_ur5e()
    named = tmp_path / "named.json"
    tvist.DynamicMap(paper.mode_maps, {**paper.metadata, "payload": payload}).save(named)
    by_map, by_flag = tmp_path / "by_map.csv", tmp_path / "by_flag.csv"
    assert main(["shape", str(move_csv), "--out", str(by_map), "--map", str(named)]) == 0
    assert "payload 5 kg, centre of mass 0 0 0.05 m (flange frame), from the map file" in (
        capsys.readouterr().out
    )
    flags = ["--payload-kg", "5", "--payload-com", "0", "0", "0.05"]
    assert main(["shape", str(move_csv), "--out", str(by_flag), "--paper-map", *flags]) == 0
    shaped = np.loadtxt(by_map, delimiter=",")
    np.testing.assert_array_equal(shaped, np.loadtxt(by_flag, delimiter=","))
    # The payload matters here: without it the map's modes (and the output) differ.
    light = tmp_path / "light.csv"
    args = ["shape", str(move_csv), "--out", str(light), "--paper-map", "--payload-kg", "0"]
    assert main(args) == 0
    unloaded = np.loadtxt(light, delimiter=",")
    assert unloaded.shape != shaped.shape or not np.array_equal(unloaded, shaped)


# --------------------------------------------------------------------------- tvist identify


@pytest.mark.slow
def test_identify_a_log_without_payload_stops_naming_the_flag(logs):
    line = _one_error_line(_tvist("identify", str(logs["plain"]), "--joint", "1"), "identify")
    assert "no payload" in line and "--payload-kg" in line and "payload columns" in line


@pytest.mark.slow
def test_identify_batch_of_logs_without_payload_stops_naming_the_flag(logs, tmp_path):
    done = _tvist("identify", str(logs["plain"]), "--out", str(tmp_path / "r.jsonl"))
    line = _one_error_line(done, "identify")
    assert str(logs["plain"]) in line and "--payload-kg" in line
    assert not (tmp_path / "r.jsonl").exists()


def test_identify_takes_the_payload_the_log_names(logs, capsys):
    assert log_payload(logs["plain"]) is None
    found = log_payload(logs["named"])
    assert found.mass_kg == LOG_PAYLOAD_KG and tuple(found.com_m) == LOG_PAYLOAD_COM_M
    assert main(["identify", str(logs["named"]), "--joint", "1", "--json"]) == 0
    captured = capsys.readouterr()
    from_log = json.loads(captured.out)  # the note goes to stderr, the JSON stays parseable
    assert "payload 3 kg, centre of mass 0 0 0.05 m (flange frame), from the log's payload" in (
        captured.err
    )
    flags = ["--payload-kg", "3", "--payload-com", "0", "0", "0.05"]
    assert main(["identify", str(logs["plain"]), "--joint", "1", "--json", *flags]) == 0
    assert json.loads(capsys.readouterr().out) == from_log


def test_identify_batch_takes_each_logs_payload(logs, tmp_path, capsys):
    out = tmp_path / "r.jsonl"
    assert main(["identify", str(logs["named"]), "--out", str(out), "--workers", "1"]) == 0
    assert "payload from each log's payload columns: 3 kg (1 logs)" in capsys.readouterr().out
    (record,) = [json.loads(line) for line in out.read_text().splitlines()]
    assert record["payload_kg"] == LOG_PAYLOAD_KG
    assert record["payload_com_m"] == list(LOG_PAYLOAD_COM_M)


def test_a_repaired_log_still_names_its_payload(logs, tmp_path, capsys):
    # A malformed row refused by default and dropped with --repair: the payload is read from
    # the rows that remain, as the log itself is.
    lines = logs["named"].read_text().splitlines()
    path = tmp_path / "torn.csv"
    path.write_text("\n".join([*lines[:50], "1.0,2.0", *lines[50:]]) + "\n")
    argv = ["identify", str(path), "--joint", "1", "--repair", "drop-bad-rows"]
    assert main(argv) == 0
    captured = capsys.readouterr()
    assert "payload 3 kg, centre of mass 0 0 0.05 m (flange frame), from the log's" in (
        captured.out
    )
    assert "dropped 1 malformed row" in captured.err


def test_a_log_whose_payload_changes_is_refused(logs, tmp_path):
    lines = logs["named"].read_text().splitlines()
    half = len(lines) // 2
    changed = [lines[0], *lines[1:half]]
    changed += [",".join([*row.split(",")[: -len(PAYLOAD_COLUMNS)], "5", "0", "0", "0.05"])
                for row in lines[half:]]  # fmt: skip
    path = tmp_path / "changed.csv"
    path.write_text("\n".join(changed) + "\n")
    line = _one_error_line(_tvist("identify", str(path), "--joint", "1"), "identify")
    assert "the payload changes during the log (3 to 5 kg)" in line


# --------------------------------------------------------------------------- tvist fit-map


def test_fit_map_modal_refuses_records_without_a_payload(tmp_path, capsys):
    # The modal fit builds each pose's mass matrix with its payload: a record without one is
    # refused, not fitted as 0 kg.
    robot = tvist.robots.ur5e(payload_kg=5.0, payload_com_m=(0.0, 0.0, 0.05))
    path = tmp_path / "r.jsonl"
    with path.open("w") as fh:
        for i, q in enumerate([Q0, Q0 + 0.3]):
            record = {
                "key": f"p{i}",
                "q": [float(v) for v in q],
                "inertia_kg_m2": [float(v) for v in robot.joint_inertia(q)],
                "modes": [{"joint": 0, "wn_rad_s": 60.0, "zeta": 0.05, "low_confidence": False}],
            }
            fh.write(json.dumps(record) + "\n")
    out = tmp_path / "m.json"
    assert main(["fit-map", str(path), "--kind", "modal", "--out", str(out)]) == 2
    captured = capsys.readouterr()
    assert "records[0] (p0): no payload_kg" in captured.err
    assert "payload from the pose records: not recorded (2 poses)" in captured.out
    assert not out.exists()


# --------------------------------------------------------------------------- the controller


def test_run_without_a_controller_payload_stops_before_moving(move_csv, monkeypatch, capsys):
    # A controller that does not publish its payload (firmware before 5.5.1) and no
    # --payload-kg: one line naming the flag, exit 2, and the move is never started.
    import tvist.live

    def no_payload(host, port=30004):
        raise ValueError(f"{host}: the controller does not provide payload, payload_cog")

    def must_not_move(*args, **kwargs):
        raise AssertionError("the arm was moved")

    monkeypatch.setattr(tvist.live, "read_controller_payload", no_payload)
    monkeypatch.setattr(tvist.live, "run_shaped_move", must_not_move)
    assert main(["run", str(move_csv), "--robot-ip", "10.0.0.9", "--paper-map"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1
    assert "no payload" in err[0] and "the controller at 10.0.0.9" in err[0]
    assert "--payload-kg" in err[0]


@pytest.fixture(scope="module")
def server():
    with twin_server() as proc:
        yield proc


def test_the_controller_payload_is_read_over_rtde(server):
    payload = tvist.live.read_controller_payload(HOST)
    assert payload.mass_kg == PAYLOAD_KG
    np.testing.assert_array_equal(payload.com_m, PAYLOAD_COM_M)


def test_record_writes_the_controller_payload_into_the_log(server, tmp_path):
    out = tmp_path / "log.csv"
    done = _tvist("record", "--robot-ip", HOST, "--out", str(out), "--duration", "0.3")
    assert done.returncode == 0, done.stderr
    found = log_payload(out)
    assert found.mass_kg == PAYLOAD_KG
    np.testing.assert_array_equal(found.com_m, PAYLOAD_COM_M)


@pytest.mark.slow
def test_run_with_a_map_uses_the_controller_payload_and_says_so(server, tmp_path):
    # A short move at the arm's current pose (the approach is then a no-op): tvist run
    # shapes with the map and the controller's payload, and prints which payload it used.
    import rtde_receive

    receive = rtde_receive.RTDEReceiveInterface(HOST, 500.0, ["actual_q"])
    q = np.array(receive.getActualQ())
    receive.disconnect()
    move = tmp_path / "hold.csv"
    np.savetxt(move, np.repeat(q[None, :], 50, axis=0), delimiter=",", fmt="%.12f")
    log = tmp_path / "log.csv"
    done = _tvist(
        "run", str(move), "--robot-ip", HOST, "--paper-map", "--tail", "0.2", "--log", str(log)
    )
    assert done.returncode == 0, done.stdout + done.stderr
    assert (
        f"payload {PAYLOAD_KG:g} kg, centre of mass 0 0 0.05 m (flange frame), from the "
        f"controller at {HOST}"
    ) in done.stdout
    assert log_payload(log).mass_kg == PAYLOAD_KG  # and the log names it for identify


def test_sensitivity_of_a_modal_map_needs_its_payload(tmp_path, capsys):
    # A modal map's PRV panels at Q1 and Q3 depend on the payload: none given, none in the map.
    path = tmp_path / "modal.json"
    from modal_fit_reference import LAWS_UR5E

    tvist.ModalMap(LAWS_UR5E, metadata={"robot": "ur5e"}).save(path)
    assert main(["sensitivity", "--map", str(path), "--out", str(tmp_path / "s")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "a modal map's PRV panels" in err[0] and "--payload-kg" in err[0]


def test_the_recorder_leaves_out_optional_fields_a_controller_lacks(server, tmp_path):
    # A controller without the payload fields (before e-Series 5.5.1) answers NOT_FOUND for
    # them: the recording goes on without them. A name the twin does not know stands in.
    from tvist.live import LOG_FIELDS, RtdeRecorder

    path = tmp_path / "log.csv"
    with RtdeRecorder(HOST, path, LOG_FIELDS, optional_fields=("no_such_field",)) as recorder:
        recorder.wait_newer(recorder.n_samples)
        assert recorder.fields == LOG_FIELDS
    with RtdeRecorder(HOST, None, ("timestamp",), optional_fields=("payload",)) as recorder:
        assert recorder.fields == ("timestamp", "payload")
        assert recorder.latest["payload"] == PAYLOAD_KG
    header = path.read_text().splitlines()[0]
    assert header.startswith("timestamp,target_q_0") and "no_such_field" not in header
    # A required field the controller lacks is still refused, naming it.
    with pytest.raises(ValueError, match="does not provide no_such_field"):
        RtdeRecorder(HOST, tmp_path / "x.csv", ("timestamp", "no_such_field"))
