"""Accelerometer preprocessing: base-frame, gravity-free (eq. 12) tangential acceleration (eq. 13).

For an excitation of joint ``j``:

1. find the quiet samples (:func:`quiet_samples`): every stretch of the log, anywhere, where
   the target stands still *relative to the log's own motion* (a real controller's targets
   hover at 1e-3-1e-2 rad/s between moves);
2. estimate, from all quiet samples by least squares, the reaction to gravity ``g`` (base
   frame) and a constant sensor bias ``b`` (flange frame) of ``ψ_A = R(q)ᵀ g + b``; ``b`` is
   separable from ``g`` only where the quiet samples see different orientations, so it is
   ridge-regularised towards zero (a single orientation gives the mean in the base frame);
3. rotate the raw flange reading into the base frame with forward kinematics of the measured
   joint angles and remove both, ``ψ_U = R(q) (ψ_A - b) - g``;
4. project onto the tangential direction of joint ``j``, the linear part of Jacobian column
   ``j`` at the flange centre (``∂P_A/∂q_j``), normalised: ``ψ_j = ψ_U · ∂P_A/∂q_j / |∂P_A/∂q_j|``.

The accelerometer sits inside the flange, so its position is taken as the flange centre.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Literal, Protocol

import numpy as np

from tvist.ident.logs import Record

__all__ = [
    "KinematicModel",
    "TangentialAcceleration",
    "quiet_samples",
    "standstill_length",
    "tangential_acceleration",
]

#: The paper estimates gravity from "e.g. 10 samples" of standstill.
MIN_STANDSTILL_SAMPLES = 10
#: A reference velocity/acceleration below this counts as standing still (rad/s, rad/s²).
STANDSTILL_TOL = 1e-6
#: A target speed (acceleration) below this fraction of the log's peak target speed
#: (acceleration) is quiet: 2 % of a 0.5 rad/s move is 1e-2 rad/s.
QUIET_FRACTION = 0.02
#: Shortest run of quiet samples that counts (shorter ones are passes through zero).
MIN_QUIET_RUN = 5
#: Ridge weight of the sensor bias against gravity (relative to the number of samples).
BIAS_RIDGE = 1e-6
#: The tangential direction is undefined when the flange is this close to joint j's axis, m.
MIN_RADIUS_M = 0.02


class KinematicModel(Protocol):
    """What preprocessing needs from a robot model (``tvist.robots.Robot`` provides it)."""

    def flange_pose_many(self, q: np.ndarray) -> np.ndarray: ...

    def jacobian_many(self, q: np.ndarray) -> np.ndarray: ...


@dataclass(frozen=True)
class TangentialAcceleration:
    """Input and output of the local fit for one excited joint.

    Attributes
    ----------
    t_s
        Sample times, s, shape (n_samples,).
    joint
        The excited joint.
    target_qdd
        Target acceleration of the excited joint, rad/s², shape (n_samples,): the fit's input.
    psi
        Tangential acceleration ``ψ_j`` of the flange, m/s², shape (n_samples,): the output.
    radius_m
        ``|∂P_A/∂q_j|``, the distance of the flange centre from joint j's axis, m,
        shape (n_samples,).
    gravity_base
        Gravity reaction estimated over the quiet samples, base frame, m/s², shape (3,).
    standstill_samples
        Number of quiet samples used for the gravity estimate (anywhere in the log).
    sensor_bias
        Constant sensor bias estimated with gravity, flange frame, m/s², shape (3,).
    accel_base
        Gravity-free flange acceleration in the base frame, m/s², shape (n_samples, 3).
    """

    t_s: np.ndarray
    joint: int
    target_qdd: np.ndarray
    psi: np.ndarray
    radius_m: np.ndarray
    gravity_base: np.ndarray
    standstill_samples: int
    sensor_bias: np.ndarray = field(default_factory=lambda: np.zeros(3))
    accel_base: np.ndarray | None = None

    @property
    def dt_s(self) -> float:
        return float(np.median(np.diff(self.t_s)))


def standstill_length(record: Record, tol: float = STANDSTILL_TOL) -> int:
    """Number of leading samples in which no joint has a reference velocity or acceleration."""
    moving = np.any(np.abs(record.target_qd) > tol, axis=1) | np.any(
        np.abs(record.target_qdd) > tol, axis=1
    )
    first = np.flatnonzero(moving)
    return int(first[0]) if first.size else record.n_samples


def _runs_at_least(mask: np.ndarray, n: int) -> np.ndarray:
    """``mask`` with its runs of True shorter than ``n`` samples cleared."""
    out = np.zeros_like(mask)
    edges = np.flatnonzero(np.diff(np.r_[0, mask.astype(np.int8), 0]))
    for start, stop in zip(edges[::2], edges[1::2], strict=True):
        if stop - start >= n:
            out[start:stop] = True
    return out


def quiet_samples(record: Record, *, fraction: float = QUIET_FRACTION) -> np.ndarray:
    """Boolean mask of the samples in which the target stands still, anywhere in the log.

    A sample is quiet when every joint's target speed is below ``fraction`` of the log's peak
    target speed, and its target acceleration below ``fraction`` of the peak acceleration
    (each at least :data:`STANDSTILL_TOL`), in a run of at least :data:`MIN_QUIET_RUN`
    samples. The thresholds follow the log's own motion, so the slow drift of a real
    controller's targets between moves (1e-3-1e-2 rad/s) counts as standing still.
    """
    speed = np.max(np.abs(record.target_qd), axis=1)
    accel = np.max(np.abs(record.target_qdd), axis=1)
    v_tol = max(STANDSTILL_TOL, fraction * float(np.max(speed)))
    a_tol = max(STANDSTILL_TOL, fraction * float(np.max(accel)))
    return _runs_at_least((speed <= v_tol) & (accel <= a_tol), MIN_QUIET_RUN)


def gravity_and_bias(rot: np.ndarray, reading: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Least-squares ``(g, b)`` of ``reading_k = rot_kᵀ g + b`` (ridge on ``b``).

    Parameters
    ----------
    rot
        Flange orientations in the base frame at the quiet samples, shape (n, 3, 3).
    reading
        Accelerometer readings in the flange frame there, m/s², shape (n, 3).
    """
    n = reading.shape[0]
    a = np.zeros((n, 3, 6))
    a[:, :, :3] = np.transpose(rot, (0, 2, 1))
    a[:, :, 3:] = np.eye(3)
    ridge = np.zeros((3, 6))
    ridge[:, 3:] = math.sqrt(BIAS_RIDGE * n) * np.eye(3)
    x, *_ = np.linalg.lstsq(
        np.vstack([a.reshape(3 * n, 6), ridge]), np.r_[reading.reshape(3 * n), np.zeros(3)]
    )
    return x[:3], x[3:]


