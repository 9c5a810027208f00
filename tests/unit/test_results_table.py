"""tools/results_table.py: the README's results table is the rendering of
docs/results/headline.json, and each row's figures are read from its command's outputs.

The synthetic outputs are written by the commands' own writers where they have one
(``results.json`` of the experiments, the campaign's results store, ``modal_fit --out``, the
twin's RTDE log), so the format the tool reads cannot drift from the one they write."""

from __future__ import annotations

import copy
import importlib.util
import json
import math
import re
import sys
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]


def _load_tool():
    spec = importlib.util.spec_from_file_location(
        "results_table", ROOT / "tools" / "results_table.py"
    )
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # dataclasses look their module up
    spec.loader.exec_module(module)
    return module


rt = _load_tool()


def _readme() -> str:
    return (ROOT / "README.md").read_text(encoding="utf-8")


# --------------------------------------------------------------------------- --check


def test_readme_table_is_the_rendering_of_the_record():
    assert rt.check(_readme(), rt.load_record()) == []
    assert rt.main(["--check"]) == 0


def test_a_hand_edited_readme_number_fails_the_check():
    readme = _readme()
    start, stop = rt._section(readme)
    table = readme[start:stop]
    assert "172.6 ns" in table or "ns with fixed modes" in table
    line = next(x for x in table.splitlines() if "ns with fixed modes" in x)
    edited_line = re.sub(r"(\d+\.\d) ns with fixed modes", r"\g<1>9 ns with fixed modes", line)
    assert edited_line != line
    edited = readme[:start] + table.replace(line, edited_line) + readme[stop:]
    problems = rt.check(edited, rt.load_record())
    assert len(problems) == 1 and "not the record's rendering" in problems[0]


def test_a_shown_figure_that_is_not_its_value_fails_the_check():
    record = copy.deepcopy(rt.load_record())
    figure = record["rows"][0]["figures"]["modal_q1_q2"]
    figure["shown"] = "99.99"  # the value stays what it was
    assert rt.figure_problems(record)
    assert rt.check(_readme(), record)


def test_every_number_of_the_measured_cells_is_a_figure_of_the_record():
    record = rt.load_record()
    assert [item["key"] for item in record["rows"]] == [row.key for row in rt.ROWS]
    for item in record["rows"]:
        # Outside the placeholders only names carry digits (FR3, iiwa14), no number.
        literal = re.sub(r"\{\w+\}", "", item["measured"])
        assert not re.search(r"(?<![\w.])\d", literal), (item["key"], literal)
        used = set(re.findall(r"\{(\w+)\}", item["result"] + item["measured"]))
        assert used == set(item["figures"]), item["key"]
        for figure in item["figures"].values():
            assert {"value", "shown", "unit", "file", "key"} <= set(figure)
        assert item["provenance"]["source"]


def test_rendering_uses_the_shown_figures_and_keeps_the_table_look():
    record = rt.load_record()
    table = rt.render_table(record)
    assert table.splitlines()[:2] == list(rt.HEADER)
    row = rt.render_row(record["rows"][0])
    assert row.startswith("| residual vibration after the paper's three test moves")
    assert "99.88 / 99.27 / 99.50 % less, delay 132 / 52 / 132 ms" in row
    readme = "intro\n" + rt.BEGIN + "\nold\n" + rt.END + "\nrest\n"
    assert rt.with_table(readme, table) == f"intro\n{rt.BEGIN}\n{table}\n{rt.END}\nrest\n"


def test_formats():
    assert rt.scientific(0.0082) == "8.2e-3"
    assert rt.scientific(1.96e-4) == "2.0e-4"
    assert rt.two_significant(0.1512) == "0.15"
    assert rt.two_significant(0.704) == "0.70"
    assert rt.two_significant(9.04) == "9.0"
    assert rt.two_significant(36.2) == "36"
    assert rt.shown_matches(0.0082, "8.2e-3")
    assert rt.shown_matches(0.7, "0.7") and not rt.shown_matches(0.76, "0.7")
    assert rt.figure(2.0, rt.fixed(0), "ms", "f", "k")["shown"] == "2"
    assert rt.figure([1.8e-4, 2.0e-4], rt.scientific, "m/s²", "f", "k")["shown"] == (
        "1.8e-4 – 2.0e-4"
    )
    assert rt.figure([2.0, 2.0], rt.fixed(0), "ms", "f", "k")["shown"] == "2"


