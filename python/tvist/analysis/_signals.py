"""Shared input checks and conversions for the analysis functions."""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike


def as_channels(name: str, x: ArrayLike, n_samples: int | None = None) -> np.ndarray:
    """A signal as ``(n_samples, n_channels)`` float array; accepts ``(n,)`` or ``(n, k)``."""
    arr = np.asarray(x, dtype=float)
    if arr.ndim == 1:
        arr = arr[:, None]
    if arr.ndim != 2 or arr.shape[0] == 0 or arr.shape[1] == 0:
        raise ValueError(f"{name} must have shape (n_samples,) or (n_samples, k), got {arr.shape}")
    if n_samples is not None and arr.shape[0] != n_samples:
        raise ValueError(f"{name} has {arr.shape[0]} samples but t_s has {n_samples}")
    not_finite = ~np.isfinite(arr)
    if not_finite.any():
        row, col = np.argwhere(not_finite)[0]
        raise ValueError(f"{name}[{row}, {col}] is {arr[row, col]} (row {row}, column {col})")
    return arr


def positive(name: str, value: float) -> float:
    """``value`` as a finite float > 0."""
    out = float(value)
    if not (math.isfinite(out) and out > 0.0):
        raise ValueError(f"{name} must be finite and > 0, got {value!r}")
    return out


def magnitude(x: np.ndarray) -> np.ndarray:
    """Euclidean norm over channels of ``(n_samples, k)``; ``|x|`` for one channel."""
    return np.abs(x[:, 0]) if x.shape[1] == 1 else np.linalg.norm(x, axis=1)
