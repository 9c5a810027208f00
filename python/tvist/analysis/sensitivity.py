"""Sensitivity of an impulse sequence to modelling errors, on a grid of modes."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

import tvist

__all__ = ["sensitivity_grid"]


def sensitivity_grid(impulses: tvist.Impulses, wn_rad_s: ArrayLike, zetas: ArrayLike) -> np.ndarray:
    """Percent residual vibration (as a fraction) of ``impulses`` over a grid of modes.

    Evaluates eqs. 52-55 through :func:`tvist.prv` (the single implementation in the core).

    Parameters
    ----------
    impulses
        The shaper, e.g. from :func:`tvist.shaper` or :func:`tvist.convolve`.
    wn_rad_s
        Natural frequencies, shape ``(n_wn,)``, rad/s.
    zetas
        Damping ratios, shape ``(n_zeta,)``.

    Returns
    -------
    numpy.ndarray
        Shape ``(n_zeta, n_wn)``: row ``i`` is the PRV across frequencies at ``zetas[i]``.
    """
    wn = np.asarray(wn_rad_s, dtype=float)
    zeta = np.asarray(zetas, dtype=float)
    if wn.ndim != 1 or zeta.ndim != 1 or wn.size == 0 or zeta.size == 0:
        raise ValueError(
            f"wn_rad_s and zetas must be non-empty 1-D arrays, got {wn.shape} and {zeta.shape}"
        )
    return np.asarray(tvist.prv(impulses, wn[None, :], zeta[:, None]), dtype=float).reshape(
        zeta.size, wn.size
    )
