"""URDF's roll-pitch-yaw angles: ``R = Rz(yaw) Ry(pitch) Rx(roll)`` (fixed axes x, y, z), rad.

The one Python home of the convention (the Rust core's is ``tvist-core``'s ``placement.rs``);
the forward maps are scipy's rotations.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.spatial.transform import Rotation

__all__ = ["rpy_angles", "rpy_matrix", "rpy_quat"]


def rpy_matrix(rpy: np.ndarray) -> np.ndarray:
    """``(3, 3)`` rotation of URDF angles ``(roll, pitch, yaw)``."""
    return Rotation.from_euler("xyz", np.asarray(rpy, dtype=float)).as_matrix()


def rpy_quat(rpy: np.ndarray) -> np.ndarray:
    """``(w, x, y, z)`` unit quaternion of URDF angles ``(roll, pitch, yaw)``."""
    return Rotation.from_euler("xyz", np.asarray(rpy, dtype=float)).as_quat(scalar_first=True)


def rpy_angles(rot: np.ndarray) -> tuple[float, float, float]:
    """``(roll, pitch, yaw)`` of a rotation matrix, pitch in [-π/2, π/2]. At pitch ±π/2 only
    roll ∓ yaw is defined: roll is taken as 0 (scipy would warn and zero the yaw instead)."""
    cos_pitch = math.hypot(rot[2, 1], rot[2, 2])
    pitch = math.atan2(-rot[2, 0], cos_pitch)
    if cos_pitch < 1e-12:
        return 0.0, pitch, math.atan2(-rot[0, 1], rot[1, 1])
    return math.atan2(rot[2, 1], rot[2, 2]), pitch, math.atan2(rot[1, 0], rot[0, 0])
