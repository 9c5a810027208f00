""" "Slow down instead": the obvious alternative to any shaper.

A softer jerk ramp or a lower acceleration limit excites the arm less; the move takes longer
but may settle sooner. For a move, every profile of a small grid (:data:`JERK_TIMES_S` ×
:data:`ACCEL_SCALES`, the speed limit unchanged) is planned by ruckig
(:func:`tvist.trajectory.double_s`), run unshaped on the twin and measured like every other
row (:mod:`tvist.experiments.settle`). The best slow-down per criterion is the candidate that
settles first, the planned (unshaped) move itself included.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from tvist.experiments.measure import tool_acceleration
from tvist.experiments.settle import CRITERIA, SettleTimes, flange_error_m, measure_settle
from tvist.sim import Twin
from tvist.trajectory import double_s

__all__ = ["ACCEL_SCALES", "JERK_TIMES_S", "Candidate", "SlowDown", "slow_down"]

#: Acceleration ramps of the grid (s; the jerk limit is a_max / ramp) ...
JERK_TIMES_S = (0.02, 0.05, 0.1, 0.2, 0.4)
#: ... and acceleration limits, as fractions of the planned move's.
ACCEL_SCALES = (1.0, 0.5)


@dataclass(frozen=True)
class Candidate:
    """One slower profile: its limits, its duration and its settle times."""

    jerk_time_s: float
    accel_scale: float
    settle: SettleTimes

    def text(self) -> str:
        return f"{1e3 * self.jerk_time_s:.0f} ms ramp, ×{self.accel_scale:g} acceleration"

    def to_json(self) -> dict[str, Any]:
        return {
            "jerk_time_s": self.jerk_time_s,
            "accel_scale": self.accel_scale,
            **self.settle.to_json(),
        }


@dataclass(frozen=True)
class SlowDown:
    """The grid's candidates of one move; the first is the planned move itself."""

    candidates: tuple[Candidate, ...]

    def best(self, key: str) -> Candidate | None:
        """The candidate that settles first by criterion ``key`` (``None`` if none does)."""
        settled = [c for c in self.candidates if c.settle.get(key) is not None]
        return min(settled, key=lambda c: c.settle.get(key)) if settled else None

    def to_json(self) -> dict[str, Any]:
        best = {}
        for c in CRITERIA:
            pick = self.best(c.key)
            best[c.key] = (
                None
                if pick is None
                else {
                    "settle_s": pick.settle.get(c.key),
                    "jerk_time_s": pick.jerk_time_s,
                    "accel_scale": pick.accel_scale,
                    "move_duration_s": pick.settle.move_s,
                }
            )
        return {
            "grid": {"jerk_times_s": list(JERK_TIMES_S), "accel_scales": list(ACCEL_SCALES)},
            "best": best,
            "candidates": [c.to_json() for c in self.candidates],
        }


def slow_down(
    q_start: np.ndarray,
    q_end: np.ndarray,
    twin: Twin,
    rest_m: np.ndarray,
    planned: Candidate,
    *,
    v_max: float,
    a_max: float,
    pre_s: float,
    tail_s: float,
    dt_s: float,
) -> SlowDown:
    """Run every profile of the grid except the planned one (``planned``, already measured)
    from ``q_start`` to ``q_end`` on ``twin`` and measure its settle times.

    ``rest_m`` is the flange's rest position at ``q_end``
    (:func:`tvist.experiments.settle.rest_flange_position`); ``pre_s`` and ``tail_s`` the rest
    before and after each move, s.
    """
    out = [planned]
    for accel_scale in ACCEL_SCALES:
        for jerk_time in JERK_TIMES_S:
            if (jerk_time, accel_scale) == (planned.jerk_time_s, planned.accel_scale):
                continue
            traj = double_s(
                q_start,
                q_end,
                dt_s=dt_s,
                v_max=v_max,
                a_max=accel_scale * a_max,
                jerk_time_s=jerk_time,
                t_pre_s=pre_s,
                t_post_s=tail_s,
            )
            record = twin.run(traj.q, dt_s=dt_s)
            settle = measure_settle(
                np.asarray(traj.t_s),
                tool_acceleration(record),
                flange_error_m(record, rest_m),
                traj.t_motion_start_s,
                traj.t_motion_end_s - traj.t_motion_start_s,
            )
            out.append(Candidate(jerk_time, accel_scale, settle))
    return SlowDown(tuple(out))
