"""Every mode that rings in one excitation log, each with its direction at the flange.

An excitation of the base or the shoulder rings more than that joint's own mode: at folded
poses an elbow-dominated mode, the other of base and shoulder, a bending link. This module
fits as many modes as ring above the noise (1 to :data:`MAX_MODES`) to the whole flange
acceleration of the log, not only its tangential component:

- **Channels.** The gravity-free base-frame flange acceleration (eq. 12,
  :func:`~tvist.ident.preprocess.tangential_acceleration`) is read in the frame that moves
  with the excited joint ``j``: its tangent ``t`` (Jacobian column ``j`` at the flange), its
  axis ``z`` and ``n = z × t``. In that frame a mode's direction is fixed while the joint
  swings ±10°.
- **Model.** Each channel is ``Σ_i (a_i s + b_i)/(s² + 2ζ_i ω_i s + ω_i²) u + d u + c q̇_j² +
  e``: the modes share ``(ω_i, ζ_i)`` over the three channels, each channel has its own
  numerators, a feedthrough and its rate (the rigid arm's and the faster modes' quasi-static
  response), a centripetal term, what is left of gravity and the sensor bias (linear and
  quadratic in the joint's swing) and an offset, all eliminated by linear least squares (variable
  projection). Input, exact sampled responses and the timing offset are those of the local
  fit (:mod:`tvist.ident.local_fit`, :mod:`tvist.ident.zoh`).
- **Model order.** Modes are added one at a time, each candidate started from a grid over the
  band and from splitting each mode already found in two; the next mode is kept only if it
  removes at least :data:`MIN_RSS_REDUCTION` of the residual energy, stands
  :data:`MIN_FREQ_RATIO` apart from the others and every mode stays resolved (frequency
  standard error under :data:`MAX_WN_REL_SE`, ζ < 0.9).
- **Merged neighbours.** Two modes closer than the fit can resolve come out as one mode with
  a damping ratio too high for either. A mode is flagged when the best fit with one mode more
  that splits it (or adds a mode within :data:`NEIGHBOUR_RATIO` of it) removes at least
  :data:`MERGE_RSS_GAIN` of the residual energy but is not resolved.
- **Model order.** A mode that moves by more than :data:`ORDER_SHIFT_SE` standard errors
  (and :data:`ORDER_SHIFT_FLOOR`) when one mode more is fitted rests on the model order: a
  weak neighbour the fit left out pulls it; it is flagged with the merged neighbours.
- **Unresolved neighbours.** A mode next to (within :data:`NEIGHBOUR_RATIO`) a mode of the
  same log whose frequency is not resolved, or that is flagged as merged, shares its
  uncertainty: the fit trades one against the other (:func:`flag_unresolved_neighbours`).
- **Direction and amplitude.** Each mode's fitted response over the three channels traces a
  path at the flange; its major axis (SVD), turned into the base frame at the pose, is the
  direction (sign: largest component positive), and the largest acceleration along the path
  the amplitude.

Standard errors are those of the local fit (:func:`~tvist.ident.local_fit._standard_errors`:
the larger of the white-residual and a Newey-West estimate).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING, Any

import numpy as np
from scipy import optimize

from tvist.ident.free_decay import decay_windows, fit_free_decays
from tvist.ident.zoh import least_squares_fit, shifted, zoh_responses

if TYPE_CHECKING:
    from tvist.ident.local_fit import FitOptions, LocalFit

__all__ = [
    "MAX_MODES",
    "RingingMode",
    "fit_ringing",
    "flag_unresolved_neighbours",
    "ringing_from_log",
]

#: Most modes fitted to one log.
MAX_MODES = 3
#: Two modes closer than this frequency ratio are one mode.
MIN_FREQ_RATIO = 1.06
#: A further mode must remove at least this fraction of the residual energy.
MIN_RSS_REDUCTION = 0.05
#: Largest relative standard error of every frequency for a further mode to be kept.
MAX_WN_REL_SE = 0.05
#: An unresolved split of a mode that removes this fraction of the residual energy flags it
#: as possibly two merged neighbours.
MERGE_RSS_GAIN = 0.03
#: A further mode this close (frequency ratio) to a fitted mode counts as its neighbour.
NEIGHBOUR_RATIO = 1.35
#: A mode that the fit with one mode more moves by more than this many of its standard
#: errors, and by more than the floor, is flagged as resting on the model order.
ORDER_SHIFT_SE = 2.0
ORDER_SHIFT_FLOOR = 0.01
#: Starts refined per added mode (the best by their residual before refinement).
N_REFINED = 3
#: A mode whose whole-log fit rings faster than its free decays (the arm at rest) by more than
#: this many combined standard errors and :data:`AT_REST_FLOOR` (relative) is not the arm at
#: rest (:func:`at_rest_reason`) and is flagged with a reason that starts with
#: :data:`AT_REST_REASON`. The floor is half the 3 % that makes an identification wrong: the
#: twin's gears (25 % stiffer at rated torque) stay inside it.
AT_REST_SE = 3.0
AT_REST_FLOOR = 0.015
AT_REST_REASON = "not the arm at rest"
#: A mode's energy over the residual energy below which it is "below noise" (dB), and below
#: which it is "weak" (dB): as the local fit's ``min_ringing_snr_db`` / ``min_confident_snr_db``.
BELOW_NOISE_DB = -10.0
WEAK_DB = 3.0


@dataclass(frozen=True)
class RingingMode:
    """One mode that rings in one log (the pose record's ``ringing`` entries).

    Attributes
    ----------
    log_joint
        The excitation log it came from (0 base, 1 shoulder, 2 elbow, 3 wrist 1).
    wn_rad_s, zeta, wn_se_rad_s, zeta_se
        Natural frequency (rad/s), damping ratio and their standard errors.
    amplitude_m_s2
        Largest acceleration of the mode's fitted ringing at the flange over the log, m/s²
        (tool accelerometer, gravity removed).
    flange_direction
        Unit vector (base frame, at the pose) of the flange's motion in this mode, largest
        component positive; ``None`` when the log has no three-axis accelerometer.
    low_confidence, reasons
        Whether any check failed, and which.
    tangent_share
        Share of the mode's ringing energy along the excited joint's tangent (0-1).
    wn_at_rest_rad_s, wn_at_rest_se_rad_s
        Natural frequency of the same mode in the log's free decays after its stops, and its
        standard error, rad/s (:func:`checked_at_rest`; NaN where there are none).
    """

    log_joint: int
    wn_rad_s: float
    zeta: float
    wn_se_rad_s: float
    zeta_se: float
    amplitude_m_s2: float
    flange_direction: tuple[float, float, float] | None
    low_confidence: bool = False
    reasons: tuple[str, ...] = field(default_factory=tuple)
    tangent_share: float = math.nan
    wn_at_rest_rad_s: float = math.nan
    wn_at_rest_se_rad_s: float = math.nan

    @property
    def fn_hz(self) -> float:
        return self.wn_rad_s / (2.0 * math.pi)

    def flagged(self, reason: str) -> RingingMode:
        """This mode marked low-confidence with one more reason."""
        if reason in self.reasons:
            return self
        return replace(self, low_confidence=True, reasons=(*self.reasons, reason))

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready; a missing or infinite number is null, never NaN (strict JSON)."""
        return {
            "log_joint": int(self.log_joint),
            "wn_rad_s": float(self.wn_rad_s),
            "zeta": float(self.zeta),
            "wn_se_rad_s": _finite_or_none(self.wn_se_rad_s),
            "zeta_se": _finite_or_none(self.zeta_se),
            "amplitude_m_s2": _finite_or_none(self.amplitude_m_s2),
            "flange_direction": None
            if self.flange_direction is None
            else [float(v) for v in self.flange_direction],
            "low_confidence": bool(self.low_confidence),
            "reasons": list(self.reasons),
            "tangent_share": _finite_or_none(self.tangent_share),
            "wn_at_rest_rad_s": _finite_or_none(self.wn_at_rest_rad_s),
            "wn_at_rest_se_rad_s": _finite_or_none(self.wn_at_rest_se_rad_s),
        }

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> RingingMode:
        direction = data.get("flange_direction")
        return cls(
            log_joint=int(data["log_joint"]),
            wn_rad_s=float(data["wn_rad_s"]),
            zeta=float(data["zeta"]),
            wn_se_rad_s=_float_or_nan(data.get("wn_se_rad_s")),
            zeta_se=_float_or_nan(data.get("zeta_se")),
            amplitude_m_s2=_float_or_nan(data.get("amplitude_m_s2")),
            flange_direction=None if direction is None else tuple(float(v) for v in direction),  # type: ignore[arg-type]
            low_confidence=bool(data.get("low_confidence", False)),
            reasons=tuple(data.get("reasons", ())),
            tangent_share=_float_or_nan(data.get("tangent_share")),
            wn_at_rest_rad_s=_float_or_nan(data.get("wn_at_rest_rad_s")),
            wn_at_rest_se_rad_s=_float_or_nan(data.get("wn_at_rest_se_rad_s")),
        )


def _finite_or_none(value: float) -> float | None:
    return float(value) if math.isfinite(value) else None


def _float_or_nan(value: Any) -> float:
    return math.nan if value is None else float(value)


class _Problem:
    """Shared-pole fit of the channels ``y`` (n_used, n_ch) from the held input ``u``."""

    def __init__(
        self,
        u: np.ndarray,
        y: np.ndarray,
        extra: np.ndarray,
        mask: np.ndarray,
        dt_s: float,
        delay_s: float,
    ) -> None:
        self.u, self.mask, self.dt_s, self.delay_s = u, mask, dt_s, delay_s
        self.y = y[mask]
        self.fixed = np.column_stack([extra[mask], np.ones(int(mask.sum()))])
        self._cache: dict[tuple[float, float], np.ndarray] = {}

    def block(self, wn: float, zeta: float) -> np.ndarray:
        """The mode's two regressors on the used samples, cached: a finite-difference
        Jacobian moves one mode at a time, the others' responses are reused."""
        key = (wn, zeta)
        found = self._cache.get(key)
        if found is None:
            if len(self._cache) > 256:
                self._cache.clear()
            found = zoh_responses(wn, zeta, self.u, self.dt_s, self.delay_s)[self.mask]
            self._cache[key] = found
        return found

    def blocks(self, modes: list[tuple[float, float]]) -> list[np.ndarray]:
        return [self.block(w, z) for w, z in modes]

    def solve(self, modes: list[tuple[float, float]]) -> tuple[np.ndarray, np.ndarray, list]:
        """Residual (n_used, n_ch), coefficients and the mode blocks."""
        blocks = self.blocks(modes)
        phi = np.column_stack([*blocks, self.fixed])
        beta = least_squares_fit(phi, self.y)
        return self.y - phi @ beta, beta, blocks

    def residual_vector(self, x: np.ndarray) -> np.ndarray:
        modes = [(math.exp(x[2 * i]), float(x[2 * i + 1])) for i in range(x.size // 2)]
        return self.solve(modes)[0].ravel()

    def rss(self, modes: list[tuple[float, float]]) -> float:
        r = self.solve(modes)[0]
        return float(np.sum(r * r))


@dataclass(frozen=True)
class _Fit:
    modes: list[tuple[float, float]]  # (ω_n, ζ), lowest first
    rss: float
    se: np.ndarray  # (2 K,): SE of ω_n (rad/s) and ζ per mode

    def resolved(self) -> bool:
        ws = [w for w, _ in self.modes]
        if any(b / a < MIN_FREQ_RATIO for a, b in zip(ws, ws[1:], strict=False)):
            return False
        for i, (w, z) in enumerate(self.modes):
            if not (self.se[2 * i] <= MAX_WN_REL_SE * w) or z >= 0.9:
                return False
        return True


def _refine(problem: _Problem, start: list[tuple[float, float]], wn_bounds) -> _Fit:
    wn_lo, wn_hi = wn_bounds
    x0, lower, upper, scale = [], [], [], []
    for w, z in start:
        x0 += [math.log(min(max(w, wn_lo * 1.001), wn_hi / 1.001)), min(max(z, 2e-3), 1.5)]
        lower += [math.log(wn_lo), 1e-3]
        upper += [math.log(wn_hi), 2.0]
        scale += [0.05, 0.02]
    lower_a, upper_a = np.array(lower), np.array(upper)

    def residual(x: np.ndarray) -> np.ndarray:
        # Levenberg-Marquardt (MINPACK's QR: far cheaper than a bounded trust region's SVD
        # of the tall Jacobian) on the parameters held inside their bounds.
        return problem.residual_vector(np.clip(x, lower_a, upper_a))

    res = optimize.least_squares(
        residual,
        np.array(x0),
        method="lm",
        x_scale=scale,
        diff_step=1e-6,
        xtol=1e-7,
        ftol=1e-8,
        max_nfev=80 * (len(x0) + 1),
    )
    res.x = np.clip(res.x, lower_a, upper_a)
    from tvist.ident.local_fit import _standard_errors

    k = res.x.size // 2
    modes = [(math.exp(res.x[2 * i]), float(res.x[2 * i + 1])) for i in range(k)]
    w = np.array([m[0] for m in modes])
    # Residual correlation reaches over about two periods of the slowest mode.
    max_lag = int(min(max(4.0 * math.pi / (float(w.min()) * problem.dt_s), 10.0), 400.0))
    se_x = _standard_errors(res.jac, res.fun, max_lag)
    se = se_x.copy()
    se[0::2] = w * se_x[0::2]  # d(e^x) = e^x dx
    order = np.argsort(w)
    modes = [modes[i] for i in order]
    se = np.concatenate([se[2 * i : 2 * i + 2] for i in order])
    return _Fit(modes=modes, rss=float(2.0 * res.cost), se=se)


def _grid_candidates(
    problem: _Problem, base: list[tuple[float, float]], wn_bounds, n_grid: int
) -> list[list[tuple[float, float]]]:
    """Starts for one mode more: the two best grid frequencies away from ``base``."""
    scored = []
    for w in np.geomspace(wn_bounds[0] * 1.01, wn_bounds[1] / 1.01, n_grid):
        if any(abs(math.log(w / b)) < math.log(MIN_FREQ_RATIO) for b, _ in base):
            continue
        for z in (0.05, 0.25):
            scored.append((problem.rss([*base, (w, z)]), w, z))
    scored.sort()
    chosen: list[tuple[float, float]] = []
    for _, w, z in scored:
        if all(abs(math.log(w / c)) > 0.15 for c, _ in chosen):
            chosen.append((w, z))
        if len(chosen) == 2:
            break
    return [[*base, c] for c in chosen]


def _split_candidates(base: list[tuple[float, float]]) -> list[list[tuple[float, float]]]:
    """Starts that split each mode of ``base`` into two neighbours."""
    out = []
    for i, (w, z) in enumerate(base):
        rest = base[:i] + base[i + 1 :]
        zs = max(0.6 * z, 0.01)
        out.append([*rest, (w / 1.08, zs), (w * 1.08, zs)])
    return out


@dataclass(frozen=True)
class RingingFit:
    """The result of :func:`fit_ringing`: the modes kept and, per mode, the reason to doubt it
    as two merged neighbours (``None`` if none)."""

    fit: _Fit
    merged: list[str | None]
    residual: np.ndarray  # (n_used, n_ch)
    responses: list[np.ndarray]  # per mode: (n_used, n_ch) fitted ringing


def fit_ringing(
    u: np.ndarray,
    channels: np.ndarray,
    extra: np.ndarray,
    dt_s: float,
    delay_s: float,
    start: tuple[float, float],
    *,
    mask: np.ndarray | None = None,
    f_min_hz: float = 1.0,
    f_max_hz: float = 100.0,
    n_grid: int = 30,
    max_modes: int = MAX_MODES,
) -> RingingFit:
    """Fit 1 to ``max_modes`` modes with shared poles to the ``channels`` (see the module
    docstring).

    Parameters
    ----------
    u
        Held input (interval-mean target acceleration of the excited joint), rad/s², (n,).
    channels
        Measured accelerations, m/s², (n, n_ch).
    extra
        Further known regressors (feedthrough, centripetal), (n, n_extra).
    dt_s, delay_s
        Sampling period and the input's timing offset (from the single-mode fit), s.
    start
        ``(ω_n, ζ)`` of the single-mode fit: the first mode's start.
    mask
        Samples used in the cost.
    """
    n = u.size
    mask = np.ones(n, dtype=bool) if mask is None else np.asarray(mask, dtype=bool)
    problem = _Problem(
        u, np.asarray(channels, float), np.asarray(extra, float), mask, dt_s, delay_s
    )
    wn_bounds = (2 * math.pi * f_min_hz, 2 * math.pi * min(f_max_hz, 0.4 / dt_s))
    # One mode: from the single-mode fit and the best grid frequencies.
    starts = [[start]] + _grid_candidates(problem, [], wn_bounds, n_grid)
    fit = min((_refine(problem, s, wn_bounds) for s in starts), key=lambda f: f.rss)
    best_more: list[_Fit] = []  # per order: the best fit with one mode more (kept or not)
    while True:
        candidates = _grid_candidates(problem, fit.modes, wn_bounds, n_grid)
        candidates += _split_candidates(fit.modes)
        # Refine the most promising starts only (by their residual before refinement).
        candidates.sort(key=problem.rss)
        more = min(
            (_refine(problem, s, wn_bounds) for s in candidates[:N_REFINED]), key=lambda f: f.rss
        )
        best_more.append(more)
        gain = 1.0 - more.rss / fit.rss if fit.rss > 0 else 0.0
        if len(fit.modes) < max_modes and gain >= MIN_RSS_REDUCTION and more.resolved():
            fit = more
            continue
        break
    # Merged neighbours: the best fit with one mode more was better but not resolved, and its
    # extra mode sits next to one of ours.
    more = best_more[-1]
    gain = 1.0 - more.rss / fit.rss if fit.rss > 0 else 0.0
    merged: list[str | None] = [None] * len(fit.modes)
    if len(fit.modes) == max_modes and gain >= MIN_RSS_REDUCTION and more.resolved():
        # More modes ring than are fitted: the modes next to the one left out are suspect.
        extra = [
            m
            for m in more.modes
            if all(abs(math.log(m[0] / w)) > math.log(MIN_FREQ_RATIO) for w, _ in fit.modes)
        ]
        for i, (w, _) in enumerate(fit.modes):
            near = [m for m in extra if abs(math.log(m[0] / w)) < math.log(NEIGHBOUR_RATIO)]
            if near:
                merged[i] = (
                    f"merged neighbours: a further mode rings at {near[0][0] / (2 * math.pi):.2f}"
                    f" Hz, beyond the {max_modes} fitted"
                )
    elif gain >= MERGE_RSS_GAIN and not more.resolved():
        for i, (w, _) in enumerate(fit.modes):
            near = [m for m in more.modes if abs(math.log(m[0] / w)) < math.log(NEIGHBOUR_RATIO)]
            if len(near) >= 2:
                pair = " and ".join(f"{m[0] / (2 * math.pi):.2f}" for m in near[:2])
                merged[i] = (
                    f"merged neighbours: {pair} Hz instead fit {100 * gain:.0f} % better but "
                    "cannot be resolved"
                )
    # Order sensitivity: a mode that the fit with one mode more moves by more than its
    # standard errors allow rests on the model order (a weak neighbour pulls it).
    for i, (w, _) in enumerate(fit.modes):
        if merged[i] is not None:
            continue
        nearest = min((m[0] for m in more.modes), key=lambda v: abs(math.log(v / w)))
        moved = abs(math.log(nearest / w))
        if moved > max(ORDER_SHIFT_SE * fit.se[2 * i] / w, ORDER_SHIFT_FLOOR):
            merged[i] = (
                f"merged neighbours: with one mode more it moves {100 * moved:.1f} % "
                f"(to {nearest / (2 * math.pi):.2f} Hz)"
            )
    residual, beta, blocks = problem.solve(fit.modes)
    responses = [block @ beta[2 * i : 2 * i + 2] for i, block in enumerate(blocks)]
    return RingingFit(fit=fit, merged=merged, residual=residual, responses=responses)


#: Reasons (prefixes) that make a mode an unresolved neighbour of the modes next to it.
_UNRESOLVED = ("uncertain frequency", "merged neighbours")


def flag_unresolved_neighbours(modes: list[RingingMode]) -> list[RingingMode]:
    """``modes`` (of one log) with every confident mode flagged that has, within
    :data:`NEIGHBOUR_RATIO`, a mode whose frequency is unresolved or merged."""
    out = list(modes)
    for i, mode in enumerate(modes):
        if mode.low_confidence:
            continue
        for other in modes:
            if other is mode or abs(math.log(other.wn_rad_s / mode.wn_rad_s)) >= math.log(
                NEIGHBOUR_RATIO
            ):
                continue
            if any(r.startswith(_UNRESOLVED) for r in other.reasons):
                out[i] = out[i].flagged(
                    f"next to an unresolved mode at {other.fn_hz:.2f} Hz: the fit trades one "
                    "against the other"
                )
                break
    return out


def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.maximum(np.linalg.norm(v, axis=-1, keepdims=True), 1e-300)


def ringing_from_log(
    record: Any,
    joint: int,
    robot: Any,
    single: LocalFit,
    q: np.ndarray,
    *,
    options: FitOptions | None = None,
    accel_frame: str = "flange",
) -> list[RingingMode]:
    """Every mode that rings in the log of ``joint``'s excitation (see the module docstring).

    Parameters
    ----------
    record
        The log (uniformly sampled; as
        :func:`~tvist.ident.local_identification.identify_local` takes).
    joint
        Excited joint (0 base, 1 shoulder, 2 elbow, 3 wrist 1).
    robot
        Kinematic model (Jacobian with rows ``[linear; angular]``).
    single
        The single-mode fit of the same log (start and timing offset).
    q
        The pose, rad: the directions are turned into the base frame there.
    options
        Search band and the local fit's confidence thresholds.
    accel_frame
        Frame of the accelerometer columns.

    Returns
    -------
    list[RingingMode]
        Lowest frequency first; a single entry flagged "below noise" if nothing rings above it.
    """
    from tvist.ident.local_fit import (
        FitOptions,
        interval_mean_acceleration,
        saturated_samples,
    )
    from tvist.ident.logs import is_uniform, resample_uniform
    from tvist.ident.preprocess import tangential_acceleration

    opts = options or FitOptions()
    if not is_uniform(record.t_s):
        record, _ = resample_uniform(record)
    dt = record.dt_s
    three_axes = record.tool_accel.ndim == 2 and record.tool_accel.shape[1] == 3
    tangential = tangential_acceleration(record, joint, robot, accel_frame=accel_frame)  # type: ignore[arg-type]
    jac = robot.jacobian_many(np.ascontiguousarray(record.actual_q))
    t_dir = _unit(jac[:, :3, joint])
    z_dir = _unit(jac[:, 3:, joint])
    n_dir = np.cross(z_dir, t_dir)
    if three_axes and tangential.accel_base is not None:
        a = tangential.accel_base
        channels = np.column_stack(
            [tangential.psi, np.einsum("ni,ni->n", a, n_dir), np.einsum("ni,ni->n", a, z_dir)]
        )
    else:
        channels = tangential.psi[:, None]
    u = interval_mean_acceleration(record.target_qd[:, joint], dt)
    lag = int(round(single.delay_s / dt))
    # The faster modes' quasi-static response, to first order in s (a feedthrough and its
    # rate), the centripetal acceleration, and what is left of gravity and the sensor bias
    # after their estimate (a slow function of the joint's swing: to second order).
    fed = shifted(u, lag)
    swing = record.target_q[:, joint] - float(np.median(record.target_q[:, joint]))
    extra = np.column_stack(
        [
            fed,
            np.diff(fed, prepend=fed[0]) / dt,
            shifted(record.target_qd[:, joint] ** 2, lag),
            swing,
            swing**2,
        ]
    )
    mask = ~saturated_samples(record.tool_accel)
    result = fit_ringing(
        u,
        channels,
        extra,
        dt,
        single.delay_s,
        (single.wn_rad_s, single.zeta),
        mask=mask,
        f_min_hz=opts.f_min_hz,
        f_max_hz=opts.f_max_hz,
    )
    # The moving frame at the pose, to turn directions into the base frame.
    jq = robot.jacobian_many(np.asarray(q, dtype=float)[None])[0]
    t0, z0 = _unit(jq[:3, joint]), _unit(jq[3:, joint])
    frame = np.column_stack([t0, np.cross(z0, t0), z0])
    noise = max(float(np.sum(result.residual**2)), 1e-300)
    fit = result.fit
    out = []
    for i, (wn, zeta) in enumerate(fit.modes):
        resp = result.responses[i]
        energy = float(np.sum(resp**2))
        snr_db = 10.0 * math.log10(max(energy / noise, 1e-30))
        amplitude = float(np.max(np.linalg.norm(resp, axis=1)))
        tangent_share = float(np.sum(resp[:, 0] ** 2) / max(energy, 1e-300))
        direction = None
        if channels.shape[1] == 3:
            _, _, vt = np.linalg.svd(resp, full_matrices=False)
            d = frame @ vt[0]
            d = d * math.copysign(1.0, d[int(np.argmax(np.abs(d)))])
            direction = (float(d[0]), float(d[1]), float(d[2]))
        wn_se, zeta_se = float(fit.se[2 * i]), float(fit.se[2 * i + 1])
        reasons: list[str] = []
        if snr_db < BELOW_NOISE_DB:
            reasons.append(
                f"below noise: the mode's ringing is {snr_db:+.1f} dB against the residual"
            )
        elif snr_db < WEAK_DB:
            reasons.append(f"weak ringing: {snr_db:+.1f} dB against the residual")
        if not wn_se <= opts.max_wn_rel_se * wn:
            reasons.append(f"uncertain frequency: standard error {100 * wn_se / wn:.2f} % of ω_n")
        if not zeta_se <= max(opts.max_zeta_rel_se * zeta, 0.005):
            reasons.append(f"uncertain damping: standard error {zeta_se:.4f}")
        if zeta >= 0.9:
            reasons.append(f"overdamped (ζ = {zeta:.3f})")
        if wn < 2 * math.pi * opts.f_min_hz * 1.02 or wn > 0.4 / dt * 2 * math.pi / 1.02:
            reasons.append("frequency at the edge of the searched band")
        if result.merged[i] is not None:
            reasons.append(result.merged[i])  # type: ignore[arg-type]
        out.append(
            RingingMode(
                log_joint=int(joint),
                wn_rad_s=float(wn),
                zeta=float(zeta),
                wn_se_rad_s=wn_se,
                zeta_se=zeta_se,
                amplitude_m_s2=amplitude,
                flange_direction=direction,
                low_confidence=bool(reasons),
                reasons=tuple(reasons),
                tangent_share=tangent_share,
            )
        )
    windows = [(b, e) for b, e in decay_windows(u, dt, lag=lag) if bool(np.all(mask[b:e]))]
    return flag_unresolved_neighbours(checked_at_rest(out, channels, dt, windows))


def checked_at_rest(
    modes: list[RingingMode], channels: np.ndarray, dt_s: float, windows: list[tuple[int, int]]
) -> list[RingingMode]:
    """``modes`` with their frequencies at rest: the free decays of the same log
    (:func:`~tvist.ident.free_decay.fit_free_decays`, all of ``modes`` fitted together);
    each one flagged where its whole-log frequency is not the one at rest
    (:func:`at_rest_reason`).

    Only a whole log *faster* than the free decays counts: a gear stiffens under load, it
    does not soften. The other way round was seen only where the free-decay fit is the one in
    doubt (two true modes merged in both fits, elbow logs 2-4 % apart either way on the
    family's variants). Flagged, not replaced by the frequency at rest: on the family's
    development seeds that lost as many wrong entries and kept the maps closer to the truth
    (a free-decay fit also merges close modes, differently)."""
    fit = fit_free_decays(channels, dt_s, windows, [(m.wn_rad_s, m.zeta) for m in modes])
    if fit is None:
        return modes
    out = []
    for mode, wn, se in zip(modes, fit.wn_rad_s, fit.wn_se_rad_s, strict=True):
        mode = replace(mode, wn_at_rest_rad_s=wn, wn_at_rest_se_rad_s=se)
        reason = at_rest_reason(mode.wn_rad_s, mode.wn_se_rad_s, mode)
        out.append(mode if reason is None else mode.flagged(reason))
    return out


def at_rest_reason(wn_rad_s: float, wn_se_rad_s: float, mode: RingingMode) -> str | None:
    """Why a frequency ``wn_rad_s`` (its standard error ``wn_se_rad_s``) fitted to a whole
    log is not the arm's at rest, or ``None``: it is higher than ``mode``'s free decays by
    more than :data:`AT_REST_SE` combined standard errors and :data:`AT_REST_FLOOR`
    (relative)."""
    at_rest, se = mode.wn_at_rest_rad_s, mode.wn_at_rest_se_rad_s
    if not (math.isfinite(at_rest) and math.isfinite(se) and at_rest > 0):
        return None
    shift = math.log(wn_rad_s / at_rest)
    combined = math.hypot(wn_se_rad_s / wn_rad_s, se / at_rest)
    if not shift > max(AT_REST_SE * combined, AT_REST_FLOOR):
        return None
    return (
        f"{AT_REST_REASON}: its free decays after the stops ring at "
        f"{at_rest / (2 * math.pi):.2f} Hz, the whole log {100 * (math.exp(shift) - 1):.1f} % "
        "higher (a gear stiffer under the moves' torque)"
    )
