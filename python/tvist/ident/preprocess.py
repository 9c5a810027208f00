"""Accelerometer preprocessing: base-frame, gravity-free (eq. 12) tangential acceleration (eq. 13).

For an excitation of joint ``j``:

1. rotate the raw flange accelerometer reading into the base frame with forward kinematics
   of the measured joint angles, ``ψ_U = R_flange(q) ψ_A``;
2. subtract gravity, estimated as the mean of ``ψ_U`` over the initial standstill (so a
   constant sensor offset and a tilted base are removed too);
3. project onto the tangential direction of joint ``j``, the linear part of Jacobian column
   ``j`` at the flange centre (``∂P_A/∂q_j``), normalised: ``ψ_j = ψ_U · ∂P_A/∂q_j / |∂P_A/∂q_j|``.

The accelerometer sits inside the flange, so its position is taken as the flange centre.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal, Protocol

import numpy as np

from tvist.ident.logs import Record

__all__ = [
    "KinematicModel",
    "TangentialAcceleration",
    "standstill_length",
    "tangential_acceleration",
]

#: The paper estimates gravity from "e.g. 10 samples" of standstill.
MIN_STANDSTILL_SAMPLES = 10
#: A reference velocity/acceleration below this counts as standing still (rad/s, rad/s²).
STANDSTILL_TOL = 1e-6
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
        Gravity reaction estimated over the standstill, base frame, m/s², shape (3,).
    standstill_samples
        Number of leading samples used for the gravity estimate.
    """

    t_s: np.ndarray
    joint: int
    target_qdd: np.ndarray
    psi: np.ndarray
    radius_m: np.ndarray
    gravity_base: np.ndarray
    standstill_samples: int

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
        The log of one excitation of ``joint`` that starts with a standstill.
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
        No (or too short a) standstill at the start, a bad joint index, or a flange on the
        axis of ``joint`` (tangential direction undefined).
    """
    if int(joint) != joint or not 0 <= joint < record.actual_q.shape[1]:
        raise ValueError(f"joint must be an integer 0-{record.actual_q.shape[1] - 1}, got {joint}")
    joint = int(joint)
    if accel_frame not in ("flange", "base"):
        raise ValueError(f"accel_frame must be 'flange' or 'base', got {accel_frame!r}")
    n_still = standstill_length(record)
    if n_still < min_standstill_samples:
        raise ValueError(
            f"the log must start with a standstill of at least {min_standstill_samples} samples "
            f"(zero target velocity and acceleration) to estimate gravity; found {n_still}"
        )
    q = np.ascontiguousarray(record.actual_q)
    if accel_frame == "flange":
        rot = robot.flange_pose_many(q)[:, :3, :3]
        psi_base = np.einsum("nij,nj->ni", rot, record.tool_accel)
    else:
        psi_base = record.tool_accel.copy()
    gravity = psi_base[:n_still].mean(axis=0)
    psi_base = psi_base - gravity

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
    )
