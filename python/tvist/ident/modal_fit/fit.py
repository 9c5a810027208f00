"""Fit a :class:`tvist.ModalMap` to the base and shoulder modes identified at many poses, each
named by its excitation joint (the label-based fit; ``tvist fit-map --kind modal
--select-folds K``, the demo's modal rows). ``tvist fit-map --kind modal`` fits every
identified mode instead, each matched to the model's eigenmode it is
(:mod:`tvist.ident.all_modes_fit`).

The same pose records as :func:`tvist.ident.map_fit.fit_map` (the campaign's JSON lines) are
used, plus each pose's configuration ``q`` and payload, from which the robot model gives the
mass matrix and the gravity torques. Two steps give the start, like the published map's fit:

1. **Stiffness** (nonlinear least squares on relative frequency errors) of the undamped map
   (no damping: the undamped modes). Per flexible joint ``k(L) = k_0 (1 + a_1 |L|_s + a_2 L²)``
   with ``L`` its gravity torque; the parameters are ``log k_0`` and ``a_1, a_2 >= 0`` (the
   load terms only for joints whose gravity torque varies over the poses).
2. **Damping** with the stiffness fixed. For light damping the damping ratio is nearly
   *linear* in the damping laws' coefficients (exactly so for the damping projected on the
   undamped modes, ``ζ = (ω/2) Σ_j (v_j²/k_j)(c_0 + c_1 |L|_s + c_2 L²)``), so it is a
   non-negative linear least-squares problem on relative errors; its columns are evaluations
   of the core map with one unit coefficient each (the physics stays in one place, the
   Rust core).

A term whose estimate is below ``drop_t`` standard errors is dropped and the step refitted.

3. **Joint refinement** (default): every kept stiffness and damping coefficient together, robust
   least squares on the relative errors of ω and ζ, each in units of its scatter (the records'
   stated standard errors weigh the poses, the residuals set each quantity's scale), from the
   two-step solution. The prediction is the core map's, the exact damped modes: their natural
   frequencies depend on the damping where modes with different damping come close (the
   UR5e's base and shoulder at folded poses), so steps 1 and 2 are only a start.

Standard errors are ``√diag(σ² (JᵀJ)⁻¹)`` at the solution (through the SVD of ``J``, residuals
beyond ``OUTLIER_SIGMAS`` robust standard deviations left out), in physical units.

:func:`select_terms` (``select_folds``) chooses the stiffness model by held-out frequency error
instead of significance alone.

:func:`cross_validate` compares this form with the published 10-coefficient form on held-out
poses (k-fold over poses), against the identified modes and, for a twin's campaign, against
the true modes.
"""

from __future__ import annotations

import math
import sys
from collections.abc import Collection, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy import optimize

from tvist.modal_map import ModalMap
from tvist.robots import Payload, Robot, params

__all__ = [
    "DEFAULT_FLEX_JOINTS",
    "ModalPoses",
    "cross_validate",
    "fit_modal_map",
    "held_out_frequency_error",
    "modal_poses",
    "relative_errors",
    "select_terms",
]

#: Flexible joints of the default fit: base, shoulder, elbow, wrists 1 and 2. The wrists'
#: compliance matters where the base inertia is small (arm pointing up): there a base-shoulder-
#: elbow map puts the base mode up to 6 % high on the UR5e twin, while the wrist stiffnesses
#: are identified from the same campaign to about ±15 %. Wrist 3 (tool axis) hardly moves
#: in the base and shoulder modes.
DEFAULT_FLEX_JOINTS = (0, 1, 2, 3, 4)
#: The identified modes, in cascade order: base, shoulder.
MODE_JOINTS = (0, 1)
#: Joints with a damper in the default fit: those of the identified modes. A campaign gives two
#: damping ratios per pose (base and shoulder mode), which cannot tell a damper at the elbow or
#: a wrist from one at the base or shoulder; left free, such dampers take up the damping
#: model's error and, through the damped eigenproblem (where ω depends on the damping), pull
#: the stiffnesses with them. Measured on the UR5e twin's 208-pose campaign (the twin damps
#: every joint): base frequency error against the true modes 0.17 % RMS, 1.6 % max in sample
#: (0.15 / 0.7 % held out), against 0.52 / 6.5 % (0.31 / 2.8 %) with a damper at every
#: flexible joint, which put wrist 1 at 11 100 N m/rad (twin: 15 000).
DEFAULT_DAMPED_JOINTS = MODE_JOINTS
#: The base carries no gravity torque; its bearing and gear friction grow with the arm's
#: tilting moment, which the shoulder's gravity torque measures (see ``tvist.sim.flex``).
DEFAULT_DAMPING_LOAD = {0: 1}
#: A joint whose gravity torque stays below this over the poses gets no load terms, N m.
MIN_LOAD_SPAN_NM = 1.0
#: Relative frequency error beyond which a residual counts as an outlier (robust loss).
ROBUST_SCALE = 0.02
#: Residuals beyond this many robust standard deviations are outliers in the stiffness fit's
#: standard errors (they are down-weighted in the fit itself by the robust loss).
OUTLIER_SIGMAS = 4.0
#: A fitted zero-load stiffness stays within this factor of its starting value.
STIFFNESS_SPAN = 100.0
#: Smallest relative measurement errors believed of a local fit's stated standard errors (ω, ζ):
#: a local fit of a few seconds of noisy response does not fix ω_n better than 0.1 % or ζ better
#: than 1 %, whatever its covariance says, and one pose must not outweigh the campaign.
MIN_RELATIVE_SE = (1.0e-3, 1.0e-2)
#: Passes of the joint refinement, each with the error scales of the previous one's residuals.
JOINT_PASSES = 2
_LSQ = {"x_scale": "jac", "xtol": 1e-12, "ftol": 1e-12, "gtol": 1e-12, "max_nfev": 400}
_INVALID_RESIDUAL = 10.0


