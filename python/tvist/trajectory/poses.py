"""Test poses of the UR5e experiments (paper section 6.1, Table 3), radians."""

from __future__ import annotations

from collections.abc import Mapping
from types import MappingProxyType

import numpy as np


def _frozen(values: list[float]) -> np.ndarray:
    pose = np.array(values, dtype=float)
    pose.setflags(write=False)
    return pose


#: The three joint-space test poses ``Q1``, ``Q2``, ``Q3`` (read-only arrays, shape (6,), rad).
#: ``Q1 -> Q2`` keeps the natural frequencies constant (only the base turns), ``Q1 -> Q3`` goes
#: from low to high frequencies and ``Q3 -> Q1`` from high to low.
PAPER_POSES: Mapping[str, np.ndarray] = MappingProxyType(
    {
        "Q1": _frozen([0.0, -np.pi, 0.0, -np.pi / 2, 0.0, 0.0]),
        "Q2": _frozen([np.pi / 2, -np.pi, 0.0, -np.pi / 2, 0.0, 0.0]),
        "Q3": _frozen([np.pi / 2, -np.pi / 2, 5 * np.pi / 6, -np.pi / 2, 0.0, 0.0]),
    }
)
