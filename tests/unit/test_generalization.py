"""The pieces of the generalization harness (``python -m tvist.experiments.generalization``): seeds,
evaluation poses, matching a map's modes to the true ones, errors, wrong-and-confident
identifications and the table. A full run (minutes per variant) is not a test."""

from __future__ import annotations

import math

import numpy as np
import pytest

from tvist.experiments.generalization import (
    EVALUATION_POSES,
    FLOOR,
    floor_misses,
    floor_summary,
    frequency_errors,
    main,
    matching_true_modes,
    parse_seeds,
    shaped_mode_names,
    table_markdown,
    wrong_confident,
)
from tvist.robots import Robot, params
from tvist.sim.family import TrueMode


def test_seeds_are_ranges_and_lists():
    assert parse_seeds("0-4") == [0, 1, 2, 3, 4]
    assert parse_seeds("3") == [3]
    assert parse_seeds("0-2, 7,1,9-10") == [0, 1, 2, 7, 9, 10]
    for bad in ("", "a", "4-2", "-3", "1-"):
        with pytest.raises(ValueError, match="--seeds"):
            parse_seeds(bad)


def test_bad_arguments_exit_2(capsys):
    with pytest.raises(SystemExit) as exc:
        main(["--seeds", "5-1"])
    assert exc.value.code == 2 and "backwards" in capsys.readouterr().err
    with pytest.raises(SystemExit) as exc:
        main(["--seeds", "0", "--workers", "3"])
    assert exc.value.code == 2 and "--workers 3" in capsys.readouterr().err


def test_evaluation_poses_are_workspace_poses_apart_from_the_plans():
    from tvist.experiments.generalization import evaluation_poses
    from tvist.ident.pose_plan import WORKSPACE_SAMPLES, workspace_poses

    q = evaluation_poses("ur5e", 3)
    assert q.shape == (EVALUATION_POSES, 6)
    np.testing.assert_array_equal(q, evaluation_poses("ur5e", 3))  # reproducible
    assert not np.allclose(q, evaluation_poses("ur5e", 4))  # each variant its own
    # The workspace: upper arm at or above the shoulder, elbow up to 150°, flange above the
    # mounting plane (checked here with the robot model's forward kinematics).
    assert np.all((q[:, 1] >= -math.pi) & (q[:, 1] <= 0.0))
    assert np.all((q[:, 2] >= 0.0) & (q[:, 2] <= 5 * math.pi / 6))
    assert np.all(Robot(params("ur5e")).flange_pose_many(q)[:, 2, 3] > 0.0)
    # None of them is among the poses the plan draws its workspace extremes from.
    plan_draws = workspace_poses("ur5e", WORKSPACE_SAMPLES, seed=3, corners=True)
    distance = np.min(np.abs(q[:, None, :] - plan_draws[None, :, :]).max(axis=2), axis=1)
    assert np.all(distance > 1e-3)


def _mode(freq_hz: float, shares: list[float]) -> TrueMode:
    return TrueMode(freq_hz, 0.1, np.array(shares), np.array([1.0, 0.0, 0.0]), 0.0)


def test_a_maps_modes_are_matched_by_its_own_naming_rule():
    # Lowest first: an elbow mode below the base- and shoulder-dominant ones.
    truth = [
        _mode(12.0, [0.1, 0.1, 0.8, 0, 0, 0]),
        _mode(15.0, [0.6, 0.3, 0.1, 0, 0, 0]),
        _mode(19.0, [0.2, 0.7, 0.1, 0, 0, 0]),
    ]
    names = shaped_mode_names({"mode_joints": [0, 1]})
    assert names == [("joint", 0), ("joint", 1)]
    assert [m.freq_hz for m in matching_true_modes(names, truth)] == [15.0, 19.0]
    names = shaped_mode_names({"shaped_modes": 2, "mode_joints": [0, 1]})
    assert names == [("rank", 0), ("rank", 1)]
    assert [m.freq_hz for m in matching_true_modes(names, truth)] == [12.0, 15.0]
    assert matching_true_modes([("rank", 3)], truth) == [None]