@dataclass(frozen=True)
class ModalPoses:
    """The campaign's poses with what the modal map needs, arrays over poses.

    Attributes
    ----------
    mass_kg_m2
        Link-side mass matrices, payload included, ``(n_poses, n_dof, n_dof)``.
    gravity_torque_nm
        ``(n_poses, n_dof)``.
    wn_rad_s, zeta
        Identified modes ``(n_poses, 2)`` (base, shoulder); NaN where not usable (missing,
        failed or flagged low-confidence).
    true_wn_rad_s, true_zeta
        The twin's true modes ``(n_poses, 2)``, NaN where unknown.
    inertia_kg_m2
        Joint inertias ``(n_poses, n_dof)`` (for the published form).
    keys
        Pose keys.
    wn_se_rad_s, zeta_se
        The local fits' stated standard errors of the identified modes ``(n_poses, 2)``, NaN
        where the record states none.
    """

    mass_kg_m2: np.ndarray
    gravity_torque_nm: np.ndarray
    wn_rad_s: np.ndarray
    zeta: np.ndarray
    true_wn_rad_s: np.ndarray
    true_zeta: np.ndarray
    inertia_kg_m2: np.ndarray
    keys: tuple[str, ...]
    wn_se_rad_s: np.ndarray | None = None
    zeta_se: np.ndarray | None = None

    def __post_init__(self) -> None:
        for name in ("wn_se_rad_s", "zeta_se"):
            if getattr(self, name) is None:
                object.__setattr__(self, name, np.full(self.wn_rad_s.shape, np.nan))

    @property
    def n_poses(self) -> int:
        return int(self.mass_kg_m2.shape[0])

    def subset(self, index: np.ndarray) -> ModalPoses:
        """The poses at ``index``."""
        return ModalPoses(
            self.mass_kg_m2[index],
            self.gravity_torque_nm[index],
            self.wn_rad_s[index],
            self.zeta[index],
            self.true_wn_rad_s[index],
            self.true_zeta[index],
            self.inertia_kg_m2[index],
            tuple(self.keys[i] for i in np.asarray(index)),
            self.wn_se_rad_s[index],
            self.zeta_se[index],
        )


def modal_poses(
    records: Sequence[Mapping[str, Any]],
    robot_name: str,
    *,
    include_low_confidence: bool = False,
) -> ModalPoses:
    """Mass matrices, gravity torques and modes of every reachable campaign pose.

    Raises
    ------
    ValueError
        No record with a configuration ``q``, or a record whose stored joint inertias are not
        this robot model's (a campaign run with another robot or payload).
    """
    robot_params = params(robot_name)
    robots: dict[tuple, Robot] = {}
    mass, tau, inertia, wn, zeta, twn, tzeta, keys = [], [], [], [], [], [], [], []
    wn_se, zeta_se = [], []
    for i, r in enumerate(records):
        q = r.get("q")
        if q is None or r.get("error"):
            continue
        q = np.asarray(q, dtype=float)
        if q.shape != (robot_params.n_dof,) or not np.all(np.isfinite(q)):
            raise ValueError(f"records[{i}]: 'q' must be {robot_params.n_dof} finite angles")
        key = _record_payload(r, i)
        if key not in robots:
            robots[key] = Robot(robot_params, Payload(key[0], key[1]))
        model = robots[key]
        _check_stored_inertia(r, i, model.joint_inertia(q), robot_name)
        mass.append(model.mass_matrix(q))
        tau.append(model.gravity_torque(q))
        inertia.append(model.joint_inertia(q))
        obs = np.full((2, 2), np.nan)
        obs_se = np.full((2, 2), np.nan)
        for mode in r.get("modes", []):
            j = mode.get("joint")
            if j not in MODE_JOINTS or "wn_rad_s" not in mode:
                continue
            if mode.get("low_confidence", False) and not include_low_confidence:
                continue
            w, z = float(mode.get("wn_rad_s", math.nan)), float(mode.get("zeta", math.nan))
            if math.isfinite(w) and math.isfinite(z) and w > 0 and z > 0:
                obs[MODE_JOINTS.index(j)] = (w, z)
                obs_se[MODE_JOINTS.index(j)] = (
                    _positive_or_nan(mode.get("wn_se_rad_s")),
                    _positive_or_nan(mode.get("zeta_se")),
                )
        truth = np.full((2, 2), np.nan)
        for mode in r.get("true_modes") or []:
            if mode.get("joint") in MODE_JOINTS:
                truth[MODE_JOINTS.index(mode["joint"])] = (mode["wn_rad_s"], mode["zeta"])
        wn.append(obs[:, 0])
        zeta.append(obs[:, 1])
        wn_se.append(obs_se[:, 0])
        zeta_se.append(obs_se[:, 1])
        twn.append(truth[:, 0])
        tzeta.append(truth[:, 1])
        keys.append(str(r.get("key", i)))
    if not mass:
        raise ValueError(f"no campaign record with a configuration 'q' among {len(records)}")
    return ModalPoses(
        np.array(mass),
        np.array(tau),
        np.array(wn),
        np.array(zeta),
        np.array(twn),
        np.array(tzeta),
        np.array(inertia),
        tuple(keys),
        np.array(wn_se),
        np.array(zeta_se),
    )


