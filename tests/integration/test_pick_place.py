"""The pick-and-place experiment (quick run: its first two moves)."""

from __future__ import annotations

import json

import numpy as np
import pytest

from tvist import DynamicMap
from tvist.cli import main
from tvist.experiments.motions import DT_S
from tvist.experiments.pick_place import (
    cell_moves,
    fastest_runnable,
    run_pick_place,
    write_pick_place,
)
from tvist.experiments.settle import CRITERIA


@pytest.fixture(scope="module")
def quick_cycle(tmp_path_factory):
    # The published UR5e map stands in for the identified one (no campaign in a test).
    result = run_pick_place(quick=True, dynmap=DynamicMap.paper_ur5e(), map_name="paper map")
    out = tmp_path_factory.mktemp("pick-place")
    write_pick_place(result, out)
    return result, out


def _sample_bounds(t, magnitude, t0, threshold):
    """Independent of the code under test: the settle time lies between the last sample
    after ``t0`` above ``threshold`` and the next sample (the crossing is interpolated
    between them), as seconds after ``t0``."""
    first = int(np.searchsorted(t, t0))
    above = np.flatnonzero(magnitude[first:] > threshold)
    if above.size == 0:
        return 0.0, 0.0
    last = first + int(above[-1])
    return t[last] - t0, t[last + 1] - t0


@pytest.mark.slow
def test_the_report_has_every_row_and_criterion(quick_cycle):
    result, out = quick_cycle
    doc = json.loads((out / "results.json").read_text())
    assert set(doc["moves"]) == {"P0->P1", "P1->P2"}
    rows = doc["cycle"]
    assert list(rows)[:2] == ["unshaped", "slow-down"]
    assert {"fixed-start", "fixed-robust", "fd-tvist-map", "ztdis-map", "modified-map"} <= set(rows)
    assert rows["ztdis"]["oracle"] and not rows["fd-tvist-map"]["oracle"]
    for row in rows.values():
        assert set(row["cycle_s"]) == {c.key for c in CRITERIA}
    report = (out / "report.md").read_text()
    assert "ZTDIS ZV, true end-pose modes (oracle)" in report
    assert "the moves themselves (the limit)" in report
    assert (out / "cycle.png").stat().st_size > 10_000
    for c in CRITERIA:
        best = fastest_runnable(result, c.key)
        assert best is not None and best.oracle is None


@pytest.mark.slow
def test_cycle_totals_are_sums_of_the_simulated_settle_times(quick_cycle):
    result, _ = quick_cycle
    accel = CRITERIA[0]
    moves = cell_moves(quick=True)
    # The limit: the planned moves' own durations, from the trajectories.
    limit = 0.0
    for move in moves:
        traj = move.reference(1.0, DT_S)
        limit += traj.t_motion_end_s - traj.t_motion_start_s
    assert result.limit_s == pytest.approx(limit, abs=1e-9)
    for key in ("unshaped", "fd-tvist-map", "fixed-robust"):
        low = high = 0.0
        for move, run in zip(moves, result.moves, strict=True):
            t0 = move.reference(0.0, DT_S).t_motion_start_s
            lo, hi = _sample_bounds(
                run.t_s, np.linalg.norm(run.run(key).psi, axis=1), t0, accel.threshold
            )
            low, high = low + lo, high + hi
        total = result.row(key).total_s(accel.key)
        assert low <= total <= high, (key, low, total, high)
        assert total > 0.0
    assert result.row("unshaped").total_s(accel.key) > result.row("fd-tvist-map").total_s(accel.key)
    # Slow down instead: per move the best of its profiles, the planned one included.
    slow = sum(
        min(c.settle.get(accel.key) for c in m.slow_down.candidates if c.settle.get(accel.key))
        for m in result.moves
    )
    assert result.row("slow-down").total_s(accel.key) == pytest.approx(slow, abs=1e-12)
    assert result.row("slow-down").total_s(accel.key) <= result.row("unshaped").total_s(accel.key)


# Fast although above the slow criterion: the cheapest test of tvist.experiments.pick_place
# (docs/test-quality.md).
def test_cli_runs_the_experiment_without_a_map(tmp_path):
    assert (
        main(
            [
                "demo",
                "--experiment",
                "pick-place",
                "--quick",
                "--no-identify",
                "--out",
                str(tmp_path),
            ]
        )
        == 0
    )
    doc = json.loads((tmp_path / "results.json").read_text())
    assert "fd-tvist-map" not in doc["cycle"] and "unshaped" in doc["cycle"]
