"""The modes of one excitation log fitted on its free decays alone: the arm at rest at the pose.

An excitation log mixes two states of the arm. While the joint moves, its gear carries the
move's torque ``J q̈``; after each stop it rings freely about its static equilibrium. A gear
that stiffens with load (the tangent stiffness ``k1 + 3 k3 δ²`` of a strain-wave gear) rings
faster under torque, so a fit of the whole log (:mod:`tvist.ident.local_fit`,
:mod:`tvist.ident.ringing`) averages a stiffer spring than the arm has at rest: on arms whose
gears stiffen two- to threefold at rated torque, base modes came out 3-5 % above the
small-signal mode (the eigen-analysis about the static equilibrium), while the ringing after
each stop of the same log gave it within 0.5 %. The ringing after an ordinary move, the one
a shaper must cancel, is such a free decay too.

Model, over the decay windows ``w`` (from each stop of the reference to the next move, at
most :data:`MAX_WINDOW_S`), per channel ``c`` and time ``τ`` since the window's start::

    y_c(τ) = Σ_i e^{-ζ_i ω_i τ} (A_iwc cos ω_{d,i} τ + B_iwc sin ω_{d,i} τ) + e_wc,

with ``ω_{d,i} = ω_i √(1 − ζ_i²)``: the modes ``(ω_i, ζ_i)`` are shared by every window and
channel, each window has its own amplitudes, phases and offset (the state at the stop),
eliminated by linear least squares (variable projection). The model is exact for a linear
mode at rest, whatever the input before the window; no timing offset or input model enters.
Standard errors are those of the projected residual's Jacobian (Gauss-Newton,
white residual).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy import optimize

__all__ = ["FreeDecayFit", "decay_windows", "fit_free_decays"]

#: A window ends at the next move or this long after its stop, s: the arm's modes (ζ ω above
#: 3 s⁻¹) have decayed by e⁻³ within it.
MAX_WINDOW_S = 1.0
#: Samples after the stop left out (the last held sample and the one after it).
SKIP_SAMPLES = 2
#: Fewest samples of a usable window.
MIN_WINDOW_SAMPLES = 25
#: The reference has stopped where its acceleration is below this (rad/s²).
STILL_RAD_S2 = 1e-9
#: Each frequency is searched within this of its start in ``ln ω`` (a factor 1.35 either way).
LN_WN_RANGE = 0.3


@dataclass(frozen=True)
class FreeDecayFit:
    """Modes fitted to the free decays of one log.

    Attributes
    ----------
    wn_rad_s, zeta, wn_se_rad_s
        Per mode: natural frequency (rad/s), damping ratio and the frequency's standard error
        (rad/s; infinite where it stopped at the bound of the search).
    """

    wn_rad_s: tuple[float, ...]
    zeta: tuple[float, ...]
    wn_se_rad_s: tuple[float, ...]


def decay_windows(
    u: np.ndarray,
    dt_s: float,
    *,
    lag: int = 0,
    max_window_s: float = MAX_WINDOW_S,
    min_samples: int = MIN_WINDOW_SAMPLES,
) -> list[tuple[int, int]]:
    """The free-decay windows of a log: after each stop of the reference acceleration ``u``
    (rad/s², held per sample), delayed by ``lag`` samples (the input's timing offset), to
    the next move's start (also delayed) or ``max_window_s`` later; windows shorter than
    ``min_samples`` are dropped."""
    moving = np.abs(np.asarray(u, dtype=float)) > STILL_RAD_S2
    n = moving.size
    stops = np.flatnonzero(moving[:-1] & ~moving[1:]) + 1
    starts = np.flatnonzero(~moving[:-1] & moving[1:]) + 1
    longest = int(round(max_window_s / dt_s))
    out = []
    for stop in stops:
        later = starts[starts > stop]
        end = int(later[0]) if later.size else n
        begin = int(stop) + lag + SKIP_SAMPLES
        end = min(end + lag, n, begin + longest)
        if end - begin >= min_samples:
            out.append((begin, end))
    return out


def _basis(wn: float, zeta: float, tau: np.ndarray) -> np.ndarray:
    wd = wn * math.sqrt(max(1.0 - zeta * zeta, 1e-12))
    decay = np.exp(-zeta * wn * tau)
    return np.column_stack([decay * np.cos(wd * tau), decay * np.sin(wd * tau)])


def _residual(
    theta: np.ndarray, y: np.ndarray, windows: list[tuple[int, int]], dt_s: float
) -> np.ndarray:
    """Projected residual for ``theta = [ln ω_1, ζ_1, ln ω_2, ζ_2, …]``, all windows and
    channels stacked."""
    modes = [(math.exp(theta[2 * i]), theta[2 * i + 1]) for i in range(theta.size // 2)]
    parts = []
    for begin, end in windows:
        tau = np.arange(end - begin) * dt_s
        design = np.column_stack([*(_basis(w, z, tau) for w, z in modes), np.ones(tau.size)])
        block = y[begin:end]
        coef, *_ = np.linalg.lstsq(design, block, rcond=None)
        parts.append((block - design @ coef).ravel())
    return np.concatenate(parts)


def fit_free_decays(
    channels: np.ndarray,
    dt_s: float,
    windows: list[tuple[int, int]],
    start: list[tuple[float, float]],
) -> FreeDecayFit | None:
    """Fit the modes ``start`` (``(ω_n, ζ)`` each, e.g. the whole log's fit) to the free
    decays of ``channels`` (m/s², shape ``(n,)`` or ``(n, n_ch)``) in ``windows``
    (:func:`decay_windows`). ``None`` when there is no window or fewer samples than twice
    the unknowns."""
    y = np.asarray(channels, dtype=float)
    y = y[:, None] if y.ndim == 1 else y
    if not windows or not start:
        return None
    n_used = sum(end - begin for begin, end in windows) * y.shape[1]
    n_linear = len(windows) * y.shape[1] * (2 * len(start) + 1)
    n_free = 2 * len(start)
    if n_used < 2 * (n_linear + n_free):
        return None
    theta0 = np.array([v for w, z in start for v in (math.log(w), min(max(z, 1e-3), 0.95))])
    lower = np.array([v for w, _ in start for v in (math.log(w) - LN_WN_RANGE, 1e-4)])
    upper = np.array([v for w, _ in start for v in (math.log(w) + LN_WN_RANGE, 0.99)])
    result = optimize.least_squares(
        _residual, theta0, bounds=(lower, upper), args=(y, windows, dt_s), x_scale="jac"
    )
    jac = result.jac
    sigma2 = 2.0 * result.cost / max(n_used - n_linear - n_free, 1)
    try:
        variances = np.clip(np.diag(np.linalg.inv(jac.T @ jac) * sigma2), 0.0, None)
    except np.linalg.LinAlgError:
        variances = np.full(theta0.size, math.inf)
    se_log = np.sqrt(variances[0::2])
    # A frequency stopped at the bound of its search is not an estimate.
    at_bound = (result.x[0::2] <= lower[0::2] + 1e-6) | (result.x[0::2] >= upper[0::2] - 1e-6)
    se_log = np.where(at_bound, math.inf, se_log)
    wn = np.exp(result.x[0::2])
    return FreeDecayFit(
        wn_rad_s=tuple(float(v) for v in wn),
        zeta=tuple(float(v) for v in result.x[1::2]),
        wn_se_rad_s=tuple(float(v) for v in wn * se_log),
    )