#: Relative difference beyond which a record's stored joint inertias are not the robot
#: model's (the campaign writes the same model's values, equal to rounding).
INERTIA_MISMATCH = 1e-6


def _check_stored_inertia(
    record: Mapping[str, Any], index: int, model_inertia: np.ndarray, robot_name: str
) -> None:
    """Refuse a record whose stored joint inertias (``inertia_kg_m2``, written by the campaign
    from its robot model) are not ``robot_name``'s at its pose: the campaign ran with another
    robot or payload, and the fit would silently use the wrong mass matrices."""
    stored = record.get("inertia_kg_m2")
    if stored is None:
        return
    stored = np.asarray(stored, dtype=float)
    if stored.shape != model_inertia.shape:
        return
    rel = np.abs(stored - model_inertia) / np.maximum(np.abs(model_inertia), 1e-9)
    worst = float(np.max(rel)) if rel.size else 0.0
    if not worst <= INERTIA_MISMATCH:
        key = record.get("key", index)
        raise ValueError(
            f"records[{index}] ({key}): its joint inertias differ from the {robot_name} "
            f"model's by {100 * worst:.3g} %: the campaign ran with another robot or payload; "
            "pass the campaign's robot (--robot)"
        )


def _positive_or_nan(value: Any) -> float:
    """A stated standard error as a float, NaN if absent, not finite or not positive."""
    try:
        value = float(value)
    except (TypeError, ValueError):
        return math.nan
    return value if math.isfinite(value) and value > 0 else math.nan


# --------------------------------------------------------------------------- the two steps


def _entries(
    flex_joints: Sequence[int],
    stiffness: Mapping[int, Sequence[float]],
    damping: Mapping[int, Sequence[float]],
    damping_load: Mapping[int, int],
) -> list[dict[str, Any]]:
    return [
        {
            "joint": j,
            "stiffness_nm_per_rad": [float(v) for v in stiffness[j]],
            "damping_nms_per_rad": [float(v) for v in damping.get(j, (0.0, 0.0, 0.0))],
            "damping_load_joint": int(damping_load.get(j, j)),
        }
        for j in flex_joints
    ]


@dataclass
class _Term:
    joint: int
    name: str  # "k_0", "a_1", "a_2" or "c_0", "c_1", "c_2"


def _stiffness_laws(
    x: np.ndarray, terms: Sequence[_Term], flex_joints: Sequence[int]
) -> dict[int, list[float]]:
    k0 = {j: 0.0 for j in flex_joints}
    a = {j: [0.0, 0.0] for j in flex_joints}
    for value, t in zip(x, terms, strict=True):
        if t.name == "k_0":
            k0[t.joint] = math.exp(value)
        else:
            a[t.joint][int(t.name[-1]) - 1] = value
    return {j: [k0[j], k0[j] * a[j][0], k0[j] * a[j][1]] for j in flex_joints}


def _predict(
    poses: ModalPoses,
    flex_joints: Sequence[int],
    stiffness: Mapping[int, Sequence[float]],
    damping: Mapping[int, Sequence[float]],
    damping_load: Mapping[int, int],
) -> np.ndarray:
    """(n_poses, 2, 2) predicted (wn, zeta) through the core map."""
    m = ModalMap(_entries(flex_joints, stiffness, damping, damping_load), MODE_JOINTS)
    tau = poses.gravity_torque_nm if m.uses_gravity else None
    return m.modes_from_mass_matrix_many(poses.mass_kg_m2, tau)


def _standard_errors(
    jac: np.ndarray, residual: np.ndarray, outlier_sigmas: float | None = None
) -> np.ndarray:
    """``√diag(σ² (JᵀJ)⁻¹)`` with ``σ² = rᵀr / (n − p)``, the inverse through the SVD of ``J``
    (``V S⁻² Vᵀ``; infinite where ``J`` is rank-deficient: an undeterminable parameter).

    With ``outlier_sigmas`` (for a fit with a robust loss), residuals beyond that many robust
    standard deviations (``1.4826 median|r|``) are left out of ``σ²`` and ``J``, as the robust
    loss leaves them out of the fit: a mode the local fit mistook for another (a 20 % residual
    among 0.5 % ones) would otherwise inflate every standard error and get determinable terms
    dropped as insignificant.
    """
    if outlier_sigmas is not None and residual.size:
        robust_sigma = 1.4826 * float(np.median(np.abs(residual)))
        inlier = np.abs(residual) <= outlier_sigmas * robust_sigma
        if robust_sigma > 0 and inlier.sum() > jac.shape[1]:
            jac, residual = jac[inlier], residual[inlier]
    n, p = jac.shape
    if p == 0:
        return np.zeros(0)
    sigma2 = float(residual @ residual) / max(n - p, 1)
    _, sv, vt = np.linalg.svd(jac, full_matrices=False)
    if sv.size < p or sv[-1] <= 1e-12 * sv[0]:
        return np.full(p, math.inf)
    variance = np.einsum("ki,k->i", vt**2, 1.0 / sv**2) * sigma2
    return np.sqrt(np.maximum(variance, 0.0))


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


