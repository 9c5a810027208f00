"""Rigid-body inertial data in one frame, and joining two bodies fixed to each other."""

from __future__ import annotations

import numpy as np

__all__ = ["NEGLIGIBLE", "Inertial", "lump"]

#: A mass or inertia below this is treated as absent (kg, kg m²).
NEGLIGIBLE = 1e-12

Inertial = tuple[float, np.ndarray, np.ndarray]
"""``(mass_kg, com_m (3,), inertia about the COM (3, 3) kg m²)`` in one frame."""


def lump(first: Inertial, second: Inertial) -> Inertial:
    """One rigid body equivalent to two bodies fixed to each other (parallel-axis theorem);
    no body (zero mass and inertia) if their mass is negligible."""
    m1, c1, i1 = first
    m2, c2, i2 = second
    mass = m1 + m2
    if mass <= NEGLIGIBLE:
        return 0.0, np.zeros(3), np.zeros((3, 3))
    com = (m1 * c1 + m2 * c2) / mass

    def shifted(m: float, c: np.ndarray) -> np.ndarray:
        r = c - com
        return m * (float(r @ r) * np.eye(3) - np.outer(r, r))

    return mass, com, i1 + shifted(m1, c1) + i2 + shifted(m2, c2)
