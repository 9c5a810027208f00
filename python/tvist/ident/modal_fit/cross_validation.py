""":func:`cross_validate`: the modal map against the published 10-coefficient form, in-sample
and on held-out poses (k-fold over poses), against the identified modes and, for a twin's
campaign, the true modes; :func:`format_comparison` tabulates it."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from tvist.ident.modal_fit.fit import fit_modal_map
from tvist.ident.modal_fit.model import DEFAULT_FLEX_JOINTS
from tvist.ident.modal_fit.poses import MODE_JOINTS, ModalPoses, modal_poses
from tvist.ident.modal_fit.statistics import relative_errors


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