def _json_number(value: float) -> float | None:
    """``value`` as a float, or ``None`` (JSON null) when it is not finite (an unidentifiable
    term's standard error)."""
    value = float(value)
    return value if math.isfinite(value) else None


def _load_span(poses: ModalPoses, joint: int) -> float:
    return float(np.ptp(np.abs(poses.gravity_torque_nm[:, joint])))


def _coefficient_stats(
    stiff_terms: Sequence[_Term],
    damp_terms: Sequence[_Term],
    stiffness: Mapping[int, Sequence[float]],
    damping: Mapping[int, Sequence[float]],
    se: np.ndarray,
    two_stage: tuple[Mapping[int, Sequence[float]], Mapping[int, Sequence[float]]] | None,
) -> tuple[list[dict[str, Any]], list[dict[str, Any]]]:
    """Every kept law coefficient with its standard error, in physical units (``se``: of the
    stiffness parameters ``log k_0, a_1, a_2``, then of the damping coefficients), and, after
    the joint refinement, the two-stage value it started from."""
    names = ("at_zero", "per_nm", "per_nm2")
    stiffness_stats, damping_stats = [], []
    for i, t in enumerate(stiff_terms):
        index = 0 if t.name == "k_0" else int(t.name[-1])
        # d k_0 = k_0 d(log k_0); k_i = k_0 a_i, d k_i ≈ k_0 d a_i.
        entry = {
            "joint": t.joint,
            "term": names[index],
            "value": float(stiffness[t.joint][index]),
            "se": _json_number(stiffness[t.joint][0] * se[i]),
        }
        if two_stage is not None:
            entry["two_stage"] = float(two_stage[0][t.joint][index])
        stiffness_stats.append(entry)
    for i, t in enumerate(damp_terms, start=len(stiff_terms)):
        index = int(t.name[-1])
        entry = {
            "joint": t.joint,
            "term": names[index],
            "value": float(damping[t.joint][index]),
            "se": _json_number(se[i]),
        }
        if two_stage is not None:
            entry["two_stage"] = float(two_stage[1][t.joint][index])
        damping_stats.append(entry)
    return stiffness_stats, damping_stats


