"""Modal maps shaping a motion on a twin, side by side: each map's reduction of residual
vibration (%), for tests that compare maps (a prior and what was learned from it)."""

from __future__ import annotations

from collections.abc import Mapping

from tvist.experiments.experiment import run_motion
from tvist.experiments.methods import default_methods, fd_tvist_modal


def reductions(motion, maps: Mapping[str, object], twin, robot) -> dict[str, float]:
    """Per map (by name): its ZV FD-TVIST row's reduction on ``motion`` on ``twin``, against
    the unshaped move in the same run."""
    rows = [m for m in default_methods() if m.key == "unshaped"]
    rows += [fd_tvist_modal(name, name, modal) for name, modal in maps.items()]
    run = run_motion(motion, rows, twin, robot, with_slow_down=False)
    return {name: run.run(name).reduction_percent for name in maps}
