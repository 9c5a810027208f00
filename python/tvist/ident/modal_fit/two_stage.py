"""Steps 1 and 2 of the modal fit, the start of the joint refinement: the stiffness laws by
robust nonlinear least squares on the relative frequency errors of the undamped map, then the
damping laws, with the stiffness fixed, by non-negative linear least squares on the relative
damping-ratio errors."""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence

import numpy as np
from scipy import optimize

from tvist.ident.modal_fit.model import _predict, _stiffness_laws, _Term
from tvist.ident.modal_fit.poses import MODE_JOINTS, ModalPoses

#: Relative frequency error beyond which a residual counts as an outlier (robust loss).
ROBUST_SCALE = 0.02
#: A fitted zero-load stiffness stays within this factor of its starting value.
STIFFNESS_SPAN = 100.0
_LSQ = {"x_scale": "jac", "xtol": 1e-12, "ftol": 1e-12, "gtol": 1e-12, "max_nfev": 400}
_INVALID_RESIDUAL = 10.0


def _fit_stiffness(
    poses: ModalPoses,
    flex_joints: Sequence[int],
    terms: list[_Term],
    damping_load: Mapping[int, int],
    start: Mapping[int, float],
) -> tuple[dict[int, list[float]], np.ndarray, np.ndarray, np.ndarray]:
    observed = np.isfinite(poses.wn_rad_s)
    target = poses.wn_rad_s[observed]

    def residual(x: np.ndarray) -> np.ndarray:
        laws = _stiffness_laws(x, terms, flex_joints)
        pred = _predict(poses, flex_joints, laws, {}, damping_load)[:, :, 0][observed]
        r = pred / target - 1.0
        return np.where(np.isfinite(r), r, _INVALID_RESIDUAL)

    x0 = np.array([math.log(start[t.joint]) if t.name == "k_0" else 0.0 for t in terms])
    # Stiffness within a factor STIFFNESS_SPAN of its start (keeps exp() finite and positive
    # for a joint the data hardly constrain); load terms non-negative.
    span = math.log(STIFFNESS_SPAN)
    lower = [x0[i] - span if t.name == "k_0" else 0.0 for i, t in enumerate(terms)]
    upper = [x0[i] + span if t.name == "k_0" else np.inf for i, t in enumerate(terms)]
    # A robust loss: a mode the local fit mistook for another (a few per cent of a campaign's
    # poses, folded ones) must not pull the stiffnesses; residuals up to ROBUST_SCALE weigh
    # as in plain least squares.
    res = optimize.least_squares(
        residual, x0, bounds=(lower, upper), loss="soft_l1", f_scale=ROBUST_SCALE, **_LSQ
    )
    return _stiffness_laws(res.x, terms, flex_joints), res.x, res.jac, res.fun


def _stiffness_start(poses: ModalPoses, flex_joints: Sequence[int]) -> dict[int, float]:
    """Single-joint guesses ``k = ω² J``: the base and shoulder from their identified modes,
    any other joint 5 times the stiffest of those (a stiff joint, refined by the fit)."""
    start = {}
    for m, j in enumerate(MODE_JOINTS):
        ok = np.isfinite(poses.wn_rad_s[:, m])
        if j in flex_joints and np.any(ok):
            start[j] = float(np.median(poses.wn_rad_s[ok, m] ** 2 * poses.mass_kg_m2[ok, j, j]))
    stiff = max(start.values(), default=1.0e4)
    return {j: start.get(j, 5.0 * stiff) for j in flex_joints}


def _fit_damping(
    poses: ModalPoses,
    flex_joints: Sequence[int],
    stiffness: Mapping[int, Sequence[float]],
    terms: list[_Term],
    damping_load: Mapping[int, int],
) -> tuple[dict[int, list[float]], np.ndarray, np.ndarray, np.ndarray]:
    observed = np.isfinite(poses.zeta) & np.isfinite(poses.wn_rad_s)
    target = poses.zeta[observed]
    columns = []
    for t in terms:
        unit = [0.0, 0.0, 0.0]
        unit[int(t.name[-1])] = 1.0
        pred = _predict(poses, flex_joints, stiffness, {t.joint: unit}, damping_load)
        columns.append(pred[:, :, 1][observed])
    a = np.column_stack(columns) / target[:, None]
    ok = np.all(np.isfinite(a), axis=1)
    a, b = a[ok], np.ones(int(ok.sum()))
    # Column scaling for a well-conditioned NNLS; the solution is scaled back.
    scale = np.linalg.norm(a, axis=0)
    scale[scale == 0] = 1.0
    x_scaled, _ = optimize.nnls(a / scale, b)
    x = x_scaled / scale
    laws = {j: [0.0, 0.0, 0.0] for j in flex_joints}
    for value, t in zip(x, terms, strict=True):
        laws[t.joint][int(t.name[-1])] = float(value)
    return laws, x, a, a @ x - b
