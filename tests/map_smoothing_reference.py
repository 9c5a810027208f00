"""Independent reference of the dynamic map's documented smoothing (tvist-core dynmap module
docs), typed in from the documentation for the tests; the library never imports it."""

from __future__ import annotations

import math

#: Relative width of each blend zone of the soft clamp into an inertia range.
RANGE_BLEND_WIDTH = 0.05
#: Smoothing torque of the gravity term k_g (√(τ² + τ_s²) − τ_s), N m.
GRAVITY_TORQUE_SMOOTHING_NM = 1.0


def soft_clamp(j: float, lo: float, hi: float) -> float:
    """The C¹ saturation of J into [lo, hi] as documented, written out piece by piece."""
    eps = RANGE_BLEND_WIDTH
    if j <= lo * (1 - eps):
        return lo
    if j < lo * (1 + eps):
        return j + (lo * (1 + eps) - j) ** 2 / (4 * lo * eps)
    if j <= hi * (1 - eps):
        return j
    if j < hi * (1 + eps):
        return j - (j - hi * (1 - eps)) ** 2 / (4 * hi * eps)
    return hi


def smooth_abs_torque(tau_nm: float) -> float:
    """√(τ² + τ_s²) − τ_s: the documented stand-in for |τ| in the gravity term."""
    return math.hypot(tau_nm, GRAVITY_TORQUE_SMOOTHING_NM) - GRAVITY_TORQUE_SMOOTHING_NM
