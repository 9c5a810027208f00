"""Scalar measures of a move: settling time, peak rates, and the number of velocity humps.

Joint arrays are ``(n_samples, n_dof)`` with time along rows; ``(n_samples,)`` is one joint.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike

from tvist.analysis._signals import as_channels, magnitude, positive
from tvist.trajectory.validation import check_time_stamps

__all__ = [
    "SETTLE_BANDS_M_S2",
    "SETTLE_HOLD_S",
    "count_velocity_peaks",
    "peak_acceleration",
    "peak_jerk",
    "peak_velocity",
    "settling_time",
]

#: The tool-acceleration bands (m/s², gravity removed) that time to settled is reported at:
#: still enough to place (0.05) and to measure or take a picture (0.01).
SETTLE_BANDS_M_S2 = (0.05, 0.01)
#: A signal has settled once it is seen inside the band for at least this long (s): several
#: periods of a robot arm's lowest modes (~5-10 Hz), so a zero crossing of the ringing near
#: the end of a record does not count.
SETTLE_HOLD_S = 0.2


def settling_time(
    t_s: ArrayLike,
    signal: ArrayLike,
    t_stop_s: float,
    threshold: float,
    *,
    hold_s: float = 0.0,
) -> float:
    """Time after ``t_stop_s`` until the signal magnitude stays at or below ``threshold``.

    Measured from the start of a move (``t_stop_s`` = when the move starts), this is the
    time to settled: until the tool is still enough, for good.

    Parameters
    ----------
    t_s
        Time stamps, shape ``(n_samples,)``, s, increasing.
    signal
        Dynamic signal (static level already removed), ``(n_samples,)`` or ``(n_samples, k)``;
        for several channels the Euclidean norm is used.
    t_stop_s
        When the motion stops, s.
    threshold
        Settling band, same unit as ``signal`` (> 0).
    hold_s
        The record must show the signal inside the band for at least this long after the
        crossing (s, >= 0); a signal that only dips into the band at the end of the record
        (a zero crossing of a ringing axis) has not been seen to settle.

    Returns
    -------
    float
        Seconds from ``t_stop_s`` to the last downward crossing of ``threshold`` (linearly
        interpolated between samples); 0.0 if the magnitude never exceeds it after the stop
        (already settled);
        ``math.inf`` (not settled within the record) if it still exceeds it at the last
        sample or the record ends less than ``hold_s`` after the crossing.

    Notes
    -----
    The crossing is found on the samples: it lies between the last sample above the band
    and the next one, and the chord between them sets it (for a convex decay such as
    ``A e^(-σt)`` it is late by at most ``σ dt²/8``). An excursion above the band that
    peaks between two samples and exceeds the band by less than the sampling misses of it
    (``1 − cos(π f dt)`` of the peak for a ringing at ``f`` Hz: 0.13 % at 8 Hz and 500 Hz)
    is not seen.
    """
    t = check_time_stamps(t_s)
    level = magnitude(as_channels("signal", signal, t.size))
    band = positive("threshold", threshold)
    hold = float(hold_s)
    if not (math.isfinite(hold) and hold >= 0.0):
        raise ValueError(f"hold_s must be finite and >= 0, got {hold_s!r}")
    t_stop = float(t_stop_s)
    if not (math.isfinite(t_stop) and t[0] <= t_stop <= t[-1]):
        raise ValueError(f"t_stop_s = {t_stop_s!r} must lie in [{t[0]}, {t[-1]}]")
    first = int(np.searchsorted(t, t_stop, side="left"))
    above = np.flatnonzero(level[first:] > band)
    if above.size == 0:
        return 0.0 if t[-1] - t_stop >= hold else math.inf
    last = first + int(above[-1])
    if last == t.size - 1:
        return math.inf
    # Linear interpolation of the crossing between the last sample above and the next one.
    frac = (level[last] - band) / (level[last] - level[last + 1])
    crossing = float(t[last] + frac * (t[last + 1] - t[last]))
    if t[-1] - crossing < hold:
        return math.inf
    return crossing - t_stop


def _joint_array(name: str, q: ArrayLike, min_samples: int) -> np.ndarray:
    arr = as_channels(name, q)
    if arr.shape[0] < min_samples:
        raise ValueError(f"{name} needs at least {min_samples} samples, got {arr.shape[0]}")
    return arr


def peak_velocity(q: ArrayLike, dt_s: float) -> float:
    """Largest ``|Δq| / dt_s`` over all samples and joints (first difference), rad/s."""
    dq = np.diff(_joint_array("q", q, 2), axis=0)
    return float(np.max(np.abs(dq)) / positive("dt_s", dt_s))


def peak_acceleration(q: ArrayLike, dt_s: float) -> float:
    """Largest ``|Δ²q| / dt_s²`` over all samples and joints (second difference), rad/s²."""
    d2q = np.diff(_joint_array("q", q, 3), n=2, axis=0)
    return float(np.max(np.abs(d2q)) / positive("dt_s", dt_s) ** 2)


def peak_jerk(q: ArrayLike, dt_s: float) -> float:
    """Largest ``|Δ³q| / dt_s³`` over all samples and joints (third difference), rad/s³.

    A position step of height ``h`` anywhere in the reference shows up as ``h / dt_s³``, so
    this exposes the jumps of rounded or reseeded delay lines.
    """
    d3q = np.diff(_joint_array("q", q, 4), n=3, axis=0)
    return float(np.max(np.abs(d3q)) / positive("dt_s", dt_s) ** 3)


def _count_humps(speed: np.ndarray, bar: float) -> int:
    """Local maxima above ``bar`` separated from the previous counted one by a dip of at
    least ``bar`` below the lower of the two.

    :func:`scipy.signal.find_peaks` proposes the candidates (a flat top is one candidate).
    Its own prominence cannot be used alone: maxima of exactly equal height, as rounding
    leaves on a cruise plateau, each get the full prominence.
    """
    from scipy.signal import find_peaks

    # Zero padding lets a hump that touches either end of the record count.
    padded = np.concatenate([[0.0], speed, [0.0]])
    kept: list[int] = []
    for i in find_peaks(padded, height=bar)[0]:
        if kept:
            last = kept[-1]
            dip = padded[last : i + 1].min()
            if min(padded[last], padded[i]) - dip < bar:
                if padded[i] > padded[last]:
                    kept[-1] = i
                continue
        kept.append(int(i))
    return len(kept)


def count_velocity_peaks(qd: ArrayLike, rel_threshold: float = 0.05) -> int | np.ndarray:
    """Number of humps of ``|velocity|`` per joint: a measure of how smooth a move is.

    A rest-to-rest move with one acceleration and one deceleration phase has one hump; a
    reference shaped with impulses spaced wider than the move has one per impulse. A hump is
    a local maximum of ``|qd|`` (a flat top counts once) that exceeds ``rel_threshold`` times
    that joint's largest ``|qd|`` and is separated from the previous hump by a dip of at least
    that much, so rounding ripples on a cruise plateau are not counted.

    Parameters
    ----------
    qd
        Joint velocity, ``(n_samples,)`` or ``(n_samples, n_dof)``.
    rel_threshold
        Relative height and dip threshold, in (0, 1).

    Returns
    -------
    int or numpy.ndarray
        The count for 1-D input, else an integer array of shape ``(n_dof,)``. A joint that
        never moves has 0.
    """
    if not 0.0 < rel_threshold < 1.0:
        raise ValueError(f"rel_threshold must be in (0, 1), got {rel_threshold}")
    raw = np.asarray(qd, dtype=float)
    speed = np.abs(as_channels("qd", raw))
    counts = np.zeros(speed.shape[1], dtype=int)
    for joint in range(speed.shape[1]):
        top = speed[:, joint].max()
        if top > 0.0:
            counts[joint] = _count_humps(speed[:, joint], rel_threshold * top)
    return int(counts[0]) if raw.ndim == 1 else counts
