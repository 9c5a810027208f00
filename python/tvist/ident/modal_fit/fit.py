""":func:`fit_modal_map`: the modal fit's stages in order (the package docstring,
:mod:`tvist.ident.modal_fit`, describes them), the significance test between them (a term
below ``drop_t`` standard errors is dropped and the stage refitted), and the fit's statistics
in the map's metadata."""

from __future__ import annotations

import math
from collections.abc import Collection, Mapping, Sequence
from typing import Any

import numpy as np

from tvist import ModalMap
from tvist.ident.modal_fit.model import (
    DEFAULT_DAMPED_JOINTS,
    DEFAULT_DAMPING_LOAD,
    DEFAULT_FLEX_JOINTS,
    MIN_LOAD_SPAN_NM,
    _entries,
    _Term,
    _term_names,
)
from tvist.ident.modal_fit.poses import MODE_JOINTS, ModalPoses, modal_poses
from tvist.ident.modal_fit.refinement import _refine_jointly
from tvist.ident.modal_fit.selection import select_terms
from tvist.ident.modal_fit.statistics import (
    OUTLIER_SIGMAS,
    _coefficient_stats,
    _json_number,
    _standard_errors,
    relative_errors,
)
from tvist.ident.modal_fit.two_stage import (
    STIFFNESS_SPAN,
    _fit_damping,
    _fit_stiffness,
    _stiffness_start,
)


def _load_span(poses: ModalPoses, joint: int) -> float:
    return float(np.ptp(np.abs(poses.gravity_torque_nm[:, joint])))


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
        # The selection refits through this function, passed in.
        selection = select_terms(
            poses,
            robot_name,
            fit=fit_modal_map,
            folds=select_folds,
            exclude_terms=exclude_terms,
            **options,
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
