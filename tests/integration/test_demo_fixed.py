"""Fixed-shaper baselines of the demo and the report's numbers."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from tvist import robots
from tvist.experiments import run_experiment
from tvist.experiments.fixed import (
    ROBUST_PRV_LIMIT,
    fixed_robust_row,
    fixed_start_row,
    modes_along,
    search_robust_shaper,
)
from tvist.experiments.method_row import Method, MotionContext
from tvist.experiments.methods import default_methods
from tvist.experiments.motions import DT_S, MOTIONS, PAYLOAD_COM_M, PAYLOAD_KG
from tvist.experiments.settle import CRITERIA
from tvist.experiments.table import format_reduction
from tvist.experiments.table import table_rows as report_rows
from tvist.experiments.verdict import recommendation
from tvist.sim import Twin


def prv_reference(amplitudes, times_s, wn_rad_s, zeta):
    """Eqs. 52-55 in plain numpy (independent of the Rust PRV)."""
    a = np.asarray(amplitudes)[:, None]
    t = np.asarray(times_s)[:, None]
    wn, z = np.asarray(wn_rad_s)[None, :], np.asarray(zeta)[None, :]
    wd = wn * np.sqrt(1 - z * z)
    growth = np.exp(z * wn * t)
    c = np.sum(a * growth * np.cos(wd * t), axis=0)
    s = np.sum(a * growth * np.sin(wd * t), axis=0)
    return np.exp(-z[0] * wn[0] * t[-1, 0]) * np.hypot(c, s)


def impulses_of(design):
    import tvist

    parts = [tvist.shaper(s.shaper, s.wn_rad_s, s.zeta) for s in design.stages]
    return parts[0] if len(parts) == 1 else tvist.convolve(*parts)


def test_robust_search_on_one_undamped_mode_is_the_shortest_zv_within_the_limit():
    # One undamped mode: ZV (half a period) is the shortest library shaper that cancels it,
    # and a ZV designed slightly above the mode is shorter still while its PRV
    # |cos(π ω / 2 ω_d)| stays within 5 %: the analytic bound is
    # ω_d <= ω π / (2 acos(0.05)), i.e. a duration >= 0.9682 π / ω.
    wn = 2 * math.pi * 10.0
    design = search_robust_shaper(np.array([[wn, 0.0]]))
    assert design.feasible
    assert [s.shaper for s in design.stages] == ["zv"]
    bound = 2 * math.acos(ROBUST_PRV_LIMIT) / math.pi * math.pi / wn
    assert bound <= design.duration_s < math.pi / wn
    # The grid is geometric with 1.6 % steps: the chosen design is within one step of it.
    assert design.duration_s <= 1.016 * bound
    imp = impulses_of(design)
    assert prv_reference(imp.amplitudes, imp.times_s, [wn], [0.0])[0] == pytest.approx(
        design.max_prv, abs=1e-12
    )


def test_robust_search_covers_every_mode_of_a_wide_range():
    # The range of the paper's Q1 -> Q3 motion on the twin: 7.6-36 Hz, ζ 0.04-0.25.
    rng = np.random.default_rng(2)
    wn = 2 * math.pi * rng.uniform(7.6, 36.0, 200)
    zeta = rng.uniform(0.04, 0.25, 200)
    design = search_robust_shaper(np.stack([wn, zeta], axis=1))
    imp = impulses_of(design)
    prv = prv_reference(imp.amplitudes, imp.times_s, wn, zeta)
    assert design.feasible and np.max(prv) <= ROBUST_PRV_LIMIT
    assert np.max(prv) == pytest.approx(design.max_prv, abs=1e-12)
    # No single ZV can cover a range this wide: the design is longer than the ZV of the
    # lowest mode, and the convolution of two shapers.
    assert design.duration_s > math.pi / wn.min()
    assert len(design.stages) == 2


def test_robust_search_reports_when_nothing_reaches_the_limit():
    # 1-200 Hz undamped: no library design or pair of them stays within 5 % everywhere.
    wn = 2 * math.pi * np.geomspace(1.0, 200.0, 60)
    design = search_robust_shaper(np.stack([wn, np.zeros_like(wn)], axis=1))
    assert not design.feasible
    assert design.max_prv > ROBUST_PRV_LIMIT


@pytest.fixture(scope="module")
def quick_fixed():
    # Q1 -> Q2 (its modes do not change along the move) with the baselines only.
    rows = [m for m in default_methods() if m.key == "unshaped"]
    return run_experiment(quick=True, methods=[*rows, fixed_start_row(), fixed_robust_row()])


@pytest.mark.slow
def test_fixed_start_reference_is_the_two_mode_zv_of_the_start_pose(quick_fixed):
    import tvist

    motion = quick_fixed.motions[0]
    twin = Twin("ur5e", payload_kg=PAYLOAD_KG, payload_com_m=PAYLOAD_COM_M)
    stages = [tvist.shaper("zv", w, z) for w, z in twin.modes(motion.motion.q_start)]
    imp = tvist.convolve(*stages)
    expected = motion.runs[0].q
    t = DT_S * np.arange(expected.shape[0])
    # One ZV per mode in series, each Σ A_i q(t − Δ_i) of its input read between samples by
    # linear interpolation (as the delay line does), written out in numpy.
    for stage in stages:
        expected = sum(
            a * np.stack([np.interp(t - d, t, expected[:, j]) for j in range(6)], axis=1)
            for a, d in zip(stage.amplitudes, stage.times_s, strict=True)
        )
    fixed = motion.run("fixed-start")
    assert np.max(np.abs(fixed.q - expected)) < 1e-12
    assert abs(fixed.delay_s - imp.duration_s) <= DT_S


@pytest.mark.slow
def test_fixed_rows_on_a_motion_with_constant_modes(quick_fixed):
    motion = quick_fixed.motions[0]
    start, robust = motion.run("fixed-start"), motion.run("fixed-robust")
    # Exactly tuned (the modes at Q1 and Q2 are the same): as good as FD-TVIST with the
    # true modes (the demo measures 99.98 %).
    assert start.reduction_percent >= 99.0
    # Within 5 % PRV on every mode of the move: at least 95 % in linear theory; the twin's
    # gear nonlinearity and the time variation during the move leave ~1 point more.
    assert robust.reduction_percent >= 90.0
    design = robust.details["robust_design"]
    assert design["feasible"] and design["max_prv"] <= ROBUST_PRV_LIMIT
    assert abs(robust.delay_s - design["duration_s"]) <= DT_S


def test_modes_along_span_the_move_from_start_to_end():
    twin = Twin("ur5e", payload_kg=PAYLOAD_KG, payload_com_m=PAYLOAD_COM_M)
    robot = robots.ur5e(PAYLOAD_KG, PAYLOAD_COM_M)
    motion = MOTIONS[1]  # Q1 -> Q3
    ctx = MotionContext(motion, motion.reference(0.5, DT_S), twin, robot, 0.1)
    modes = modes_along(ctx)
    assert modes[0] == pytest.approx(np.array(twin.modes(motion.q_start)))
    assert modes[-1] == pytest.approx(np.array(twin.modes(motion.q_end)))


@pytest.mark.parametrize(
    ("percent", "text"),
    [(99.977, "99.977"), (97.73, "97.7"), (99.2, "99.20"), (44.9, "44.9"), (99.9996, "99.99960")],
)
def test_reductions_never_round_to_100(percent, text):
    assert format_reduction(percent) == text


@pytest.mark.slow
def test_recommendation_takes_the_row_that_settles_first(quick_fixed):
    motion = quick_fixed.motions[0]
    key = CRITERIA[0].key
    # Computed from the simulated signals: the pick is the runnable row (or the best
    # slow-down profile) whose |ψ| leaves 0.05 m/s² for good first.
    settles = {r.method.label: r.settle.get(key) for r in motion.runs}
    best_slow = motion.slow_down.best(key)
    fastest = min(v for v in settles.values() if v is not None)
    assert best_slow.settle.get(key) > fastest  # on Q1 -> Q2 a shaper beats slowing down
    winner = min(settles, key=lambda k: settles[k] if settles[k] is not None else math.inf)
    line = recommendation(motion)
    assert f"**{winner}**" in line
    assert f"{settles[winner]:.3f} s" in line


def _with_settle(run, first_s, second_s):
    times = dict(run.settle.times_s)
    times[CRITERIA[0].key], times[CRITERIA[1].key] = first_s, second_s
    return dataclasses.replace(run, settle=dataclasses.replace(run.settle, times_s=times))


@pytest.mark.slow
def test_recommendation_breaks_a_one_sample_tie_at_the_stricter_band(quick_fixed):
    # Two runnable rows one sample apart at 0.05 m/s²: a tie, so the faster to 0.01 m/s²
    # wins; three samples apart, the faster at 0.05 m/s² wins.
    motion = quick_fixed.motions[0]
    a, b = motion.runs[1], motion.runs[2]
    for gap_samples, winner in ((1, b), (3, a)):
        runs = [
            motion.runs[0],
            _with_settle(a, 1.800, 2.100),
            _with_settle(b, 1.800 + gap_samples * DT_S, 1.900),
        ]
        line = recommendation(dataclasses.replace(motion, runs=runs, slow_down=None))
        assert f"**{winner.method.label}**" in line, (gap_samples, line)


@pytest.mark.slow
def test_recommendation_never_picks_an_oracle_row(quick_fixed):
    # An oracle row that settles well before every other is shown, marked, and never picked.
    motion = quick_fixed.motions[0]
    fixed = motion.runs[1]
    oracle = dataclasses.replace(
        _with_settle(fixed, 0.5, 0.6),
        method=dataclasses.replace(fixed.method, label="Oracle row", oracle="reads the twin"),
    )
    changed = dataclasses.replace(motion, runs=[*motion.runs, oracle])
    line = recommendation(changed)
    assert "**Oracle row**" not in line
    assert "Oracle row (0.500 s), an oracle row" in line
    assert recommendation(motion).split(" Not recommended")[0] == line.split(" Not recommended")[0]
    assert ["(oracle)" in row[0] for row in report_rows(changed)][-2:] == [True, False]


def test_methods_keep_their_keys():
    # The rows' results.json keys are part of the demo's interface.
    assert fixed_start_row().key == "fixed-start" and fixed_robust_row().key == "fixed-robust"
    assert isinstance(fixed_start_row(), Method)
