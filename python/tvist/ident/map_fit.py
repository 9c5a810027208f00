"""Fit the dynamic map's coefficients to identified modes (paper section 5.3).

Per mode, by nonlinear least squares on relative errors:

1. **Frequency** (``k_0``, ``k_J``, ``k_p`` and the gravity term ``k_g``). For a mode with
   several candidate frequency joints (the base mode: ``J_0`` or ``J_1``), each is fitted and
   the one with the smaller residual is kept.
2. **Damping** (``c_0``, ``c_1``, ``c_2``, ``c_τ``) with the stiffness terms fixed.

**``k_0`` is not a scale.** The paper fixes ``k_0`` (eqs. 44-45) as if ``ω_n`` fixed only ratios
of the stiffness terms, but with ``x = 1/J`` (and ``k_g = 0``)
``ω_n² = (1 + k_p x)(k_0 x + k_J) = k_J + (k_0 + k_p k_J) x + k_p k_0 x²``: three coefficients
for three unknowns, so poses with different inertias determine ``k_0``; a wrong fixed value
biases ``k_J`` and ``k_p`` and leaves a misfit. It is estimated here. What the frequencies
cannot tell apart is the swap ``(k_0, k_p) ↔ (k_p k_J, k_0 / k_J)``, which leaves all three
coefficients (so every ``ω_n``) unchanged: the fit reports the branch with ``k_0 >= k_p k_J``,
the one both published UR5e modes are on (10000 against 2692 and 1320 N m/rad). Passing
``k_0`` fixes it instead (the paper's reduced map).

**Physical signs.** Every coefficient is constrained to be ``>= 0``:

- ``ω_n² = (1 + k_p/J)(k_0 + k_J J + k_g |τ|)/J`` must stay positive for every inertia and
  load: ``k_p >= 0`` (else ``1 + k_p/J < 0`` for ``J < −k_p``), ``k_0 >= 0`` (the stiffness with
  no inertia and no load), ``k_J >= 0`` (for ``J → ∞``, ``ω_n² → k_J``) and ``k_g >= 0`` (the
  gear stiffens with load, eqs. 22-23 with ``k_3 >= 0``; a negative ``k_g`` makes the stiffness
  fall to zero at a finite torque).
- ``(c_0 + c_1 √J + c_2 J)(1 + c_τ J)`` is a viscous damping coefficient, friction that grows
  with the load (eq. 35, ``c (1 + c_load |L|)``): ``c_0 >= 0`` and ``c_1, c_2, c_τ >= 0``;
  a negative ``c_2`` or ``c_τ`` makes it negative beyond some inertia, a mode that grows.

A coefficient that ends on its bound is reported **at bound** (``fit_statistics``:
``at_bound``, its value exactly 0 and its standard error ``NaN``, ``null`` in a map file): it
is a constraint, not an estimate.

A term whose estimate is smaller than ``drop_t`` standard errors (``k_g`` and ``c_1`` on the
UR5e) is dropped (set to 0) and the step refitted, as the paper did.

The fitted map is limited to the data: each mode stores the range ``[min, max]`` of ``J_f`` and
of ``J_d`` over the poses it was fitted to, and the map clamps inertias into those ranges when
evaluated (see :mod:`tvist.maps.paper10`), so it never extrapolates beyond what was identified.

The map equations are evaluated only through :class:`tvist.DynamicMap` (the Rust core). The
starting values use the fact that, for a fixed ``k_p``, ``ω_n²`` is affine in
``(k_J, k_g)``, and for a fixed ``c_τ``, ``ζ`` is linear in ``(c_0, c_1, c_2)``: the columns of
those linear problems are themselves map evaluations.

Input poses are mappings (the campaign's JSON-lines records have this form)::

    {"inertia_kg_m2": [J_0, ..., J_5],
     "gravity_torque_nm": [τ_0, ..., τ_5],            # optional; needed for k_g
     "modes": [{"joint": 0, "wn_rad_s": ..., "zeta": ..., "low_confidence": false}, ...]}
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy import optimize

from tvist import _core
from tvist.maps.paper10 import DynamicMap

__all__ = [
    "DEFAULT_MODE_SPECS",
    "ModeSpec",
    "PoseTable",
    "data_range",
    "evaluate_mode",
    "fit_map",
    "fitted_terms",
    "pose_table",
    "poses_needed",
]

#: The paper's fixed stiffness at zero inertia, N m/rad (eqs. 44-45; pass ``k_0`` to use it).
K_0_FIXED = 10000.0
#: Lower bound of every coefficient (see the module docstring: physical signs).
_LOWER_BOUND = 0.0
#: Tight tolerances: the damping valley along c_0, c_τ is flat (see :func:`fit_map`).
_LSQ = {"x_scale": "jac", "xtol": 1e-14, "ftol": 1e-14, "gtol": 1e-14, "max_nfev": 2000}
#: A term whose removal changes no prediction by more than this (relative) is negligible; the
#: local identification itself is good to about 1 % (SPEC acceptance of the local fit).
NEGLIGIBLE_EFFECT = 0.005
#: Residual (relative error) returned where the map gives no valid mode for a trial parameter.
_INVALID_RESIDUAL = 10.0


@dataclass(frozen=True)
class ModeSpec:
    """Which mode to fit and which inertias may drive it.

    Attributes
    ----------
    joint
        The joint whose excitation identified the mode (0 = base, 1 = shoulder).
    frequency_joints
        Candidate joints for ``J_f``; each is fitted and the best kept.
    damping_joint
        Joint for ``J_d``.
    """

    joint: int
    frequency_joints: tuple[int, ...]
    damping_joint: int


#: The paper's two UR5e modes: the base mode tries J_0 and J_1 for its frequency (section
#: 5.3.1), damping from J_0; the shoulder mode uses J_1 throughout.
DEFAULT_MODE_SPECS = (ModeSpec(0, (0, 1), 0), ModeSpec(1, (1,), 1))


@dataclass(frozen=True)
class PoseTable:
    """Observations of one mode over many poses.

    Attributes
    ----------
    inertia_kg_m2
        Joint inertias per pose, shape (n_poses, n_dof).
    gravity_torque_nm
        Gravity torques per pose, shape (n_poses, n_dof) (zeros if unknown).
    wn_rad_s, zeta
        Identified mode per pose, shape (n_poses,).
    has_gravity
        Whether real gravity torques were given.
    """

    inertia_kg_m2: np.ndarray
    gravity_torque_nm: np.ndarray
    wn_rad_s: np.ndarray
    zeta: np.ndarray
    has_gravity: bool

    @property
    def n_poses(self) -> int:
        return int(self.wn_rad_s.size)


def pose_table(
    poses: Sequence[Mapping[str, Any]], joint: int, *, include_low_confidence: bool = False
) -> PoseTable:
    """Collect the observations of the mode identified through ``joint``.

    Poses without that mode, with a non-finite value, or flagged ``low_confidence`` (unless
    ``include_low_confidence``) are skipped.
    """
    inertia, gravity, wn, zeta = [], [], [], []
    has_gravity = True
    for i, pose in enumerate(poses):
        if "inertia_kg_m2" not in pose:
            raise ValueError(f"poses[{i}]: missing 'inertia_kg_m2'")
        for mode in pose.get("modes", []):
            if mode.get("joint") != joint:
                continue
            if mode.get("low_confidence", False) and not include_low_confidence:
                continue
            w, z = float(mode.get("wn_rad_s", math.nan)), float(mode.get("zeta", math.nan))
            if not (math.isfinite(w) and math.isfinite(z) and w > 0 and z > 0):
                continue
            inertia.append(np.asarray(pose["inertia_kg_m2"], dtype=float))
            tau = pose.get("gravity_torque_nm")
            if tau is None:
                has_gravity = False
                tau = np.zeros_like(inertia[-1])
            gravity.append(np.asarray(tau, dtype=float))
            wn.append(w)
            zeta.append(z)
    if not wn:
        raise ValueError(f"no usable identified mode for joint {joint} in {len(poses)} poses")
    return PoseTable(
        inertia_kg_m2=np.array(inertia),
        gravity_torque_nm=np.array(gravity),
        wn_rad_s=np.array(wn),
        zeta=np.array(zeta),
        has_gravity=has_gravity,
    )


def _mode_dict(
    coefficients: Mapping[str, float], frequency_joint: int, damping_joint: int
) -> dict[str, Any]:
    """A complete mode record (unbounded); the exponents follow the map's two published
    forms."""
    same = frequency_joint == damping_joint
    mode: dict[str, Any] = {
        "k_0": 0.0,
        "k_j": 0.0,
        "k_g": 0.0,
        "k_p": 0.0,
        "c_0": 0.0,
        "c_1": 0.0,
        "c_2": 0.0,
        "c_tau": 0.0,
    }
    mode.update({k: float(v) for k, v in coefficients.items()})
    mode.update(
        frequency_joint=frequency_joint,
        damping_joint=damping_joint,
        # eqs. 43/51: √(1 + k_p/J); eq. 48 as printed: (1 + k_p/J_0) / √(1 + k_p/J_1)
        damping_gain_exponent=0.5 if same else 1.0,
        frequency_gain_exponent=0.0 if same else -0.5,
    )
    return mode


def data_range(table: PoseTable, joint: int) -> list[float]:
    """``[min, max]`` of ``J_joint`` over the poses of ``table``, kg m².

    Raises
    ------
    ValueError
        If the inertia does not vary over the poses (no range to fit, or to trust, a map on).
    """
    j = table.inertia_kg_m2[:, joint]
    lo, hi = float(np.min(j)), float(np.max(j))
    if not (math.isfinite(lo) and math.isfinite(hi) and 0.0 < lo < hi):
        raise ValueError(
            f"J_{joint} over the {table.n_poses} poses spans [{lo}, {hi}] kg m²: the map needs "
            "poses with different, positive inertias"
        )
    return [lo, hi]


def evaluate_mode(
    mode: Mapping[str, Any], inertia_kg_m2: np.ndarray, gravity_torque_nm: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """``(ω_n, ζ)`` of one mode at every pose, by the core's map equations.

    The mode is a trial point of the fit: checked for form, not for the physical rules a
    :class:`tvist.DynamicMap` obeys (the fitted map is). Returns two arrays of shape
    (n_poses,); NaN where the coefficients give no mode.
    """
    wn, zeta = _core.evaluate_trial_mode(
        dict(mode),
        np.ascontiguousarray(inertia_kg_m2, dtype=float),
        np.ascontiguousarray(gravity_torque_nm, dtype=float),
    )
    return wn, zeta


@dataclass
class _StepResult:
    values: dict[str, float]
    se: dict[str, float]
    rms_rel_error: float
    dropped: dict[str, dict[str, float]]
    n_poses: int
    at_bound: list[str]


def _at_bound(res: optimize.OptimizeResult, terms: Sequence[str]) -> list[str]:
    """The coefficients that end on their lower bound (a constraint, not an estimate): those
    the solver reports active, and those within 1e-6 of their own standard error (computed
    as if free) of the bound (the solver's iterates stay strictly inside the bounds, so an
    active bound can be reported as a value of ~1e-12 instead)."""
    se = _free_se(res.jac, res.fun, terms, raise_if_singular=False)
    return [
        t
        for t, x, active in zip(terms, res.x, res.active_mask, strict=True)
        if active != 0 or (math.isfinite(se[t]) and x - _LOWER_BOUND <= 1e-6 * se[t])
    ]


def _covariance_se(
    jac: np.ndarray,
    residual: np.ndarray,
    names: Sequence[str],
    *,
    raise_if_singular: bool,
    at_bound: Sequence[str] = (),
) -> dict[str, float]:
    """Standard errors ``√diag(σ² (JᵀJ)⁻¹)`` of the coefficients off their bounds (those at
    a bound are held there: ``NaN``); infinite (or an error) for a singular ``J``."""
    free = [i for i, name in enumerate(names) if name not in at_bound]
    out = {name: math.nan for name in names if name in at_bound}
    if not free:
        return out
    return {
        **out,
        **_free_se(jac[:, free], residual, [names[i] for i in free], raise_if_singular),
    }


def _free_se(
    jac: np.ndarray, residual: np.ndarray, names: Sequence[str], raise_if_singular: bool
) -> dict[str, float]:
    n, p = jac.shape
    sigma2 = float(residual @ residual) / max(n - p, 1)
    _, sv, vt = np.linalg.svd(jac, full_matrices=False)
    if sv[-1] <= 1e-10 * sv[0]:
        if raise_if_singular:
            raise ValueError(
                f"singular map fit: parameters {', '.join(names)} are not identifiable from "
                "these poses (too little variation in inertia?)"
            )
        return {name: math.inf for name in names}
    # (JᵀJ)⁻¹ = V diag(1/s²) Vᵀ from the SVD: forming JᵀJ would square the condition number,
    # and a Jacobian that passes the 1e-10 test above can still give a JᵀJ that inv() finds
    # singular in floating point.
    cov = (vt.T / sv**2) @ vt * sigma2
    return {name: float(math.sqrt(max(cov[i, i], 0.0))) for i, name in enumerate(names)}


def _refine(residual, starts, what: str):
    """Least squares of ``residual`` with every coefficient ``>= 0`` (see the module
    docstring), from the best of the ``starts`` (smallest sum of squared residuals, each
    start moved onto the bounds first)."""
    best: tuple[float, np.ndarray] | None = None
    for x in starts:
        x = np.maximum(np.asarray(x, dtype=float), _LOWER_BOUND)
        cost = float(np.sum(residual(x) ** 2))
        if best is None or cost < best[0]:
            best = (cost, x)
    if best is None:
        raise ValueError(f"map fit: no valid starting point for the {what} coefficients")
    return optimize.least_squares(residual, best[1], bounds=(_LOWER_BOUND, np.inf), **_LSQ)


def _cost(res: optimize.OptimizeResult) -> float:
    return float(res.fun @ res.fun)


def _fit_frequency(
    table: PoseTable, f_joint: int, d_joint: int, terms: list[str], k_0: float | None
) -> _StepResult:
    """Frequency coefficients ``terms``; ``k_0`` among them unless fixed (``k_0`` given)."""
    j, tau, w_meas = table.inertia_kg_m2, table.gravity_torque_nm, table.wn_rad_s
    fixed = {} if k_0 is None else {"k_0": k_0}

    def mode_for(values: Mapping[str, float]) -> dict[str, float | int]:
        return _mode_dict({**fixed, **values}, f_joint, d_joint)

    def residual(x: np.ndarray) -> np.ndarray:
        wn, _ = evaluate_mode(mode_for(dict(zip(terms, x, strict=True))), j, tau)
        r = wn / w_meas - 1.0
        return np.where(np.isfinite(r), r, _INVALID_RESIDUAL)

    # Start: for fixed k_p, ω_n² is affine in (k_0, k_J, k_g); columns from map evaluations
    # about a base point with a positive stiffness (k_0 = 1 N m/rad if k_0 is fitted).
    linear = [t for t in terms if t != "k_p"]

    def starts():
        for k_p in (0.0, 0.3, 1.0, 2.0, 4.0, 8.0, 16.0):
            base = {"k_p": k_p, **{t: 0.0 for t in linear}}
            if k_0 is None:
                base["k_0"] = 1.0
            w0, _ = evaluate_mode(mode_for(base), j, tau)
            cols = []
            for t in linear:
                w1, _ = evaluate_mode(mode_for({**base, t: base[t] + 1.0}), j, tau)
                cols.append((w1**2 - w0**2) / w_meas**2)
            if not np.all(np.isfinite(w0)) or not all(np.all(np.isfinite(c)) for c in cols):
                continue
            coef, *_ = np.linalg.lstsq(np.column_stack(cols), 1.0 - w0**2 / w_meas**2, rcond=None)
            values = {t: base[t] + c for t, c in zip(linear, coef, strict=True)}
            yield np.array([k_p if t == "k_p" else values[t] for t in terms])

    res = _refine(residual, starts(), "frequency")
    if {"k_0", "k_p"} <= set(terms):
        # The swap (k_0, k_p) -> (k_p k_J, k_0 / k_J) leaves every ω_n unchanged (without
        # k_g exactly): keep the branch with k_0 >= k_p k_J (module docstring).
        values = dict(zip(terms, res.x, strict=True))
        if values["k_j"] > 0.0 and values["k_0"] < values["k_p"] * values["k_j"]:
            swapped = {
                **values,
                "k_0": values["k_p"] * values["k_j"],
                "k_p": values["k_0"] / values["k_j"],
            }
            other = _refine(residual, [np.array([swapped[t] for t in terms])], "frequency")
            # Equal costs up to rounding (relative residuals of 1e-12 per pose): the swap.
            if _cost(other) <= _cost(res) * (1.0 + 1e-9) + res.fun.size * 1e-24:
                res = other
    at_bound = _at_bound(res, terms)
    values = dict(zip(terms, (float(v) for v in res.x), strict=True))
    values.update(dict.fromkeys(at_bound, _LOWER_BOUND))
    # Where the two branches meet (k_0 = k_p k_J) the Jacobian is singular although the
    # coefficients are unique (data whose curvature no real pair (k_0, k_p) reaches end
    # there): infinite standard errors, not an error.
    fold = "k_0" in values and math.isclose(
        values["k_0"], values["k_p"] * values["k_j"], rel_tol=1e-4
    )
    se = _covariance_se(res.jac, res.fun, terms, raise_if_singular=not fold, at_bound=at_bound)
    return _StepResult(
        values=values,
        se=se,
        rms_rel_error=float(np.sqrt(np.mean(res.fun**2))),
        dropped={},
        n_poses=int(res.fun.size),
        at_bound=at_bound,
    )


def _fit_damping(
    table: PoseTable, stiffness: Mapping[str, float], f_joint: int, d_joint: int, terms: list[str]
) -> _StepResult:
    j, tau, z_meas = table.inertia_kg_m2, table.gravity_torque_nm, table.zeta

    def mode_for(values: Mapping[str, float]) -> dict[str, float | int]:
        return _mode_dict({**stiffness, **values}, f_joint, d_joint)

    def residual(x: np.ndarray) -> np.ndarray:
        _, zeta = evaluate_mode(mode_for(dict(zip(terms, x, strict=True))), j, tau)
        r = zeta / z_meas - 1.0
        return np.where(np.isfinite(r), r, _INVALID_RESIDUAL)

    # Start: for fixed c_τ, ζ is linear in (c_0, c_1, c_2); columns from map evaluations.
    linear = [t for t in terms if t != "c_tau"]

    def starts():
        for c_tau in (0.0, 0.1, 0.3, 1.0, 3.0, 10.0, 30.0, 100.0, 300.0):
            cols = []
            for t in linear:
                _, z1 = evaluate_mode(mode_for({"c_tau": c_tau, t: 1.0}), j, tau)
                cols.append(z1 / z_meas)
            a = np.column_stack(cols)
            if not np.all(np.isfinite(a)):
                continue
            coef, *_ = np.linalg.lstsq(a, np.ones(len(z_meas)), rcond=None)
            values = dict(zip(linear, coef, strict=True))
            yield np.array([c_tau if t == "c_tau" else values[t] for t in terms])

    res = _refine(residual, starts(), "damping")
    values = dict(zip(terms, (float(v) for v in res.x), strict=True))
    if "c_1" not in terms and _other_branch_is_canonical(values):
        # Without c_1, (c_0 + c_2 J)(1 + c_τ J) = (c_0 + c_0 c_τ J)(1 + (c_2/c_0) J): the two
        # factorisations fit identically. Keep the paper's branch, c_2 <= c_0 c_τ.
        swapped = {**values, "c_2": values["c_0"] * values["c_tau"]}
        swapped["c_tau"] = values["c_2"] / values["c_0"]
        x0 = np.array([swapped[t] for t in terms])
        res = _refine(residual, [x0], "damping")
        values = dict(zip(terms, (float(v) for v in res.x), strict=True))
    # The frequency step has already rejected poses without inertia variation; here an
    # ill-conditioned Jacobian means c_0 and c_τ trade off (reported as poorly determined).
    at_bound = _at_bound(res, terms)
    values.update(dict.fromkeys(at_bound, _LOWER_BOUND))
    se = _covariance_se(res.jac, res.fun, terms, raise_if_singular=False, at_bound=at_bound)
    return _StepResult(
        values=values,
        se=se,
        rms_rel_error=float(np.sqrt(np.mean(res.fun**2))),
        dropped={},
        n_poses=int(res.fun.size),
        at_bound=at_bound,
    )


def _other_branch_is_canonical(values: Mapping[str, float]) -> bool:
    """True if the swapped factorisation exists and has ``c_2 <= c_0 c_τ``."""
    c_0, c_2, c_tau = values["c_0"], values["c_2"], values["c_tau"]
    return c_0 != 0.0 and c_2 / c_0 >= 0.0 and c_2 > c_0 * c_tau


def _fit_dropping(
    fit, predict, terms: list[str], droppable: Sequence[str], drop_t: float
) -> _StepResult:
    """Fit, then drop negligible droppable terms one at a time and refit.

    A term is kept only if it matters (a nested-model F-test): removing it and refitting must
    raise the residual sum of squares by more than ``drop_t²`` residual variances (the square
    of a t-test at ``drop_t`` standard errors), and zeroing it must change some prediction by
    more than :data:`NEGLIGIBLE_EFFECT`. The F-test rather than the coefficient's own
    t-value, because a term can look significant at a different local minimum that fits no
    better. If the fit with the droppable terms is singular, they are all dropped (recorded
    with a NaN value). ``predict(values)`` gives the fitted quantity at every pose.
    """
    dropped: dict[str, dict[str, float]] = {}
    try:
        result = fit(terms)
    except ValueError:
        optional = [t for t in terms if t in droppable]
        if not optional:
            raise
        for t in optional:
            dropped[t] = {"value": math.nan, "se": math.inf}
        terms = [t for t in terms if t not in droppable]
        result = fit(terms)
    while True:
        n, p = result.n_poses, len(terms)
        ssr = result.n_poses * result.rms_rel_error**2
        variance = ssr / max(n - p, 1)
        scores: dict[str, tuple[float, _StepResult]] = {}
        full = predict(result.values)
        for t in terms:
            if t not in droppable:
                continue
            reduced = fit([u for u in terms if u != t])
            f_stat = (n * reduced.rms_rel_error**2 - ssr) / max(variance, 1e-300)
            effect = float(np.max(np.abs(predict({**result.values, t: 0.0}) / full - 1.0)))
            if f_stat < drop_t**2 or effect < NEGLIGIBLE_EFFECT:
                scores[t] = (min(f_stat / drop_t**2, effect / NEGLIGIBLE_EFFECT), reduced)
        if not scores:
            break
        worst = min(scores, key=lambda t: scores[t][0])
        dropped[worst] = {"value": result.values[worst], "se": result.se[worst]}
        terms = [t for t in terms if t != worst]
        result = scores[worst][1]
    result.dropped = dropped
    return result


def _stats(step: _StepResult) -> dict[str, Any]:
    return {
        "coefficients": {k: {"value": v, "se": step.se[k]} for k, v in step.values.items()},
        "rms_relative_error": step.rms_rel_error,
        "dropped": step.dropped,
        # On its bound: held by a sign constraint, not estimated (its "se" is NaN).
        "at_bound": list(step.at_bound),
        # A coefficient known to worse than ±50 %: the data cannot separate it from the others.
        "poorly_determined": [
            k
            for k, v in step.values.items()
            if k not in step.at_bound and not step.se[k] < 0.5 * abs(v)
        ],
    }


def fitted_terms(
    use_gravity: bool, drop_negligible: bool, fit_k_0: bool
) -> tuple[list[str], list[str]]:
    """The frequency and damping coefficients :func:`fit_map` fits for each mode."""
    freq_terms = (["k_0"] if fit_k_0 else []) + ["k_j", "k_p"]
    freq_terms += ["k_g"] if use_gravity else []
    damp_terms = ["c_0", "c_2", "c_tau"] + (["c_1"] if drop_negligible else [])
    return freq_terms, damp_terms


def poses_needed(
    use_gravity: bool = True, drop_negligible: bool = True, fit_k_0: bool = True
) -> int:
    """Fewest usable poses per mode :func:`fit_map` accepts: two more than the coefficients
    of its larger step (6 for the defaults), so every fit keeps residual degrees of freedom
    for its standard errors."""
    freq_terms, damp_terms = fitted_terms(use_gravity, drop_negligible, fit_k_0)
    return max(len(freq_terms), len(damp_terms)) + 2


def fit_map(
    poses: Sequence[Mapping[str, Any]],
    *,
    mode_specs: Sequence[ModeSpec] = DEFAULT_MODE_SPECS,
    k_0: float | None = None,
    drop_negligible: bool = True,
    drop_t: float = 3.0,
    include_low_confidence: bool = False,
    limit_to_data: bool = True,
    metadata: Mapping[str, Any] | None = None,
) -> DynamicMap:
    """Fit a :class:`tvist.DynamicMap` to modes identified at many poses.

    Parameters
    ----------
    poses
        Per-pose records (see the module docstring).
    mode_specs
        One entry per mode, in cascade order (default: base, shoulder).
    k_0
        ``None`` (default): the stiffness at zero inertia is estimated with the other
        frequency coefficients (see the module docstring). A value fixes it (N m/rad; the
        paper's reduced map: :data:`K_0_FIXED`).
    drop_negligible
        Drop ``k_g`` and ``c_1`` when smaller than ``drop_t`` standard errors; otherwise
        ``k_g`` and ``c_1`` are fixed at 0 (the reduced map, eqs. 44-45).
    drop_t
        Significance threshold, in standard errors.
    include_low_confidence
        Also use identifications flagged low-confidence.
    limit_to_data
        Store, per mode, the range of ``J_f`` and ``J_d`` over the poses used, so that the map
        clamps inertias into it (no extrapolation). ``False`` gives an unbounded map.
    metadata
        Extra map metadata (``robot``, ``payload``, ``source``); ``fit_statistics`` is filled
        in here.

    Returns
    -------
    DynamicMap
        With ``metadata["fit_statistics"]``: per mode the coefficients with standard errors,
        the RMS relative errors, the dropped terms and the frequency-joint comparison; with
        ``limit_to_data``, each mode carries its inertia ranges.

    Raises
    ------
    ValueError
        Too few usable poses for the parameters, or a singular (non-identifiable) problem.
    """
    if k_0 is not None and not (math.isfinite(k_0) and k_0 > 0):
        raise ValueError(f"k_0 must be finite and > 0, got {k_0}")
    modes = []
    stats: dict[str, Any] = {"k_0_fixed": k_0, "drop_t": drop_t, "modes": []}
    for spec in mode_specs:
        table = pose_table(poses, spec.joint, include_low_confidence=include_low_confidence)
        use_gravity = drop_negligible and table.has_gravity
        freq_terms, damp_terms = fitted_terms(use_gravity, drop_negligible, k_0 is None)
        needed = poses_needed(use_gravity, drop_negligible, k_0 is None)
        if table.n_poses < needed:
            raise ValueError(
                f"mode of joint {spec.joint}: {table.n_poses} usable poses, need at least "
                f"{needed} for {len(damp_terms)} damping coefficients"
            )
        droppable = ("k_g", "c_1") if drop_negligible else ()
        candidates: dict[int, _StepResult] = {}
        failed: dict[str, str] = {}
        for f_joint in spec.frequency_joints:

            def fit_freq(terms, f=f_joint, table=table, d=spec.damping_joint):
                return _fit_frequency(table, f, d, terms, k_0)

            def predict_freq(values, f=f_joint, table=table, d=spec.damping_joint):
                mode = _mode_dict({**({} if k_0 is None else {"k_0": k_0}), **values}, f, d)
                return evaluate_mode(mode, table.inertia_kg_m2, table.gravity_torque_nm)[0]

            try:
                candidates[f_joint] = _fit_dropping(
                    fit_freq, predict_freq, list(freq_terms), droppable, drop_t
                )
            except ValueError as exc:
                failed[f"J_{f_joint}"] = str(exc)
        if not candidates:
            raise ValueError(f"mode of joint {spec.joint}: " + "; ".join(failed.values()))
        f_joint = min(candidates, key=lambda f: candidates[f].rms_rel_error)
        freq = candidates[f_joint]
        stiffness = {**({} if k_0 is None else {"k_0": k_0}), **freq.values}

        def fit_damp(terms, table=table, stiffness=stiffness, f=f_joint, d=spec.damping_joint):
            return _fit_damping(table, stiffness, f, d, terms)

        def predict_damp(values, table=table, stiffness=stiffness, f=f_joint, d=spec.damping_joint):
            mode = _mode_dict({**stiffness, **values}, f, d)
            return evaluate_mode(mode, table.inertia_kg_m2, table.gravity_torque_nm)[1]

        damp = _fit_dropping(fit_damp, predict_damp, list(damp_terms), droppable, drop_t)
        mode = _mode_dict({**stiffness, **damp.values}, f_joint, spec.damping_joint)
        if limit_to_data:
            mode["frequency_inertia_range_kg_m2"] = data_range(table, f_joint)
            mode["damping_inertia_range_kg_m2"] = data_range(table, spec.damping_joint)
        modes.append(mode)
        stats["modes"].append(
            {
                "joint": spec.joint,
                "n_poses": table.n_poses,
                "frequency_joint": f_joint,
                "damping_joint": spec.damping_joint,
                "frequency": _stats(freq),
                "damping": _stats(damp),
                "frequency_joint_rms_relative_error": {
                    f"J_{f}": r.rms_rel_error for f, r in candidates.items()
                },
                "frequency_joint_failures": failed,
            }
        )
    meta = dict(metadata or {})
    meta.setdefault("source", "tvist.ident.fit_map")
    meta["fit_statistics"] = stats
    return DynamicMap(modes, meta)
