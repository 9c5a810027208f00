"""``tvist demo``: run the experiment and write the report (the command prints the table)."""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

from tvist.experiments.experiment import DemoResult, run_experiment
from tvist.experiments.method_row import Method
from tvist.experiments.methods import default_methods


def run_demo(
    out_dir: str | Path = "out/demo",
    quick: bool = False,
    methods: Sequence[Method] | None = None,
    *,
    identify: bool = True,
    verbose: bool = True,
    show_table: Callable[[DemoResult, Any], None] | None = None,
) -> DemoResult:
    """Run the experiment and write ``results.json``, ``report.md`` and the figures to
    ``out_dir``; ``show_table`` prints the table.

    Parameters
    ----------
    out_dir
        Output folder (created if missing).
    quick
        Only the first motion (Q1->Q2) with a shorter tail, and a smaller campaign
        (:data:`~tvist.experiments.identified.QUICK_PLAN`).
    methods
        The rows, unshaped first (default :func:`~tvist.experiments.methods.default_methods`).
    identify
        Identify a map on the twin first: a reduced mapping campaign
        (:func:`~tvist.experiments.identified.identify_map`,
        :data:`~tvist.experiments.identified.DEMO_PLAN`, 1-3 min on two cores, depending on
        their load; its records are cached in ``out_dir`` and reused by the next run) and the
        map fit; its FD-TVIST row joins the map rows.
        ``False`` skips it.
    verbose
        Print progress lines (and the table, through ``show_table``).
    show_table
        Called with the result and the rich console once the outputs are written (``tvist
        demo`` passes :func:`tvist.cli.demo_table.print_table`); ``None``: no table.
    """
    from rich.console import Console

    from tvist.experiments.identified import DEMO_PLAN, QUICK_PLAN, identify_map
    from tvist.experiments.report import write_outputs

    console = Console(quiet=not verbose)
    if not console.is_terminal and console.width < 160:
        console.width = 160  # a log file or pipe: keep table rows on one line
    start = time.perf_counter()
    rows = list(default_methods() if methods is None else methods)
    identification = None
    if identify:
        plan = QUICK_PLAN if quick else DEMO_PLAN
        console.print(
            f"identifying a dynamic map on the twin (reduced campaign, {plan.n_poses} poses) ..."
        )
        identified = identify_map(out_dir, plan=plan, log=console.print)
        identification = identified.summary
        if identified.method is not None:
            # Right after the last map-driven row, so the map rows stand together.
            after = max((i for i, m in enumerate(rows) if m.dynmap is not None), default=0)
            rows.insert(after + 1, identified.method)
            from tvist.experiments.modal_rows import identify_modal_map

            modal_row, modal_summary = identify_modal_map(
                identified.records, out_dir, console.print
            )
            identification = {**identification, "modal_map": modal_summary}
            if modal_row is not None:
                rows.insert(after + 2, modal_row)
    result = run_experiment(quick=quick, methods=rows, log=console.print)
    result = dataclasses.replace(
        result,
        identification=identification,
        wall_time_s=time.perf_counter() - start,
    )
    outputs = write_outputs(result, out_dir)
    if show_table is not None:
        show_table(result, console)
    n_figures = sum(len(v) for v in outputs["figures"].values())
    n_figures += len((identification or {}).get("figures", []))
    console.print(
        f"wrote {outputs['results']}, {outputs['report']} and {n_figures} figures "
        f"(total {time.perf_counter() - start:.1f} s)"
    )
    return result
