"""The demo's modal-map row: a :class:`tvist.ModalMap` fitted to the same reduced campaign as
the identified published map, shaping through the same real-time path
(``tvist.ModalDynamics(robot, modal_map)``, evaluated in Rust every cycle)."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import tvist
from tvist.experiments.method_row import Method
from tvist.experiments.methods import fd_tvist_modal
from tvist.maps.modal import ModalMap

KEY = "fd-tvist-identified-modal-map"
LABEL = "FD-TVIST ZV, identified modal map"
MAP_FILE = "identified_modal_map.json"


def identify_modal_map(
    records: Sequence[dict], out_dir: str | Path, log: Any = None
) -> tuple[Method | None, dict[str, Any]]:
    """Fit the modal map to every mode the demo campaign's ``records`` identified (the fit
    ``tvist fit-map --kind modal`` makes, :func:`tvist.ident.all_modes_fit.fit_all_modes`),
    save it next to them, and return its row with a summary (the shaped modes' frequency
    errors against the twin's true modes at workspace poses unlike the campaign's,
    :func:`tvist.experiments.generalization.map_vs_truth`),
    or ``(None, {"error": ...})`` if the fit fails."""
    from tvist.ident.all_modes_fit import fit_all_modes, fitted_map

    try:
        fit = fit_all_modes(records, "ur5e")
        n_poses = fit.statistics["n_poses"]
        modal = fitted_map(fit, {"source": f"reduced campaign on the twin ({n_poses} poses)"})
        modal.save(Path(out_dir) / MAP_FILE)
        # The real-time provider rejects a map with an overdamped mode at a sampled pose.
        from tvist.experiments.motions import PAYLOAD_COM_M, PAYLOAD_KG

        tvist.ModalDynamics(
            tvist.robots.ur5e(payload_kg=PAYLOAD_KG, payload_com_m=PAYLOAD_COM_M), modal
        )
    except ValueError as exc:
        if log is not None:
            log(f"identified modal map skipped: {exc}")
        return None, {"error": str(exc)}
    summary = {
        "map_file": MAP_FILE,
        "flex_joints": modal.flex_joints,
        "shaped_modes": modal.shaped_modes,
        "mode_joints": modal.mode_joints,
        "fit_statistics": modal.metadata["fit_statistics"],
        "versus_true_modes": _versus_true_modes(modal),
    }
    return fd_tvist_modal(KEY, LABEL, modal), summary


def _versus_true_modes(modal: ModalMap) -> list[dict[str, Any]]:
    """Per shaped mode of ``modal``: RMS and largest frequency error (%) against the default
    twin's true modes at the generalization harness's evaluation poses."""
    from tvist.experiments.generalization import evaluation_poses, map_vs_truth
    from tvist.experiments.motions import PAYLOAD_COM_M, PAYLOAD_KG
    from tvist.sim.family import nominal_variant

    robot = tvist.robots.ur5e(payload_kg=PAYLOAD_KG, payload_com_m=PAYLOAD_COM_M)
    return map_vs_truth(nominal_variant("ur5e"), modal, robot, evaluation_poses("ur5e", None))[
        "modes"
    ]


def compare_on_variant(variant: str, records_path: str | Path) -> list[tuple[str, str, float]]:
    """Both identified map forms on the twin variant ``variant`` (:mod:`tvist.sim.variants`),
    fitted to that variant's campaign records: ``(motion, row label, reduction %)`` for the
    experiment's three motions, e.g.
    ``compare_on_variant("ur5e-soft-gears", "out/campaign_variant.jsonl")`` (or a family
    variant, ``"family:ur5e:17"``)."""
    from tvist.experiments.experiment import run_experiment
    from tvist.experiments.methods import default_methods, fd_tvist_map
    from tvist.ident.campaign import load_results
    from tvist.ident.map_fit import fit_map
    from tvist.ident.modal_fit import fit_modal_map
    from tvist.sim.variants import variant_robot, variant_twin_kwargs

    if variant_robot(variant) != "ur5e":
        raise ValueError(f"the demo's motions are the UR5e's; {variant!r} is not a UR5e")
    records = load_results(records_path)
    rows = [m for m in default_methods() if m.key == "unshaped"]
    rows.append(
        fd_tvist_map("fd-tvist-identified-map", "identified published map", fit_map(records))
    )
    rows.append(fd_tvist_modal(KEY, "identified modal map", fit_modal_map(records, "ur5e")))
    result = run_experiment(methods=rows, **variant_twin_kwargs(variant))
    return [
        (m.motion.name, run.method.label, float(run.to_json()["reduction_percent"]))
        for m in result.motions
        for run in m.runs[1:]
    ]
