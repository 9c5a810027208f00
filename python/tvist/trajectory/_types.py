"""The sampled trajectory returned by every generator, and its assembly from a motion part."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Trajectory:
    """A rest-to-rest joint trajectory sampled on a uniform grid.

    Attributes
    ----------
    t_s
        Sample times ``k * dt_s``, shape ``(n_samples,)``, s; starts at 0.
    q, qd, qdd
        Joint position (rad), velocity (rad/s) and acceleration (rad/s²), each
        ``(n_samples, n_dof)``.
    dt_s
        Sample period, s.
    t_motion_start_s
        When the move starts (the end of the rest padding before it), s. On the grid.
    t_motion_end_s
        When the move stops: from here on ``q`` equals the end pose and ``qd``, ``qdd`` are 0.
        On the grid unless a generator says otherwise.
    """

    t_s: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    qdd: np.ndarray
    dt_s: float
    t_motion_start_s: float
    t_motion_end_s: float

    @property
    def n_samples(self) -> int:
        """Number of samples (rows)."""
        return int(self.t_s.shape[0])

    @property
    def n_dof(self) -> int:
        """Number of joints (columns)."""
        return int(self.q.shape[1])

    @property
    def duration_s(self) -> float:
        """Length of the move itself, without the rest padding, s."""
        return self.t_motion_end_s - self.t_motion_start_s


def samples_for(duration_s: float, dt_s: float) -> int:
    """Whole samples covering ``duration_s``: ``ceil(duration_s / dt_s)``.

    A relative slack of 1e-9 keeps durations that are a multiple of ``dt_s`` up to rounding
    (for example 0.1 / 0.002 = 50.000000000000004) from gaining a sample.
    """
    return max(0, math.ceil(duration_s / dt_s * (1.0 - 1e-9)))


def assemble(
    q0: np.ndarray,
    q1: np.ndarray,
    motion: tuple[np.ndarray, np.ndarray, np.ndarray],
    dt_s: float,
    t_pre_s: float,
    t_post_s: float,
    motion_duration_s: float,
) -> Trajectory:
    """Wrap the samples of a move in rest padding and pin the end samples to the poses.

    ``motion`` holds ``q, qd, qdd`` of shape ``(n_motion, n_dof)`` sampled at ``k * dt_s``,
    ``k = 0 .. n_motion - 1``, from the start of the move; its first row is at ``q0`` and its
    last row is at or after the end of the move. The last row is set exactly to ``q1`` (with
    zero velocity and acceleration), which removes the generator's rounding at the target.
    """
    q_m, qd_m, qdd_m = (np.array(a, dtype=float) for a in motion)
    q_m[0], q_m[-1] = q0, q1
    qd_m[-1] = 0.0
    qdd_m[-1] = 0.0
    n_pre, n_post = samples_for(t_pre_s, dt_s), samples_for(t_post_s, dt_s)
    n_dof = q0.shape[0]
    zeros_pre, zeros_post = np.zeros((n_pre, n_dof)), np.zeros((n_post, n_dof))
    q = np.vstack([np.tile(q0, (n_pre, 1)), q_m, np.tile(q1, (n_post, 1))])
    qd = np.vstack([zeros_pre, qd_m, zeros_post])
    qdd = np.vstack([zeros_pre, qdd_m, zeros_post])
    for arr in (q, qd, qdd):
        arr.setflags(write=False)
    t = dt_s * np.arange(q.shape[0])
    t.setflags(write=False)
    t_start = n_pre * dt_s
    return Trajectory(
        t_s=t,
        q=q,
        qd=qd,
        qdd=qdd,
        dt_s=dt_s,
        t_motion_start_s=t_start,
        t_motion_end_s=t_start + motion_duration_s,
    )
