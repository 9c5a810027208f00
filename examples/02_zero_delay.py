"""Shape a fast move with zero added delay: ZTDIS vs modified ZTDIS.

A 0.734 s minimum-jerk move of a payload whose 2.55 Hz mode (zeta 0.04) needs a 0.39 s ZVD
shaper: conventional shaping would make it 53 % longer. Both zero-delay methods finish at
0.734 s; the modified one keeps a single velocity peak. Prints the benchmark tables for a
minimum-jerk and a trapezoidal reference and writes the Fig. 13-style plot.

    python examples/02_zero_delay.py [output.png]
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

import tvist
from tvist.experiments.ztdis_benchmark import format_table, plot_benchmark, run_benchmark
from tvist.trajectory import min_jerk

wn_rad_s, zeta, dt_s = 2.0 * np.pi * 2.55, 0.04, 0.002
move = min_jerk([0.0], [0.3], duration_s=0.734, dt_s=dt_s).q  # (n_samples, 1), rest to rest

for method in ("ztdis", "modified"):
    result = tvist.zero_delay(move, dt_s, [(wn_rad_s, zeta)], shaper="zvd", method=method)
    print(
        f"{method:>8}: alpha = {result.alpha:.4f}, shaper delay {result.delay_s:.4f} s, "
        f"reference ends at {result.move_s:.3f} s, final error {result.tail_error:.1e}"
    )
print()

benches = [run_benchmark(reference, dt_s=dt_s) for reference in ("min_jerk", "trapezoid")]
for bench in benches:
    print(format_table(bench))
    print()
out = Path(sys.argv[1]) if len(sys.argv) > 1 else Path("out/zero_delay.png")
print(f"plot: {plot_benchmark(benches, out)}")
