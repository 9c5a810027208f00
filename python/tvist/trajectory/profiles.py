"""Closed-form rest-to-rest moves: minimum-jerk (quintic) and trapezoidal velocity.

Both move every joint along the straight line from ``q0`` to ``q1`` in joint space with one
normalized profile ``s(t)`` from 0 to 1: ``q(t) = q0 + (q1 - q0) s(t)``.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike

from tvist.trajectory._types import Trajectory, assemble, samples_for
from tvist.trajectory.validation import (
    as_joint_limits,
    check_pose_limits,
    non_negative_scalar,
    pose_pair,
    positive_per_joint,
    positive_scalar,
)

__all__ = ["min_jerk", "trapezoid"]


def _checked_poses(
    q0: ArrayLike, q1: ArrayLike, joint_limits_rad: ArrayLike | None
) -> tuple[np.ndarray, np.ndarray]:
    start, end = pose_pair(q0, q1)
    if joint_limits_rad is not None:
        # A straight line between two poses inside a box of limits stays inside it.
        limits = as_joint_limits(joint_limits_rad, start.shape[0])
        check_pose_limits("q0", start, limits)
        check_pose_limits("q1", end, limits)
    return start, end


def _from_path(
    start: np.ndarray,
    end: np.ndarray,
    s: np.ndarray,
    sd: np.ndarray,
    sdd: np.ndarray,
    dt: float,
    pre: float,
    post: float,
    duration: float,
) -> Trajectory:
    """Map the normalized profile ``s, s', s''`` (n_motion,) onto the joints."""
    h = end - start
    motion = (start + np.outer(s, h), np.outer(sd, h), np.outer(sdd, h))
    return assemble(start, end, motion, dt, pre, post, duration)


def min_jerk(
    q0: ArrayLike,
    q1: ArrayLike,
    duration_s: float,
    dt_s: float,
    t_pre_s: float = 0.0,
    t_post_s: float = 0.0,
    *,
    joint_limits_rad: ArrayLike | None = None,
) -> Trajectory:
    """Minimum-jerk rest-to-rest move: ``s = 10τ³ − 15τ⁴ + 6τ⁵`` with ``τ = t / duration_s``.

    Parameters
    ----------
    q0, q1
        Start and end pose, shape ``(n_dof,)``, rad.
    duration_s
        Length of the move, s (> 0). It need not be a multiple of ``dt_s``: the profile is
        evaluated at the grid times and ``t_motion_end_s`` is ``t_pre + duration_s``.
    dt_s
        Sample period, s.
    t_pre_s, t_post_s
        Rest before and after the move, s, rounded up to whole samples.
    joint_limits_rad
        Optional ``(n_dof, 2)`` joint limits; both poses must lie inside.

    Returns
    -------
    Trajectory
        Samples on the grid; the first sample at or after the end of the move is exactly ``q1``.
        Peak speed is ``1.875 |q1 - q0| / duration_s`` at mid-move.
    """
    start, end = _checked_poses(q0, q1, joint_limits_rad)
    duration = positive_scalar("duration_s", duration_s)
    dt = positive_scalar("dt_s", dt_s)
    pre = non_negative_scalar("t_pre_s", t_pre_s)
    post = non_negative_scalar("t_post_s", t_post_s)
    tau = np.minimum(dt * np.arange(samples_for(duration, dt) + 1) / duration, 1.0)
    s = tau**3 * (10.0 - 15.0 * tau + 6.0 * tau**2)
    sd = 30.0 * tau**2 * (1.0 - tau) ** 2 / duration
    sdd = 60.0 * tau * (1.0 - tau) * (1.0 - 2.0 * tau) / duration**2
    return _from_path(start, end, s, sd, sdd, dt, pre, post, duration)


def trapezoid(
    q0: ArrayLike,
    q1: ArrayLike,
    v_max: ArrayLike,
    a_max: ArrayLike,
    dt_s: float,
    t_pre_s: float = 0.0,
    t_post_s: float = 0.0,
    *,
    joint_limits_rad: ArrayLike | None = None,
    snap_to_grid: bool = True,
) -> Trajectory:
    """Fastest straight-line joint move with a trapezoidal (or triangular) velocity profile.

    The acceleration is a step function (``±a``, 0), so the jerk is unbounded.

    Parameters
    ----------
    q0, q1
        Start and end pose, shape ``(n_dof,)``, rad.
    v_max, a_max
        Velocity (rad/s) and acceleration (rad/s²) limits, scalar or per joint ``(n_dof,)``.
        The joint that hits its limit first sets the profile for all.
    dt_s
        Sample period, s.
    t_pre_s, t_post_s
        Rest before and after the move, s, rounded up to whole samples.
    joint_limits_rad
        Optional ``(n_dof, 2)`` joint limits; both poses must lie inside.
    snap_to_grid
        If true (default), the duration is stretched to a whole number of samples by lowering
        the cruise speed (acceleration stays at its limit), so the move ends on a sample.

    Returns
    -------
    Trajectory
        Samples on the grid; the last sample of the move is exactly ``q1``.
    """
    start, end = _checked_poses(q0, q1, joint_limits_rad)
    n_dof = start.shape[0]
    v_lim = positive_per_joint("v_max", v_max, n_dof)
    a_lim = positive_per_joint("a_max", a_max, n_dof)
    dt = positive_scalar("dt_s", dt_s)
    pre = non_negative_scalar("t_pre_s", t_pre_s)
    post = non_negative_scalar("t_post_s", t_post_s)

    h = np.abs(end - start)
    moving = h > 0.0
    if not moving.any():
        zero = np.zeros(1)
        return _from_path(start, end, zero, zero, zero, dt, pre, post, 0.0)
    # Limits on the normalized path s in [0, 1] (1/s and 1/s²).
    v_s = float(np.min(v_lim[moving] / h[moving]))
    a_s = float(np.min(a_lim[moving] / h[moving]))
    if v_s * v_s >= a_s:  # the cruise speed is never reached: triangular profile
        duration = 2.0 / math.sqrt(a_s)
    else:
        duration = 1.0 / v_s + v_s / a_s
    if snap_to_grid:
        duration = samples_for(duration, dt) * dt
    # Peak speed v for duration T at acceleration a solves v² − aTv + a = 0 (cruise distance
    # 1 − v²/a covered at v); the smaller root, written without cancellation.
    disc = max(a_s * a_s * duration * duration - 4.0 * a_s, 0.0)
    v_peak = 2.0 * a_s / (a_s * duration + math.sqrt(disc))
    t_acc = v_peak / a_s

    t = np.minimum(dt * np.arange(samples_for(duration, dt) + 1), duration)
    t_left = duration - t
    accelerating, decelerating = t < t_acc, t_left < t_acc
    s = np.where(
        accelerating,
        0.5 * a_s * t**2,
        np.where(
            decelerating, 1.0 - 0.5 * a_s * t_left**2, 0.5 * a_s * t_acc**2 + v_peak * (t - t_acc)
        ),
    )
    sd = np.where(accelerating, a_s * t, np.where(decelerating, a_s * t_left, v_peak))
    sdd = np.where(accelerating, a_s, np.where(decelerating, -a_s, 0.0))
    return _from_path(start, end, s, sd, sdd, dt, pre, post, duration)
