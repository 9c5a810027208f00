"""Local second-order fit (eq. 17) from target joint acceleration to tangential acceleration.

The model is ``G(s) = (k_a s + k_b)/(s² + k_c s + k_d)`` with ``ω_n = √k_d`` and
``ζ = k_c/(2√k_d)`` (eq. 19), plus a constant output offset and an input timing offset
(``delay_s``, any real value of either sign). It is fitted by output-error (prediction-error)
minimisation: the model is simulated from the target acceleration and the sum of squared
differences to the measured tangential acceleration is minimised.

The input is the *interval-mean* target acceleration ``(qd[k+1] - qd[k]) / dt_s`` held over
``[t_k, t_{k+1})``, which integrates exactly to the logged target velocities wherever the
profile switches between samples (a real controller's ``movej`` switches between ticks; point
samples of ``target_qdd`` would then be up to one sample off at every switch and bias ζ high).
The mode is simulated exactly for that input and any sub-sample delay
(:mod:`tvist.ident.zoh`). Given ``(ω_n, ζ, delay)``, the output is linear in
``(k_a, k_b, offset)``; those are eliminated by linear least squares (variable projection):

1. a coarse grid over ``ω_n`` (log-spaced over the whole searchable band) and ``ζ``, and local
   refinement from the best few, well separated grid frequencies (multi-start), at zero delay;
2. a half-sample grid over the delay in ``±max_delay_s``, then joint refinement of
   ``(ω_n, ζ, delay)`` from the two best separated delays;
3. a final least-squares pass over all six parameters, whose Jacobian gives the standard
   errors: the larger of the white-residual estimate and a Newey-West estimate that accounts
   for the correlated residuals a real arm leaves (:func:`_standard_errors`).

Bad data raise ``ValueError`` (too short, no excitation, mostly saturated); doubtful results are
returned with ``low_confidence=True`` and the reasons. A log whose response is explained as
well by a rigid arm (``y = g u + offset``) as by a mode is flagged :data:`NO_RINGING`.
"""

from __future__ import annotations

import math
from dataclasses import MISSING, dataclass, field, fields
from typing import Any

import numpy as np
from scipy import optimize

from tvist.ident.mode_estimates import TwoModeFit
from tvist.ident.zoh import shifted, zoh_responses

__all__ = [
    "NO_RINGING",
    "FitOptions",
    "LocalFit",
    "fit_local",
    "interval_mean_acceleration",
    "saturated_samples",
]

#: Shortest log a local fit accepts, s, at any rate (500 samples at 500 Hz, 125 at 125 Hz;
#: never fewer than 100: :func:`min_samples_for`); the paper logs about 8 s.
MIN_DURATION_S = 1.0
#: The searched band ends at this fraction of the sampling rate (0.8 of Nyquist).
NYQUIST_FRACTION = 0.4
#: Reason (prefix) of a log whose response shows no mode above the noise.
NO_RINGING = "no ringing above noise"


def min_samples_for(dt_s: float) -> int:
    """Fewest samples a local fit accepts at sampling period ``dt_s``."""
    return max(int(math.ceil(MIN_DURATION_S / dt_s - 1e-9)), 100)


