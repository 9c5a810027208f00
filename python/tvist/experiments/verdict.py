"""The verdict of the UR5e experiment: per motion, which method a user can run settles first
(printed under each console table and listed in ``report.md``)."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from tvist.experiments.experiment import MotionRun
from tvist.experiments.motions import DT_S
from tvist.experiments.settle import CRITERIA
from tvist.experiments.table import planned_move_s

#: Recommendations rank by time to settled at this criterion (the first of CRITERIA) ...
RANK_CRITERION = CRITERIA[0]
#: ... rows within this much of the fastest tie (s: one and a half control periods of the
#: UR5e, the grid of the stop),
#: and the tie goes to the faster one at the stricter band (the second criterion), then to
#: the higher reduction.
SETTLE_TIE_S = 1.5 * DT_S


@dataclass(frozen=True)
class _Option:
    """A runnable choice of the recommendation: a row, or the best slow-down profile."""

    label: str
    settle: Any
    reduction_percent: float
    run: Any = None


def _options(motion: MotionRun) -> list[_Option]:
    """The runnable rows (no oracle) and the best slow-down profile at the ranking criterion."""
    out = [
        _Option(r.method.label, r.settle, r.reduction_percent, r)
        for r in motion.runs
        if r.method.oracle is None and r.settle is not None
    ]
    if motion.slow_down is not None:
        best = motion.slow_down.best(RANK_CRITERION.key)
        # The grid's first candidate is the planned move: already the unshaped row.
        if best is not None and best is not motion.slow_down.candidates[0]:
            out.append(_Option(f"Slow down instead ({best.text()})", best.settle, math.nan))
    return out


def _rank_key(option: _Option) -> tuple[float, float]:
    second = option.settle.get(CRITERIA[1].key)
    reduction = option.reduction_percent if math.isfinite(option.reduction_percent) else 0.0
    return (math.inf if second is None else second, -reduction)


def recommendation(motion: MotionRun) -> str:
    """One line: which runnable method settles first on this motion, and by how much.

    Rows a user can run are those without :attr:`~tvist.experiments.method_row.Method.oracle`, the
    unshaped move and the best "slow down instead" profile included. The one that settles
    first at :data:`RANK_CRITERION` wins; rows within :data:`SETTLE_TIE_S` of it tie, and
    the tie goes to the faster at the stricter band, then to the higher reduction.
    """
    name = motion.motion.name.replace("->", " → ")
    key = RANK_CRITERION.key
    options = [o for o in _options(motion) if o.settle.get(key) is not None]
    if not options:
        return f"{name}: no runnable row settles to {RANK_CRITERION.text} within the record."
    fastest = min(o.settle.get(key) for o in options)
    pick = min((o for o in options if o.settle.get(key) <= fastest + SETTLE_TIE_S), key=_rank_key)
    t_pick = pick.settle.get(key)
    why = (
        f"settled ({RANK_CRITERION.text}) {t_pick:.3f} s after the move starts; the move "
        f"itself lasts {planned_move_s(motion):.3f} s"
    )
    unshaped = motion.runs[0].settle.get(key)
    if pick.run is not motion.runs[0] and unshaped is not None:
        why += f", unshaped {unshaped:.3f} s ({100 * (1 - t_pick / unshaped):.0f} % sooner)"
    others = sorted(
        (o for o in options if o is not pick and o.run is not motion.runs[0]),
        key=lambda o: o.settle.get(key),
    )[:2]
    if others:
        why += "; next: " + ", ".join(f"{o.label} {o.settle.get(key):.3f} s" for o in others)
    caveat = ""
    if pick.run is not None and "alpha" in pick.run.details:
        caveat = (
            " (zero-delay shaping needs the whole rest-to-rest move in advance and the modes "
            "at its end pose)"
        )
    line = f"{name}: use **{pick.label}**: {why}{caveat}."
    oracles = [
        r for r in motion.runs if r.method.oracle is not None and r.settle and r.settle.get(key)
    ]
    if oracles:
        best_oracle = min(oracles, key=lambda r: r.settle.get(key))
        if best_oracle.settle.get(key) < t_pick:
            line += (
                f" Not recommended although faster: {best_oracle.method.label} "
                f"({best_oracle.settle.get(key):.3f} s), an oracle row: it "
                f"{best_oracle.method.oracle}."
            )
    return line
