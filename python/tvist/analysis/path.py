"""How far joint-space shaping bends the tool path away from the planned one.

Shaping filters every joint separately in time. A straight Cartesian line is a curve in joint
space whose joints move in a fixed non-linear relation; delaying and blending each joint's
motion with impulses that land at different points of that relation moves the tool off the
line. :func:`path_deviation` measures the result on the robot model: for every sample of the
shaped tool path the distance to the nearest point of the planned tool path (not to the
planned point at the same time: running behind along the same path is no deviation).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

__all__ = ["PathDeviation", "path_deviation", "point_to_polyline_distance"]

#: Shaped points per block of the distance computation (bounds memory to
#: ``_BLOCK × n_planned × 3`` doubles, ~100 MB for 5000 planned samples).
_BLOCK = 800


@dataclass(frozen=True)
class PathDeviation:
    """The shaped tool path against the planned one (positions of the flange origin + TCP).

    Attributes
    ----------
    max_m
        Largest distance of a shaped tool position from the planned tool path, m.
    index
        Sample of the shaped trajectory where ``max_m`` occurs.
    path_fraction
        Where along the planned path (by arc length, 0 = start, 1 = end) the nearest planned
        point to that sample lies.
    distance_m
        Distance of every shaped sample from the planned path, m, ``(n_shaped,)``.
    """

    max_m: float
    index: int
    path_fraction: float
    distance_m: np.ndarray


def point_to_polyline_distance(
    points: ArrayLike, polyline: ArrayLike
) -> tuple[np.ndarray, np.ndarray]:
    """Distance of each point to a polyline, and the arc length (m) of the nearest point on it.

    Parameters
    ----------
    points
        ``(n_points, 3)``.
    polyline
        Vertices ``(n_vertices, 3)``, ``n_vertices >= 1``; repeated vertices are allowed.

    Returns
    -------
    (distance, arc_length)
        Both ``(n_points,)``: the Euclidean distance to the nearest point of the polyline, and
        that point's arc length from the first vertex.
    """
    p = np.asarray(points, dtype=float)
    v = np.asarray(polyline, dtype=float)
    a, b = v[:-1], v[1:]
    if a.shape[0] == 0:  # a single vertex: the path is a point
        a, b = v, v
    ab = b - a
    seg_len2 = np.einsum("ij,ij->i", ab, ab)
    seg_len = np.sqrt(seg_len2)
    arc_start = np.concatenate([[0.0], np.cumsum(seg_len)[:-1]])
    safe = np.where(seg_len2 > 0.0, seg_len2, 1.0)
    dist = np.empty(p.shape[0])
    arc = np.empty(p.shape[0])
    for lo in range(0, p.shape[0], _BLOCK):
        blk = p[lo : lo + _BLOCK]
        ap = blk[:, None, :] - a[None, :, :]  # (blk, n_seg, 3)
        # Projection parameter on each segment, clamped to the segment; 0 on empty segments.
        u = np.clip(np.einsum("psk,sk->ps", ap, ab) / safe, 0.0, 1.0)
        u[:, seg_len2 == 0.0] = 0.0
        diff = ap - u[:, :, None] * ab[None, :, :]
        d2 = np.einsum("psk,psk->ps", diff, diff)
        best = np.argmin(d2, axis=1)
        rows = np.arange(blk.shape[0])
        dist[lo : lo + _BLOCK] = np.sqrt(d2[rows, best])
        arc[lo : lo + _BLOCK] = arc_start[best] + u[rows, best] * seg_len[best]
    return dist, arc


def _tool_positions(robot, Q: np.ndarray, tcp: np.ndarray) -> np.ndarray:
    poses = robot.flange_pose_many(Q)  # (n, 4, 4)
    return poses[:, :3, 3] + poses[:, :3, :3] @ tcp


def path_deviation(
    robot, Q_planned: ArrayLike, Q_shaped: ArrayLike, tcp_m: ArrayLike = (0.0, 0.0, 0.0)
) -> PathDeviation:
    """Largest distance of the shaped tool path from the planned tool path, and where.

    Parameters
    ----------
    robot
        A :class:`tvist.robots.Robot` (its forward kinematics places the tool).
    Q_planned, Q_shaped
        Joint trajectories, rad, ``(n_samples, n_dof)``; their lengths may differ (shaping
        with delay adds samples). The planned tool path is the polyline through the planned
        samples: sampled at the control rate its chords lie within ``r (Δθ)²/8`` of the true
        arc (below 1 µm for a 1 m radius at 1.5 mrad per sample).
    tcp_m
        Tool centre point in the flange frame, m (default: the flange origin).

    Returns
    -------
    PathDeviation
        ``max_m`` is 0 for identical paths (also when the shaped one runs behind in time).

    Raises
    ------
    ValueError
        Arrays that are not ``(n_samples, robot.n_dof)``, empty, or not finite; a TCP that is
        not 3 finite numbers.
    """
    tcp = np.asarray(tcp_m, dtype=float)
    if tcp.shape != (3,) or not np.all(np.isfinite(tcp)):
        raise ValueError(f"tcp_m must be 3 finite numbers (m); got {tcp_m!r}")
    arrays = []
    for name, Q in (("Q_planned", Q_planned), ("Q_shaped", Q_shaped)):
        q = np.asarray(Q, dtype=float)
        if q.ndim != 2 or q.shape[0] == 0 or q.shape[1] != robot.n_dof:
            raise ValueError(
                f"{name} must have shape (n_samples, {robot.n_dof}) with n_samples >= 1; "
                f"got {q.shape}"
            )
        arrays.append(q)
    planned = _tool_positions(robot, arrays[0], tcp)
    # Rest samples repeat a vertex: drop consecutive repeats (zero-length segments).
    planned = planned[np.concatenate([[True], np.any(np.diff(planned, axis=0) != 0.0, axis=1)])]
    shaped = _tool_positions(robot, arrays[1], tcp)
    dist, arc = point_to_polyline_distance(shaped, planned)
    total = float(np.sum(np.linalg.norm(np.diff(planned, axis=0), axis=1)))
    k = int(np.argmax(dist))
    return PathDeviation(
        max_m=float(dist[k]),
        index=k,
        path_fraction=float(arc[k] / total) if total > 0.0 else 0.0,
        distance_m=dist,
    )
