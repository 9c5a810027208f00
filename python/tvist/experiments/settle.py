"""Time to settled: from the start of a move until the tool is still enough, for good.

Users pay in cycle time: the tool must be still enough to grip, place, measure or take a
picture. Each run is measured against the criteria of :data:`CRITERIA`:

- the gravity-free tool acceleration ``|ψ|`` (:func:`tvist.experiments.measure.tool_acceleration`)
  stays below 0.05 and 0.01 m/s²;
- the flange stays within 0.1 mm of where it comes to rest: the twin's flange at rest under
  gravity with the motors at the end pose (:func:`rest_flange_position`). The commanded
  (rigid) pose is no reference for this: at rest the gears deflect under the payload's weight
  by several millimetres at the flange, which a rigid model does not see.

The physical limit is the move's own duration: a perfect shaper adds nothing to it.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from tvist.analysis import SETTLE_BANDS_M_S2, SETTLE_HOLD_S, settling_time
from tvist.sim import SimRecord, Twin

__all__ = [
    "CRITERIA",
    "SETTLE_HOLD_S",
    "Criterion",
    "SettleTimes",
    "flange_error_m",
    "format_settle",
    "measure_settle",
    "rest_flange_position",
    "settle_config",
]


@dataclass(frozen=True)
class Criterion:
    """A settling band.

    Attributes
    ----------
    key
        Name in ``results.json``.
    signal
        ``"acceleration"`` (``|ψ|``, m/s²) or ``"flange"`` (distance from rest, m).
    threshold
        Band, in the signal's unit.
    text
        How tables name it.
    """

    key: str
    signal: str
    threshold: float
    text: str


#: The settling bands every run is measured against; the first decides recommendations.
CRITERIA: tuple[Criterion, ...] = (
    *(
        Criterion(f"accel_{band:g}_m_s2", "acceleration", band, f"|ψ| < {band:g} m/s²")
        for band in SETTLE_BANDS_M_S2
    ),
    Criterion("flange_0.1_mm", "flange", 1e-4, "flange within 0.1 mm"),
)


@dataclass(frozen=True)
class SettleTimes:
    """Time to settled of one run, per criterion of :data:`CRITERIA`.

    Attributes
    ----------
    move_s
        Duration of the planned move: the physical limit, s.
    times_s
        Per criterion key: seconds from the start of the move until settled for good, or
        ``None`` if the run has not settled within its record.
    record_s
        How long the record lasts after the start of the move, s (a ``None`` means "later
        than this minus :data:`SETTLE_HOLD_S`").
    """

    move_s: float
    times_s: dict[str, float | None]
    record_s: float

    def get(self, key: str) -> float | None:
        return self.times_s[key]

    def to_json(self) -> dict[str, Any]:
        return {
            "move_duration_s": self.move_s,
            "settle_s": dict(self.times_s),
            "settled": {k: v is not None for k, v in self.times_s.items()},
            "record_after_move_start_s": self.record_s,
            "hold_s": SETTLE_HOLD_S,
        }


def settle_config() -> dict[str, Any]:
    """The criteria and the hold, as stored in ``results.json``."""
    return {
        "criteria": [
            {"key": c.key, "signal": c.signal, "threshold": c.threshold, "text": c.text}
            for c in CRITERIA
        ],
        "hold_s": SETTLE_HOLD_S,
        "from": "start of the move",
        "flange_reference": "the twin's flange at rest under gravity at the end pose",
    }


def rest_flange_position(twin: Twin, q_motor: Sequence[float] | np.ndarray) -> np.ndarray:
    """Flange position (m, base frame) of the twin at rest under gravity with the motors at
    ``q_motor``: where the flange ends up once every vibration has died out."""
    hold = np.tile(np.asarray(q_motor, dtype=float), (2, 1))
    # The twin starts in static equilibrium, so its first recorded sample is the rest pose.
    return np.array(twin.run(hold).actual_TCP_pose[0, :3])


def flange_error_m(record: SimRecord, rest_m: np.ndarray) -> np.ndarray:
    """Distance of the recorded flange from ``rest_m`` per sample, m, ``(n_samples,)``."""
    return np.linalg.norm(record.actual_TCP_pose[:, :3] - np.asarray(rest_m), axis=1)


def measure_settle(
    t_s: np.ndarray,
    psi: np.ndarray,
    flange_err_m: np.ndarray,
    t_move_start_s: float,
    move_s: float,
) -> SettleTimes:
    """Settle times of one run from its gravity-free tool acceleration ``psi`` (m/s²,
    ``(n, 3)``) and flange distance from rest ``flange_err_m`` (m, ``(n,)``), measured from
    the start of the move ``t_move_start_s``; ``move_s`` is the planned move's duration."""
    signals = {"acceleration": psi, "flange": flange_err_m}
    times: dict[str, float | None] = {}
    for c in CRITERIA:
        value = settling_time(
            t_s, signals[c.signal], t_move_start_s, c.threshold, hold_s=SETTLE_HOLD_S
        )
        times[c.key] = value if math.isfinite(value) else None
    return SettleTimes(move_s=move_s, times_s=times, record_s=float(t_s[-1] - t_move_start_s))


def format_settle(value: float | None, record_s: float | None = None) -> str:
    """A settle time in s for tables (three decimals: the 2 ms grid), or "not settled"."""
    if value is None:
        if record_s is None:
            return "not settled"
        return f"not settled (> {record_s - SETTLE_HOLD_S:.1f})"
    return f"{value:.3f}"