def fit_modal_map(
    records: Sequence[Mapping[str, Any]] | ModalPoses,
    robot_name: str = "ur5e",
    *,
    flex_joints: Sequence[int] = DEFAULT_FLEX_JOINTS,
    damped_joints: Sequence[int] = DEFAULT_DAMPED_JOINTS,
    damping_load: Mapping[int, int] | None = None,
    drop_t: float = 3.0,
    include_low_confidence: bool = False,
    refine: bool = True,
    select_folds: int | None = None,
    exclude_terms: Collection[str] = (),
    stiffness_drop_t: float | None = None,
    metadata: Mapping[str, Any] | None = None,
) -> ModalMap:
    """Fit a :class:`tvist.ModalMap` to a campaign's identified modes.

    Parameters
    ----------
    records
        Campaign pose records (JSON lines of :func:`tvist.ident.campaign.run_campaign`), or
        :func:`modal_poses` of them.
    robot_name
        The robot model (mass matrices, gravity torques).
    flex_joints
        Flexible joints (default base, shoulder, elbow, wrists 1-2); must include 0 and 1.
    damped_joints
        Flexible joints with a damper (default base and shoulder, see
        :data:`DEFAULT_DAMPED_JOINTS`); the others are undamped springs. Must include 0 and 1.
    damping_load
        ``{joint: load joint}`` of the damping laws (default: the base's damper is loaded by
        the shoulder's gravity torque, every other by its own).
    drop_t
        Terms below ``drop_t`` standard errors are dropped (set to 0) and the step refitted.
    include_low_confidence
        Also use identifications flagged low-confidence.
    refine
        After the two steps (stiffness on ω, damping on ζ, with term dropping), refine every
        kept coefficient together on ω and ζ (:func:`_refine_jointly`); the standard errors
        are then the joint fit's. ``False``: the two-step solution.
    select_folds
        Also select the stiffness model by held-out error (:func:`select_terms`, this many
        folds over the poses): a flexible joint other than base and shoulder, or a stiffness
        load term, is kept only if it lowers the held-out frequency error. About
        ``folds × (candidates + 1)`` fits per round; ``None`` (default): no selection.
    exclude_terms
        Terms left out from the start, as :func:`select_terms` names them: ``"joint 3"``
        (made rigid), ``"stiffness a_1 of joint 1"``.
    stiffness_drop_t
        ``drop_t`` of the stiffness load terms (default ``drop_t``; 0: keep every term not
        excluded, as after a selection).
    metadata
        Extra metadata; ``fit_statistics`` is filled in here.

    Returns
    -------
    ModalMap
        With ``metadata["fit_statistics"]``: every law coefficient with its standard error,
        the dropped terms, the RMS relative errors per mode against the identified modes.

    Raises
    ------
    ValueError
        Too few usable identifications, or flexible joints without base and shoulder.
    """
    flex_joints = tuple(int(j) for j in flex_joints)
    if not set(MODE_JOINTS) <= set(flex_joints):
        raise ValueError(
            f"flex_joints must include the base and shoulder (0, 1), got {flex_joints}"
        )
    damped_joints = tuple(int(j) for j in damped_joints)
    if not set(MODE_JOINTS) <= set(damped_joints) <= set(flex_joints):
        raise ValueError(
            f"damped_joints must include the base and shoulder (0, 1) and be flexible joints "
            f"{flex_joints}, got {damped_joints}"
        )
    load = dict(DEFAULT_DAMPING_LOAD if damping_load is None else damping_load)
    poses = (
        records
        if isinstance(records, ModalPoses)
        else modal_poses(records, robot_name, include_low_confidence=include_low_confidence)
    )
    options = {"flex_joints": flex_joints, "damping_load": load, "drop_t": drop_t}
    options["damped_joints"] = damped_joints
    options["refine"] = refine
    selection = None
    if select_folds is not None and not 2 <= select_folds <= poses.n_poses:
        raise ValueError(
            f"select_folds: must be in [2, {poses.n_poses}] (folds over the poses), "
            f"got {select_folds}"
        )
    if select_folds is not None:
        selection = select_terms(
            poses, robot_name, folds=select_folds, exclude_terms=exclude_terms, **options
        )
        exclude_terms = tuple(selection["exclude"])
        stiffness_drop_t = 0.0
    stiff_drop_t = drop_t if stiffness_drop_t is None else stiffness_drop_t
    for name in exclude_terms:
        if name not in _term_names(flex_joints):
            raise ValueError(f"exclude_terms: unknown term {name!r}")
    rigid = {int(n.split()[1]) for n in exclude_terms if n.startswith("joint ")}
    if rigid & set(MODE_JOINTS):
        raise ValueError("exclude_terms: the base and shoulder cannot be made rigid")
    flex_joints = tuple(j for j in flex_joints if j not in rigid)
    if poses.mass_kg_m2.shape[1] <= max(flex_joints):
        raise ValueError(f"flex_joints {flex_joints}: the robot has {poses.mass_kg_m2.shape[1]}")
    n_obs = int(np.isfinite(poses.wn_rad_s).sum())
    stiff_terms = [_Term(j, "k_0") for j in flex_joints]
    for j in flex_joints:
        if _load_span(poses, j) > MIN_LOAD_SPAN_NM:
            stiff_terms += [
                _Term(j, a)
                for a in ("a_1", "a_2")
                if f"stiffness {a} of joint {j}" not in exclude_terms
            ]
    damp_terms = []
    for j in (j for j in flex_joints if j in damped_joints):
        damp_terms.append(_Term(j, "c_0"))
        if _load_span(poses, load.get(j, j)) > MIN_LOAD_SPAN_NM:
            damp_terms += [_Term(j, "c_1"), _Term(j, "c_2")]
    if n_obs < len(stiff_terms) + 2:
        raise ValueError(
            f"{n_obs} usable identified frequencies, need at least {len(stiff_terms) + 2} for "
            f"{len(stiff_terms)} stiffness parameters"
        )
    start = _stiffness_start(poses, flex_joints)

    dropped: dict[str, Any] = {}
    while True:
        stiffness, x, jac, fun = _fit_stiffness(poses, flex_joints, stiff_terms, load, start)
        se = _standard_errors(jac, fun, OUTLIER_SIGMAS)
        # A flexible joint other than base and shoulder whose stiffness the poses cannot
        # determine (standard error of log k above 0.5, or k at its bound) is made rigid.
        undetermined = [
            (se[i], t.joint)
            for i, t in enumerate(stiff_terms)
            if t.name == "k_0"
            and t.joint not in MODE_JOINTS
            and (
                not se[i] < 0.5
                or abs(x[i] - math.log(start[t.joint])) > 0.999 * math.log(STIFFNESS_SPAN)
            )
        ]
        if undetermined:
            rigid = max(undetermined)[1]
            i = next(i for i, t in enumerate(stiff_terms) if t.joint == rigid and t.name == "k_0")
            dropped[f"joint {rigid} made rigid"] = {
                "stiffness_nm_per_rad": stiffness[rigid][0],
                "se_log": _json_number(se[i]),
            }
            flex_joints = tuple(j for j in flex_joints if j != rigid)
            stiff_terms = [t for t in stiff_terms if t.joint != rigid]
            damp_terms = [t for t in damp_terms if t.joint != rigid]
            continue
        weak = [
            (abs(x[i]) / se[i] if se[i] > 0 else math.inf, i)
            for i, t in enumerate(stiff_terms)
            if t.name != "k_0"
        ]
        weak = [w for w in weak if w[0] < stiff_drop_t]
        if not weak:
            break
        _, i = min(weak)
        t = stiff_terms.pop(i)
        dropped[f"stiffness {t.name} of joint {t.joint}"] = {
            "value": float(x[i]),
            "se": _json_number(se[i]),
        }
    while True:
        damping, xd, a, fun_d = _fit_damping(poses, flex_joints, stiffness, damp_terms, load)
        active = xd > 0
        se_d = np.full(len(damp_terms), math.inf)
        if active.any():
            se_d[active] = _standard_errors(a[:, active], fun_d)
        weak = [
            (xd[i] / se_d[i] if se_d[i] > 0 else math.inf, i)
            for i in range(len(damp_terms))
            if damp_terms[i].name != "c_0" or damp_terms[i].joint not in MODE_JOINTS
        ]
        weak = [w for w in weak if w[0] < drop_t]
        if not weak or len(damp_terms) <= 1:
            break
        _, i = min(weak)
        t = damp_terms.pop(i)
        dropped[f"damping {t.name} of joint {t.joint}"] = {
            "value": float(xd[i]),
            "se": _json_number(se_d[i]),
        }
    two_stage = (stiffness, damping)
    se_all = np.concatenate([se, se_d])
    refinement: dict[str, Any] | None = None
    if refine:
        while True:
            joint = _refine_jointly(poses, flex_joints, stiff_terms, damp_terms, load, x, xd, start)
            # The significance test again, on the joint fit: a load term the two stages kept
            # may have lost its significance (it is dropped, and the refinement repeated).
            n_s = len(stiff_terms)
            weak = [
                (abs(joint.x[i]) / joint.se[i] if joint.se[i] > 0 else math.inf, i)
                for i, t in enumerate([*stiff_terms, *damp_terms])
                if t.name not in ("k_0", "c_0") or (t.name == "c_0" and t.joint not in MODE_JOINTS)
            ]
            weak = [w for w in weak if w[0] < (stiff_drop_t if w[1] < n_s else drop_t)]
            if not weak:
                break
            _, i = min(weak)
            terms = stiff_terms if i < n_s else damp_terms
            t = terms.pop(i if i < n_s else i - n_s)
            what = "stiffness" if i < n_s else "damping"
            dropped[f"{what} {t.name} of joint {t.joint}"] = {
                "value": float(joint.x[i]),
                "se": _json_number(joint.se[i]),
                "stage": "joint refinement",
            }
            if i < n_s:
                x, xd = np.delete(joint.x[:n_s], i), joint.x[n_s:]
            else:
                x, xd = joint.x[:n_s], np.delete(joint.x[n_s:], i - n_s)
        stiffness, damping, se_all = joint.stiffness, joint.damping, joint.se
        refinement = {
            "weighting": joint.weighting,
            "relative_scale": {"frequency": joint.scales[0], "damping": joint.scales[1]},
            "cost_two_stage": joint.cost_start,
            "cost": joint.cost,
            "nfev": joint.nfev,
        }
    stiffness_stats, damping_stats = _coefficient_stats(
        stiff_terms, damp_terms, stiffness, damping, se_all, two_stage if refine else None
    )
    entries = _entries(flex_joints, stiffness, damping, load)
    fitted = ModalMap(entries, MODE_JOINTS)
    pred = fitted.modes_from_mass_matrix_many(
        poses.mass_kg_m2, poses.gravity_torque_nm if fitted.uses_gravity else None
    )
    stats = {
        "robot": robot_name,
        "n_poses": poses.n_poses,
        "usable_identifications": {
            "base": int(np.isfinite(poses.wn_rad_s[:, 0]).sum()),
            "shoulder": int(np.isfinite(poses.wn_rad_s[:, 1]).sum()),
        },
        "stiffness_nm_per_rad": stiffness_stats,
        "damping_nms_per_rad": damping_stats,
        "dropped": dropped,
        "drop_t": drop_t,
        "joint_refinement": refinement,
        "excluded": list(exclude_terms),
        "term_selection": selection,
        "versus_identified": relative_errors(pred, poses.wn_rad_s, poses.zeta),
    }
    meta = {"robot": robot_name, "source": "tvist.ident.fit_modal_map", **(metadata or {})}
    meta["fit_statistics"] = stats
    return ModalMap(entries, MODE_JOINTS, meta)


