"""Waypoints in, shaped time-stamped trajectory out.

:func:`shape_waypoints` resamples a planner's waypoints to the control grid
(:func:`~tvist.trajectory.resample`), shapes the samples with FD-TVIST (any dynamics
provider) or with zero added delay (ZTDIS, modified ZTDIS), and returns times, positions and
velocities. :func:`shape_samples` is the same on samples already on the grid (``tvist shape``
uses it for files without a time column).

Arrays are ``(n_samples, n_dof)``, time along rows; SI units, radians.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from tvist.maps.paper10 import warn_outside_range
from tvist.trajectory.resample import resample

__all__ = ["METHODS", "ShapedTrajectory", "modes_at", "shape_samples", "shape_waypoints"]

#: Shaping methods: FD-TVIST, ZTDIS and modified ZTDIS (the ``tvist shape --method`` names).
METHODS: tuple[str, ...] = ("tvist", "ztdis", "modified")

#: Samples the interpolation stencil of the delay line reads after the delayed time: an output
#: sample depends on input samples up to this many after ``t − delay`` (linear 1, cubic 2).
_STENCIL_LEAD = {"linear": 1, "cubic": 2}


@dataclass(frozen=True)
class ShapedTrajectory:
    """A shaped trajectory on the control grid and the unshaped one it was made from.

    Attributes
    ----------
    t_s
        Sample times, s, ``(n_samples,)``; starts at the first waypoint's time.
    q, qd
        Shaped positions (rad) and velocities (rad/s, central differences of ``q``),
        ``(n_samples, n_dof)``.
    planned
        The unshaped samples (the resampled waypoints), held at the end pose to the length of
        ``q``, ``(n_samples, n_dof)``.
    dt_s
        Sample period, s.
    method
        ``"tvist"``, ``"ztdis"`` or ``"modified"``.
    planned_end_s
        Time of the last waypoint, s.
    added_delay_s
        How much later than ``planned_end_s`` the shaped trajectory ends, s (0 for the
        zero-delay methods).
    end_modes
        Modes ``[(wn_rad_s, zeta), ...]`` at the end pose.
    alpha
        Time scale of a zero-delay method (``nan`` for FD-TVIST).
    status_counts
        FD-TVIST's per-step status counts (empty for the zero-delay methods).
    """

    t_s: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    planned: np.ndarray
    dt_s: float
    method: str
    planned_end_s: float
    added_delay_s: float
    end_modes: list[tuple[float, float]]
    alpha: float = math.nan
    status_counts: dict[str, int] = field(default_factory=dict)


def modes_at(dynamics: Any, q: np.ndarray) -> list[tuple[float, float]]:
    """Modes ``[(wn_rad_s, zeta), ...]`` of a dynamics provider at the pose ``q`` (rad).

    ``dynamics``: a list of modes, :class:`tvist.ConstantModes`, :class:`tvist.MapDynamics`
    (anything with a ``modes(q)`` method) or a callable ``f(q) -> modes``.
    """
    pose = np.ascontiguousarray(q, dtype=float)
    modes = getattr(dynamics, "modes", None)
    if modes is not None:
        found = modes(pose) if callable(modes) else modes
    elif callable(dynamics):
        found = dynamics(pose)
    else:
        found = dynamics
    try:
        return [(float(w), float(z)) for w, z in found]
    except (TypeError, ValueError):
        raise ValueError(
            "dynamics must be a list of (wn_rad_s, zeta), ConstantModes, MapDynamics or a "
            f"callable f(q) -> modes; got {type(dynamics).__name__}"
        ) from None


def _provider(dynamics: Any):
    from tvist import _core

    if isinstance(dynamics, (list, tuple)):
        return _core.ConstantModes([(float(w), float(z)) for w, z in dynamics])
    return dynamics


def shape_samples(
    Q: ArrayLike,
    dt_s: float,
    dynamics: Any,
    *,
    method: str = "tvist",
    shaper: str = "zv",
    interp: str = "linear",
    max_delay_s: float | None = None,
) -> tuple[np.ndarray, float, list[tuple[float, float]], float, dict[str, int]]:
    """Shape samples ``Q`` ``(n_samples, n_dof)`` on the grid ``dt_s``.

    Returns ``(shaped, added_delay_s, end_modes, alpha, status_counts)``. FD-TVIST holds the
    end pose after ``Q`` until the filter has settled on it (``shaped`` is longer by
    ``added_delay_s``); the zero-delay methods keep the length (rest padding is kept, only
    the motion is compressed, see :func:`tvist.zero_delay`) and use the modes at the end pose.
    """
    import tvist

    if method not in METHODS:
        raise ValueError(f"unknown method {method!r}; expected one of {METHODS}")
    q = np.ascontiguousarray(Q, dtype=float)
    if q.ndim != 2:
        raise ValueError(f"Q must have shape (n_samples, n_dof); got {q.shape}")
    # A map identified on other inertias holds its modes at a bound: say so, once per call.
    warn_outside_range(dynamics, q)
    end_modes = modes_at(dynamics, q[-1])
    if method == "tvist":
        if interp not in _STENCIL_LEAD:
            raise ValueError(f"unknown interp {interp!r}; expected 'linear' or 'cubic'")
        kwargs = {} if max_delay_s is None else {"max_delay_s": max_delay_s}
        shaper_ = tvist.TvShaper(
            _provider(dynamics), dt_s=dt_s, n_dof=q.shape[1], shaper=shaper, interp=interp, **kwargs
        )
        # A frequency-ranked modal map shapes the K lowest modes this move needs.
        from tvist.maps.mode_choice import set_modes_for_move

        choice = set_modes_for_move(shaper_, dynamics, q, dt_s)
        if choice is not None:
            end_modes = sorted(end_modes)[: choice.n_modes]
        end_delay = tvist.convolve(*(tvist.shaper(shaper, w, z) for w, z in end_modes))
        # Hold the end pose until every impulse's interpolation stencil reads only it.
        n_tail = math.ceil(end_delay.duration_s / dt_s - 1e-9) + _STENCIL_LEAD[interp]
        padded = np.vstack([q, np.repeat(q[-1:], n_tail, axis=0)])
        out = shaper_.shape(padded)
        # The shaper's own delay at the end (its filters keep the modes they followed along the
        # move until it rests) may exceed that of the modes at the end pose: hold on until it
        # too has read only the end pose.
        extra = math.ceil(shaper_.delay_s / dt_s - 1e-9) + _STENCIL_LEAD[interp] - n_tail
        if extra > 0:
            out = np.vstack([out, shaper_.shape(np.repeat(q[-1:], extra, axis=0))])
            n_tail += extra
        return out, n_tail * dt_s, end_modes, math.nan, dict(shaper_.status_counts)
    result = tvist.zero_delay(
        q,
        dt_s,
        end_modes,
        shaper=shaper,
        method=method,
        interp="cubic" if interp == "cubic" else "linear",
    )
    return np.asarray(result.Q), 0.0, end_modes, result.alpha, {}


def shape_waypoints(
    times_s: ArrayLike,
    positions: ArrayLike,
    dt_s: float,
    dynamics: Sequence[tuple[float, float]] | Callable[..., Any] | Any,
    *,
    method: str = "tvist",
    shaper: str = "zv",
    velocities: ArrayLike | None = None,
    accelerations: ArrayLike | None = None,
    interp: str = "linear",
    max_delay_s: float | None = None,
) -> ShapedTrajectory:
    """Resample time-stamped waypoints to ``dt_s`` and shape them.

    Parameters
    ----------
    times_s, positions, velocities, accelerations
        The waypoints, as :func:`~tvist.trajectory.resample` takes them
        (``positions`` ``(n_waypoints, n_dof)``, rad).
    dt_s
        Control period, s.
    dynamics
        Modes ``[(wn_rad_s, zeta), ...]``, :class:`tvist.ConstantModes`,
        :class:`tvist.MapDynamics` or a callable ``f(q) -> modes`` (FD-TVIST then needs
        ``max_delay_s``).
    method
        ``"tvist"`` (FD-TVIST: ends ``added_delay_s`` after the last waypoint), ``"ztdis"``
        or ``"modified"`` (zero added delay: ends at the last waypoint; the waypoints must start
        and end at rest).
    shaper
        Registry shaper (:data:`tvist.SHAPERS`).
    interp
        Fractional-delay interpolation, ``"linear"`` (default) or ``"cubic"``.
    max_delay_s
        Delay-line length for a callable provider (FD-TVIST).

    Raises
    ------
    ValueError
        Bad waypoints (see :func:`~tvist.trajectory.resample`), an unknown method or shaper,
        and everything :func:`tvist.zero_delay` refuses.
    """
    t, q = resample(times_s, positions, dt_s, velocities, accelerations)
    if q.ndim == 1:
        q = q[:, None]
    shaped, added, end_modes, alpha, counts = shape_samples(
        q, dt_s, dynamics, method=method, shaper=shaper, interp=interp, max_delay_s=max_delay_s
    )
    n = shaped.shape[0]
    t_out = t[0] + dt_s * np.arange(n)
    planned = np.vstack([q, np.repeat(q[-1:], n - q.shape[0], axis=0)])
    t_wp = np.asarray(times_s, dtype=float)
    return ShapedTrajectory(
        t_s=t_out,
        q=shaped,
        qd=np.gradient(shaped, dt_s, axis=0),
        planned=planned,
        dt_s=float(dt_s),
        method=method,
        planned_end_s=float(t_wp[-1]),
        added_delay_s=float(t_out[-1] - t_wp[-1]) if method == "tvist" else 0.0,
        end_modes=end_modes,
        alpha=alpha,
        status_counts=counts,
    )
