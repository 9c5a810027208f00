"""The demo's identified modal map, fitted again from the demo campaign's own records: what
``make demo`` shows (README: 99.88 / 99.27 / 99.50 %, delays 132 / 52 / 132 ms) is kept by
``make test`` too, so a change of the all-modes fit that breaks the demo fails here.

``tests/data/demo_campaign.jsonl`` is the campaign file ``make demo`` writes
(``out/demo/campaign.jsonl``: 36 poses of the twin's MuJoCo logs, identified), kept so that
this test pays for the fit (~30 s) and not for the campaign. It guards the fit and the
shaping, not the identification (the campaign tests do that); to refresh it after a change
of the identification, copy the new ``out/demo/campaign.jsonl`` over it. The truth it is
judged against is not in the file: the twin's own eigen-analysis and MuJoCo runs of the
three moves."""

from __future__ import annotations

import pytest

from shared_fits import DEMO_CAMPAIGN
from tvist.experiments import default_methods, run_experiment
from tvist.experiments.motions import DT_S
from tvist.ident.results_store import load_results


@pytest.mark.slow
def test_the_demo_campaigns_modal_map_shapes_every_demo_move_to_99_percent(tmp_path) -> None:
    from tvist.experiments.modal_rows import identify_modal_map

    records = load_results(DEMO_CAMPAIGN)
    assert len(records) == 36
    row, summary = identify_modal_map(records, tmp_path)
    assert row is not None, summary
    # The accuracy floor for every shaped mode, at workspace poses the campaign did
    # not visit, against the twin's eigen-analysis (measured 0.22 % RMS / 0.61 % max and
    # 0.51 / 1.51 %): 3 % RMS, 8 % max.
    assert len(summary["versus_true_modes"]) == summary["shaped_modes"] >= 2
    for mode in summary["versus_true_modes"]:
        assert mode["rms_percent"] <= 3.0 and mode["max_percent"] <= 8.0, mode
    unshaped = [m for m in default_methods() if m.key == "unshaped"]
    result = run_experiment(methods=[*unshaped, row]).to_json()
    for name, motion in result["motions"].items():
        shaped = motion["methods"][row.key]
        # >= 99 % on each demo move (measured 99.88 / 99.27 / 99.50 %): the floor the demo
        # keeps; a fit that left the elbow's modes undamped once gave 94.7 % on Q1 -> Q3.
        assert shaped["reduction_percent"] >= 99.0, (name, shaped["reduction_percent"])
        # The delay is ZV's for the map's modes at the stop, within one 2 ms sample.
        analytic = motion["analytic_zv_delay_map_s"][row.label]
        assert abs(shaped["delay_s"] - analytic) <= DT_S + 1e-9, (name, shaped["delay_s"])