# --------------------------------------------------------------------------- synthetic outputs


def _residual(amplitude: float):
    from tvist.analysis import ResidualVibration

    return ResidualVibration(
        amplitude=amplitude,
        method="log_decay",
        log_decay_amplitude=amplitude,
        peak_amplitude=amplitude,
        decay_rate_1_s=1.0,
        freq_hz=8.0,
        zeta=0.1,
        t_stop_s=1.0,
        t_peaks_s=np.zeros(3),
        peaks=np.zeros(3),
        r_squared=1.0,
        fit_residual_rms=0.0,
        noise_std=0.0,
        reliable=True,
        note="",
    )


def _method_run(key: str, reduction: float, delay_s: float, settle_s: float = 2.0):
    from tvist.analysis import EnergySpectrum
    from tvist.experiments.experiment import MethodRun
    from tvist.experiments.method_row import Method
    from tvist.experiments.settle import CRITERIA, SettleTimes
    from tvist.robots import params

    return MethodRun(
        method=Method(key, key, build=None),
        q=np.zeros((8, 6)),
        psi=np.zeros((8, 3)),
        t_stop_s=1.0 + delay_s,
        delay_s=delay_s,
        residual=_residual(1.0 - reduction / 100),
        reduction_percent=reduction,
        peak_jerk_rad_s3=50.0,
        spectrum=EnergySpectrum(np.zeros(2), np.zeros(2)),
        dt_s=params("ur5e").control_period_s,
        settle=SettleTimes(move_s=1.5, times_s={c.key: settle_s for c in CRITERIA}, record_s=3.0),
    )


def _motion_run(name: str, runs):
    from tvist.experiments.experiment import MotionRun
    from tvist.experiments.motions import MOTIONS

    motion = next(m for m in MOTIONS if m.name == name)
    return MotionRun(
        motion=motion,
        t_s=np.zeros(8),
        t_stop_unshaped_s=1.0,
        true_end_modes=[(48.0, 0.2), (50.0, 0.1)],
        map_end_modes={},
        runs=runs,
        tracks=None,
    )


def _demo_result(quick: bool = False):
    from tvist.experiments.experiment import DemoResult
    from tvist.experiments.modal_rows import KEY

    motions = []
    for i, name in enumerate(rt.MOTIONS):
        runs = [
            _method_run("unshaped", 0.0, 0.0),
            _method_run(KEY, 99.0 + 0.1 * i + 0.0123, 0.132 - 0.04 * i),
            _method_run("fixed-start", 80.0 + i, 0.132),
        ]
        motions.append(_motion_run(name, runs))
    return DemoResult(motions=motions, config={"payload_kg": 5.0, "quick": quick}, wall_time_s=1.0)


def _write_demo(root: Path, quick: bool = False) -> Path:
    from tvist.experiments.results_json import write_json

    folder = root / "out" / "demo"
    folder.mkdir(parents=True)
    return write_json(_demo_result(quick), folder / "results.json")


def test_demo_figures_from_results_json(tmp_path):
    _write_demo(tmp_path)
    figures = rt.demo_figures(tmp_path)
    assert figures["payload_kg"]["shown"] == "5"
    assert figures["modal_q1_q2"]["shown"] == "99.01"
    assert figures["modal_q1_q3"]["shown"] == "99.11"
    assert figures["delay_q1_q2"]["shown"] == "132"
    assert figures["delay_q1_q3"]["shown"] == "92"
    assert figures["fixed_q3_q1"]["shown"] == "82.0"
    assert figures["delay_q1_q2"]["key"].endswith("delay_s × 1000")
    assert figures["modal_q1_q2"]["file"] == "out/demo/results.json"