# --------------------------------------------------------------------------- term selection


def _term_names(flex_joints: Sequence[int]) -> list[str]:
    """Names of the terms :func:`select_terms` may leave out, for ``flex_joints``."""
    names = [f"joint {j}" for j in flex_joints if j not in MODE_JOINTS]
    return names + [f"stiffness {a} of joint {j}" for j in flex_joints for a in ("a_1", "a_2")]


def held_out_frequency_error(
    poses: ModalPoses,
    robot_name: str = "ur5e",
    *,
    folds: int = 5,
    seed: int = 0,
    **options: Any,
) -> float:
    """RMS relative error of the natural frequencies (base and shoulder pooled) on held-out
    poses: ``folds``-fold over poses (a seeded permutation), each fold predicted by
    :func:`fit_modal_map` (``options``) of the others; infinite if a fold cannot be fitted."""
    n = poses.n_poses
    if not 2 <= folds <= n:
        raise ValueError(f"folds must be in [2, {n}], got {folds}")
    order = np.random.default_rng(seed).permutation(n)
    errors = []
    for k in range(folds):
        test = np.sort(order[k::folds])
        train, held = poses.subset(np.setdiff1d(np.arange(n), test)), poses.subset(test)
        try:
            modal = fit_modal_map(train, robot_name, **options)
        except ValueError:
            return math.inf
        pred = modal.modes_from_mass_matrix_many(
            held.mass_kg_m2, held.gravity_torque_nm if modal.uses_gravity else None
        )[:, :, 0]
        observed = np.isfinite(held.wn_rad_s)
        rel = pred[observed] / held.wn_rad_s[observed] - 1.0
        if not np.all(np.isfinite(rel)):
            return math.inf
        errors.append(rel)
    pooled = np.concatenate(errors)
    return float(np.sqrt(np.mean(pooled**2))) if pooled.size else math.inf


