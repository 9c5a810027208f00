"""A paper10 map used outside the inertias it was identified on says so, once per run.

The map clamps (holds its modes at a range's bound) inside the Rust core, every cycle; the
warning is the Python side's check of the whole reference before shaping.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import tvist
from tvist.cli import main
from tvist.maps.paper10 import MapRangeWarning
from tvist.robots import ur5e
from tvist.trajectory import PAPER_POSES, double_s, shape_samples

DT = 0.002
#: The range the demo's reduced plan spans at 5 kg (J_0 and J_1, kg m²): Q1 (J_0 8.9) is
#: outside, Q3 (J_0 1.1, J_1 1.2) inside.
RANGE_KG_M2 = [1.06, 8.55]


def ranged_paper_map() -> tvist.DynamicMap:
    """The published UR5e map limited to :data:`RANGE_KG_M2` for every inertia it reads."""
    modes = [
        {
            **mode,
            "frequency_inertia_range_kg_m2": RANGE_KG_M2,
            "damping_inertia_range_kg_m2": RANGE_KG_M2,
        }
        for mode in tvist.DynamicMap.paper_ur5e().mode_maps
    ]
    return tvist.DynamicMap(modes, {"robot": "ur5e"})


def move(start: str, end: str) -> np.ndarray:
    return double_s(PAPER_POSES[start], PAPER_POSES[end], dt_s=DT, t_pre_s=0.02).q


def test_a_move_that_leaves_the_range_is_warned_once_with_the_pose_and_the_range():
    robot = ur5e(5.0, (0.0, 0.0, 0.05))
    q = move("Q1", "Q3")
    inertia = robot.joint_inertia_many(q)
    lo, hi = RANGE_KG_M2
    outside = np.any((inertia[:, :2] < lo) | (inertia[:, :2] > hi), axis=1)
    assert outside[0] and not outside[-1]  # Q1 outside (J_0 > 8.55), Q3 inside
    provider = tvist.MapDynamics(robot, ranged_paper_map())
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        shape_samples(q, DT, provider)
    ranges = [w for w in caught if issubclass(w.category, MapRangeWarning)]
    assert len(ranges) == 1
    text = str(ranges[0].message)
    first = ", ".join(f"{v:.3f}" for v in q[0])
    assert f"first at sample 0, q = [{first}] rad" in text
    assert f"J_0 = {inertia[0, 0]:.3g} kg m² is outside [1.06, 8.55] kg m²" in text
    assert f"at {int(outside.sum())} of {len(q)} samples" in text


def test_a_move_inside_the_range_is_not_warned():
    robot = ur5e(5.0, (0.0, 0.0, 0.05))
    q = move("Q3", "Q3")
    provider = tvist.MapDynamics(robot, ranged_paper_map())
    with warnings.catch_warnings():
        warnings.simplefilter("error", MapRangeWarning)
        shape_samples(q, DT, provider)


def test_tvist_shape_prints_the_warning_once(tmp_path, capsys):
    path = tmp_path / "move.csv"
    np.savetxt(path, move("Q1", "Q3"), delimiter=",", fmt="%.12f")
    map_path = tmp_path / "map.json"
    ranged_paper_map().save(map_path)
    args = ["shape", str(path), "--out", str(tmp_path / "out.csv"), "--map", str(map_path)]
    assert main([*args, "--payload-kg", "5"]) == 0
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1, err
    assert err[0].startswith("tvist shape: warning: the map holds its mode 0 at the bound")
    assert "is outside [1.06, 8.55] kg m²" in err[0]


@pytest.mark.parametrize("kind", ["unbounded", "constant"])
def test_no_range_no_warning(kind):
    robot = ur5e(5.0, (0.0, 0.0, 0.05))
    provider = (
        tvist.MapDynamics(robot, tvist.DynamicMap.paper_ur5e())
        if kind == "unbounded"
        else [(50.0, 0.1)]
    )
    with warnings.catch_warnings():
        warnings.simplefilter("error", MapRangeWarning)
        shape_samples(move("Q1", "Q3"), DT, provider)


def test_tvist_run_warns_before_the_arm_moves(tmp_path, capsys):
    """``tvist run`` builds its shaper from the whole move first: a map that leaves its range
    along it is warned on one line before anything is sent to the arm."""
    from tvist.cli import build_parser
    from tvist.cli.live import _shaper

    map_path = tmp_path / "map.json"
    ranged_paper_map().save(map_path)
    args = build_parser().parse_args(
        ["run", "move.csv", "--robot-ip", "127.0.0.1", "--map", str(map_path)]
        + ["--payload-kg", "5"]
    )
    assert _shaper(args, move("Q1", "Q3")) is not None
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("tvist run: warning: the map holds its mode 0")
    _shaper(args, move("Q3", "Q3"))
    assert capsys.readouterr().err == ""