def test_a_quick_demo_run_is_not_used(tmp_path):
    _write_demo(tmp_path, quick=True)
    with pytest.raises(rt.UnusableOutput, match="quick"):
        rt.demo_figures(tmp_path)


def test_pick_place_figures_from_results_json(tmp_path):
    from tvist.experiments.pick_place import CycleRow, PickPlaceResult
    from tvist.experiments.results_json import write_document
    from tvist.experiments.settle import CRITERIA, settle_config

    def row(key, seconds):
        return CycleRow(key, key, None, {c.key: [seconds / 2, seconds / 2] for c in CRITERIA})

    moves = [_motion_run("Q1->Q2", [_method_run("unshaped", 0.0, 0.0)])] * 2
    result = PickPlaceResult(
        moves=moves,
        rows=[row("unshaped", 9.0274), row("slow-down", 7.964), row("ztdis-map", 5.11)],
        config={"quick": False, "settle_criteria": settle_config()},
        wall_time_s=1.0,
    )
    folder = tmp_path / "out" / "demo-pick-place"
    folder.mkdir(parents=True)
    write_document(result.to_json(), folder / "results.json")
    figures = rt.pick_place_figures(tmp_path)
    shown = {name: f["shown"] for name, f in figures.items()}
    assert shown == {
        "band_m_s2": "0.05",
        "unshaped": "9.027",
        "slow_down": "7.964",
        "ztdis": "5.110",
        "limit": "3.000",
    }


def test_payload_figures_from_results_json(tmp_path):
    from tvist.experiments.flexible_payload import PayloadRun
    from tvist.experiments.results_json import write_document

    def run(key, reduction, delay_s):
        return PayloadRun(
            key=key,
            label=key,
            X=np.zeros((2, 6)),
            Q=np.zeros((2, 6)),
            tip_acceleration_m_s2=np.zeros((2, 3)),
            t_stop_s=1.0,
            delay_s=delay_s,
            residual_m_s2=0.01,
            residual_method="log_decay",
            residual_freq_hz=2.5,
            residual_zeta=0.04,
            reduction_percent=reduction,
            velocity_peaks=1,
            peak_jerk_m_s3=10.0,
            peak_speed_m_s=0.5,
            peak_joint_speed_rad_s=1.0,
        )

    runs = [run("conventional", 99.583, 0.392), run("ztdis", 97.51, 0.002)]
    runs.append(run("modified", 94.2, 0.004))
    # PayloadExperiment.to_json's "config" and "methods", as it builds them.
    document = {
        "config": {"payload": {"freq_hz": 2.55, "zeta": 0.04}},
        "methods": {r.key: r.to_json() for r in runs},
    }
    folder = tmp_path / "out" / "demo-payload"
    folder.mkdir(parents=True)
    write_document(document, folder / "results.json")
    figures = rt.payload_figures(tmp_path)
    assert figures["payload_hz"]["shown"] == "2.55"
    assert figures["conventional"]["shown"] == "99.58"
    assert figures["conventional_delay"]["shown"] == "392"
    assert figures["zero_delay"]["shown"] == "2 – 4"
    assert figures["modified"]["shown"] == "94.2"


def test_campaign_figures_from_the_results_store(tmp_path):
    from tvist.ident.results_store import ResultsStore, fingerprint

    def record(key, base_error, shoulder_error):
        return {
            "key": key,
            "modes": [
                {"joint": 0, "wn_rad_s": 60.0 * (1 + base_error), "low_confidence": False},
                {"joint": 1, "wn_rad_s": 50.0 * (1 + shoulder_error), "low_confidence": False},
            ],
            "true_modes": [{"joint": 0, "wn_rad_s": 60.0}, {"joint": 1, "wn_rad_s": 50.0}],
        }

    path = tmp_path / rt.CAMPAIGN
    path.parent.mkdir(parents=True)
    with ResultsStore(path, fingerprint({"test": 1})) as store:
        store.append(record("a", 0.01, 0.0))
        store.append(record("b", 0.05, 0.02))
        store.append(record("c", -0.02, 0.001))
    shown = {name: f["shown"] for name, f in rt.campaign_figures(tmp_path).items()}
    assert shown == {
        "n_poses": "3",
        "shoulder_within": "3",
        "shoulder_compared": "3",
        "base_within": "2",
        "base_compared": "3",
    }


