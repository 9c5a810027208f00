"""Local second-order fit (eq. 17) from target joint acceleration to tangential acceleration.

The model is ``G(s) = (k_a s + k_b)/(s² + k_c s + k_d)`` with ``ω_n = √k_d`` and
``ζ = k_c/(2√k_d)`` (eq. 19), plus a constant output offset and a whole-sample input delay.
It is fitted by output-error (prediction-error) minimisation: the model is simulated from the
target acceleration and the sum of squared differences to the measured tangential acceleration
is minimised.

The input is held constant over each sample (zero-order hold), so the model is simulated
exactly by its ZOH discretisation. Given ``(ω_n, ζ)``, the output is linear in
``(k_a, k_b, offset)``; those are eliminated by linear least squares (variable projection), so
the nonlinear search runs over two parameters only:

1. a coarse grid over ``ω_n`` (log-spaced over the whole searchable band) and ``ζ``;
2. local refinement with ``scipy.optimize.least_squares`` from the best few, well separated
   grid frequencies (multi-start), for every input delay up to ``max_delay_s``;
3. a final least-squares pass over all five parameters, whose Jacobian gives the standard
   errors (``σ² (JᵀJ)⁻¹`` with ``σ²`` the residual variance; the residuals of a real arm are
   not white, so these are lower bounds).

Bad data raise ``ValueError`` (too short, no excitation, mostly saturated); doubtful results are
returned with ``low_confidence=True`` and the reasons.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field, replace
from typing import TYPE_CHECKING

import numpy as np
from scipy import linalg, optimize, signal

from tvist.ident.logs import Record
from tvist.ident.preprocess import (
    MIN_STANDSTILL_SAMPLES,
    KinematicModel,
    TangentialAcceleration,
    tangential_acceleration,
)

if TYPE_CHECKING:
    from tvist.ident.two_mode import TwoModeFit

__all__ = [
    "FitOptions",
    "LocalFit",
    "fit_local",
    "identify_local",
    "saturated_samples",
]

#: Fewest samples a local fit accepts (1 s at 500 Hz; the paper logs about 8 s).
MIN_SAMPLES = 500


@dataclass(frozen=True)
class FitOptions:
    """Settings of the local fit and of its confidence checks.

    Attributes
    ----------
    f_min_hz, f_max_hz
        Band searched for the natural frequency. ``f_max_hz`` is also capped at 0.4 times the
        sampling rate.
    max_delay_s
        Largest input delay (target to measured acceleration) tried, s; whole samples.
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
        Above this relative standard error of ``ζ`` (and above ``0.005`` absolute), flagged.
    max_saturated_fraction
        More saturated samples than this fraction is an error; fewer are excluded from the
        fit and flagged.
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
        Input delay chosen, s.
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
        The two-mode fit of the same data, if requested (:mod:`tvist.ident.two_mode`).
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

    def to_dict(self) -> dict:
        """Plain-Python form (JSON-serialisable)."""
        out = asdict(self)
        out["reasons"] = list(self.reasons)
        return out


def _zoh_matrices(wn: float, zeta: float, dt_s: float) -> tuple[np.ndarray, np.ndarray]:
    """``(A_d, B_d)`` of ``ÿ + 2ζω ẏ + ω² y = u`` held over ``dt_s``, state ``[y, ẏ]``.

    Sylvester's formula with the eigenvalues ``λ_1,2 = -ζω ± ω√(ζ²-1)`` (complex for ζ < 1),
    ``e^{At} = c_0 I + c_1 A`` with ``c_0 = (λ_1 e^{λ_2 t} - λ_2 e^{λ_1 t})/(λ_1 - λ_2)`` and
    ``c_1 = (e^{λ_1 t} - e^{λ_2 t})/(λ_1 - λ_2)``, and ``B_d = A⁻¹ (A_d - I) B``. Near
    critical damping the eigenvalues merge and the augmented matrix exponential is used.
    """
    a = np.array([[0.0, 1.0], [-(wn**2), -2.0 * zeta * wn]])
    root = wn * np.sqrt(complex(zeta * zeta - 1.0))
    if abs(root) < 1e-4 * wn:
        m = np.zeros((3, 3))
        m[:2, :2] = a
        m[1, 2] = 1.0
        e = linalg.expm(m * dt_s)
        return e[:2, :2], e[:2, 2]
    l1, l2 = -zeta * wn + root, -zeta * wn - root
    e1, e2 = np.exp(l1 * dt_s), np.exp(l2 * dt_s)
    c0 = ((l1 * e2 - l2 * e1) / (l1 - l2)).real
    c1 = ((e1 - e2) / (l1 - l2)).real
    ad = c0 * np.eye(2) + c1 * a
    # A⁻¹ (A_d - I) [0, 1]ᵀ with A⁻¹ = [[-2ζ/ω, -1/ω²], [1, 0]]
    d = ad - np.eye(2)
    col = d[:, 1]
    bd = np.array([-2.0 * zeta / wn * col[0] - col[1] / wn**2, col[0]])
    return ad, bd