@dataclass(frozen=True)
class FitOptions:
    """Settings of the local fit and of its confidence checks.

    Attributes
    ----------
    f_min_hz, f_max_hz
        Band searched for the natural frequency. ``f_max_hz`` is also capped at 0.4 times the
        sampling rate.
    max_delay_s
        Largest timing offset between the target and the measured acceleration, s; searched
        in both directions (``±max_delay_s``) to a fraction of a sample.
    n_grid_freq
        Points of the coarse log-spaced frequency grid.
    grid_zeta
        Damping ratios of the coarse grid.
    n_starts
        Number of refinements started from the best separated grid minima.
    min_fit_percent
        Below this NRMSE fit (%), the result is flagged low-confidence.
    max_wn_rel_se
        Above this relative standard error of ``ω_n``, the result is flagged.
    max_zeta_rel_se
        Above this relative standard error of ``ζ`` (and above ``0.005`` absolute), flagged;
        so is a ``ζ`` less than 2 standard errors above zero, whatever the floor.
    max_saturated_fraction
        More saturated samples than this fraction is an error; fewer are excluded from the
        fit and flagged.
    min_ringing_snr_db
        The residual energy the mode removes beyond a response without a mode, relative to
        the energy left (dB); below it the result is flagged :data:`NO_RINGING`.
    min_confident_snr_db
        Below this ringing SNR (dB) a mode is reported but flagged: the residual is as large
        as the ringing it explains, so the result rests on the residual being white noise
        (measured on logs whose model is right at 20 dB noise: 7.6 dB and more; a log with a
        misplaced accelerometer column: -0.7 to 1.7 dB).
    """

    f_min_hz: float = 1.0
    f_max_hz: float = 100.0
    max_delay_s: float = 0.01
    n_grid_freq: int = 60
    grid_zeta: tuple[float, ...] = (0.05, 0.25)
    n_starts: int = 3
    min_fit_percent: float = 50.0
    max_wn_rel_se: float = 0.01
    max_zeta_rel_se: float = 0.1
    max_saturated_fraction: float = 0.05
    min_ringing_snr_db: float = -10.0
    min_confident_snr_db: float = 3.0


@dataclass(frozen=True)
class LocalFit:
    """Identified local dynamics of one mode (eqs. 17 and 19).

    Attributes
    ----------
    wn_rad_s, zeta
        Natural frequency (rad/s) and damping ratio.
    k_a, k_b, k_c, k_d
        Coefficients of eq. 17 (``k_c = 2 ζ ω_n``, ``k_d = ω_n²``).
    offset
        Constant output offset, m/s² (residual gravity after the standstill estimate).
    delay_s
        Timing offset of the input, s (positive: the response lags the logged target).
    fit_percent
        NRMSE fit ``100 (1 - |y - ŷ| / |y - mean(y)|)`` over the samples used, %.
    wn_se_rad_s, zeta_se
        Standard errors from the Jacobian of the final fit (white-residual assumption).
    n_samples, n_used
        Samples in the log and samples used (saturated ones excluded).
    low_confidence
        True if any check failed; ``reasons`` says which.
    joint
        Excited joint, if known.
    two_mode
        The two-mode fit of the same data, if made (:mod:`tvist.ident.two_mode`).
    ringing_snr_db
        Energy the mode explains beyond a rigid arm's response over the residual energy, dB.
    method
        ``"single-mode"`` (eq. 17) or ``"two-mode"`` (the base mode separated from a second
        mode that rings in the same log; ``k_a``, ``k_b``, ``offset`` are then those of the
        separated mode in the two-mode fit).
    apparent
        When ``method`` is ``"two-mode"``: the single-mode fit it replaced,
        ``{"wn_rad_s", "zeta", "low_confidence"}`` (1.0 if that fit was flagged).
    """

    wn_rad_s: float
    zeta: float
    k_a: float
    k_b: float
    k_c: float
    k_d: float
    offset: float
    delay_s: float
    fit_percent: float
    wn_se_rad_s: float
    zeta_se: float
    n_samples: int
    n_used: int
    low_confidence: bool
    reasons: tuple[str, ...] = field(default_factory=tuple)
    joint: int | None = None
    two_mode: TwoModeFit | None = None
    ringing_snr_db: float = float("nan")
    method: str = "single-mode"
    apparent: dict[str, float] | None = None

    @property
    def fn_hz(self) -> float:
        """Natural frequency, Hz (eq. 49)."""
        return self.wn_rad_s / (2.0 * math.pi)

    @property
    def fd_hz(self) -> float:
        """Damped natural frequency ``ω_n √(1-ζ²) / 2π``, Hz (NaN if ``ζ >= 1``)."""
        if self.zeta >= 1.0:
            return float("nan")
        return self.fn_hz * math.sqrt(1.0 - self.zeta**2)

    @property
    def reason(self) -> str:
        """The reasons joined into one line ("" when confident)."""
        return "; ".join(self.reasons)

    @property
    def no_ringing(self) -> bool:
        """True when the log shows no mode above the noise (flagged :data:`NO_RINGING`)."""
        return any(r.startswith(NO_RINGING) for r in self.reasons)

    def to_dict(self) -> dict[str, Any]:
        """Plain-Python form (JSON types only); :meth:`from_dict` reads it back."""
        out = {f.name: getattr(self, f.name) for f in fields(self)}
        out["reasons"] = list(self.reasons)
        out["two_mode"] = None if self.two_mode is None else self.two_mode.to_dict()
        out["apparent"] = None if self.apparent is None else dict(self.apparent)
        return out

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> LocalFit:
        """The fit from :meth:`to_dict`'s form (unknown keys, e.g. a record's, are ignored)."""
        known = {f.name for f in fields(cls)}
        kwargs = {k: v for k, v in data.items() if k in known}
        missing = {
            f.name
            for f in fields(cls)
            if f.default is MISSING and f.default_factory is MISSING and f.name not in kwargs
        }
        if missing:
            raise ValueError(f"local fit record lacks {', '.join(sorted(missing))}")
        kwargs["reasons"] = tuple(kwargs.get("reasons", ()))
        for name in ("k_a", "k_b", "offset"):
            if kwargs.get(name) is None:
                kwargs[name] = float("nan")
        if kwargs.get("two_mode") is not None:
            kwargs["two_mode"] = TwoModeFit.from_dict(kwargs["two_mode"])
        return cls(**kwargs)