def _cross_validation(folds: int) -> dict:
    from tvist.ident.modal_fit.statistics import relative_errors

    true_wn = np.array([[60.0, 50.0], [62.0, 51.0]])
    zeta = np.full((2, 2), 0.1)

    def prediction(error):
        pred = np.empty((2, 2, 2))
        pred[:, :, 0] = true_wn * (1 + np.array([[error, 0.0], [-error / 2, 0.0]]))
        pred[:, :, 1] = 0.1
        return pred

    cv = {"n_poses": 2, "folds": folds, "seed": 0}
    for form, error in (("modal", 0.007), ("published", 0.36)):
        cv[form] = {
            where: {
                "versus_identified": relative_errors(prediction(error), true_wn, zeta),
                "versus_true": relative_errors(prediction(error), true_wn, zeta),
            }
            for where in ("in_sample", "held_out")
        }
    return cv


def test_cross_validation_figures_from_modal_fit_out(tmp_path):
    from tvist.cli.modal_fit import _write_comparison

    path = tmp_path / rt.CROSS_VALIDATION
    path.parent.mkdir(parents=True)
    _write_comparison(_cross_validation(rt.FOLDS), rt.CAMPAIGN, "ur5e", str(path))
    shown = {name: f["shown"] for name, f in rt.cross_validation_figures(tmp_path).items()}
    # base errors +0.7 % and -0.35 %: RMS 0.553 %, max 0.7 %; published 36 % and 18 %.
    assert shown == {
        "modal_rms": "0.55",
        "modal_max": "0.70",
        "published_rms": "28",
        "published_max": "36",
    }
    _write_comparison(_cross_validation(3), rt.CAMPAIGN, "ur5e", str(path))
    with pytest.raises(rt.UnusableOutput, match="3-fold"):
        rt.cross_validation_figures(tmp_path)


def _arm_result(arm: str, base: float) -> dict:
    """``run_variant``'s result.json, with what ``table_markdown`` and the tool read."""
    moves = {
        name: {
            "identified": {
                "reduction_percent": base + i,
                "modes_shaped": 2,
                "delay_minus_zv_samples": 0.4,
            },
            "ceiling": {"reduction_percent": 99.9},
            "end_pose_map": {"reduction_percent": 99.0},
        }
        for i, name in enumerate(rt.MOTIONS)
    }
    modes = [
        {"name": "mode 1", "rms_percent": 0.37, "max_percent": 1.0, "n_poses": 20},
        {"name": "mode 2", "rms_percent": 1.274, "max_percent": 2.7, "n_poses": 20},
    ]
    return {
        "variant": f"family:{arm}:nominal",
        "map_vs_truth": {"modes": modes},
        "moves": moves,
        "wrong_confident": {"count": 0},
    }


def test_arm_figures_from_the_variant_results(tmp_path):
    from tvist.experiments.generalization import RESULT_FILE, table_markdown

    for arm, base in (("fr3", 97.123), ("iiwa14", 98.5)):
        folder = tmp_path / "out" / f"demo-{arm}" / f"{arm}-nominal"
        folder.mkdir(parents=True)
        result = _arm_result(arm, base)
        table_markdown([result])  # the harness's own reader takes it
        (folder / RESULT_FILE).write_text(json.dumps(result, indent=1) + "\n", encoding="utf-8")
    figures = rt.arm_figures(tmp_path)
    assert figures["fr3_q1_q2"]["shown"] == "97.12"
    assert figures["fr3_q3_q1"]["shown"] == "99.12"
    assert figures["iiwa14_q1_q3"]["shown"] == "99.50"
    assert figures["fr3_rms"]["shown"] == "1.27"
    (tmp_path / "out" / "demo-iiwa14" / "iiwa14-nominal" / RESULT_FILE).unlink()
    with pytest.raises(rt.MissingOutput, match="iiwa14"):
        rt.arm_figures(tmp_path)


