"""The paper's section-6 experiment on the simulated flexible UR5e (``tvist demo``).

Three test motions with a 5 kg payload, each run unshaped, with two-mode ZV FD-TVIST (true
modes of the twin, and the paper's published map on the real-time path) and with zero-delay
shaping; the residual vibration, delay and reference jerk are reported like the paper's
Table 4, with figures like its Figs. 32-36.

Examples
--------
>>> from tvist.demo import run_demo
>>> result = run_demo("out/demo", quick=True)  # doctest: +SKIP

More rows (for example a map identified on the twin) are added to the list of methods::

    from tvist import DynamicMap
    from tvist.demo import default_methods, fd_tvist_map, run_demo

    rows = [*default_methods(), fd_tvist_map("fd-tvist-identified", "FD-TVIST ZV, identified
            map", DynamicMap.load("map.json"))]
    run_demo("out/demo", methods=rows)
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

from tvist.demo.experiment import DemoResult, MethodRun, MotionRun, run_experiment, run_motion
from tvist.demo.linear import run_linear_demo
from tvist.demo.methods import (
    Method,
    MotionContext,
    Reference,
    default_methods,
    fd_tvist_map,
    zero_delay_row,
)
from tvist.demo.motions import MOTIONS, Motion

__all__ = [
    "MOTIONS",
    "DemoResult",
    "Method",
    "MethodRun",
    "Motion",
    "MotionContext",
    "MotionRun",
    "Reference",
    "default_methods",
    "fd_tvist_map",
    "run_demo",
    "run_experiment",
    "run_linear_demo",
    "run_motion",
    "zero_delay_row",
]


def run_demo(
    out_dir: str | Path = "out/demo",
    quick: bool = False,
    methods: Sequence[Method] | None = None,
    *,
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
        The rows, unshaped first (default :func:`default_methods`).
    verbose
        Print progress lines and the table.
    """
    import time

    from rich.console import Console

    from tvist.demo.report import print_table, write_outputs

    console = Console(quiet=not verbose)
    if not console.is_terminal and console.width < 120:
        console.width = 120  # a log file or pipe: keep table rows on one line
    start = time.perf_counter()
    result = run_experiment(quick=quick, methods=methods, log=console.print)
    outputs = write_outputs(result, out_dir)
    print_table(result, console)
    console.print(
        f"wrote {outputs['results']}, {outputs['report']} and "
        f"{sum(len(v) for v in outputs['figures'].values())} figures "
        f"(total {time.perf_counter() - start:.1f} s)"
    )
    return result
