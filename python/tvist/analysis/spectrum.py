"""Vibration energy spectrum of a multi-axis acceleration record (paper eq. 56)."""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike

from tvist.analysis._signals import as_channels, positive

__all__ = ["EnergySpectrum", "energy_spectrum"]


class EnergySpectrum(NamedTuple):
    """One-sided energy spectrum; unpacks as ``freq_hz, energy``.

    Attributes
    ----------
    freq_hz
        Bin frequencies ``0 .. 1/(2 dt_s)``, shape ``(n_samples // 2 + 1,)``, Hz.
    energy
        ``E_k = Σ_axes |X_k|² / n_samples`` at each bin, in (signal unit)².
    """

    freq_hz: np.ndarray
    energy: np.ndarray


def energy_spectrum(
    accel_xyz: ArrayLike, dt_s: float, *, remove_mean: bool = False
) -> EnergySpectrum:
    """Energy spectrum ``E = (|FFT ψ_x|² + |FFT ψ_y|² + |FFT ψ_z|²) / n_samples`` (eq. 56).

    Only the non-negative frequencies are returned (the input is real, so the negative half
    mirrors them). The values are eq. 56 per bin, not doubled; Parseval's theorem reads
    ``E[0] + 2 Σ E[1:-1] + E[-1] = Σ_t |ψ(t)|²`` for even ``n_samples`` (without the ``E[-1]``
    exception for odd).

    Parameters
    ----------
    accel_xyz
        Gravity-compensated acceleration, shape ``(n_samples, k)`` (k = 3 for the tool
        accelerometer) or ``(n_samples,)``.
    dt_s
        Sample period, s.
    remove_mean
        Subtract each axis's mean first (a leftover static level only fills the 0 Hz bin).

    Returns
    -------
    EnergySpectrum
        ``(freq_hz, energy)``.
    """
    psi = as_channels("accel_xyz", accel_xyz)
    dt = positive("dt_s", dt_s)
    if remove_mean:
        psi = psi - psi.mean(axis=0)
    n = psi.shape[0]
    spectrum = np.fft.rfft(psi, axis=0)
    energy = np.sum(np.abs(spectrum) ** 2, axis=1) / n
    return EnergySpectrum(np.fft.rfftfreq(n, d=dt), energy)
