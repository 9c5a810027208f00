"""The papers' experiments and studies on the twin (``tvist demo``, ``tvist zero-delay``).

Exported here: the FD-TVIST paper's section-6 experiment on the simulated flexible UR5e.
Three test motions with a 5 kg payload, each run unshaped, with two-mode ZV FD-TVIST (true
modes of the twin; the paper's published map and a map identified on the twin, both on the
real-time path) and with zero-delay shaping; the residual vibration, delay and reference jerk
are reported like the paper's Table 4, with figures like its Figs. 32-36.

Examples
--------
>>> from tvist.experiments import run_demo
>>> result = run_demo("out/demo", quick=True)  # doctest: +SKIP

More rows (for example a map identified on the twin) are added to the list of methods::

    from tvist import DynamicMap
    from tvist.experiments import default_methods, fd_tvist_map, run_demo

    identified = DynamicMap.load("map.json")
    rows = [*default_methods(), fd_tvist_map("my-map", "FD-TVIST ZV, my map", identified)]
    run_demo("out/demo", methods=rows)

By default ``run_demo`` first identifies a map on the twin itself (a reduced mapping campaign
and the map fit, :mod:`tvist.experiments.identified`) and adds its row; ``identify=False``
(``tvist demo --no-identify``) skips that.
"""

from __future__ import annotations

from tvist.experiments.experiment import (
    DemoResult,
    MethodRun,
    MotionRun,
    run_experiment,
    run_motion,
)
from tvist.experiments.linear import run_linear_demo
from tvist.experiments.method_row import Method, MotionContext, Reference
from tvist.experiments.methods import default_methods, fd_tvist_map, zero_delay_row
from tvist.experiments.motions import MOTIONS, Motion
from tvist.experiments.run import run_demo

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