def _zoh_responses(wn: float, zeta: float, u: np.ndarray, dt_s: float) -> np.ndarray:
    """Exact ZOH responses of ``1/den`` and ``s/den`` to ``u``, shape (n_samples, 2).

    State ``x = [y, ẏ]`` of ``ÿ + 2ζω ẏ + ω² y = u``: ``1/den`` is ``x_0`` and ``s/den`` is
    ``x_1``. The recursion ``x[k+1] = A_d x[k] + B_d u[k]`` is run by ``lfilter`` on the
    equivalent transfer functions.
    """
    ad, bd = _zoh_matrices(wn, zeta, dt_s)
    # Denominator: characteristic polynomial of A_d. Numerators: C adj(zI - A_d) B_d with
    # C = [1, 0] or [0, 1] (strictly proper: x[k] depends on u up to k-1).
    a1 = -(ad[0, 0] + ad[1, 1])
    a2 = ad[0, 0] * ad[1, 1] - ad[0, 1] * ad[1, 0]
    den = np.array([1.0, a1, a2])
    num0 = np.array([0.0, bd[0], ad[0, 1] * bd[1] - ad[1, 1] * bd[0]])
    num1 = np.array([0.0, bd[1], ad[1, 0] * bd[0] - ad[0, 0] * bd[1]])
    return np.column_stack([signal.lfilter(num0, den, u), signal.lfilter(num1, den, u)])


def _delayed(u: np.ndarray, delay_samples: int) -> np.ndarray:
    if delay_samples == 0:
        return u
    return np.concatenate([np.zeros(delay_samples), u[:-delay_samples]])


class _Problem:
    """Output-error problem on the used samples; ``u`` already delayed."""

    def __init__(self, u: np.ndarray, y: np.ndarray, mask: np.ndarray, dt_s: float) -> None:
        self.u, self.y, self.mask, self.dt_s = u, y, mask, dt_s
        self.y_used = y[mask]

    def regressors(self, wn: float, zeta: float) -> np.ndarray:
        resp = _zoh_responses(wn, zeta, self.u, self.dt_s)[self.mask]
        return np.column_stack([resp, np.ones(resp.shape[0])])

    def projected(self, wn: float, zeta: float) -> tuple[np.ndarray, np.ndarray]:
        """Residual and linear coefficients ``[k_b, k_a, offset]`` for ``(ω_n, ζ)``."""
        phi = self.regressors(wn, zeta)
        # Normal equations on unit-norm columns: a 3x3 solve (cheaper than an SVD per call).
        scale = np.linalg.norm(phi, axis=0)
        scale[scale == 0.0] = 1.0
        phi_n = phi / scale
        beta = np.linalg.solve(phi_n.T @ phi_n, phi_n.T @ self.y_used) / scale
        return self.y_used - phi @ beta, beta

    def full_residual(self, p: np.ndarray) -> np.ndarray:
        wn, zeta, k_a, k_b, offset = p
        phi = self.regressors(wn, zeta)
        return self.y_used - phi @ np.array([k_b, k_a, offset])


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
    cost = np.array(
        [[float(np.sum(problem.projected(wn, z)[0] ** 2)) for z in zetas] for wn in wn_grid]
    )
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


