"""Every CLI argument that names a file: a missing input or an unusable output is one line
``tvist <command>: error: FLAG PATH: ...`` naming the argument, exit code 2; and ``tvist
sensitivity`` reads either map kind through the loader the other commands use."""

from __future__ import annotations

import json

import numpy as np
import pytest

import tvist
from modal_fit_reference import LAWS_UR5E, exact_records, write_jsonl
from tvist.cli import main
from tvist.ident.campaign import campaign_poses
from tvist.ident.robustness import evaluate_map
from tvist.maps.modal import ModalMap


@pytest.fixture
def files(tmp_path):
    move = tmp_path / "move.csv"
    move.write_text("q0,q1,q2,q3,q4,q5\n" + "0,-3.14,0,-1.57,0,0\n" * 3)
    results = tmp_path / "c.jsonl"
    results.write_text("")
    a_file = tmp_path / "a_file"
    a_file.write_text("")
    return {
        "move": str(move),
        "results": str(results),
        "missing": str(tmp_path / "missing.json"),
        "dir": str(tmp_path),
        "under_a_file": str(a_file / "out.json"),
    }


CASES = [
    # (argv with {placeholders}, the argument the message must name, the path it must name)
    ("run {move} --robot-ip 127.0.0.1 --map {missing}", "--map", "missing"),
    ("run {missing} --robot-ip 127.0.0.1 --paper-map", "move", "missing"),
    ("run {move} --robot-ip 127.0.0.1 --paper-map --log {dir}", "--log", "dir"),
    ("record --robot-ip 127.0.0.1 --out {under_a_file}", "--out", "under_a_file"),
    ("shape {move} --out o.csv --map {missing}", "--map", "missing"),
    ("shape {missing} --out o.csv --paper-map", "input", "missing"),
    ("shape {move} --out {dir} --paper-map", "--out", "dir"),
    ("shape --bag {missing} --topic /t --out ob --paper-map", "--bag", "missing"),
    ("sensitivity --map {missing} --out {dir}", "--map", "missing"),
    ("sensitivity --results {missing} --out {dir}", "--results", "missing"),
    ("fit-map {missing}", "results", "missing"),
    ("fit-map {dir}", "results", "dir"),
    ("fit-map {results} --kind modal --out {under_a_file}", "--out", "under_a_file"),
    ("identify {missing} --joint 0", "logs", "missing"),
    ("demo --quick --map {missing} --out {dir}", "--map", "missing"),
    ("campaign --sim --out {under_a_file}", "--out", "under_a_file"),
]


@pytest.mark.parametrize(
    ("argv", "flag", "path"), CASES, ids=[c[0].split()[0] + " " + c[1] for c in CASES]
)
def test_a_path_argument_that_cannot_be_used_names_itself(files, capsys, argv, flag, path):
    code = main(argv.format(**files).split())
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2, err
    assert len(err) == 1, err
    command = argv.split()[0]
    assert err[0].startswith(f"tvist {command}: error: {flag} {files[path]}: "), err[0]
    assert "Errno" not in err[0]


@pytest.mark.slow
def test_sensitivity_reads_a_modal_map_and_judges_it_at_the_campaign_poses(tmp_path, capsys):
    poses = []
    for p in campaign_poses("ur5e", payloads_kg=(0.0, 5.0))[::9]:
        if p.q is not None:
            poses.append((p.key, p.q, p.payload_kg, p.payload_com_m))
    records = exact_records(LAWS_UR5E, poses, noise_wn=0.0, noise_zeta=0.0, seed=0)
    for r in records:  # what a campaign record carries besides the modes
        robot = tvist.robots.ur5e(payload_kg=r["payload_kg"], payload_com_m=r["payload_com_m"])
        r["inertia_kg_m2"] = robot.joint_inertia(np.array(r["q"])).tolist()
    results = write_jsonl(records, tmp_path / "c.jsonl")
    modal = ModalMap(LAWS_UR5E, metadata={"robot": "ur5e"})
    map_path = tmp_path / "modal.json"
    modal.save(map_path)
    out = tmp_path / "sens"
    argv = ["sensitivity", "--map", str(map_path), "--results", str(results), "--out", str(out)]
    code = main([*argv, "--payload-kg", "0"])  # the PRV panels' payload: none
    assert code == 0, capsys.readouterr().err
    for name in ("prv_sensitivity", "base_frequency", "shoulder_frequency", "map_fit"):
        assert (out / f"{name}.png").stat().st_size > 10_000
    summary = json.loads((out / "robustness.json").read_text())
    assert summary["n_poses"] == len(records)
    # The map's modes at each pose are the core's for that pose's payload, and the records'
    # (exact damped) modes are within the shaper's 10 % PRV of them.
    evaluations = evaluate_map(records, modal)
    for e, r in zip(evaluations, records, strict=True):
        robot = tvist.robots.ur5e(payload_kg=r["payload_kg"], payload_com_m=r["payload_com_m"])
        np.testing.assert_allclose(e.predicted, modal.modes(robot, r["q"]), rtol=1e-12)
    assert summary["within_10_percent_prv"] == len(records)
    # A modal map identified on another robot is refused, naming --robot.
    code = main(["sensitivity", "--map", str(map_path), "--robot", "ur10e", "--out", str(out)])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and "not on ur10e (--robot)" in err[0], err
    # The published form still works as before.
    assert main(["sensitivity", "--results", str(results), "--out", str(tmp_path / "p")]) == 0
