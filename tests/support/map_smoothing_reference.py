"""Independent reference of the dynamic map's documented smoothing (tvist-core dynmap module
docs), typed in from the documentation for the tests; the library never imports it."""

from __future__ import annotations

import math

#: Relative width of each blend zone of the soft clamp into an inertia range.
RANGE_BLEND_WIDTH = 0.05
#: Smoothing torque of the gravity term k_g (√(τ² + τ_s²) − τ_s), N m.
GRAVITY_TORQUE_SMOOTHING_NM = 1.0


def soft_clamp(j: float, lo: float, hi: float) -> float:
    """The C² saturation of J into [lo, hi] as documented, written out piece by piece."""
    eps = RANGE_BLEND_WIDTH

    def blend(x: float) -> float:  # B(x) = x − x³ + x⁴/2
        return x - x**3 + x**4 / 2

    if j <= lo * (1 - eps):
        return lo
    if j < lo * (1 + eps):
        return lo * (1 + eps) - 2 * lo * eps * blend((lo * (1 + eps) - j) / (2 * lo * eps))
    if j <= hi * (1 - eps):
        return j
    if j < hi * (1 + eps):
        return hi * (1 - eps) + 2 * hi * eps * blend((j - hi * (1 - eps)) / (2 * hi * eps))
    return hi


def smooth_abs_torque(tau_nm: float) -> float:
    """√(τ² + τ_s²) − τ_s: the documented stand-in for |τ| in the gravity term."""
    return math.hypot(tau_nm, GRAVITY_TORQUE_SMOOTHING_NM) - GRAVITY_TORQUE_SMOOTHING_NM