def test_no_true_mode_stands_for_two_of_the_maps_modes():
    # One 18.2 Hz true mode stores the largest share of both the base's strain (0.5 against
    # 0.15 and 0.3) and the shoulder's (0.45 against 0.05 and 0.4). The map's slots never
    # shape one eigenmode twice: the base takes it and the shoulder the next one in the
    # shoulder, the 25 Hz mode. A map right about both modes (18.3 and 24.5 Hz) is then
    # 0.5 % and 2 % off, not 35 % off in the shoulder against the base's mode.
    truth = [
        _mode(14.0, [0.15, 0.05, 0.8, 0, 0, 0]),
        _mode(18.2, [0.5, 0.45, 0.05, 0, 0, 0]),
        _mode(25.0, [0.3, 0.4, 0.3, 0, 0, 0]),
    ]
    names = shaped_mode_names({"mode_joints": [0, 1]})
    matched = matching_true_modes(names, truth)
    assert [m.freq_hz for m in matched] == [18.2, 25.0]
    base, shoulder = frequency_errors(
        np.array([[18.3, 24.5]]), np.array([[m.freq_hz for m in matched]])
    )
    assert base["max_percent"] == pytest.approx(100 * (18.3 / 18.2 - 1), rel=1e-9)
    assert shoulder["max_percent"] == pytest.approx(2.0, rel=1e-9)
    # Slots in the map's order: shoulder first takes the 18.2 Hz mode, the base the 25 Hz.
    names = shaped_mode_names({"mode_joints": [1, 0]})
    assert [m.freq_hz for m in matching_true_modes(names, truth)] == [18.2, 25.0]
    # More slots than true modes: the last one has none left.
    names = shaped_mode_names({"mode_joints": [0, 1, 2, 3]})
    assert [m and m.freq_hz for m in matching_true_modes(names, truth)] == [18.2, 25.0, 14.0, None]


def test_frequency_errors_per_mode():
    predicted = np.array([[10.3, 20.0], [9.8, 21.0], [10.0, np.nan]])
    true = np.array([[10.0, 20.0], [10.0, 20.0], [10.0, 20.0]])
    base, shoulder = frequency_errors(predicted, true)
    # Relative errors 3 %, -2 %, 0 % and 0 %, 5 % (the NaN pose left out).
    assert base["rms_percent"] == pytest.approx(math.sqrt((9 + 4 + 0) / 3), rel=1e-9)
    assert base["max_percent"] == pytest.approx(3.0, rel=1e-9) and base["n_poses"] == 3
    assert shoulder["rms_percent"] == pytest.approx(math.sqrt(25 / 2), rel=1e-9)
    assert shoulder["max_percent"] == pytest.approx(5.0, rel=1e-9) and shoulder["n_poses"] == 2


def test_wrong_confident_counts_unflagged_fits_far_from_every_true_mode():
    two_pi = 2 * math.pi
    records = [
        {
            "key": "a",
            "modes": [
                {"joint": 0, "wn_rad_s": two_pi * 17.28, "low_confidence": False},  # wrong
                {"joint": 1, "wn_rad_s": two_pi * 19.3, "low_confidence": False},  # 0.5 %
            ],
            # The same base fit again among the ringing modes (counted once), a flagged wrong
            # one (not counted) and a confident third mode at the 29.82 Hz true mode.
            "ringing": [
                {"log_joint": 0, "wn_rad_s": two_pi * 17.28, "low_confidence": False},
                {"log_joint": 0, "wn_rad_s": two_pi * 25.0, "low_confidence": True},
                {"log_joint": 1, "wn_rad_s": two_pi * 29.5, "low_confidence": False},
            ],
        },
        {"key": "b", "modes": [{"joint": 0, "error": "no log"}]},
    ]
    truth = {"a": [16.56, 19.20, 29.82], "b": [10.0]}
    wrong = wrong_confident(records, truth)
    assert [(w["key"], w["log_joint"]) for w in wrong] == [("a", 0)]
    assert wrong[0]["nearest_percent"] == pytest.approx(100 * (17.28 / 16.56 - 1), rel=1e-9)


