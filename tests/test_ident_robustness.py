"""Map robustness against the two-mode shaper's 10 % PRV band (paper section 5.4) and plots."""

from __future__ import annotations

import math

import numpy as np
import pytest

import tvist
from tvist.ident.plots import (
    plot_damping_robustness,
    plot_frequency_robustness,
    plot_map_fit,
    plot_prv_sensitivity,
)
from tvist.ident.robustness import PRV_LIMIT, evaluate_map, prv_band, summarize, two_mode_shaper

PAPER = tvist.DynamicMap.paper_ur5e()


def test_zv_band_matches_the_closed_form():
    # Undamped ZV: PRV(r) = |cos(π r / 2)| for the frequency ratio r, so PRV <= 0.1 for
    # |r - 1| <= 1 - 2 arccos(0.1)/π = 0.0637.
    wn = 2 * math.pi * 10.0
    lo, hi = prv_band(tvist.shaper("zv", wn, 0.0), wn, 0.0, n=20001)
    half = 1.0 - 2.0 * math.acos(0.1) / math.pi
    grid_step = math.log(9.0) / 20000  # relative spacing of the geometric scan
    assert lo / wn == pytest.approx(1.0 - half, abs=grid_step)
    assert hi / wn == pytest.approx(1.0 + half, abs=grid_step)


def test_two_mode_shaper_cancels_both_design_modes():
    modes = PAPER.modes_from_inertia([9.73, 9.25, 1, 1, 1, 1])  # Q1 of Table 3
    impulses = two_mode_shaper(modes)
    assert len(impulses.amplitudes) == 4
    # Table 4: the two-mode ZV delay at Q1 is 1/(2 f_d0) + 1/(2 f_d1) = 134.7 ms
    assert impulses.times_s[-1] == pytest.approx(0.1347, abs=5e-4)
    for wn, zeta in modes:
        assert tvist.prv(impulses, wn, zeta) < 1e-12
        lo, hi = prv_band(impulses, wn, zeta)
        assert lo < wn < hi
        z_lo, z_hi = prv_band(impulses, wn, zeta, vary="damping")
        assert z_lo <= zeta <= z_hi


def synthetic_results(freq_error: float) -> list[dict]:
    """Poses whose identified modes are the paper map's prediction times (1 + freq_error)."""
    rng = np.random.default_rng(0)
    results = []
    for i in range(6):
        inertia = [rng.uniform(0.5, 9.0), rng.uniform(1.0, 9.0), 1.0, 1.0, 1.0, 1.0]
        modes = PAPER.modes_from_inertia(inertia)
        results.append(
            {
                "key": f"p{i}",
                "inertia_kg_m2": inertia,
                "modes": [
                    {"joint": j, "wn_rad_s": w * (1 + freq_error), "zeta": z}
                    for j, (w, z) in enumerate(modes)
                ],
            }
        )
    results.append(
        {
            "key": "flagged",
            "inertia_kg_m2": [1.0] * 6,
            "modes": [
                {"joint": 0, "wn_rad_s": 1.0, "zeta": 0.1, "low_confidence": True},
                {"joint": 1, "wn_rad_s": 1.0, "zeta": 0.1},
            ],
        }
    )
    return results


def test_exact_map_is_within_the_limit_and_errors_follow_the_band():
    exact = evaluate_map(synthetic_results(0.0), PAPER)
    assert len(exact) == 6  # the low-confidence pose is skipped
    assert all(e.within_limit for e in exact)
    assert max(max(e.prv) for e in exact) < 1e-9
    # With only the frequency wrong (damping as designed), "identified frequency inside the
    # 10 % band" and "PRV <= 10 %" are the same statement.
    for error in (-0.3, -0.05, 0.05, 0.2):
        for e in evaluate_map(synthetic_results(error), PAPER):
            for (w, _), band, prv in zip(e.identified, e.wn_band_rad_s, e.prv, strict=True):
                assert (band[0] <= w <= band[1]) == (prv <= PRV_LIMIT)
    off = evaluate_map(synthetic_results(-0.3), PAPER)
    summary = summarize(off)
    assert summary["n_poses"] == 6
    assert summary["within_10_percent_prv"] == sum(e.within_limit for e in off) < 6
    assert summary["per_mode"][0]["rms_wn_error"] == pytest.approx(1 / 0.7 - 1)
    assert summary["per_mode"][1]["max_prv"] > PRV_LIMIT


def test_plots_are_written(tmp_path):
    results = synthetic_results(0.03)
    paths = [
        plot_prv_sensitivity(PAPER, tmp_path / "fig27.png"),
        plot_frequency_robustness(PAPER, results, tmp_path / "fig28.png", mode=0),
        plot_frequency_robustness(PAPER, results, tmp_path / "fig29.png", mode=1),
        plot_damping_robustness(PAPER, results, tmp_path / "fig30.png"),
        plot_map_fit(PAPER, results, tmp_path / "map_fit.png"),
    ]
    for path in paths:
        assert path.exists() and path.stat().st_size > 10_000
        assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
