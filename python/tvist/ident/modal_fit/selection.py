"""Selection of the stiffness model by held-out frequency error (``select_folds`` of
:func:`~tvist.ident.modal_fit.fit.fit_modal_map`): a term is kept only if it lowers the
frequency error on the poses a fit did not see.

The selection refits the map many times, so it takes the fit as an argument (``fit``,
:func:`~tvist.ident.modal_fit.fit.fit_modal_map` itself): that function calls
:func:`select_terms`, and the two modules would otherwise import each other."""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import numpy as np

from tvist import ModalMap
from tvist.ident.modal_fit.model import DEFAULT_FLEX_JOINTS, _term_names
from tvist.ident.modal_fit.poses import MODE_JOINTS, ModalPoses
from tvist.ident.modal_fit.statistics import _json_number


def held_out_frequency_error(
    poses: ModalPoses,
    robot_name: str = "ur5e",
    *,
    fit: Callable[..., ModalMap],
    folds: int = 5,
    seed: int = 0,
    **options: Any,
) -> float:
    """RMS relative error of the natural frequencies (base and shoulder pooled) on held-out
    poses: ``folds``-fold over poses (a seeded permutation), each fold predicted by
    :func:`~tvist.ident.modal_fit.fit.fit_modal_map` (``fit``, with ``options``) of the others;
    infinite if a fold cannot be fitted."""
    n = poses.n_poses
    if not 2 <= folds <= n:
        raise ValueError(f"folds must be in [2, {n}], got {folds}")
    order = np.random.default_rng(seed).permutation(n)
    errors = []
    for k in range(folds):
        test = np.sort(order[k::folds])
        train, held = poses.subset(np.setdiff1d(np.arange(n), test)), poses.subset(test)
        try:
            modal = fit(train, robot_name, **options)
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
    fit: Callable[..., ModalMap],
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
    "held_out_rms": e}``; ``exclude`` as ``exclude_terms`` of
    :func:`~tvist.ident.modal_fit.fit.fit_modal_map` takes it
    (with ``stiffness_drop_t=0``).
    """
    options = {
        k: v
        for k, v in options.items()
        if k not in ("select_folds", "exclude_terms", "stiffness_drop_t")
    }
    every = _term_names(options.get("flex_joints", DEFAULT_FLEX_JOINTS))
    full = fit(poses, robot_name, **options)
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
            fit=fit,
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