def _result(name: str, worst_max: float) -> dict:
    def move(reduction: float, ceiling: float, shaped: int, off: float, held=False) -> dict:
        return {
            "identified": {
                "reduction_percent": reduction,
                "modes_shaped": shaped,
                "held_at_end_pose": held,
                "delay_minus_zv_samples": off,
            },
            "ceiling": {"reduction_percent": ceiling},
        }

    return {
        "variant": name,
        "map_vs_truth": {
            "modes": [
                {"name": "joint 0", "rms_percent": 1.0, "max_percent": worst_max},
                {"name": "joint 1", "rms_percent": 2.5, "max_percent": 3.0},
            ]
        },
        "moves": {
            "Q1->Q2": move(99.61, 100.0, 2, 0.2),
            "Q1->Q3": move(96.1, 99.9, 3, -0.7),
            "Q3->Q1": move(99.7, 99.6, 2, 0.1, held=True),
        },
        "wrong_confident": {"count": 3},
    }


def test_table_has_a_row_per_variant():
    table = table_markdown(
        [
            _result("family:ur5e:0", 7.9),
            _result("family:ur5e:1", 1.5),
            {"variant": "x", "error": "boom"},
        ]
    )
    lines = table.strip().splitlines()
    rows = lines[: 2 + 3]
    header = [c.strip() for c in rows[0].strip("|").split("|")]
    assert len(header) == 9 and all(
        len(line.split("|")) == len(rows[0].split("|")) for line in rows
    )
    row0 = [c.strip() for c in lines[2].strip("|").split("|")]
    assert row0 == [
        "family:ur5e:0",
        "joint 0: 1.00 / 7.90; joint 1: 2.50 / 3.00",
        "99.61 (100.00)",
        "96.10 (99.90)",
        "99.70 held (99.60)",
        "2/3",
        "0.70",
        "3",
        "Q1->Q3 96.10 %; 3 wrong & confident",
    ]
    row1 = [c.strip() for c in lines[3].strip("|").split("|")]
    assert row1[1] == "joint 0: 1.00 / 1.50; joint 1: 2.50 / 3.00"
    assert "failed: boom" in lines[4]
    # 9 moves, 3 of them the failed variant's; 4 of the other 6 at 99 % or more.
    assert lines[-1] == (
        "Moves at 99 % or more: 4 of 9 (least 96.10 %); variants meeting every line of the "
        "floor: 0 of 3."
    )


def test_the_floor_names_every_line_a_variant_misses():
    good = _result("a", 7.9)
    good["moves"]["Q1->Q3"]["identified"]["reduction_percent"] = 99.0  # the floor itself
    good["wrong_confident"]["count"] = 0
    assert floor_misses(good) == []
    assert floor_summary([good])["meeting_every_line"] == 1

    bad = _result("b", 8.01)
    bad["map_vs_truth"]["modes"].append(
        {"name": "mode 3", "rms_percent": math.nan, "max_percent": math.nan}
    )
    bad["map_vs_truth"]["modes"][1]["rms_percent"] = 3.01
    bad["moves"]["Q3->Q1"]["identified"]["delay_minus_zv_samples"] = -1.04
    bad["moves"]["Q1->Q2"]["identified"] = {"error": "over the speed limit", "modes_shaped": 2}
    assert floor_misses(bad) == [
        "joint 0 max 8.01 %",
        "joint 1 RMS 3.01 %",
        "mode 3 not compared (no true mode)",
        "Q1->Q2 refused",
        "Q1->Q3 96.10 %",
        "Q3->Q1 delay -1.04 samples from ZV's",
        "3 wrong & confident",
    ]
    assert floor_misses({"variant": "c", "error": "boom"}) == ["failed"]
    summary = floor_summary([good, bad, {"variant": "c", "error": "boom"}])
    assert summary == {
        "variants": 3,
        "meeting_every_line": 1,
        "moves": 9,
        "moves_at_floor": 4,  # good's three, bad's Q3->Q1 (99.7 %)
        "least_reduction_percent": 96.1,
        "wrong_confident": 3,
        "failed": 1,
    }
    assert FLOOR.reduction_percent == 99.0 and FLOOR.map_rms_percent == 3.0
