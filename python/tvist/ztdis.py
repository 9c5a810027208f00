"""Zero-time-delay input shaping: ZTDIS and modified ZTDIS (Zhao and Tomizuka).

Conventional input shaping delays a move of length ``T`` by the shaper's delay ``Δ_n``. The two
methods here make the shaped move end at ``T``:

- ``"ztdis"``: compress the move in time by ``α = (T − Δ_n)/T`` and shape it. Zero delay, but
  when ``Δ_n`` is close to ``T`` the compressed move is very fast and the shaped reference
  splits into several velocity peaks.
- ``"modified"``: compress by ``α' = T/(T + Δ_n)`` (> α), pass the compressed move through the
  compensator ``F(s) = (s² + 2ζω s + ω²)/((α's)² + 2α'ζω s + ω²)`` (one section per mode),
  and shape with every delay scaled by ``α'``. With ``F(s)G(s) = G(α's)`` the plant answers
  like the conventionally shaped plant sped up by ``1/α'``.

Time compression is an offline operation on a planned move (here). The compensator and the
shaper are the real-time core's (:class:`tvist._core.Compensator`, :class:`tvist.TvShaper`),
so the same filters can run per control cycle on a robot.

Arrays are ``(n_samples, n_dof)`` with time along rows; SI units.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike

from tvist import _core

__all__ = ["METHODS", "ZeroDelayResult", "compress", "motion_span", "zero_delay"]

Method = Literal["ztdis", "modified"]

#: The zero-delay methods :func:`zero_delay` accepts.
METHODS: tuple[str, ...] = ("ztdis", "modified")

#: A move is "at rest" at an end when its end velocity, estimated by a second-order one-sided
#: difference (exact for a constant acceleration, so a move that starts with an acceleration
#: step passes), is at most this fraction of its peak speed. 1e-3 leaves room for rounding
#: and for a jerk-limited start sampled coarsely (error ~ jerk·dt²/3), and rejects any move that
#: starts or ends with a visible velocity.
REST_TOLERANCE = 1e-3

#: Rest padding: a sample is at the start (end) pose when every joint is within this many
#: radians of it, times ``max(1, max |q|)`` (rounding of stored poses). Padding written by a
#: planner or read back from a file repeats the pose exactly; anything that moves more is
#: part of the motion.
REST_POSITION_TOLERANCE = 1e-12

#: The shaper may be at most this many times longer than the motion it shapes with zero
#: delay (modified ZTDIS; ZTDIS itself needs ``Δ_n < T``). The compressed motion lasts
#: ``α'T = T²/(T + Δ_n)`` and the compensator's high-frequency gain is ``1/α'²``: on a
#: 0.8 s minimum-jerk move (ZVD, ζ 0.04) the reference stays inside the move's range up to
#: ``Δ_n = 1.5 T`` (α' = 0.40, peak speed 3.8× the unshaped one), then overshoots the move by
#: 2.6 % at 1.6 T, 18 % at 1.75 T, 47 % at 2 T, 3× its length at 3 T and hundreds of radians
#: for ω_n = 0.1 rad/s (Δ_n ≈ 80 T).
MAX_DELAY_TO_MOVE = 1.5

#: Samples of the continued output inspected beyond ``T`` to measure what truncation leaves
#: out, in periods of the slowest shaped mode (plus the shaper delay).
_TAIL_PERIODS = 2.0


@dataclass(frozen=True)
class ZeroDelayResult:
    """A zero-delay reference and how it was made.

    Attributes
    ----------
    Q
        The zero-delay reference, same shape as the input: the input's rest padding, and the
        shaped motion in between, which ends where the input's motion ends.
    compressed
        The time-compressed input (held at its end pose after ``alpha * T``), same shape.
    alpha
        Time scale used: ``α`` for ``"ztdis"``, ``α'`` for ``"modified"``.
    delay_s
        Delay ``Δ_n`` of the underlying (unscaled) shaper, s: what conventional shaping adds.
    method
        ``"ztdis"`` or ``"modified"``.
    move_s
        Length ``T`` of the motion, s: ``(n_samples − 1) * dt_s`` without rest padding; with
        padding, from the last sample at the start pose to the first sample at the end pose
        (see :func:`motion_span`).
    motion_start_s
        When the motion starts in the input (end of the leading rest), s; the shaped motion
        ends at ``motion_start_s + move_s``.
    impulses
        The impulse sequence actually applied (multi-mode: the convolution; ``"modified"``:
        times scaled by ``α'``).
    tail_error
        Largest ``|q − q_end|`` of the output (continued past the input's end) from the end
        of the motion on, in position units: what cutting the reference at ``T`` leaves out.
        ``"ztdis"`` is a finite filter and ends exactly (up to interpolation); ``"modified"``
        relies on the shaper cancelling the compensator's own ringing, which a sampled shaper
        does up to its interpolation error.
    """

    Q: np.ndarray
    compressed: np.ndarray
    alpha: float
    delay_s: float
    method: str
    move_s: float
    motion_start_s: float
    impulses: _core.Impulses
    tail_error: float


def compress(Q: ArrayLike, dt_s: float, alpha: float) -> np.ndarray:
    """Time-compress a sampled rest-to-rest move: ``q_c(t) = q(t/α)``, held at the end pose.

    The move is interpolated with a cubic spline with zero end slopes ("clamped": the move is
    at rest at both ends). The spline is C², so the compressed move keeps a continuous
    acceleration wherever the original has one (linear interpolation would turn every sample
    into a velocity kink, i.e. an acceleration spike that compression amplifies by ``1/α²``);
    it is exact for cubics and fourth-order accurate otherwise. Where the original has an
    acceleration step (trapezoidal velocity), the spline spreads it over about one sample.

    Parameters
    ----------
    Q
        Move, ``(n_samples, n_dof)`` (or ``(n_samples,)``), sampled every ``dt_s``.
    dt_s
        Sample period, s.
    alpha
        Time scale, ``0 < alpha <= 1``.

    Returns
    -------
    numpy.ndarray
        Same shape as ``Q``: sample ``k`` is ``q(k dt / alpha)``, or the end pose after
        ``alpha * T``.
    """
    from scipy.interpolate import CubicSpline

    q = np.asarray(Q, dtype=float)
    if not (np.isfinite(alpha) and 0.0 < alpha <= 1.0):
        raise ValueError(f"alpha = {alpha} must lie in (0, 1]")
    if not (np.isfinite(dt_s) and dt_s > 0.0):
        raise ValueError(f"dt_s = {dt_s} must be finite and > 0")
    if q.ndim not in (1, 2) or q.shape[0] < 2 or not np.all(np.isfinite(q)):
        raise ValueError(
            f"Q must be a finite (n_samples, n_dof) array, n_samples >= 2; got {q.shape}"
        )
    n = q.shape[0]
    t = dt_s * np.arange(n)
    spline = CubicSpline(t, q, axis=0, bc_type="clamped")
    t_original = np.minimum(t / alpha, t[-1])
    out = spline(t_original)
    out[t / alpha >= t[-1]] = q[-1]
    return out


def _as_moves(Q: ArrayLike) -> tuple[np.ndarray, bool]:
    q = np.asarray(Q, dtype=float)
    if q.ndim == 1:
        return q[:, None], True
    if q.ndim != 2:
        raise ValueError(f"Q must have shape (n_samples, n_dof); got {q.shape}")
    return q, False


def _check_samples(q: np.ndarray, dt_s: float) -> None:
    if not (np.isfinite(dt_s) and dt_s > 0.0):
        raise ValueError(f"dt_s = {dt_s} must be finite and > 0")
    n, n_dof = q.shape
    if n < 4 or n_dof < 1:
        raise ValueError(f"Q must hold at least 4 samples of at least 1 joint; got {q.shape}")
    bad = np.argwhere(~np.isfinite(q))
    if bad.size:
        k, j = bad[0]
        raise ValueError(f"Q contains NaN or inf (first at sample {k}, joint {j})")


def motion_span(Q: ArrayLike) -> tuple[int, int]:
    """First and last sample of the motion inside rest padding: ``(k_start, k_end)``.

    ``k_start`` is the last sample still at the start pose before the first sample that leaves
    it, ``k_end`` the first sample at the end pose after the last sample away from it (a
    sample is at a pose when every joint is within :data:`REST_POSITION_TOLERANCE` of it).
    Without padding this is ``(0, n_samples − 1)``. Raises ``ValueError`` if nothing moves.
    """
    q, _ = _as_moves(Q)
    scale = max(1.0, float(np.max(np.abs(q))))
    tol = REST_POSITION_TOLERANCE * scale
    away_start = np.flatnonzero(np.any(np.abs(q - q[0]) > tol, axis=1))
    away_end = np.flatnonzero(np.any(np.abs(q - q[-1]) > tol, axis=1))
    if away_start.size == 0:
        raise ValueError("Q never leaves its first pose; there is no move to shape")
    if away_end.size == 0:  # pragma: no cover - a move that leaves q[0] is away from q[-1] too
        raise ValueError("Q never leaves its last pose; there is no move to shape")
    return max(0, int(away_start[0]) - 1), min(q.shape[0] - 1, int(away_end[-1]) + 1)


def _check_rest(q: np.ndarray, dt_s: float, where: str) -> None:
    """Refuse a motion ``q`` (n, n_dof) whose ends move (velocity estimated from samples)."""
    v_peak = np.max(np.abs(np.diff(q, axis=0)), axis=0) / dt_s
    # A joint that does not move has v_peak = 0; its end-velocity estimate is round-off, so the
    # scale has a floor of 1e-6 of the fastest joint's peak.
    v_scale = np.maximum(v_peak, 1e-6 * np.max(v_peak))
    # Second-order one-sided differences: exact for a quadratic start or end.
    v_start = (-3.0 * q[0] + 4.0 * q[1] - q[2]) / (2.0 * dt_s)
    v_end = (3.0 * q[-1] - 4.0 * q[-2] + q[-3]) / (2.0 * dt_s)
    for name, v in (("start", v_start), ("end", v_end)):
        moving = np.abs(v) > REST_TOLERANCE * v_scale
        if moving.any():
            j = int(np.argmax(moving))
            raise ValueError(
                f"Q is not at rest at its {name}{where}: joint {j} moves at {v[j]:.4g} /s "
                f"there (peak speed {v_peak[j]:.4g} /s); zero-delay shaping needs a "
                "rest-to-rest move"
            )


def _check_shaper_fits(
    delay_s: float, move_s: float, modes: list[tuple[float, float]], method: str
) -> None:
    """Refuse a shaper that is far longer than the motion (see :data:`MAX_DELAY_TO_MOVE`)."""
    limit = 1.0 if method == "ztdis" else MAX_DELAY_TO_MOVE
    if delay_s < limit * move_s:
        return
    w_slow = min(w for w, _ in modes)
    hint = "use conventional shaping (tvist.TvShaper) or lengthen the move"
    if method == "ztdis" and delay_s < MAX_DELAY_TO_MOVE * move_s:
        hint = "use method 'modified', conventional shaping or a longer move"
    raise ValueError(
        f"{method}: the motion of T = {move_s:.4g} s is too short for the shaper, which lasts "
        f"{delay_s:.4g} s (slowest mode {w_slow:.4g} rad/s = {w_slow / (2 * np.pi):.4g} Hz); "
        f"zero-delay shaping needs a shaper shorter than {limit:g} T. Check that the modes "
        f"are in rad/s, or {hint}"
    )


def _per_joint_limit(name: str, value: ArrayLike | None, n_dof: int) -> np.ndarray | None:
    if value is None:
        return None
    lim = np.asarray(value, dtype=float)
    if lim.ndim == 0:
        lim = np.full(n_dof, float(lim))
    if lim.shape != (n_dof,):
        raise ValueError(f"{name} must be a scalar or have shape ({n_dof},); got {lim.shape}")
    if not np.all(np.isfinite(lim) & (lim > 0.0)):
        raise ValueError(f"{name} must be finite and > 0; got {lim}")
    return lim


def _velocity(q: np.ndarray, dt_s: float) -> np.ndarray:
    """Velocity of a sampled reference: central differences (one-sided at the ends)."""
    return np.gradient(q, dt_s, axis=0)


def _acceleration(q: np.ndarray, dt_s: float) -> np.ndarray:
    """Acceleration of a sampled reference: second differences ``(q[k+1] − 2q[k] + q[k−1])/dt²``."""
    return np.diff(q, 2, axis=0) / dt_s**2


def _check_limits(
    what: str,
    q: np.ndarray,
    dt_s: float,
    v_max: np.ndarray | None,
    a_max: np.ndarray | None,
    method: str,
    alpha: float,
) -> None:
    for name, lim, deriv in (
        ("v_max", v_max, _velocity),
        ("a_max", a_max, _acceleration),
    ):
        if lim is None:
            continue
        peak = np.max(np.abs(deriv(q, dt_s)), axis=0)
        over = peak > lim
        if over.any():
            j = int(np.argmax(peak / lim))
            raise ValueError(
                f"{name} exceeded: the {what} of method {method!r} (alpha = {alpha:.4f}) "
                f"reaches {peak[j]:.4g} on joint {j}, limit {lim[j]:.4g}; the move is too short "
                "for zero-delay shaping within the limits (lengthen it or use conventional shaping)"
            )


def zero_delay(
    Q: ArrayLike,
    dt_s: float,
    modes: Sequence[tuple[float, float]],
    shaper: str = "zvd",
    method: Method = "modified",
    v_max: ArrayLike | None = None,
    a_max: ArrayLike | None = None,
    *,
    interp: str = "cubic",
    discretization: str = "matched",
) -> ZeroDelayResult:
    """Shape a rest-to-rest move with zero added delay.

    Parameters
    ----------
    Q
        The move, ``(n_samples, n_dof)`` (or ``(n_samples,)``), sampled every ``dt_s``, at rest
        at both ends. Rest padding (samples repeating the start or end pose) is kept as it is:
        only the motion between is compressed and shaped (:func:`motion_span`), so ``T`` and
        ``α`` are those of the motion and the shaped motion ends where the planned one ends.
    dt_s
        Sample period, s.
    modes
        Modes to suppress, ``[(wn_rad_s, zeta), ...]``. Several modes: the shaper is the
        convolution of the per-mode shapers and the compensator has one section per mode.
    shaper
        Registry shaper (see :data:`tvist.SHAPERS`).
    method
        ``"modified"`` (default) or ``"ztdis"``.
    v_max, a_max
        Optional velocity and acceleration limits (scalar or per joint). Both the compressed
        move and the final reference are checked with finite differences of the samples.
    interp
        Fractional-delay interpolation of the shaper, ``"cubic"`` (default) or ``"linear"``.
    discretization
        Compensator discretization, ``"matched"`` (default: matched pole-zero, exact
        cancellation of the sampled plant mode) or ``"tustin"`` (pre-warped at each ``ω_n``).

    Returns
    -------
    ZeroDelayResult
        ``.Q`` has the input's shape; its motion ends where the input's does. See
        :class:`ZeroDelayResult`.

    Raises
    ------
    ValueError
        NaN/inf in ``Q``, a move not at rest at both ends or that never moves, an unknown
        method or shaper, invalid modes, a move not longer than the shaper delay (ZTDIS) or
        more than :data:`MAX_DELAY_TO_MOVE` times shorter (modified: a mode far too slow for
        the move; the message says what to do), a compensator mode above the Nyquist
        frequency (modified), or a compressed move or reference that breaks ``v_max`` or
        ``a_max`` (the message names the limit).
    """
    if method not in METHODS:
        raise ValueError(f"unknown method {method!r}; expected one of {METHODS}")
    q, was_1d = _as_moves(Q)
    dt_s = float(dt_s)
    _check_samples(q, dt_s)
    n, n_dof = q.shape
    k_start, k_end = motion_span(q)
    motion = q[k_start : k_end + 1]
    if motion.shape[0] < 4:
        raise ValueError(
            f"the motion inside the rest padding has only {motion.shape[0]} samples "
            f"(samples {k_start}..{k_end}); zero-delay shaping needs at least 4"
        )
    padded = (k_start, k_end) != (0, n - 1)
    _check_rest(motion, dt_s, " (of the motion inside the rest padding)" if padded else "")
    vlim = _per_joint_limit("v_max", v_max, n_dof)
    alim = _per_joint_limit("a_max", a_max, n_dof)
    mode_list = [(float(w), float(z)) for w, z in modes]
    if not mode_list:
        raise ValueError("at least one mode (wn_rad_s, zeta) is required")

    per_mode = [_core.design_shaper(shaper, w, z) for w, z in mode_list]
    delay_s = float(sum(s.duration_s for s in per_mode))
    move_s = (k_end - k_start) * dt_s
    _check_shaper_fits(delay_s, move_s, mode_list, method)
    try:
        if method == "ztdis":
            alpha = _core.ztdis_alpha(move_s, delay_s)
        else:
            alpha = _core.modified_alpha(move_s, delay_s)
    except ValueError as e:
        raise ValueError(f"{method}: the move of T = {move_s:.4g} s is too short: {e}") from None

    # Only the motion is compressed; the rest before and after it is kept as it is.
    compressed = np.array(q)
    compressed[k_start : k_end + 1] = compress(motion, dt_s, alpha)
    compressed[k_end + 1 :] = q[k_end]
    _check_limits("compressed move", compressed, dt_s, vlim, alim, method, alpha)

    if method == "ztdis":
        shaped_modes = mode_list
    else:
        shaped_modes = [_core.scaled_mode(w, z, alpha) for w, z in mode_list]
    impulses = _core.convolve(*(_core.design_shaper(shaper, w, z) for w, z in shaped_modes))

    # Continue past the end of the input to see what truncation leaves out.
    slowest_period_s = max(2.0 * np.pi / w for w, _ in shaped_modes)
    n_tail = int(np.ceil((impulses.duration_s + _TAIL_PERIODS * slowest_period_s) / dt_s))
    drive = np.vstack([compressed, np.repeat(compressed[-1:], n_tail, axis=0)])
    if method == "modified":
        try:
            comp = _core.Compensator(mode_list, alpha, dt_s, n_dof, discretization)
        except ValueError as e:
            raise ValueError(f"modified: cannot build the compensator: {e}") from None
        comp.reset(np.ascontiguousarray(q[0]))
        drive = comp.filter(np.ascontiguousarray(drive))
    shaper_filter = _core.TvShaper(
        _core.ConstantModes(shaped_modes), dt_s, n_dof, shaper=shaper, interp=interp
    )
    shaper_filter.reset(np.ascontiguousarray(q[0]))
    shaped = shaper_filter.shape(np.ascontiguousarray(drive))
    # From the end of the motion on, the shaped reference should sit at the end pose.
    tail_error = float(np.max(np.abs(shaped[k_end:] - q[-1])))

    out = np.array(shaped[:n])
    # The rest after the motion is kept as given: the reference is cut at the motion's end
    # (what that leaves out is tail_error), exactly as a move without padding is cut at T.
    out[k_end + 1 :] = q[k_end + 1 :]
    _check_limits("zero-delay reference", out, dt_s, vlim, alim, method, alpha)
    if was_1d:
        out, compressed = out[:, 0], compressed[:, 0]
    return ZeroDelayResult(
        Q=out,
        compressed=compressed,
        alpha=float(alpha),
        delay_s=delay_s,
        method=method,
        move_s=move_s,
        motion_start_s=k_start * dt_s,
        impulses=impulses,
        tail_error=tail_error,
    )