class _Problem:
    """Output-error problem on the used samples: held input ``u``, output ``y``."""

    def __init__(self, u: np.ndarray, y: np.ndarray, mask: np.ndarray, dt_s: float) -> None:
        self.u, self.y, self.mask, self.dt_s = u, y, mask, dt_s
        self.y_used = y[mask]

    def regressors(self, wn: float, zeta: float, delay_s: float) -> np.ndarray:
        resp = zoh_responses(wn, zeta, self.u, self.dt_s, delay_s)[self.mask]
        return np.column_stack([resp, np.ones(resp.shape[0])])

    def projected(
        self, wn: float, zeta: float, delay_s: float
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Residual, linear coefficients ``[k_b, k_a, offset]`` and the regressors."""
        phi = self.regressors(wn, zeta, delay_s)
        # Normal equations on unit-norm columns: a 3x3 solve (cheaper than an SVD per call).
        scale = np.linalg.norm(phi, axis=0)
        scale[scale == 0.0] = 1.0
        phi_n = phi / scale
        beta = np.linalg.solve(phi_n.T @ phi_n, phi_n.T @ self.y_used) / scale
        return self.y_used - phi @ beta, beta, phi

    def cost(self, wn: float, zeta: float, delay_s: float) -> float:
        r = self.projected(wn, zeta, delay_s)[0]
        return float(r @ r)

    def full_residual(self, p: np.ndarray) -> np.ndarray:
        wn, zeta, delay_s, k_a, k_b, offset = p
        phi = self.regressors(wn, zeta, delay_s)
        return self.y_used - phi @ np.array([k_b, k_a, offset])

    def rigid_residual(self, delay_s: float) -> np.ndarray:
        """Residual of the best response without a mode: ``y`` a combination of the three
        held input samples around the delay (a mode much faster than the sampling, with any
        sub-sample timing) plus an offset."""
        d = int(math.floor(delay_s / self.dt_s))
        taps = [shifted(self.u, d + k)[self.mask] for k in (0, 1, 2)]
        phi = np.column_stack([*taps, np.ones(self.y_used.size)])
        beta, *_ = np.linalg.lstsq(phi, self.y_used, rcond=None)
        return self.y_used - phi @ beta


def _standard_errors(jac: np.ndarray, residual: np.ndarray, max_lag: int) -> np.ndarray:
    """Standard errors of least-squares parameters that stay honest for coloured residuals.

    The larger of the white-residual estimate ``σ² (JᵀJ)⁻¹`` and the Newey-West
    (heteroscedasticity- and autocorrelation-consistent) sandwich
    ``(JᵀJ)⁻¹ S (JᵀJ)⁻¹``, ``S = Σ_{|l|<=L} (1 - |l|/(L+1)) Σ_k g_k g_{k-l}ᵀ`` with
    ``g_k = J_k r_k``. Model mismatch leaves residuals correlated over about a period of the
    mode; the white estimate then understates the uncertainty several-fold.
    """
    n, p = jac.shape
    dof = max(n - p, 1)
    try:
        inv = np.linalg.inv(jac.T @ jac)
    except np.linalg.LinAlgError:
        return np.full(p, np.inf)
    white = np.diag(inv) * float(residual @ residual) / dof
    g = jac * residual[:, None]
    s = g.T @ g
    for lag in range(1, min(max_lag, n - 1) + 1):
        c = g[lag:].T @ g[:-lag]
        s += (1.0 - lag / (max_lag + 1.0)) * (c + c.T)
    hac = np.diag(inv @ s @ inv) * n / dof
    return np.sqrt(np.clip(np.maximum(white, hac), 0.0, None))


def saturated_samples(
    accel: np.ndarray, *, limit_m_s2: float | None = None, min_plateau: int = 3
) -> np.ndarray:
    """Boolean mask of samples where any accelerometer axis is clipped.

    A sample is saturated if ``|a| >= limit_m_s2`` on any axis (when a limit is known), or if
    it sits on a plateau at the axis' extreme value: the same extreme value reached on at least
    ``min_plateau`` samples, which a continuous signal with noise does not do.

    Parameters
    ----------
    accel
        Raw readings, shape (n_samples, n_axes).
    limit_m_s2
        Known sensor range, m/s² (optional).
    min_plateau
        Samples at the extreme that reveal clipping.
    """
    accel = np.asarray(accel, dtype=float)
    mask = np.zeros(accel.shape[0], dtype=bool)
    if limit_m_s2 is not None:
        mask |= np.any(np.abs(accel) >= limit_m_s2, axis=1)
    for col in accel.T:
        for extreme in (col.max(), col.min()):
            at = col == extreme
            centre = np.median(col)
            if extreme != centre and np.count_nonzero(at) >= min_plateau:
                mask |= at
    return mask


def _nrmse_fit(y: np.ndarray, residual: np.ndarray) -> float:
    spread = np.linalg.norm(y - y.mean())
    if spread == 0:
        return float("-inf")
    return float(100.0 * (1.0 - np.linalg.norm(residual) / spread))


def _grid_starts(problem: _Problem, wn_grid: np.ndarray, zetas: tuple[float, ...], n: int):
    """Best ``(ω_n, ζ)`` grid points at ``n`` well separated frequencies (local minima first)."""
    cost = np.array([[problem.cost(wn, z, 0.0) for z in zetas] for wn in wn_grid])
    best_z = np.argmin(cost, axis=1)
    best = cost[np.arange(len(wn_grid)), best_z]
    # Local minima along frequency, best first; fall back to the global order.
    interior = np.flatnonzero(np.r_[True, best[1:] < best[:-1]] & np.r_[best[:-1] < best[1:], True])
    order = list(interior[np.argsort(best[interior])]) + list(np.argsort(best))
    chosen: list[int] = []
    for i in order:
        if all(abs(math.log(wn_grid[i] / wn_grid[j])) > 0.1 for j in chosen):
            chosen.append(int(i))
        if len(chosen) == n:
            break
    return [(float(wn_grid[i]), float(zetas[best_z[i]])) for i in chosen]


def _refine(
    problem: _Problem,
    start: tuple[float, float, float],
    wn_bounds: tuple[float, float],
    delay_bounds: tuple[float, float] | None,
) -> tuple[float, float, float, float]:
    """Variable-projection refinement over ``(log ω_n, ζ[, delay])``; (cost, ω_n, ζ, delay).

    With ``delay_bounds = None`` the delay stays at ``start[2]``.
    """
    wn_lo, wn_hi = wn_bounds
    wn0, zeta0, delay0 = start
    x0 = [math.log(min(max(wn0, wn_lo * 1.001), wn_hi / 1.001)), zeta0]
    lower, upper = [math.log(wn_lo), 1e-4], [math.log(wn_hi), 2.0]
    scale = [0.05, 0.02]
    if delay_bounds is not None:
        x0.append(min(max(delay0, delay_bounds[0]), delay_bounds[1]))
        lower.append(delay_bounds[0])
        upper.append(delay_bounds[1])
        scale.append(problem.dt_s / 4)

    def residual(x: np.ndarray) -> np.ndarray:
        delay = x[2] if delay_bounds is not None else delay0
        return problem.projected(math.exp(x[0]), x[1], delay)[0]

    res = optimize.least_squares(
        residual,
        np.array(x0),
        bounds=(lower, upper),
        x_scale=scale,
        diff_step=1e-6,
        xtol=1e-9,
        ftol=1e-10,
    )
    delay = float(res.x[2]) if delay_bounds is not None else delay0
    return float(2.0 * res.cost), math.exp(res.x[0]), float(res.x[1]), delay


# Values that overflow the fit's arithmetic (a corrupt cell of 1e300 is finite, so it gets
# here) make it fail with a ValueError (a singular system, a non-finite cost); numpy's
# RuntimeWarnings on the way would only be printed before that one-line error.
@np.errstate(over="ignore", invalid="ignore", divide="ignore")
def fit_local(
    u: np.ndarray,
    y: np.ndarray,
    dt_s: float,
    *,
    mask: np.ndarray | None = None,
    options: FitOptions | None = None,
    joint: int | None = None,
    extra_reasons: tuple[str, ...] = (),
) -> LocalFit:
    """Fit eq. 17 from input ``u`` (target joint acceleration) to output ``y``.

    Parameters
    ----------
    u
        Target acceleration of the excited joint, rad/s², shape (n_samples,); sample ``k``
        holds over ``[t_k, t_{k+1})`` (the interval mean ``(qd[k+1] - qd[k]) / dt_s``,
        :func:`interval_mean_acceleration`).
    y
        Measured tangential acceleration, m/s², shape (n_samples,).
    dt_s
        Sampling period, s (uniform).
    mask
        Samples to use in the cost (default all); the model is still simulated through the
        excluded ones.
    options
        Search band and confidence thresholds.
    joint
        Stored in the result.
    extra_reasons
        Low-confidence reasons found before the fit (e.g. saturation).

    Returns
    -------
    LocalFit

    Raises
    ------
    ValueError
        Shapes differ, non-finite values, fewer samples than :func:`min_samples_for` the rate, no
        excitation, or a band that the sampling rate cannot resolve.
    """
    opts = options or FitOptions()
    u = np.asarray(u, dtype=float)
    y = np.asarray(y, dtype=float)
    if u.ndim != 1 or u.shape != y.shape:
        raise ValueError(f"u and y must be 1-D of equal length, got {u.shape} and {y.shape}")
    if not (np.all(np.isfinite(u)) and np.all(np.isfinite(y))):
        raise ValueError("u and y must be finite")
    if not (math.isfinite(dt_s) and dt_s > 0):
        raise ValueError(f"dt_s must be finite and > 0, got {dt_s}")
    mask = np.ones(u.size, dtype=bool) if mask is None else np.asarray(mask, dtype=bool)
    n_used = int(np.count_nonzero(mask))
    min_samples = min_samples_for(dt_s)
    if u.size < min_samples or n_used < min_samples:
        raise ValueError(
            f"log too short for a local fit: {n_used} usable of {u.size} samples, need at "
            f"least {min_samples} ({min_samples * dt_s:.2f} s at this rate)"
        )
    n_steps = _acceleration_changes(u)
    if np.max(np.abs(u)) == 0.0 or n_steps == 0:
        raise ValueError("no excitation: the target joint acceleration never changes")
    if np.std(y[mask]) == 0.0:
        raise ValueError("no response: the tangential acceleration is constant")

    wn_lo = 2.0 * math.pi * opts.f_min_hz
    wn_hi = 2.0 * math.pi * min(opts.f_max_hz, NYQUIST_FRACTION / dt_s)
    if not wn_lo < wn_hi:
        raise ValueError(
            f"search band {opts.f_min_hz}-{opts.f_max_hz} Hz is empty at {1 / dt_s:.0f} Hz sampling"
        )
    wn_grid = np.geomspace(wn_lo, wn_hi, opts.n_grid_freq)
    if not (math.isfinite(opts.max_delay_s) and opts.max_delay_s >= 0):
        raise ValueError(f"max_delay_s must be finite and >= 0, got {opts.max_delay_s}")
    delay_bounds = (-opts.max_delay_s, opts.max_delay_s) if opts.max_delay_s > 0 else None

    # 1. Multi-start over frequency at zero delay.
    problem = _Problem(u, y, mask, dt_s)
    starts = _grid_starts(problem, wn_grid, opts.grid_zeta, opts.n_starts)
    results = [_refine(problem, (wn, z, 0.0), (wn_lo, wn_hi), None) for wn, z in starts]
    _, wn_b, z_b, _ = min(results)
    # 2. The timing offset, both directions: a half-sample grid at the best mode so far, then
    # joint refinement of (ω_n, ζ, delay) from the two best separated delays.
    if delay_bounds is not None:
        n_half = int(math.floor(opts.max_delay_s / (dt_s / 2)))
        delays = (dt_s / 2) * np.arange(-n_half, n_half + 1)
        ranked = sorted(delays, key=lambda d: problem.cost(wn_b, z_b, float(d)))
        chosen = [float(ranked[0])]
        for d in ranked[1:]:
            if abs(d - chosen[0]) > dt_s:
                chosen.append(float(d))
                break
        for d in chosen:
            results.append(_refine(problem, (wn_b, z_b, d), (wn_lo, wn_hi), delay_bounds))
    _, wn_b, z_b, delay_b = min(results)

    # 3. Final pass over all parameters for the Jacobian (and any last improvement); the
    # delay is left out when it is fixed.
    _, beta, _ = problem.projected(wn_b, z_b, delay_b)
    free = np.ones(6, dtype=bool)
    free[2] = delay_bounds is not None
    full = np.array([wn_b, z_b, delay_b, beta[1], beta[0], beta[2]])
    lo = np.array([wn_lo, 1e-4, -opts.max_delay_s, -np.inf, -np.inf, -np.inf])[free]
    hi = np.array([wn_hi, 2.0, opts.max_delay_s, np.inf, np.inf, np.inf])[free]

    def residual_of(p: np.ndarray) -> np.ndarray:
        x = full.copy()
        x[free] = p
        return problem.full_residual(x)

    final = optimize.least_squares(
        residual_of,
        np.clip(full[free], lo, hi),
        bounds=(lo, hi),
        x_scale="jac",
        diff_step=1e-7,
        xtol=1e-12,
        ftol=1e-12,
    )
    full[free] = final.x
    wn, zeta, delay, k_a, k_b, offset = (float(v) for v in full)
    residual = final.fun
    # Residual correlation reaches over about two periods of the mode.
    max_lag = int(min(max(2.0 * 2.0 * math.pi / (wn * dt_s), 10.0), 400.0))
    se = _standard_errors(final.jac, residual, max_lag)
    wn_se, zeta_se = float(se[0]), float(se[1])
    fit = _nrmse_fit(problem.y_used, residual)
    rigid = problem.rigid_residual(delay)
    ringing_energy = max(float(rigid @ rigid) - float(residual @ residual), 0.0)
    noise_energy = max(float(residual @ residual), 1e-300)
    ringing_snr_db = 10.0 * math.log10(max(ringing_energy / noise_energy, 1e-10))

    reasons = list(extra_reasons)
    if ringing_snr_db < opts.min_ringing_snr_db:
        reasons.append(
            f"{NO_RINGING}: the mode's ringing is {-ringing_snr_db:.1f} dB below the "
            f"residual noise (needs at least {opts.min_ringing_snr_db:.0f} dB)"
        )
    elif ringing_snr_db < opts.min_confident_snr_db:
        reasons.append(
            f"weak ringing: the mode's ringing is {ringing_snr_db:+.1f} dB against the "
            f"residual noise (needs at least {opts.min_confident_snr_db:+.0f} dB)"
        )
    if fit < opts.min_fit_percent:
        reasons.append(f"poor fit: {fit:.1f} % < {opts.min_fit_percent:.0f} %")
    if not wn_se <= opts.max_wn_rel_se * wn:
        reasons.append(f"uncertain frequency: standard error {100 * wn_se / wn:.2f} % of ω_n")
    if not zeta_se <= max(opts.max_zeta_rel_se * zeta, 0.005):
        reasons.append(f"uncertain damping: standard error {zeta_se:.4f}")
    elif not zeta >= 2.0 * zeta_se:
        reasons.append(
            f"uncertain damping: ζ = {zeta:.4f} ± {zeta_se:.4f} is not 2 standard errors above zero"
        )
    if wn < wn_lo * 1.02 or wn > wn_hi / 1.02:
        reasons.append(
            f"frequency {wn / (2 * math.pi):.2f} Hz at the edge of the searched band "
            f"{wn_lo / (2 * math.pi):.2f}-{wn_hi / (2 * math.pi):.2f} Hz"
        )
    if zeta >= 1.0:
        reasons.append(f"overdamped (ζ = {zeta:.3f}): no vibration mode found")
    elif zeta <= 2e-4:
        reasons.append("damping at the lower search bound")
    if n_steps < 6:
        reasons.append(f"weak excitation: only {n_steps} acceleration changes")
    return LocalFit(
        wn_rad_s=wn,
        zeta=zeta,
        k_a=k_a,
        k_b=k_b,
        k_c=2.0 * zeta * wn,
        k_d=wn**2,
        offset=offset,
        delay_s=delay,
        fit_percent=fit,
        wn_se_rad_s=wn_se,
        zeta_se=zeta_se,
        n_samples=int(u.size),
        n_used=n_used,
        low_confidence=bool(reasons),
        reasons=tuple(reasons),
        joint=joint,
        ringing_snr_db=ringing_snr_db,
    )


def _acceleration_changes(u: np.ndarray) -> int:
    """Number of distinct changes of the acceleration (a switch between samples spreads over
    the interval mean and counts once)."""
    changing = np.abs(np.diff(u)) > 1e-6 * max(float(np.max(np.abs(u))), 1e-300)
    return int(np.count_nonzero(changing[1:] & ~changing[:-1]) + bool(changing[0]))


def interval_mean_acceleration(target_qd: np.ndarray, dt_s: float) -> np.ndarray:
    """Mean acceleration over each sample interval, ``(qd[k+1] - qd[k]) / dt_s``, rad/s².

    Sample ``k`` holds on ``[t_k, t_{k+1})``; the last sample repeats the one before. Unlike
    point samples of the target acceleration, this is exact for a profile whose acceleration
    switches anywhere between samples: it integrates to the logged velocities.
    """
    qd = np.asarray(target_qd, dtype=float)
    mean = np.diff(qd) / dt_s
    return np.append(mean, mean[-1] if mean.size else 0.0)
