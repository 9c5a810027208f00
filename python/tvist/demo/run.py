"""``tvist demo``: run the experiment, print the table, write the report."""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Sequence
from pathlib import Path

from tvist.demo.experiment import DemoResult, run_experiment
from tvist.demo.methods import Method, default_methods


def run_demo(
    out_dir: str | Path = "out/demo",
    quick: bool = False,
    methods: Sequence[Method] | None = None,
    *,
    identify: bool = False,
    verbose: bool = True,
) -> DemoResult:
    """Run the experiment, print the table and write ``results.json``, ``report.md`` and the
    figures to ``out_dir``.

    Parameters
    ----------
    out_dir
        Output folder (created if missing).
    quick
        Only the first motion (Q1->Q2) with a shorter tail.
    methods
        The rows, unshaped first (default :func:`~tvist.demo.methods.default_methods`).
    identify
        Also identify a map on the twin with a reduced campaign
        (:func:`~tvist.demo.identified.identify_map`, 15-40 s) and add its FD-TVIST row.
    verbose
        Print progress lines and the table.
    """
    from rich.console import Console

    from tvist.demo.identified import identify_map
    from tvist.demo.report import print_table, write_outputs

    console = Console(quiet=not verbose)
    if not console.is_terminal and console.width < 120:
        console.width = 120  # a log file or pipe: keep table rows on one line
    start = time.perf_counter()
    rows = list(default_methods() if methods is None else methods)
    identification = None
    if identify:
        console.print("identifying a dynamic map on the twin (reduced campaign) ...")
        identified = identify_map(out_dir, log=console.print)
        identification = identified.summary
        if identified.method is not None:
            # Right after the last map-driven row, so the map rows stand together.
            after = max((i for i, m in enumerate(rows) if m.dynmap is not None), default=0)
            rows.insert(after + 1, identified.method)
    result = run_experiment(quick=quick, methods=rows, log=console.print)
    result = dataclasses.replace(
        result,
        identification=identification,
        wall_time_s=time.perf_counter() - start,
    )
    outputs = write_outputs(result, out_dir)
    print_table(result, console)
    console.print(
        f"wrote {outputs['results']}, {outputs['report']} and "
        f"{sum(len(v) for v in outputs['figures'].values())} figures "
        f"(total {time.perf_counter() - start:.1f} s)"
    )
    return result