def test_unseen_figures_from_the_held_out_variants_results(tmp_path):
    from tvist.experiments.generalization import RESULT_FILE, parse_seeds

    seeds = parse_seeds(rt.UNSEEN_SEEDS)
    for i, seed in enumerate(seeds):
        folder = tmp_path / rt.UNSEEN / f"ur5e-{seed}"
        folder.mkdir(parents=True)
        # Q1->Q2 at 97.5 + i / 10, Q1->Q3 one point and Q3->Q1 two points above: at 99 % or
        # more on 5, 15 and 20 variants. Largest RMS error 1.274 % except on the second (4 %).
        result = _arm_result("ur5e", 97.5 + i / 10)
        if i == 0:  # a shaped mode with no true mode: a miss, not an error figure
            result["map_vs_truth"]["modes"].insert(
                0, {"name": "mode 3", "rms_percent": math.nan, "max_percent": math.nan}
            )
        if i == 1:
            result["map_vs_truth"]["modes"][1]["rms_percent"] = 4.0
            result["wrong_confident"]["count"] = 2
        (folder / RESULT_FILE).write_text(json.dumps(result) + "\n", encoding="utf-8")
    figures = rt.unseen_figures(tmp_path)
    shown = {key: f["shown"] for key, f in figures.items()}
    assert shown == {
        "variants": "20",
        "moves": "60",
        "moves_at_floor": "40",
        "meeting_every_line": "5",
        "wrong_confident": "2",
        "least": "97.50",
        "rms_median": "1.3",
        "rms_range": "1.3 – 4.0",
        "floor": "99",
        "tolerance": "3",
    }
    (tmp_path / rt.UNSEEN / f"ur5e-{seeds[-1]}" / RESULT_FILE).unlink()
    with pytest.raises(rt.MissingOutput, match=f"ur5e-{seeds[-1]}"):
        rt.unseen_figures(tmp_path)


def _write_log(path: Path, deviation_m_s2: float) -> None:
    """A move that stops at 0.5 s, then ``deviation_m_s2`` on the accelerometer's x for 1 s
    and rest: residual vibration (RMS over 1 s after the stop) ``deviation_m_s2``."""
    from tvist.sim.record import SimRecord

    t = np.arange(0.0, 2.0, 0.002)
    q = np.zeros((t.size, 6))
    q[:, 0] = np.minimum(t, 0.5)
    accel = np.tile([0.0, 0.0, 9.81], (t.size, 1))
    stop = np.flatnonzero(t >= 0.502)[0]
    accel[stop : stop + 500, 0] += deviation_m_s2
    qd = np.gradient(q, t, axis=0)
    SimRecord(
        timestamp=t,
        target_q=q,
        target_qd=qd,
        target_qdd=np.gradient(qd, t, axis=0),
        actual_q=q,
        actual_qd=qd,
        actual_TCP_pose=np.zeros((t.size, 6)),
        actual_tool_accelerometer=accel,
        deflection_rad=np.zeros_like(q),
    ).to_csv(path)


def test_live_figures_from_the_runs_logs(tmp_path):
    folder = tmp_path / rt.LIVE
    folder.mkdir(parents=True)
    for n, value in enumerate((0.0082, 0.00821, 0.00819), start=1):
        _write_log(folder / f"unshaped-{n}.csv", value)
    for n, value in enumerate((1.8e-4, 1.96e-4), start=1):
        _write_log(folder / f"paper-map-{n}.csv", value)
    figures = rt.live_figures(tmp_path)
    assert figures["unshaped"]["shown"] == "8.2e-3"
    assert figures["paper_map"]["shown"] == "1.8e-4 – 2.0e-4"
    assert figures["paper_map"]["file"] == "out/live/paper-map-*.csv"