def _refine(problem: _Problem, wn0: float, zeta0: float, wn_lo: float, wn_hi: float):
    """Variable-projection refinement over ``(log ω_n, ζ)``; returns (cost, ω_n, ζ)."""

    def residual(x: np.ndarray) -> np.ndarray:
        return problem.projected(math.exp(x[0]), x[1])[0]

    x0 = np.array([math.log(min(max(wn0, wn_lo * 1.001), wn_hi / 1.001)), zeta0])
    res = optimize.least_squares(
        residual,
        x0,
        bounds=([math.log(wn_lo), 1e-4], [math.log(wn_hi), 2.0]),
        x_scale=[0.05, 0.02],
        diff_step=1e-6,
        xtol=1e-9,
        ftol=1e-10,
    )
    return float(2.0 * res.cost), math.exp(res.x[0]), float(res.x[1])


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
        Target acceleration of the excited joint, rad/s², held over each sample,
        shape (n_samples,).
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
        Shapes differ, non-finite values, fewer than :data:`MIN_SAMPLES` samples, no
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
    if u.size < MIN_SAMPLES or n_used < MIN_SAMPLES:
        raise ValueError(
            f"log too short for a local fit: {n_used} usable of {u.size} samples, need at "
            f"least {MIN_SAMPLES} ({MIN_SAMPLES * dt_s:.2f} s at this rate)"
        )
    n_steps = int(np.count_nonzero(np.abs(np.diff(u)) > 1e-9))
    if np.max(np.abs(u)) == 0.0 or n_steps == 0:
        raise ValueError("no excitation: the target joint acceleration never changes")
    if np.std(y[mask]) == 0.0:
        raise ValueError("no response: the tangential acceleration is constant")

    wn_lo = 2.0 * math.pi * opts.f_min_hz
    wn_hi = 2.0 * math.pi * min(opts.f_max_hz, 0.4 / dt_s)
    if not wn_lo < wn_hi:
        raise ValueError(
            f"search band {opts.f_min_hz}-{opts.f_max_hz} Hz is empty at {1 / dt_s:.0f} Hz sampling"
        )
    wn_grid = np.geomspace(wn_lo, wn_hi, opts.n_grid_freq)

    # Multi-start over frequency at zero delay, then the delay search from the best start.
    problem0 = _Problem(u, y, mask, dt_s)
    starts = _grid_starts(problem0, wn_grid, opts.grid_zeta, opts.n_starts)
    results = [_refine(problem0, wn, z, wn_lo, wn_hi) + (0,) for wn, z in starts]
    max_delay = int(round(opts.max_delay_s / dt_s))
    _, wn_b, z_b, _ = min(results)
    # Rank the delays by the cost at the best mode so far; refine the three most promising.
    problems = {d: _Problem(_delayed(u, d), y, mask, dt_s) for d in range(1, max_delay + 1)}
    ranked = sorted(problems, key=lambda d: float(np.sum(problems[d].projected(wn_b, z_b)[0] ** 2)))
    for d in ranked[:3]:
        results.append(_refine(problems[d], wn_b, z_b, wn_lo, wn_hi) + (d,))
    _, wn_b, z_b, delay = min(results)

    # Final pass over all parameters for the Jacobian (and any last improvement).
    problem = _Problem(_delayed(u, delay), y, mask, dt_s)
    _, beta = problem.projected(wn_b, z_b)
    p0 = np.array([wn_b, z_b, beta[1], beta[0], beta[2]])
    lo = [wn_lo, 1e-4, -np.inf, -np.inf, -np.inf]
    hi = [wn_hi, 2.0, np.inf, np.inf, np.inf]
    final = optimize.least_squares(
        problem.full_residual,
        np.clip(p0, lo, hi),
        bounds=(lo, hi),
        x_scale="jac",
        diff_step=1e-7,
        xtol=1e-12,
        ftol=1e-12,
    )
    wn, zeta, k_a, k_b, offset = (float(v) for v in final.x)
    residual = final.fun
    dof = max(n_used - 5, 1)
    sigma2 = float(residual @ residual) / dof
    jtj = final.jac.T @ final.jac
    try:
        cov = np.linalg.inv(jtj) * sigma2
        se = np.sqrt(np.clip(np.diag(cov), 0.0, None))
        wn_se, zeta_se = float(se[0]), float(se[1])
    except np.linalg.LinAlgError:
        wn_se = zeta_se = float("inf")
    fit = _nrmse_fit(problem.y_used, residual)

    reasons = list(extra_reasons)
    if fit < opts.min_fit_percent:
        reasons.append(f"poor fit: {fit:.1f} % < {opts.min_fit_percent:.0f} %")
    if not wn_se <= opts.max_wn_rel_se * wn:
        reasons.append(f"uncertain frequency: standard error {100 * wn_se / wn:.2f} % of ω_n")
    if not zeta_se <= max(opts.max_zeta_rel_se * zeta, 0.005):
        reasons.append(f"uncertain damping: standard error {zeta_se:.4f}")
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
        delay_s=delay * dt_s,
        fit_percent=fit,
        wn_se_rad_s=wn_se,
        zeta_se=zeta_se,
        n_samples=int(u.size),
        n_used=n_used,
        low_confidence=bool(reasons),
        reasons=tuple(reasons),
        joint=joint,
    )


