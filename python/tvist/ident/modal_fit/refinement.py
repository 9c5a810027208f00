"""Step 3 of the modal fit: every kept stiffness and damping coefficient refined together,
by robust least squares on the relative errors of ω and ζ, each in units of its own scatter,
starting from the two-stage solution."""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
from scipy import optimize

from tvist.ident.modal_fit.model import _predict, _stiffness_laws, _Term
from tvist.ident.modal_fit.poses import ModalPoses
from tvist.ident.modal_fit.statistics import OUTLIER_SIGMAS, _standard_errors
from tvist.ident.modal_fit.two_stage import _INVALID_RESIDUAL, _LSQ, STIFFNESS_SPAN

#: Smallest relative measurement errors believed of a local fit's stated standard errors (ω, ζ):
#: a local fit of a few seconds of noisy response does not fix ω_n better than 0.1 % or ζ better
#: than 1 %, whatever its covariance says, and one pose must not outweigh the campaign.
MIN_RELATIVE_SE = (1.0e-3, 1.0e-2)
#: Passes of the joint refinement, each with the error scales of the previous one's residuals.
JOINT_PASSES = 2


@dataclass
class _Refinement:
    """The joint least-squares refinement's solution and what its standard errors need."""

    stiffness: dict[int, list[float]]
    damping: dict[int, list[float]]
    x: np.ndarray  # stiffness parameters (log k_0, a_1, a_2), then damping c (N m s/rad)
    se: np.ndarray  # standard errors of x
    scales: tuple[float, float]  # relative error scale of ω and of ζ, dimensionless
    weighting: str  # "stated standard errors" or "residual scale", per quantity
    nfev: int
    cost_start: float
    cost: float


def _relative_sigma(
    value: np.ndarray, stated_se: np.ndarray, relative_error: np.ndarray, floor: float
) -> tuple[np.ndarray, float, str]:
    """Per-observation relative error scale of one quantity (ω or ζ) and the family scale.

    The stated standard errors (relative, floored at ``floor``) weigh the observations
    against each other where every observation states one; otherwise they weigh alike. The
    scale of the family is the robust spread of its residuals at the two-stage solution
    (``1.4826 median|e/w|``), so that ω and ζ residuals enter the joint fit in units of their
    own scatter: a local fit's stated error leaves out the map's model error, and the two
    quantities' errors differ tenfold (about 0.5 % on ω, 5 % on ζ)."""
    rel = stated_se / value
    stated = bool(rel.size) and bool(np.all(np.isfinite(rel)))
    w = np.maximum(rel, floor) if stated else np.ones_like(value)
    ratio = np.abs(relative_error / w)
    ratio = ratio[np.isfinite(ratio)]
    scale = 1.4826 * float(np.median(ratio)) if ratio.size else 1.0
    scale = max(scale, 1e-3 * floor)  # exact data: any small positive scale
    return w * scale, scale, "stated standard errors" if stated else "residual scale"


def _refine_jointly(
    poses: ModalPoses,
    flex_joints: Sequence[int],
    stiff_terms: Sequence[_Term],
    damp_terms: Sequence[_Term],
    damping_load: Mapping[int, int],
    x_stiffness: np.ndarray,
    x_damping: np.ndarray,
    start: Mapping[int, float],
) -> _Refinement:
    """All kept stiffness and damping coefficients together, by robust least squares on the
    relative errors of ω and ζ (each in units of its scatter, :func:`_relative_sigma`),
    starting from the two-stage solution. The prediction is the core map's, so the fit is
    right for whichever eigenproblem the core solves: when ω depends on the damping (the
    exact damped modes), the two-stage solution is only a start."""
    obs_w = np.isfinite(poses.wn_rad_s)
    obs_z = np.isfinite(poses.zeta) & obs_w
    n_s = len(stiff_terms)

    def laws(x: np.ndarray) -> tuple[dict[int, list[float]], dict[int, list[float]]]:
        damping = {j: [0.0, 0.0, 0.0] for j in flex_joints}
        for value, t in zip(x[n_s:], damp_terms, strict=True):
            damping[t.joint][int(t.name[-1])] = float(value)
        return _stiffness_laws(x[:n_s], stiff_terms, flex_joints), damping

    def relative(x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        stiffness, damping = laws(x)
        pred = _predict(poses, flex_joints, stiffness, damping, damping_load)
        return (
            pred[:, :, 0][obs_w] / poses.wn_rad_s[obs_w] - 1.0,
            pred[:, :, 1][obs_z] / poses.zeta[obs_z] - 1.0,
        )

    # Bounds: stiffness within STIFFNESS_SPAN of its start (k_0 > 0 through its logarithm),
    # load terms and damping coefficients non-negative.
    span = math.log(STIFFNESS_SPAN)
    lower, upper = [], []
    for t in stiff_terms:
        k0 = math.log(start[t.joint])
        lower.append(k0 - span if t.name == "k_0" else 0.0)
        upper.append(k0 + span if t.name == "k_0" else np.inf)
    lower += [0.0] * len(damp_terms)
    upper += [np.inf] * len(damp_terms)
    x_start = np.clip(np.concatenate([x_stiffness, x_damping]), lower, upper)

    def scaled(x_at: np.ndarray):
        """Residual function with the error scales of the residuals at ``x_at``."""
        e_w, e_z = relative(x_at)
        sigma_w, scale_w, how_w = _relative_sigma(
            poses.wn_rad_s[obs_w], poses.wn_se_rad_s[obs_w], e_w, MIN_RELATIVE_SE[0]
        )
        sigma_z, scale_z, how_z = _relative_sigma(
            poses.zeta[obs_z], poses.zeta_se[obs_z], e_z, MIN_RELATIVE_SE[1]
        )

        def residual(x: np.ndarray) -> np.ndarray:
            rw, rz = relative(x)
            r = np.concatenate([rw / sigma_w, rz / sigma_z])
            return np.where(np.isfinite(r), r, _INVALID_RESIDUAL / min(scale_w, scale_z))

        return residual, (scale_w, scale_z), f"frequency: {how_w}; damping: {how_z}"

    # Two passes: the error scales of the first are those of the two-stage residuals, which
    # carry the two-stage solution's own error where ω depends on the damping; the second
    # pass's are those of the first pass's residuals.
    x, nfev = x_start, 0
    for _ in range(JOINT_PASSES):
        residual, scales, weighting = scaled(x)
        # The same robust loss as the stiffness step, in units of the residuals' scatter: a
        # residual up to OUTLIER_SIGMAS weighs as in plain least squares.
        res = optimize.least_squares(
            residual, x, bounds=(lower, upper), loss="soft_l1", f_scale=OUTLIER_SIGMAS, **_LSQ
        )
        x, nfev = res.x, nfev + int(res.nfev)
    stiffness, damping = laws(x)
    r0 = residual(x_start)
    # scipy's soft_l1 cost at the start: ½ Σ C² ρ((r/C)²), ρ(z) = 2(√(1+z) − 1).
    cost_start = OUTLIER_SIGMAS**2 * float(np.sum(np.sqrt(1 + (r0 / OUTLIER_SIGMAS) ** 2) - 1))
    return _Refinement(
        stiffness=stiffness,
        damping=damping,
        x=x,
        se=_standard_errors(res.jac, res.fun, OUTLIER_SIGMAS),
        scales=scales,
        weighting=weighting,
        nfev=nfev,
        cost_start=cost_start,
        cost=float(res.cost),
    )
