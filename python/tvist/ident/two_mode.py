"""Two-mode output-error fit: separates two modes that ring in the same direction.

When the base joint is excited in a pose where its own mode is heavily damped (small base
inertia, arm near vertical), the tangential acceleration rings mostly at the *shoulder* mode,
and the single-mode fit of eq. 17 returns the shoulder frequency, or a blend of both (the
paper's Fig. 22 situation). Fitting two modes plus a feedthrough ``d``,

``G(s) = Σ_{i=1,2} (a_i s + b_i)/(s² + 2ζ_i ω_i s + ω_i²) + d``,

to the same data separates them. ``d`` is the quasi-static response of the arm's faster
modes, which a base excitation also rings; without it the base frequency comes out 3-5 % low
on the twin. Like :mod:`tvist.ident.local_fit`, the numerator
coefficients, the feedthrough and an output offset are eliminated by linear least squares,
and the four ``(ω_i, ζ_i)`` are searched from the single-mode estimate plus a grid over the
second mode.

The second mode is *significant* if it lowers the residual sum of squares by at least
:data:`MIN_RSS_REDUCTION`, the two frequencies differ by at least :data:`MIN_FREQ_RATIO`, and
both are determined to within :data:`MAX_WN_REL_SE`.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np
from scipy import optimize

from tvist.ident.mode_estimates import ModeEstimate, TwoModeFit
from tvist.ident.zoh import least_squares_fit, shifted, zoh_responses

if TYPE_CHECKING:
    from tvist.ident.local_fit import LocalFit

__all__ = ["fit_two_modes"]

#: The second mode must remove at least this fraction of the single-mode residual energy.
MIN_RSS_REDUCTION = 0.2
#: Two modes closer than this frequency ratio are one mode.
MIN_FREQ_RATIO = 1.15
#: Largest relative standard error of either frequency for a significant split.
MAX_WN_REL_SE = 0.05


def _energy_shares(
    x: np.ndarray,
    u: np.ndarray,
    y_used: np.ndarray,
    mask: np.ndarray,
    dt_s: float,
    delay_s: float,
) -> tuple[tuple[float, float], np.ndarray]:
    """Fraction of the fitted response energy carried by each of the two modes, and the
    linear coefficients ``[k_b1, k_a1, k_b2, k_a2, d, offset]``."""
    blocks = [
        zoh_responses(math.exp(x[0]), x[1], u, dt_s, delay_s)[mask],
        zoh_responses(math.exp(x[2]), x[3], u, dt_s, delay_s)[mask],
    ]
    fed = shifted(u, int(round(delay_s / dt_s)))[mask]
    phi = np.column_stack([*blocks, fed, np.ones(int(mask.sum()))])
    beta = least_squares_fit(phi, y_used)
    parts = [blocks[0] @ beta[0:2], blocks[1] @ beta[2:4]]
    energy = [float(p @ p) for p in parts]
    total = sum(energy) or 1.0
    return (energy[0] / total, energy[1] / total), beta


def fit_two_modes(
    u: np.ndarray,
    y: np.ndarray,
    dt_s: float,
    single: LocalFit,
    *,
    mask: np.ndarray | None = None,
    f_min_hz: float = 1.0,
    f_max_hz: float = 100.0,
    n_grid: int = 30,
) -> TwoModeFit:
    """Fit two modes from target acceleration ``u`` to tangential acceleration ``y``.

    Parameters
    ----------
    u, y, dt_s, mask
        As for :func:`~tvist.ident.local_fit.fit_local`.
    single
        The single-mode fit of the same data (start, input delay and reference residual).
    f_min_hz, f_max_hz
        Band for the second mode (capped at 0.4 times the sampling rate).
    n_grid
        Grid points for the second mode's starting frequency.
    """
    u = np.asarray(u, dtype=float)
    delay_s = single.delay_s
    fed = shifted(u, int(round(delay_s / dt_s)))
    y = np.asarray(y, dtype=float)
    mask = np.ones(u.size, dtype=bool) if mask is None else np.asarray(mask, dtype=bool)
    y_used = y[mask]
    wn_lo = 2.0 * math.pi * f_min_hz
    wn_hi = 2.0 * math.pi * min(f_max_hz, 0.4 / dt_s)

    def residual(x: np.ndarray) -> np.ndarray:
        w1, z1, w2, z2 = math.exp(x[0]), x[1], math.exp(x[2]), x[3]
        phi = np.column_stack(
            [
                zoh_responses(w1, z1, u, dt_s, delay_s)[mask],
                zoh_responses(w2, z2, u, dt_s, delay_s)[mask],
                fed[mask],  # feedthrough: the quasi-static response of the faster modes
                np.ones(int(mask.sum())),
            ]
        )
        beta = least_squares_fit(phi, y_used)
        return y_used - phi @ beta

    w1 = min(max(single.wn_rad_s, wn_lo * 1.001), wn_hi / 1.001)
    z1 = min(max(single.zeta, 1e-3), 1.5)
    best = None
    for w2 in np.geomspace(wn_lo, wn_hi, n_grid):
        if abs(math.log(w2 / w1)) < math.log(MIN_FREQ_RATIO):
            continue
        for z2 in (0.05, 0.3):
            x = np.array([math.log(w1), z1, math.log(w2), z2])
            cost = float(np.sum(residual(x) ** 2))
            if best is None or cost < best[0]:
                best = (cost, x)
    assert best is not None
    lower = [math.log(wn_lo), 1e-3, math.log(wn_lo), 1e-3]
    upper = [math.log(wn_hi), 2.0, math.log(wn_hi), 2.0]
    res = optimize.least_squares(
        residual,
        np.clip(best[1], lower, upper),
        bounds=(lower, upper),
        x_scale=[0.05, 0.02, 0.05, 0.02],
        diff_step=1e-6,
    )
    rss2 = float(np.sum(res.fun**2))
    shares, beta = _energy_shares(res.x, u, y_used, mask, dt_s, delay_s)
    # fit % = 100 (1 - |r| / |y - ȳ|), so the single-mode residual energy is:
    rss1 = (1.0 - single.fit_percent / 100.0) ** 2 * float(np.sum((y_used - y_used.mean()) ** 2))
    dof = max(y_used.size - 10, 1)  # 4 nonlinear + 6 linear parameters
    try:
        cov = np.linalg.inv(res.jac.T @ res.jac) * rss2 / dof
        se = np.sqrt(np.clip(np.diag(cov), 0.0, None))
    except np.linalg.LinAlgError:
        se = np.full(4, np.inf)
    modes = []
    for k, i in enumerate((0, 2)):
        wn = math.exp(res.x[i])
        modes.append(
            ModeEstimate(
                wn_rad_s=wn,
                zeta=float(res.x[i + 1]),
                wn_se_rad_s=float(wn * se[i]),  # d(exp x) = exp(x) dx
                zeta_se=float(se[i + 1]),
                energy_share=shares[k],
                k_a=float(beta[2 * k + 1]),
                k_b=float(beta[2 * k]),
            )
        )
    modes.sort(key=lambda m: m.wn_rad_s)
    ratio = rss2 / rss1 if rss1 > 0 else 1.0
    significant = (
        ratio < 1.0 - MIN_RSS_REDUCTION
        and modes[1].wn_rad_s / modes[0].wn_rad_s >= MIN_FREQ_RATIO
        and all(m.wn_se_rad_s <= MAX_WN_REL_SE * m.wn_rad_s for m in modes)
        and all(m.zeta < 1.0 for m in modes)
    )
    return TwoModeFit(modes=(modes[0], modes[1]), rss_ratio=ratio, significant=bool(significant))
