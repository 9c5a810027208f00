"""Batch identification end to end: CSV logs on disk → ``tvist identify --out`` →
``tvist fit-map`` → :class:`tvist.MapDynamics` shaping a move.

The logs come from the independent generator (:mod:`ident_reference`), one base and one
shoulder excitation per pose, under shuffled file names, so the pairing must come from the
logs' ``actual_q``. Their modes follow the paper's map at each pose's inertia (the pipeline is
under test here, not the map law).
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

import tvist
from ident_reference import generate_log
from tvist.cli import main
from tvist.ident.batch import excited_joint, group_logs
from tvist.ident.campaign import campaign_poses
from tvist.ident.pose import PoseRecord
from tvist.robots import ur5e

#: One pose per angle V ≠ π/2 (there base and shoulder move the flange alike) and radius.
KEYS = [f"m0kg-V{v}-R{r}" for v in (0, 1, 3) for r in (1, 6, 11)]


@pytest.fixture(scope="module")
def campaign_logs(tmp_path_factory):
    folder = tmp_path_factory.mktemp("logs")
    poses = {p.key: p for p in campaign_poses(payloads_kg=(0.0,))}
    robot = ur5e()
    paper = tvist.DynamicMap.paper_ur5e()
    truth = {}
    order = np.random.default_rng(5).permutation(2 * len(KEYS))
    for i, key in enumerate(KEYS):
        q = poses[key].q
        modes = paper.modes_from_inertia(robot.joint_inertia(q))
        for joint in (0, 1):
            name = folder / f"log_{order[2 * i + joint]:02d}.csv"
            wn, zeta = modes[joint]
            generate_log(
                name,
                seed=100 + 2 * i + joint,
                joint=joint,
                wn_rad_s=wn,
                zeta=zeta,
                q0=q,
                duration_s=4.0,
            )
            truth[name.name] = (key, joint, wn, zeta)
    return folder, truth


@pytest.mark.slow
def test_identify_pairs_logs_by_pose_and_writes_records(campaign_logs, tmp_path, capsys):
    folder, truth = campaign_logs
    out = tmp_path / "results.jsonl"
    args = ["identify", str(folder), "--robot", "ur5e", "--payload-kg", "0", "--out", str(out)]
    assert main([*args, "--workers", "2"]) == 0
    assert f"{2 * len(KEYS)} logs -> {len(KEYS)} poses" in capsys.readouterr().out
    records = [json.loads(line) for line in out.read_text().splitlines()]
    assert len(records) == len(KEYS)
    for record in records:
        pose = PoseRecord.from_dict(record)
        assert pose.to_dict() == record  # the record round-trips
        names = {int(j): path.rsplit("/", 1)[-1] for j, path in record["logs"].items()}
        keys = {truth[name][0] for name in names.values()}
        assert len(keys) == 1, names  # both logs of one pose
        for joint, name in names.items():
            _, true_joint, wn, zeta = truth[name]
            assert joint == true_joint
            fit = pose.mode(joint)
            assert fit is not None and not fit.low_confidence, (name, fit)
            # The local-fit acceptance: 1 % in ω_n, 5 % in ζ.
            assert fit.wn_rad_s == pytest.approx(wn, rel=0.01)
            assert fit.zeta == pytest.approx(zeta, rel=0.05)
        assert len(record["inertia_kg_m2"]) == 6 and len(record["gravity_torque_nm"]) == 6

    # fit-map reads the records directly; the map then shapes a move.
    map_path = tmp_path / "map.json"
    assert main(["fit-map", str(out), "--out", str(map_path), "--k0", "12000"]) == 0
    dynmap = tvist.DynamicMap.load(map_path)
    assert all(m["k_0"] == 12000.0 for m in dynmap.mode_maps)
    robot = ur5e()
    for record in records:  # the map reproduces the identified modes (paper law: ~exact)
        predicted = dynmap.modes_from_inertia(record["inertia_kg_m2"])
        for fit, (wn, _) in zip(record["modes"], predicted, strict=True):
            assert wn == pytest.approx(fit["wn_rad_s"], rel=0.02)
    q_a, q_b = (np.array(r["q"]) for r in records[:2])
    s = np.linspace(0.0, 1.0, 501)
    move = q_a + np.outer(10 * s**3 - 15 * s**4 + 6 * s**5, q_b - q_a)
    move = np.vstack([move, np.repeat(q_b[None], 400, axis=0)])
    shaper = tvist.TvShaper(tvist.MapDynamics(robot, dynmap), dt_s=0.002, n_dof=6)
    shaped = shaper.shape(move)
    assert shaper.last_status == 0
    np.testing.assert_allclose(shaped[-1], q_b, atol=1e-9)
    # The shaper's delay is the two-mode ZV delay of the map's modes at q_b (half damped
    # periods of both modes).
    modes = dynmap.modes_from_inertia(robot.joint_inertia(q_b))
    zv = sum(math.pi / (wn * math.sqrt(1 - z * z)) for wn, z in modes)
    assert shaper.delay_s == pytest.approx(zv, rel=0.05)


def test_pairing_and_joint_detection(campaign_logs):
    from tvist.ident.batch import load_log

    folder, truth = campaign_logs
    logs = [load_log(folder / name) for name in sorted(truth)[:6]]
    for log in logs:
        assert excited_joint(log.record) == truth[log.path.name][1]
    pairs, others = group_logs(logs)
    assert not others
    for pair in pairs:
        if pair.base is not None and pair.shoulder is not None:
            assert truth[pair.base.path.name][0] == truth[pair.shoulder.path.name][0]


def test_identify_usage_errors_are_one_line(campaign_logs, tmp_path, capsys):
    folder, _ = campaign_logs
    assert main(["identify", str(folder)]) == 2  # many logs need --out
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [f"tvist identify: error: {2 * len(KEYS)} logs: name the results file with --out"]
    missing = tmp_path / "none.jsonl"
    assert main(["fit-map", str(missing)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("tvist fit-map: error: ") and str(missing) in err[0]
