"""Time-stamped waypoints (a planner's output) to samples on the control grid.

A planner (MoveIt, a ROS 2 ``trajectory_msgs/JointTrajectory``, an offline tool writing a CSV
with a time column) hands out waypoints at arbitrary times, often with velocities and
sometimes accelerations. :func:`resample` turns them into the ``(n_samples, n_dof)`` array,
one row every ``dt_s``, that the shapers and the robot consume. The interpolant is chosen the
way ROS 2's ``joint_trajectory_controller`` chooses it per segment:

- positions, velocities and accelerations: quintic Hermite polynomial per segment;
- positions and velocities: cubic Hermite polynomial per segment;
- positions only: a C²-continuous cubic spline with zero velocity at both ends (the controller
  would interpolate linearly, which puts a velocity step at every waypoint).

Every interpolant passes through every waypoint (and its given derivatives) exactly.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike

from tvist.trajectory.validation import positive_scalar

__all__ = ["MAX_GRID_SAMPLES", "interpolant", "resample"]

#: Largest grid :func:`resample` builds (10⁷ rows: 5.5 h at 500 Hz, 480 MB for 6 joints).
#: A longer one is almost always a time column in the wrong unit (ms or ns read as s).
MAX_GRID_SAMPLES = 10_000_000


def _as_waypoint_array(name: str, value: ArrayLike, n_points: int | None) -> np.ndarray:
    """``value`` as a finite float array ``(n_points, n_dof)`` (1-D input: one joint)."""
    try:
        arr = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a numeric array") from None
    if arr.ndim == 1:
        arr = arr[:, None]
    if arr.ndim != 2:
        raise ValueError(f"{name} must have shape (n_waypoints, n_dof); got {arr.shape}")
    if arr.shape[0] == 0 or arr.shape[1] == 0:
        raise ValueError(f"{name} is empty (shape {arr.shape}); the trajectory has no waypoints")
    if n_points is not None and arr.shape[0] != n_points:
        raise ValueError(
            f"{name} has {arr.shape[0]} waypoints but times_s has {n_points}; give one row "
            "per time stamp"
        )
    bad = np.argwhere(~np.isfinite(arr))
    if bad.size:
        k, j = bad[0]
        raise ValueError(f"{name}[{k}, {j}] is {arr[k, j]}; waypoints must be finite")
    return arr


def _check_times(times_s: ArrayLike) -> np.ndarray:
    try:
        t = np.asarray(times_s, dtype=float)
    except (TypeError, ValueError):
        raise ValueError("times_s must be a numeric 1-D array") from None
    if t.ndim != 1:
        raise ValueError(f"times_s must be 1-D (one time per waypoint); got shape {t.shape}")
    if t.size == 0:
        raise ValueError("times_s is empty; the trajectory has no waypoints")
    bad = np.flatnonzero(~np.isfinite(t))
    if bad.size:
        raise ValueError(f"times_s[{bad[0]}] is {t[bad[0]]}; time stamps must be finite")
    if t.size < 2:
        raise ValueError("a trajectory needs at least 2 waypoints (a start and an end)")
    step = np.diff(t)
    back = np.flatnonzero(step <= 0.0)
    if back.size:
        k = int(back[0]) + 1
        raise ValueError(
            f"times_s must be strictly increasing; times_s[{k}] = {t[k]:.9g} s follows "
            f"times_s[{k - 1}] = {t[k - 1]:.9g} s"
        )
    return t


def interpolant(
    times_s: ArrayLike,
    positions: ArrayLike,
    velocities: ArrayLike | None = None,
    accelerations: ArrayLike | None = None,
):
    """The piecewise polynomial through the waypoints (see the module docstring).

    Returns a :class:`scipy.interpolate.PPoly`-like callable ``f(t, nu=0)`` of shape
    ``(n_dof,)`` per time (``nu``: derivative order), valid on ``[times_s[0], times_s[-1]]``.

    Raises
    ------
    ValueError
        Fewer than 2 waypoints, non-increasing or non-finite times, NaN/inf in any array,
        arrays whose shapes disagree, or accelerations without velocities.
    """
    from scipy.interpolate import BPoly, CubicSpline

    t = _check_times(times_s)
    q = _as_waypoint_array("positions", positions, t.size)
    if velocities is None:
        if accelerations is not None:
            raise ValueError(
                "accelerations were given without velocities; give both (quintic "
                "interpolation) or velocities only (cubic)"
            )
        # Zero end slopes ("clamped"): the trajectory starts and ends at rest; C² inside.
        return CubicSpline(t, q, axis=0, bc_type="clamped")
    v = _as_waypoint_array("velocities", velocities, t.size)
    derivs = [q, v]
    if accelerations is not None:
        derivs.append(_as_waypoint_array("accelerations", accelerations, t.size))
    for name, arr in zip(("velocities", "accelerations"), derivs[1:], strict=False):
        if arr.shape != q.shape:
            raise ValueError(
                f"{name} has shape {arr.shape} but positions has {q.shape}; give one value "
                "per joint and waypoint"
            )
    # BPoly.from_derivatives takes, per waypoint, [value, first derivative, ...] of one
    # component: cubic Hermite with (q, v), quintic Hermite with (q, v, a).
    stacked = np.stack(derivs, axis=1)  # (n_points, n_derivs, n_dof)
    pieces = [BPoly.from_derivatives(t, stacked[:, :, j]) for j in range(q.shape[1])]
    return _Columns(pieces)


class _Columns:
    """Several scalar piecewise polynomials evaluated side by side as one ``(…, n_dof)`` value."""

    def __init__(self, pieces: list) -> None:
        self._pieces = pieces

    def __call__(self, t: ArrayLike, nu: int = 0) -> np.ndarray:
        return np.stack([p(t, nu) for p in self._pieces], axis=-1)


def resample(
    times_s: ArrayLike,
    positions: ArrayLike,
    dt_s: float,
    velocities: ArrayLike | None = None,
    accelerations: ArrayLike | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Sample time-stamped waypoints every ``dt_s``.

    Parameters
    ----------
    times_s
        Time of each waypoint, ``(n_waypoints,)``, s, strictly increasing (for example
        ``time_from_start``). The grid starts at ``times_s[0]``.
    positions
        Joint positions at the waypoints, ``(n_waypoints, n_dof)`` (or ``(n_waypoints,)`` for
        one joint), rad.
    dt_s
        Control period, s.
    velocities, accelerations
        Optional joint velocities (rad/s) and accelerations (rad/s²) at the waypoints, same
        shape as ``positions``; see the module docstring for the interpolant each selects.

    Returns
    -------
    (t_s, Q)
        ``t_s = times_s[0] + k dt_s`` for ``k = 0 … N`` with ``N = ceil((t_end − t_0)/dt_s)``
        (the last sample is at or just after the last waypoint), shape ``(N + 1,)``; and
        ``Q`` of shape ``(N + 1, n_dof)`` (``(N + 1,)`` for 1-D ``positions``). Samples after
        the last waypoint hold its position. A sample at a waypoint's time equals the
        waypoint up to rounding of the time stamps.

    Raises
    ------
    ValueError
        As :func:`interpolant`, plus a non-positive ``dt_s`` or a grid longer than
        :data:`MAX_GRID_SAMPLES` (usually a time column in ms or ns).
    """
    dt_s = positive_scalar("dt_s", dt_s)
    f = interpolant(times_s, positions, velocities, accelerations)
    t_wp = np.asarray(times_s, dtype=float)
    span = float(t_wp[-1] - t_wp[0])
    # A relative slack of 1e-9 keeps a span that is a whole number of periods up to rounding
    # (0.1 / 0.002 = 50.000000000000004) from gaining a sample.
    n_steps = max(1, math.ceil(span / dt_s * (1.0 - 1e-9)))
    if n_steps + 1 > MAX_GRID_SAMPLES:
        raise ValueError(
            f"the waypoints span {span:.6g} s, which at dt_s = {dt_s:g} s needs "
            f"{n_steps + 1} samples (limit {MAX_GRID_SAMPLES}); are the times in seconds?"
        )
    t = t_wp[0] + dt_s * np.arange(n_steps + 1)
    q = f(np.minimum(t, t_wp[-1]))
    # Snap samples that fall on a waypoint to within rounding (|Δt| < 1e-9 dt) to the waypoint
    # itself, so on-grid waypoints are reproduced bit for bit despite time-stamp rounding.
    pos = _as_waypoint_array("positions", positions, t_wp.size)
    k = np.rint((t_wp - t_wp[0]) / dt_s).astype(np.int64)
    on_grid = (k <= n_steps) & (np.abs(t_wp[0] + k * dt_s - t_wp) <= 1e-9 * dt_s)
    q[k[on_grid]] = pos[on_grid]
    if np.asarray(positions).ndim == 1:
        q = q[:, 0]
    return t, q
