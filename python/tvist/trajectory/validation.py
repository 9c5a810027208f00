"""Input checks shared by the trajectory generators, and checks of finished references.

Every check raises :class:`ValueError` with a message that names the argument and, for arrays,
the first offending row and joint. Arrays are ``(n_samples, n_dof)``, time along rows.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike

__all__ = ["check_time_stamps", "check_uniform_time", "validate_reference"]


def as_pose(name: str, q: ArrayLike) -> np.ndarray:
    """Return ``q`` as a finite 1-D float array of joint angles (rad)."""
    arr = np.asarray(q, dtype=float)
    if arr.ndim != 1 or arr.size == 0:
        raise ValueError(
            f"{name} must be a non-empty 1-D array of joint angles, got shape {arr.shape}"
        )
    bad = np.flatnonzero(~np.isfinite(arr))
    if bad.size:
        raise ValueError(f"{name}[{bad[0]}] is {arr[bad[0]]}; joint angles must be finite")
    return arr


def pose_pair(q0: ArrayLike, q1: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """Validate a start and an end pose of equal length."""
    start, end = as_pose("q0", q0), as_pose("q1", q1)
    if start.shape != end.shape:
        raise ValueError(f"q0 and q1 must have the same shape, got {start.shape} and {end.shape}")
    return start, end


def positive_scalar(name: str, value: float) -> float:
    """Return ``value`` as a float that is finite and > 0."""
    try:
        out = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a positive number, got {value!r}") from None
    if not (math.isfinite(out) and out > 0.0):
        raise ValueError(f"{name} must be finite and > 0, got {out}")
    return out


def non_negative_scalar(name: str, value: float) -> float:
    """Return ``value`` as a float that is finite and >= 0."""
    try:
        out = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a non-negative number, got {value!r}") from None
    if not (math.isfinite(out) and out >= 0.0):
        raise ValueError(f"{name} must be finite and >= 0, got {out}")
    return out


def positive_per_joint(name: str, value: ArrayLike, n_dof: int) -> np.ndarray:
    """Broadcast a scalar or per-joint limit to shape ``(n_dof,)``; every entry finite and > 0."""
    arr = np.asarray(value, dtype=float)
    if arr.ndim == 0:
        arr = np.full(n_dof, float(arr))
    if arr.shape != (n_dof,):
        raise ValueError(f"{name} must be a scalar or have shape ({n_dof},), got {arr.shape}")
    bad = np.flatnonzero(~(np.isfinite(arr) & (arr > 0.0)))
    if bad.size:
        raise ValueError(f"{name}[{bad[0]}] is {arr[bad[0]]}; limits must be finite and > 0")
    return arr


def as_joint_limits(joint_limits_rad: ArrayLike, n_dof: int) -> np.ndarray:
    """Validate joint limits of shape ``(n_dof, 2)`` with ``lower < upper`` (infinite allowed)."""
    limits = np.asarray(joint_limits_rad, dtype=float)
    if limits.shape != (n_dof, 2):
        raise ValueError(f"joint_limits_rad must have shape ({n_dof}, 2), got {limits.shape}")
    for joint, (lower, upper) in enumerate(limits):
        if math.isnan(lower) or math.isnan(upper) or not lower < upper:
            raise ValueError(
                f"joint_limits_rad[{joint}] = [{lower}, {upper}] must satisfy lower < upper"
            )
    return limits


def _check_within_limits(name: str, q: np.ndarray, limits: np.ndarray) -> None:
    """Raise naming the first sample (row) and joint of ``q`` (n_samples, n_dof) outside limits."""
    outside = (q < limits[:, 0]) | (q > limits[:, 1])
    if outside.any():
        row, joint = np.argwhere(outside)[0]
        lower, upper = limits[joint]
        raise ValueError(
            f"{name}[{row}, {joint}] = {q[row, joint]:.6g} rad is outside the joint limits "
            f"[{lower:.6g}, {upper:.6g}] of joint {joint}"
        )


def check_pose_limits(name: str, q: np.ndarray, limits: np.ndarray) -> None:
    """Raise if the pose ``q`` (n_dof,) leaves ``limits`` (n_dof, 2), naming the joint."""
    outside = np.flatnonzero((q < limits[:, 0]) | (q > limits[:, 1]))
    if outside.size:
        joint = outside[0]
        lower, upper = limits[joint]
        raise ValueError(
            f"{name}[{joint}] = {q[joint]:.6g} rad is outside the joint limits "
            f"[{lower:.6g}, {upper:.6g}] of joint {joint}"
        )


def validate_reference(
    Q: ArrayLike, dt_s: float, joint_limits_rad: ArrayLike | None = None
) -> np.ndarray:
    """Check a joint reference before it is shaped or sent to a robot.

    Parameters
    ----------
    Q
        Joint positions, shape ``(n_samples, n_dof)``, rad; one row per sample.
    dt_s
        Sample period, s (finite, > 0).
    joint_limits_rad
        Optional ``(n_dof, 2)`` array of ``[lower, upper]`` limits per joint, rad.

    Returns
    -------
    numpy.ndarray
        ``Q`` as a C-contiguous float64 array of shape ``(n_samples, n_dof)``.

    Raises
    ------
    ValueError
        If ``Q`` is not 2-D or empty, ``dt_s`` is not positive, an entry is NaN or infinite
        (the message names its row and joint), or a sample is outside the joint limits (the
        message names the first such row and joint).
    """
    positive_scalar("dt_s", dt_s)
    arr = np.ascontiguousarray(Q, dtype=float)
    if arr.ndim != 2 or arr.shape[0] == 0 or arr.shape[1] == 0:
        raise ValueError(
            f"Q must have shape (n_samples, n_dof) with both > 0, got shape {arr.shape}"
        )
    not_finite = ~np.isfinite(arr)
    if not_finite.any():
        row, joint = np.argwhere(not_finite)[0]
        raise ValueError(f"Q[{row}, {joint}] is {arr[row, joint]} (row {row}, joint {joint})")
    if joint_limits_rad is not None:
        limits = as_joint_limits(joint_limits_rad, arr.shape[1])
        _check_within_limits("Q", arr, limits)
    return arr


def check_time_stamps(t_s: ArrayLike) -> np.ndarray:
    """Return time stamps (s) as a float array after checking that they are 1-D, at least 2,
    finite and strictly increasing.

    Raises
    ------
    ValueError
        Naming the first row whose stamp is not finite or not above the previous one.
    """
    t = np.asarray(t_s, dtype=float)
    if t.ndim != 1 or t.size < 2:
        raise ValueError(f"t_s must be 1-D with at least 2 samples, got shape {t.shape}")
    bad = np.flatnonzero(~np.isfinite(t))
    if bad.size:
        raise ValueError(f"t_s[{bad[0]}] is {t[bad[0]]} (row {bad[0]}); time stamps must be finite")
    not_increasing = np.flatnonzero(np.diff(t) <= 0.0)
    if not_increasing.size:
        row = not_increasing[0] + 1
        raise ValueError(
            f"t_s is not increasing at row {row}: t_s[{row}] = {float(t[row])!r} <= "
            f"t_s[{row - 1}] = {float(t[row - 1])!r}"
        )
    return t


def check_uniform_time(t_s: ArrayLike, rtol: float = 1e-3) -> float:
    """Check that time stamps are finite, increasing and evenly spaced; return the period.

    Parameters
    ----------
    t_s
        Time stamps, shape ``(n_samples,)``, s, ``n_samples >= 2``.
    rtol
        Allowed deviation of any step from the median step, relative to the median step.
        The default 1e-3 accepts time stamps printed with 6 decimals at 500 Hz (rounding
        moves a 2 ms step by at most 1 µs = 5e-4 relative) and rejects a dropped sample
        (a step of twice the period).

    Returns
    -------
    float
        The median step, s.

    Raises
    ------
    ValueError
        Naming the first row whose stamp is not finite, or whose step from the previous row
        is not positive or differs from the median step by more than ``rtol``.
    """
    t = check_time_stamps(t_s)
    step = np.diff(t)
    dt = float(np.median(step))
    uneven = np.flatnonzero(np.abs(step - dt) > rtol * dt)
    if uneven.size:
        row = uneven[0] + 1
        raise ValueError(
            f"t_s is not uniform at row {row}: step t_s[{row}] - t_s[{row - 1}] = "
            f"{step[row - 1]:.9g} s differs from the period {dt:.9g} s by more than "
            f"rtol = {rtol:g}"
        )
    return dt
