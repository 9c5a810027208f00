"""Cartesian-space shaping: shape the TCP reference, then convert it to joints.

Joint-space shaping of a straight-line TCP move bends the line: the shaped reference is a
weighted sum of *joint* poses at different times, and forward kinematics is not linear. Shaping
the TCP coordinates instead keeps every shaped point on the planned line (a weighted sum of
points of a line with weights summing to 1 lies on that line), and inverse kinematics turns the
shaped TCP reference into joints every sample.

TCP coordinates
---------------
A TCP reference is an array ``X`` ``(n_samples, 6)``: the flange position in the base frame
(m) and the rotation vector (rad) of ``R(t) R_0ᵀ``, the flange orientation relative to the
start orientation ``R_0``, in the base frame. Orientation held: the last three columns are
zero. Orientation interpolated about one axis (a slerp between two orientations): they are the
start-to-end rotation vector scaled by the same path parameter as the position, so both are
affine in that parameter, and any shaper with amplitudes summing to 1 keeps position and
orientation on the planned path.

The tool centre point is the flange (DH frame ``n``); arrays are ``(n_samples, n_dof)`` with
time along rows; SI units.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

import tvist
from tvist.maps.paper10 import DynamicMap
from tvist.robots import Robot
from tvist.trajectory.shaping import METHODS

__all__ = [
    "CartesianShaped",
    "joints_from_tcp",
    "shape_cartesian",
    "shape_tcp",
    "solve_ik",
    "straight_line",
    "tcp_coordinates",
    "tcp_path_deviation_m",
]

#: Inverse kinematics converges when the position error is below this (m) and the orientation
#: error below this (rad): far below any vibration of interest (micrometres) and above the
#: round-off of the forward kinematics (~1e-15 m).
IK_TOL = 1e-10
#: Damping ``λ`` of the damped least-squares step ``Δq = Jᵀ (J Jᵀ + λ² I)⁻¹ e`` (m or rad).
#: Far from singularities it changes the step by ``(λ/σ_min)²`` ~1e-8, and Newton still
#: converges quadratically; near one it keeps the step bounded.
IK_DAMPING = 1e-4
#: Newton iterations per sample before giving up (a warm start needs 2-3).
IK_MAX_ITER = 50


def _rotvec(matrix: np.ndarray) -> np.ndarray:
    from scipy.spatial.transform import Rotation

    return Rotation.from_matrix(np.array(matrix, dtype=float)).as_rotvec()


def _matrix(rotvec: np.ndarray) -> np.ndarray:
    from scipy.spatial.transform import Rotation

    return Rotation.from_rotvec(np.array(rotvec, dtype=float)).as_matrix()


def solve_ik(
    robot: Robot,
    position_m: ArrayLike,
    rotation: ArrayLike,
    q_seed: ArrayLike,
    *,
    tol: float = IK_TOL,
    max_iter: int = IK_MAX_ITER,
) -> np.ndarray:
    """Joint pose whose flange reaches ``position_m`` (3,) with orientation ``rotation`` (3, 3).

    Damped least squares (Levenberg-Marquardt) on the 6-D pose error with the robot's
    geometric Jacobian, started at ``q_seed``; the solution is the one nearest the seed that
    Newton's method reaches (for a warm start along a path: the continuous branch).

    Raises
    ------
    ValueError
        If it does not converge to ``tol`` in ``max_iter`` iterations (target out of reach or
        across a singularity).
    """
    target_p = np.asarray(position_m, dtype=float)
    target_r = np.asarray(rotation, dtype=float)
    q = np.array(q_seed, dtype=float)
    damping_sq = IK_DAMPING**2
    err_norm = math.inf
    for _ in range(max_iter):
        pose = robot.flange_pose(q)
        err = np.concatenate([target_p - pose[:3, 3], _rotvec(target_r @ pose[:3, :3].T)])
        err_norm = float(np.max(np.abs(err)))
        if err_norm < tol:
            return q
        jac = robot.jacobian(q)
        q = q + jac.T @ np.linalg.solve(jac @ jac.T + damping_sq * np.eye(6), err)
    raise ValueError(
        f"inverse kinematics did not converge (pose error {err_norm:.3g} after {max_iter} "
        "iterations): the TCP target is out of reach or crosses a singularity"
    )


def tcp_coordinates(robot: Robot, Q: ArrayLike) -> tuple[np.ndarray, np.ndarray]:  # noqa: N803
    """TCP coordinates ``X`` ``(n_samples, 6)`` of the joint reference ``Q`` and the start
    orientation ``R_0`` (3, 3) they are relative to (see the module docstring)."""
    poses = robot.flange_pose_many(np.ascontiguousarray(Q, dtype=float))
    r0 = poses[0, :3, :3]
    rel = np.einsum("nij,kj->nik", poses[:, :3, :3], r0)  # R(t) R_0ᵀ
    return np.hstack([poses[:, :3, 3], _rotvec(rel)]), r0


def joints_from_tcp(
    robot: Robot,
    X: ArrayLike,  # noqa: N803
    rotation0: ArrayLike,
    q_seed: ArrayLike,
) -> np.ndarray:
    """Joint reference ``(n_samples, n_dof)`` of the TCP reference ``X`` by inverse kinematics
    at every sample, each warm-started at the previous solution (the first at ``q_seed``).

    Raises
    ------
    ValueError
        Malformed ``X``, or a sample inverse kinematics cannot reach (named by its index).
    """
    x = np.asarray(X, dtype=float)
    if x.ndim != 2 or x.shape[1] != 6 or not np.all(np.isfinite(x)):
        raise ValueError(f"X must be a finite (n_samples, 6) TCP reference, got {x.shape}")
    r0 = np.asarray(rotation0, dtype=float)
    out = np.empty((x.shape[0], robot.n_dof))
    q = np.asarray(q_seed, dtype=float)
    for k in range(x.shape[0]):
        try:
            q = solve_ik(robot, x[k, :3], _matrix(x[k, 3:]) @ r0, q)
        except ValueError as e:
            raise ValueError(f"TCP sample {k}: {e}") from None
        out[k] = q
    return out


def straight_line(
    robot: Robot,
    q_start: ArrayLike,
    displacement_m: ArrayLike,
    duration_s: float,
    dt_s: float | None = None,
    *,
    rotation_rad: ArrayLike = (0.0, 0.0, 0.0),
    t_pre_s: float = 0.0,
    t_post_s: float = 0.0,
) -> tuple[tvist.trajectory.Trajectory, np.ndarray]:
    """A minimum-jerk straight-line TCP move from the flange pose at ``q_start``.

    Parameters
    ----------
    robot, q_start
        The arm and its start pose (rad, ``(n_dof,)``).
    displacement_m
        Translation of the flange, base frame, m, ``(3,)``.
    duration_s, dt_s, t_pre_s, t_post_s
        Length of the move, sample period and rest before and after it, s; ``dt_s=None``: the
        robot's control period (:attr:`~tvist.robots.RobotParams.control_period_s`).
    rotation_rad
        Rotation vector (base frame) from the start to the end orientation, rad; zero holds
        the orientation, otherwise it is interpolated about that axis along the path.

    Returns
    -------
    (Trajectory, numpy.ndarray)
        The TCP reference (``.q`` is ``X`` ``(n_samples, 6)``) and ``R_0`` (3, 3).
    """
    pose = robot.flange_pose(np.asarray(q_start, dtype=float))
    start = np.concatenate([pose[:3, 3], np.zeros(3)])
    end = start + np.concatenate([np.asarray(displacement_m, float), np.asarray(rotation_rad)])
    dt_s = robot.params.sample_period_s(dt_s)
    traj = tvist.trajectory.min_jerk(
        start, end, duration_s, dt_s, t_pre_s=t_pre_s, t_post_s=t_post_s
    )
    return traj, pose[:3, :3]


def _moving_span(x: np.ndarray) -> tuple[int, int]:
    """First and last sample of the rest-to-rest move inside ``x`` (rest padding excluded)."""
    away_start = np.flatnonzero(np.any(x != x[0], axis=1))
    away_end = np.flatnonzero(np.any(x != x[-1], axis=1))
    if away_start.size == 0:
        raise ValueError("the TCP reference does not move")
    return max(int(away_start[0]) - 1, 0), min(int(away_end[-1]) + 1, x.shape[0] - 1)


ModeSource = Sequence[tuple[float, float]] | DynamicMap | Callable[[np.ndarray], Any]


def shape_tcp(
    X: ArrayLike,  # noqa: N803
    dt_s: float,
    modes: ModeSource,
    *,
    method: str = "tvist",
    shaper: str = "zv",
    joints_of: Callable[[np.ndarray], np.ndarray] | None = None,
    robot: Robot | None = None,
    max_delay_s: float | None = None,
) -> np.ndarray:
    """Shape a TCP reference ``X`` ``(n_samples, 6)`` with a tvist method.

    Parameters
    ----------
    X
        TCP reference (see the module docstring), at rest at both ends. Give enough rest
        after the move for the shaper delay (``"tvist"``); the zero-delay methods compress the
        move between its rest padding.
    dt_s
        Sample period, s.
    modes
        ``[(wn_rad_s, zeta), ...]`` (time-invariant); or, for ``"tvist"`` only, a
        :class:`~tvist.DynamicMap` or a callable ``f(q) -> [(wn_rad_s, zeta), ...]`` of the
        *joint* pose, evaluated every cycle at the joints of the previous shaped TCP sample
        (needs ``joints_of`` and ``max_delay_s``; a map also needs ``robot``).
    method
        One of :data:`tvist.trajectory.shaping.METHODS`: FD-TVIST (time-invariant with
        constant modes, time-varying with a map or a provider), ZTDIS, modified ZTDIS.
    shaper
        Registry shaper (:data:`tvist.SHAPERS`).
    joints_of
        ``joints_of(x) -> q``: the joints of one TCP sample (warm-started inverse
        kinematics), for time-varying modes.
    robot
        The arm a :class:`~tvist.DynamicMap` is evaluated on.
    max_delay_s
        Longest shaper delay the time-varying modes need (delay-line size), s.

    Returns
    -------
    numpy.ndarray
        The shaped TCP reference, same shape as ``X``.
    """
    x = np.ascontiguousarray(X, dtype=float)
    if x.ndim != 2 or x.shape[1] != 6:
        raise ValueError(f"X must be a (n_samples, 6) TCP reference, got {x.shape}")
    if method not in METHODS:
        raise ValueError(f"unknown method {method!r}; expected one of {METHODS}")
    fixed = not (isinstance(modes, DynamicMap) or callable(modes))
    if method != "tvist":
        if not fixed:
            raise ValueError(f"method {method!r} needs fixed modes [(wn_rad_s, zeta), ...]")
        first, last = _moving_span(x)
        result = tvist.zero_delay(x[first : last + 1], dt_s, modes, shaper=shaper, method=method)
        out = x.copy()
        out[first : last + 1] = result.Q
        out[last + 1 :] = x[-1]
        return out
    if fixed:
        shaper_filter = tvist.TvShaper(
            tvist.ConstantModes([(float(w), float(z)) for w, z in modes]), dt_s, 6, shaper=shaper
        )
    else:
        if joints_of is None or max_delay_s is None:
            raise ValueError("time-varying modes need joints_of and max_delay_s")
        if isinstance(modes, DynamicMap):
            if robot is None:
                raise ValueError("a DynamicMap needs the robot it is evaluated on")
            dynmap = modes

            def of_joints(q: np.ndarray) -> Any:
                return dynmap.modes(robot, q)
        else:
            of_joints = modes

        # The shaper probes its provider once when it is built, before it holds any TCP
        # sample; that probe is answered at the start of X.
        armed = [False]

        def provider(x_prev: np.ndarray) -> Any:
            return of_joints(joints_of(np.asarray(x_prev) if armed[0] else x[0]))

        shaper_filter = tvist.TvShaper(provider, dt_s, 6, shaper=shaper, max_delay_s=max_delay_s)
        armed[0] = True
    shaper_filter.reset(np.ascontiguousarray(x[0]))
    out = np.array(shaper_filter.shape(x))
    if np.max(np.abs(out[-1] - x[-1])) > 1e-9:
        raise ValueError(
            "the shaped TCP reference has not come to rest at its end: add rest after the move "
            "(at least the shaper delay)"
        )
    return out


@dataclass(frozen=True)
class CartesianShaped:
    """A TCP reference shaped in Cartesian space and its joints.

    Attributes
    ----------
    X
        Shaped TCP reference ``(n_samples, 6)``.
    Q
        Its joints by inverse kinematics, rad, ``(n_samples, n_dof)``.
    rotation0
        Start orientation ``R_0`` the rotation vectors of ``X`` are relative to.
    """

    X: np.ndarray
    Q: np.ndarray
    rotation0: np.ndarray
    details: dict[str, Any] = field(default_factory=dict)


class _WarmIk:
    """Joints of successive TCP samples, each inverse kinematics started at the last one."""

    def __init__(self, robot: Robot, rotation0: np.ndarray, q_seed: np.ndarray) -> None:
        self.robot, self.rotation0, self.q = robot, rotation0, np.asarray(q_seed, dtype=float)

    def __call__(self, x: np.ndarray) -> np.ndarray:
        self.q = solve_ik(self.robot, x[:3], _matrix(x[3:]) @ self.rotation0, self.q)
        return self.q


def shape_cartesian(
    robot: Robot,
    q_start: ArrayLike,
    X: ArrayLike,  # noqa: N803
    rotation0: ArrayLike,
    dt_s: float,
    modes: ModeSource,
    *,
    method: str = "tvist",
    shaper: str = "zv",
    max_delay_s: float | None = None,
) -> CartesianShaped:
    """Shape the TCP reference ``X`` (:func:`shape_tcp`) and convert it to joints
    (:func:`joints_from_tcp`), so a straight line stays straight.

    ``q_start`` is the joint pose at ``X[0]`` (it picks the inverse-kinematics branch);
    ``modes`` may depend on the joint pose (see :func:`shape_tcp`), evaluated at the joints
    of the previous shaped sample.
    """
    r0 = np.asarray(rotation0, dtype=float)
    q0 = np.asarray(q_start, dtype=float)
    shaped = shape_tcp(
        X,
        dt_s,
        modes,
        method=method,
        shaper=shaper,
        joints_of=_WarmIk(robot, r0, q0),
        robot=robot,
        max_delay_s=max_delay_s,
    )
    q = joints_from_tcp(robot, shaped, r0, q0)
    return CartesianShaped(X=shaped, Q=q, rotation0=r0, details={"method": method})


def tcp_path_deviation_m(
    robot: Robot,
    Q_planned: ArrayLike,  # noqa: N803
    Q_shaped: ArrayLike,  # noqa: N803
) -> np.ndarray:
    """Distance (m) of every flange position of ``Q_shaped`` from the planned flange path.

    The planned path is the polyline through the flange positions of ``Q_planned``
    ``(n_planned, n_dof)``; the result is ``(n_shaped,)``. Timing does not enter: a shaped
    reference that follows the planned path late has zero deviation.
    """
    planned = robot.flange_pose_many(np.ascontiguousarray(Q_planned, dtype=float))[:, :3, 3]
    points = robot.flange_pose_many(np.ascontiguousarray(Q_shaped, dtype=float))[:, :3, 3]
    start, seg = planned[:-1], np.diff(planned, axis=0)
    length_sq = np.einsum("ij,ij->i", seg, seg)
    keep = length_sq > 1e-24  # rest samples repeat a point: no segment
    start, seg, length_sq = start[keep], seg[keep], length_sq[keep]
    if start.shape[0] == 0:
        return np.linalg.norm(points - planned[0], axis=1)
    out = np.empty(points.shape[0])
    for i in range(0, points.shape[0], 256):  # chunks bound the (chunk, segments, 3) array
        p = points[i : i + 256, None, :]
        s = np.clip(np.einsum("nij,ij->ni", p - start, seg) / length_sq, 0.0, 1.0)
        nearest = start + s[..., None] * seg
        out[i : i + 256] = np.min(np.linalg.norm(p - nearest, axis=2), axis=1)
    return out