def select_terms(
    poses: ModalPoses,
    robot_name: str = "ur5e",
    *,
    folds: int = 5,
    seed: int = 0,
    **options: Any,
) -> dict[str, Any]:
    """Selection of the stiffness model by held-out frequency error.

    Significance (a term beyond ``drop_t`` standard errors) does not show model error: a
    wrong law can be "significant" (on the demo campaign a wrist stiffness 2.6 times too
    soft is; with little damping the shoulder's load law can take ``|L|`` for ``L²``).
    Starting from the terms the significance test keeps, each move is tried: leave out a
    flexible joint other than base and shoulder (made rigid) or a stiffness load term, or
    swap a load term for its dropped sibling (``a_1`` ↔ ``a_2``). Every trial fit keeps its
    stiffness terms as given (no significance dropping) and is scored by
    :func:`held_out_frequency_error`; the best move is made if it does not raise the error
    (a swap: if it lowers it), and the search repeats. A term is thus kept only if it
    lowers the held-out frequency error. Damping terms are left to the significance test.

    Returns ``{"folds", "seed", "exclude": [names], "moves": [{"move", "held_out_rms"}],
    "held_out_rms": e}``; ``exclude`` as ``exclude_terms`` of :func:`fit_modal_map` takes it
    (with ``stiffness_drop_t=0``).
    """
    options = {
        k: v
        for k, v in options.items()
        if k not in ("select_folds", "exclude_terms", "stiffness_drop_t")
    }
    every = _term_names(options.get("flex_joints", DEFAULT_FLEX_JOINTS))
    full = fit_modal_map(poses, robot_name, **options)
    included = {f"joint {e['joint']}" for e in full.flex_joints if e["joint"] not in MODE_JOINTS}
    included |= {
        f"stiffness a_{('per_nm', 'per_nm2').index(t['term']) + 1} of joint {t['joint']}"
        for t in full.metadata["fit_statistics"]["stiffness_nm_per_rad"]
        if t["term"] != "at_zero"
    }

    def exclude(terms: set[str]) -> list[str]:
        return [n for n in every if n not in terms]

    def score(terms: set[str]) -> float:
        return held_out_frequency_error(
            poses,
            robot_name,
            folds=folds,
            seed=seed,
            exclude_terms=exclude(terms),
            stiffness_drop_t=0.0,
            **options,
        )

    current = score(included)
    moves: list[dict[str, Any]] = []
    while True:
        trials: dict[str, tuple[set[str], float, bool]] = {}
        for name in sorted(included):
            if name.startswith("joint "):
                joint = name.split()[1]
                fewer = {n for n in included if n != name and not n.endswith(f"joint {joint}")}
                trials[f"leave out {name}"] = (fewer, score(fewer), False)
                continue
            fewer = included - {name}
            trials[f"leave out {name}"] = (fewer, score(fewer), False)
            sibling = name.replace("a_1", "a_2") if "a_1" in name else name.replace("a_2", "a_1")
            if sibling not in included and sibling in every:
                swapped = fewer | {sibling}
                trials[f"swap {name} for {sibling}"] = (swapped, score(swapped), True)
        if not trials:
            break
        move = min(trials, key=lambda m: trials[m][1])
        terms, error, is_swap = trials[move]
        if not (error < current if is_swap else error <= current):
            break
        moves.append({"move": move, "held_out_rms": _json_number(error)})
        included, current = terms, error
    return {
        "folds": folds,
        "seed": seed,
        "exclude": exclude(included),
        "moves": moves,
        "held_out_rms": _json_number(current),
    }


# --------------------------------------------------------------------------- evaluation


def relative_errors(pred: np.ndarray, wn_rad_s: np.ndarray, zeta: np.ndarray) -> dict[str, Any]:
    """RMS and max relative errors of predictions ``(n, 2, 2)`` against modes ``(n, 2)``,
    per mode (base, shoulder), over the finite entries."""
    out: dict[str, Any] = {}
    for m, name in enumerate(("base", "shoulder")):
        entry: dict[str, Any] = {}
        for q, ref in (("frequency", wn_rad_s[:, m]), ("damping", zeta[:, m])):
            rel = pred[:, m, 0 if q == "frequency" else 1] / ref - 1.0
            rel = rel[np.isfinite(rel)]
            entry[q] = {
                "n": int(rel.size),
                "rms": float(np.sqrt(np.mean(rel**2))) if rel.size else math.nan,
                "max": float(np.max(np.abs(rel))) if rel.size else math.nan,
            }
        out[name] = entry
    return out


def _published_predictions(
    train: ModalPoses, test: ModalPoses, records_like: bool = True
) -> np.ndarray:
    """Fit the published 10-coefficient form on ``train`` and predict ``test``."""
    from tvist.ident.map_fit import fit_map

    train_records = _as_records(train)
    dynmap = fit_map(train_records)
    tau = test.gravity_torque_nm if dynmap.uses_gravity else None
    return dynmap.modes_from_inertia_many(test.inertia_kg_m2, tau)


def _as_records(poses: ModalPoses) -> list[dict[str, Any]]:
    """The map fit's record form of ``poses`` (usable identifications only)."""
    out = []
    for i in range(poses.n_poses):
        modes = [
            {"joint": j, "wn_rad_s": float(poses.wn_rad_s[i, m]), "zeta": float(poses.zeta[i, m])}
            for m, j in enumerate(MODE_JOINTS)
            if np.isfinite(poses.wn_rad_s[i, m])
        ]
        out.append(
            {
                "inertia_kg_m2": poses.inertia_kg_m2[i].tolist(),
                "gravity_torque_nm": poses.gravity_torque_nm[i].tolist(),
                "modes": modes,
            }
        )
    return out