def tangential_acceleration(
    record: Record,
    joint: int,
    robot: KinematicModel,
    *,
    accel_frame: Literal["flange", "base"] = "flange",
    min_standstill_samples: int = MIN_STANDSTILL_SAMPLES,
) -> TangentialAcceleration:
    """Tangential flange acceleration of ``joint`` from a log (eqs. 12-13).

    Parameters
    ----------
    record
        The log of one excitation of ``joint``, with standstills (anywhere) between moves.
    joint
        Excited joint (0 = base, 1 = shoulder, …).
    robot
        Kinematic model, e.g. ``tvist.robots.ur5e(...)``.
    accel_frame
        Frame of ``record.tool_accel``: ``"flange"`` (raw sensor reading, rotated with forward
        kinematics) or ``"base"`` (already in the base frame).
    min_standstill_samples
        Fewest standstill samples accepted for the gravity estimate.

    Returns
    -------
    TangentialAcceleration

    Raises
    ------
    ValueError
        Too few quiet samples, a bad joint index, or a flange on the axis of ``joint``
        (tangential direction undefined).
    """
    if int(joint) != joint or not 0 <= joint < record.actual_q.shape[1]:
        raise ValueError(f"joint must be an integer 0-{record.actual_q.shape[1] - 1}, got {joint}")
    joint = int(joint)
    if accel_frame not in ("flange", "base"):
        raise ValueError(f"accel_frame must be 'flange' or 'base', got {accel_frame!r}")
    quiet = quiet_samples(record)
    n_still = int(np.count_nonzero(quiet))
    if n_still < min_standstill_samples:
        raise ValueError(
            f"the log needs at least {min_standstill_samples} samples of standstill (target "
            f"speed and acceleration below {100 * QUIET_FRACTION:g} % of their peaks) to "
            f"estimate gravity; found {n_still}"
        )
    q = np.ascontiguousarray(record.actual_q)
    if accel_frame == "flange":
        rot = robot.flange_pose_many(q)[:, :3, :3]
        gravity, bias = gravity_and_bias(rot[quiet], record.tool_accel[quiet])
        psi_base = np.einsum("nij,nj->ni", rot, record.tool_accel - bias) - gravity
    else:
        bias = np.zeros(3)
        gravity = record.tool_accel[quiet].mean(axis=0)
        psi_base = record.tool_accel - gravity

    tangent = robot.jacobian_many(q)[:, :3, joint]
    radius = np.linalg.norm(tangent, axis=1)
    if np.min(radius) < MIN_RADIUS_M:
        k = int(np.argmin(radius))
        raise ValueError(
            f"the flange is {radius[k] * 1e3:.1f} mm from the axis of joint {joint} at sample "
            f"{k}: its tangential direction is undefined; excite from another pose"
        )
    psi = np.einsum("ni,ni->n", psi_base, tangent) / radius
    return TangentialAcceleration(
        t_s=record.t_s.copy(),
        joint=joint,
        target_qdd=record.target_qdd[:, joint].copy(),
        psi=psi,
        radius_m=radius,
        gravity_base=gravity,
        standstill_samples=n_still,
        sensor_bias=bias,
        accel_base=psi_base,
    )
