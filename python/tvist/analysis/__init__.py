"""Measures of vibration and smoothness for moves and shapers.

- :func:`residual_vibration`: amplitude of the tool acceleration when the motion stops,
  from the log decay of the peaks after it (paper section 6.2).
- :func:`energy_spectrum`: vibration energy per frequency bin (eq. 56).
- :func:`settling_time`, :func:`peak_velocity`, :func:`peak_acceleration`, :func:`peak_jerk`,
  :func:`count_velocity_peaks`: scalar measures of a move.
- :func:`path_deviation`: how far the shaped tool path strays from the planned one.
- :func:`sensitivity_grid`: percent residual vibration of a shaper over a grid of modes.

Signals are ``(n_samples,)`` or ``(n_samples, k)``, time along rows.
"""

from __future__ import annotations

from tvist.analysis.metrics import (
    SETTLE_BANDS_M_S2,
    SETTLE_HOLD_S,
    count_velocity_peaks,
    peak_acceleration,
    peak_jerk,
    peak_velocity,
    settling_time,
)
from tvist.analysis.path import PathDeviation, path_deviation
from tvist.analysis.residual import ResidualVibration, estimate_noise_std, residual_vibration
from tvist.analysis.sensitivity import sensitivity_grid
from tvist.analysis.spectrum import EnergySpectrum, energy_spectrum

__all__ = [
    "SETTLE_BANDS_M_S2",
    "SETTLE_HOLD_S",
    "EnergySpectrum",
    "PathDeviation",
    "ResidualVibration",
    "count_velocity_peaks",
    "energy_spectrum",
    "estimate_noise_std",
    "path_deviation",
    "peak_acceleration",
    "peak_jerk",
    "peak_velocity",
    "residual_vibration",
    "sensitivity_grid",
    "settling_time",
]