def cross_validate(
    records: Sequence[Mapping[str, Any]],
    robot_name: str = "ur5e",
    *,
    folds: int = 5,
    seed: int = 0,
    flex_joints: Sequence[int] = DEFAULT_FLEX_JOINTS,
) -> dict[str, Any]:
    """Both map forms, in-sample and on held-out poses (``folds``-fold over poses).

    Returns, per form (``"modal"``, ``"published"``) and per set (``"in_sample"``,
    ``"held_out"``), :func:`relative_errors` against the identified modes and, where the
    records carry them (a twin's campaign), against the true modes. Held-out predictions
    come from the fold's fit on the other poses; every pose is held out once.
    """
    from tvist.ident.map_fit import fit_map

    poses = modal_poses(records, robot_name)
    n = poses.n_poses
    if folds < 2 or folds > n:
        raise ValueError(f"folds must be in [2, {n}], got {folds}")
    order = np.random.default_rng(seed).permutation(n)
    held = {"modal": np.full((n, 2, 2), np.nan), "published": np.full((n, 2, 2), np.nan)}
    for k in range(folds):
        test = np.sort(order[k::folds])
        train = np.setdiff1d(np.arange(n), test)
        tr, te = poses.subset(train), poses.subset(test)
        modal = fit_modal_map(tr, robot_name, flex_joints=flex_joints)
        held["modal"][test] = modal.modes_from_mass_matrix_many(
            te.mass_kg_m2, te.gravity_torque_nm if modal.uses_gravity else None
        )
        held["published"][test] = _published_predictions(tr, te)
    modal = fit_modal_map(poses, robot_name, flex_joints=flex_joints)
    published = fit_map(_as_records(poses))
    in_sample = {
        "modal": modal.modes_from_mass_matrix_many(
            poses.mass_kg_m2, poses.gravity_torque_nm if modal.uses_gravity else None
        ),
        "published": published.modes_from_inertia_many(
            poses.inertia_kg_m2, poses.gravity_torque_nm if published.uses_gravity else None
        ),
    }
    has_truth = bool(np.isfinite(poses.true_wn_rad_s).any())
    out: dict[str, Any] = {"n_poses": n, "folds": folds, "seed": seed}
    for form in ("modal", "published"):
        out[form] = {}
        for label, pred in (("in_sample", in_sample[form]), ("held_out", held[form])):
            entry = {"versus_identified": relative_errors(pred, poses.wn_rad_s, poses.zeta)}
            if has_truth:
                entry["versus_true"] = relative_errors(pred, poses.true_wn_rad_s, poses.true_zeta)
            out[form][label] = entry
    return out


def format_comparison(cv: Mapping[str, Any]) -> str:
    """A markdown table of :func:`cross_validate`'s frequency and damping errors."""
    lines = [
        "| form | poses | against | mode | f RMS [%] | f max [%] | ζ RMS [%] | ζ max [%] |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for form, label in (("modal", "modal map"), ("published", "published form")):
        for where in ("in_sample", "held_out"):
            for against in ("versus_true", "versus_identified"):
                entry = cv[form][where].get(against)
                if entry is None:
                    continue
                for mode in ("base", "shoulder"):
                    f, z = entry[mode]["frequency"], entry[mode]["damping"]
                    lines.append(
                        f"| {label} | {where.replace('_', ' ')} | "
                        f"{against.replace('versus_', '')} | {mode} | {100 * f['rms']:.2f} | "
                        f"{100 * f['max']:.2f} | {100 * z['rms']:.1f} | {100 * z['max']:.1f} |"
                    )
    return "\n".join(lines)


def _record_payload(record: Mapping[str, Any], i: int) -> tuple[float, tuple[float, ...]]:
    """``(payload_kg, payload_com_m)`` of pose record ``i``: both must be there (the mass
    matrices depend on them), except the centre of mass of a zero payload."""
    name = f"records[{i}] ({record.get('key', 'no key')})"
    if "payload_kg" not in record:
        raise ValueError(
            f"{name}: no payload_kg; a pose record names its payload (tvist identify "
            "--payload-kg, or logs recorded with it)"
        )
    mass = float(record["payload_kg"])
    com = record.get("payload_com_m")
    if com is None and mass != 0.0:
        raise ValueError(f"{name}: payload_kg {mass:g} without payload_com_m")
    return mass, tuple(float(v) for v in (com or (0.0, 0.0, 0.0)))


def main(argv: Sequence[str] | None = None) -> int:
    """``python -m tvist.ident.modal_fit RESULTS.jsonl [--robot R] [--folds K]``: both map
    forms' errors, in-sample and on held-out poses, as a markdown table."""
    import argparse

    from tvist.ident.campaign import load_results

    p = argparse.ArgumentParser(prog="python -m tvist.ident.modal_fit", description=main.__doc__)
    p.add_argument("results", help="campaign results (JSON lines)")
    p.add_argument("--robot", default="ur5e", help="robot model (default ur5e)")
    p.add_argument("--folds", type=int, default=5, help="folds over poses (default 5)")
    args = p.parse_args(argv)
    records = load_results(args.results)
    try:
        cv = cross_validate(records, args.robot, folds=args.folds)
    except ValueError as exc:
        print(f"python -m tvist.ident.modal_fit: error: {exc}", file=sys.stderr)
        return 2
    print(f"{cv['n_poses']} poses, {cv['folds']}-fold over poses (seed {cv['seed']})")
    print(format_comparison(cv))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