def identify_local(
    record: Record,
    joint: int,
    robot: KinematicModel,
    *,
    options: FitOptions | None = None,
    accel_frame: str = "flange",
    accel_limit_m_s2: float | None = None,
    min_standstill_samples: int = MIN_STANDSTILL_SAMPLES,
    two_modes: bool = False,
) -> LocalFit:
    """Identify ``(ω_n, ζ)`` of the mode excited through ``joint`` from one log.

    Preprocesses the accelerometer (eqs. 12-13, :func:`tangential_acceleration`), excludes
    saturated samples, and fits eq. 17 (:func:`fit_local`).

    Parameters
    ----------
    record
        Log of one excitation (standstill first), e.g. from :func:`read_rtde_csv`.
    joint
        Excited joint (0 = base, 1 = shoulder).
    robot
        Kinematic model, e.g. ``tvist.robots.ur5e(payload_kg, payload_com_m)``.
    options
        Fit settings.
    accel_frame
        ``"flange"`` (raw sensor frame) or ``"base"``.
    accel_limit_m_s2
        Known accelerometer range, for the saturation check (optional).
    min_standstill_samples
        Fewest initial standstill samples accepted for the gravity estimate.
    two_modes
        Also fit two modes (:func:`tvist.ident.two_mode.fit_two_modes`) and attach the result
        as ``two_mode``.

    Raises
    ------
    ValueError
        Non-uniform sampling, no standstill, too short, no excitation or mostly saturated
        accelerometer.
    """
    opts = options or FitOptions()
    step = np.diff(record.t_s)
    dt = record.dt_s
    if np.any(np.abs(step - dt) > 0.25 * dt):
        raise ValueError(
            "the log is not uniformly sampled (skipped samples?); read it with "
            "read_rtde_csv(..., resample=True)"
        )
    tangential: TangentialAcceleration = tangential_acceleration(
        record,
        joint,
        robot,
        accel_frame=accel_frame,  # type: ignore[arg-type]
        min_standstill_samples=min_standstill_samples,
    )
    saturated = saturated_samples(record.tool_accel, limit_m_s2=accel_limit_m_s2)
    reasons: tuple[str, ...] = ()
    n_sat = int(np.count_nonzero(saturated))
    if n_sat:
        fraction = n_sat / record.n_samples
        if fraction > opts.max_saturated_fraction:
            raise ValueError(
                f"accelerometer saturated on {n_sat} of {record.n_samples} samples "
                f"({100 * fraction:.1f} %); lower the excitation's acceleration"
            )
        reasons = (f"accelerometer saturated on {n_sat} samples (excluded from the fit)",)
    fit = fit_local(
        tangential.target_qdd,
        tangential.psi,
        dt,
        mask=~saturated,
        options=opts,
        joint=joint,
        extra_reasons=reasons,
    )
    if two_modes:
        from tvist.ident.two_mode import fit_two_modes

        split = fit_two_modes(
            tangential.target_qdd,
            tangential.psi,
            dt,
            fit,
            mask=~saturated,
            f_min_hz=opts.f_min_hz,
            f_max_hz=opts.f_max_hz,
        )
        fit = replace(fit, two_mode=split)
    return fit