BENCH_OUTPUT = """\
41 interleaved rounds of 20000 cycles per case (500 Hz, linear reads unless noted); ns per cycle; \
ratio: median over the rounds of case / reference (same round); 1-minute load average 0.31 before \
the rounds, 1.27 after

| # | case | min ns | median ns | ratio to | ratio | target |
|---|---|---|---|---|---|---|
| 5 | 6 DOF, 2 modes ZV: plain fixed convolution | 14.6 | 16.4 |  |  |  |
| 6 | 6 DOF, 2 modes ZV: TvShaper, constant modes | 20.6 | 21.74 | #5 | 1.37 | ≤ 1.5 (met) |
| 10 | 6 DOF, 2 modes ZV: UR5e inertia + paper map + shaping | 144.2 | 172.6 | #6 | 7.00 | |

#10 / #14 (the general path against its hand-written floor): 1.26
"""


def test_bench_figures_from_the_saved_table(tmp_path):
    path = tmp_path / rt.BENCH
    path.parent.mkdir(parents=True)
    path.write_text(BENCH_OUTPUT, encoding="utf-8")
    shown = {name: f["shown"] for name, f in rt.bench_figures(tmp_path).items()}
    assert shown == {"fixed": "21.7", "fixed_ratio": "1.37", "map": "172.6", "map_ratio": "7.00"}
    path.write_text(BENCH_OUTPUT.replace("TvShaper, constant modes", "renamed"), encoding="utf-8")
    with pytest.raises(rt.UnusableOutput, match="no case"):
        rt.bench_figures(tmp_path)


# --------------------------------------------------------------------------- --update


def test_update_replaces_only_the_rows_whose_outputs_exist(tmp_path):
    _write_demo(tmp_path)
    record = rt.load_record()
    updated, lines = rt.update(tmp_path, copy.deepcopy(record))
    assert [item["key"] for item in updated["rows"]] == [row.key for row in rt.ROWS]
    demo = updated["rows"][0]
    assert demo["provenance"]["source"] == "outputs"
    assert list(demo["provenance"]["outputs"]) == ["out/demo/results.json"]
    assert demo["provenance"]["tvist_commit"] is None  # tmp_path is no checkout
    assert demo["figures"]["modal_q1_q2"]["shown"] == "99.01"
    assert updated["rows"][1:] == record["rows"][1:]
    assert lines[0].startswith("demo: updated from out/demo/results.json")
    assert all("kept the record's entry" in line for line in lines[1:])
    assert rt.figure_problems(updated) == []
    readme = rt.with_table(_readme(), rt.render_table(updated))
    assert rt.check(readme, updated) == []
    assert "99.01 / 99.11 / 99.21 % less, delay 132 / 92 / 52 ms" in readme
    assert rt.check(readme, record)  # the committed record no longer matches it


def test_update_keeps_the_entry_of_an_unusable_output(tmp_path):
    _write_demo(tmp_path, quick=True)
    record = rt.load_record()
    updated, lines = rt.update(tmp_path, copy.deepcopy(record))
    assert updated == record
    assert "quick run" in lines[0]


def test_modal_fit_out_is_checked_before_the_fit(tmp_path, capsys):
    from tvist.cli.modal_fit import main

    assert main([str(tmp_path / "none.jsonl"), "--out", str(tmp_path)]) == 2
    assert "--out" in capsys.readouterr().err


def test_made_with_names_the_commit_the_outputs_were_made_with(tmp_path):
    import subprocess

    def git(*args: str) -> str:
        return subprocess.run(
            ["git", "-c", "user.name=t", "-c", "user.email=t@t", *args],
            cwd=tmp_path,
            capture_output=True,
            text=True,
            check=True,
        ).stdout.strip()

    git("init", "-q")
    git("commit", "-q", "--allow-empty", "-m", "made the outputs")
    made = git("rev-parse", "HEAD")
    _write_demo(tmp_path)  # written after the commit (commit times are whole seconds)
    figures = rt.demo_figures(tmp_path)
    source = rt.provenance(tmp_path, figures, made)
    assert source["tvist_commit"] == made and "stated" in source["commit_note"]
    with pytest.raises(ValueError, match="--made-with 0000000"):
        rt.provenance(tmp_path, figures, "0000000")
    with pytest.raises(ValueError, match="no row nonsense"):
        rt.update(tmp_path, rt.load_record(), {"nonsense": made})
