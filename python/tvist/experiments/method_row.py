"""One row of the experiment's table: a :class:`Method` builds the reference of one motion
from a :class:`MotionContext` and returns it as a :class:`Reference`. The rows themselves are
in :mod:`tvist.experiments.methods` and :mod:`tvist.experiments.fixed`."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from tvist.experiments.motions import Motion
from tvist.maps.paper10 import DynamicMap
from tvist.robots import Robot
from tvist.sim import Twin
from tvist.trajectory import Trajectory

__all__ = ["Method", "MotionContext", "Reference"]


@dataclass(frozen=True)
class MotionContext:
    """What a method may use to build its reference for one motion.

    Attributes
    ----------
    motion
        The motion.
    trajectory
        The planned (unshaped) double-S reference, rest padding included.
    twin
        The simulated arm; ``twin.modes(q)`` is the ground truth by eigen-analysis.
    robot
        The rigid-body model (with payload) that map providers evaluate every cycle.
    max_mode_delay_s
        Longest one-mode ZV delay ``π/ω_d`` of the true modes along the planned move, s.
    """

    motion: Motion
    trajectory: Trajectory
    twin: Twin
    robot: Robot
    max_mode_delay_s: float


@dataclass(frozen=True)
class Reference:
    """A method's reference for one motion and how it was made.

    Attributes
    ----------
    q
        Joint reference sent to the twin, rad, same shape as the planned one.
    details
        JSON-ready facts about the construction (shaper, provider, flags, ...).
    """

    q: np.ndarray
    details: dict[str, Any] = field(default_factory=dict)


@dataclass(frozen=True)
class Method:
    """One row of the table.

    Attributes
    ----------
    key
        Identifier in ``results.json`` (``"unshaped"`` is the baseline of every motion).
    label
        Human-readable name for tables and legends.
    build
        ``build(context) -> Reference``.
    motions
        Names of the motions the row is run for (``"Q1->Q2"``); ``None`` is all.
    dynmap
        The dynamic map the method uses, if any (its modes are plotted along each motion).
    oracle
        Why a user cannot run this row on a robot (it reads what only the twin knows), or
        ``None`` for a row a user can run. Oracle rows are references, never recommended.
    """

    key: str
    label: str
    build: Callable[[MotionContext], Reference]
    motions: tuple[str, ...] | None = None
    dynmap: DynamicMap | None = None
    oracle: str | None = None

    def applies_to(self, motion: Motion) -> bool:
        """Whether this row is run for ``motion``."""
        return self.motions is None or motion.name in self.motions
