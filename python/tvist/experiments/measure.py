"""Measurements of one run: stop time of a reference, gravity-free tool acceleration, residual
vibration, spectrum window, and mode helpers.

Arrays are ``(n_samples, ...)`` with time along rows; SI units.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from tvist import REST_TOLERANCE
from tvist.analysis import EnergySpectrum, ResidualVibration, energy_spectrum, residual_vibration
from tvist.sim import GRAVITY_M_S2, SimRecord

#: A reference has stopped once it stays within this distance of its end pose (rad). The
#: twin interpolates the reference linearly between samples, so a reference stops moving at
#: the first sample from which all samples equal the end pose; "equal" allows for round-off
#: (the impulse amplitudes sum to 1 within ~1e-15). A ZV-shaped jerk-limited approach
#: (jerk 100 rad/s³) is still ~1e-8 rad away one sample before its end, so the stop is found
#: to the sample. The zero-delay references keep a truncation residue of a few 1e-9 rad at
#: their last sample (``tail_error``), so by this measure they stop one sample after ``T``.
#: The shaper's own rest tolerance, so that a stop here is where the shaper is at rest.
STOP_TOL_RAD = REST_TOLERANCE


def stop_time_s(
    t_s: np.ndarray, q: np.ndarray, q_end: np.ndarray, tol_rad: float = STOP_TOL_RAD
) -> float:
    """Time of the first sample from which every later sample is within ``tol_rad`` of ``q_end``.

    Parameters
    ----------
    t_s
        Sample times, s, ``(n_samples,)``.
    q
        Reference, rad, ``(n_samples, n_dof)``.
    q_end
        End pose, rad, ``(n_dof,)``.
    tol_rad
        Distance (max over joints) that counts as arrived.

    Raises
    ------
    ValueError
        If the reference has not come to rest before its last sample.
    """
    q = np.asarray(q, dtype=float)
    if q.ndim != 2 or q.shape[0] != len(t_s):
        raise ValueError(f"q must have shape ({len(t_s)} samples, n_dof), got {q.shape}")
    away = np.flatnonzero(np.max(np.abs(q - np.asarray(q_end)), axis=1) > tol_rad)
    if away.size == 0:
        return float(t_s[0])
    last = int(away[-1])
    if last >= len(t_s) - 1:
        raise ValueError("the reference does not come to rest at its end pose before the end")
    return float(t_s[last + 1])


def tool_acceleration(record: SimRecord) -> np.ndarray:
    """Gravity-free acceleration of the flange in flange axes (m/s²), ``(n_samples, 3)``.

    The accelerometer reads the specific force ``f = R^T (a - g)`` with ``g = [0, 0, -g]`` in
    the base frame and ``R`` the flange orientation. Subtracting ``R^T [0, 0, g]`` with the
    recorded orientation of every sample leaves ``ψ = R^T a``: the paper's gravity-compensated
    reading in the sensor's own frame (eq. 56), at rest exactly zero.
    """
    from scipy.spatial.transform import Rotation

    rot = Rotation.from_rotvec(record.actual_TCP_pose[:, 3:]).as_matrix()
    # R^T e_z is the third row of R.
    return record.actual_tool_accelerometer - GRAVITY_M_S2 * rot[:, 2, :]


def measure_residual(t_s: np.ndarray, psi: np.ndarray, t_stop_s: float) -> ResidualVibration:
    """Residual vibration of the gravity-free acceleration ``psi`` at the stop ``t_stop_s``.

    The paper's log-decay extrapolation of the acceleration peaks back to the stop
    (:func:`tvist.analysis.residual_vibration`), refined by a one-mode fit where one mode
    explains the decay. ``psi`` is already free of gravity, so no baseline is subtracted.
    """
    return residual_vibration(t_s, psi, t_stop_s, baseline="none")


def residual_spectrum(
    psi: np.ndarray, t_s: np.ndarray, t_stop_s: float, window_s: float, dt_s: float
) -> EnergySpectrum:
    """Energy spectrum (eq. 56) of ``psi`` over ``[t_stop_s, t_stop_s + window_s)``."""
    first = int(np.searchsorted(t_s, t_stop_s - 1e-9 * dt_s))
    n = int(round(window_s / dt_s))
    if first + n > len(t_s):
        raise ValueError(
            f"the record ends {t_s[-1] - t_stop_s:.3f} s after the stop; the spectrum window "
            f"needs {window_s:.3f} s"
        )
    return energy_spectrum(psi[first : first + n], dt_s)


def damped_frequency_hz(wn_rad_s: float, zeta: float) -> float:
    """``f_d = ω_n √(1 − ζ²) / 2π``, Hz."""
    return wn_rad_s * math.sqrt(1.0 - zeta * zeta) / (2.0 * math.pi)


def zv_delay_s(modes: Sequence[tuple[float, float]]) -> float:
    """Delay of a ZV shaper cascade, ``Σ 1 / (2 f_d,i)``, s (paper Table 4)."""
    return float(sum(1.0 / (2.0 * damped_frequency_hz(w, z)) for w, z in modes))


def modes_json(modes: Sequence[tuple[float, float]]) -> list[dict[str, float]]:
    """Modes as ``[{"wn_rad_s", "zeta", "f_d_hz"}, ...]`` (base first, then shoulder)."""
    return [
        {"wn_rad_s": float(w), "zeta": float(z), "f_d_hz": damped_frequency_hz(w, z)}
        for w, z in modes
    ]
