"""The demo's modal-map row: a :class:`tvist.ModalMap` fitted to the same reduced campaign as
the identified published map, shaping through the same real-time path
(``tvist.MapDynamics(robot, modal_map)``, evaluated in Rust every cycle)."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

import tvist
from tvist.demo.methods import TVIST_SHAPER, Method, MotionContext, Reference, _run_tv_shaper
from tvist.modal_map import ModalMap

KEY = "fd-tvist-identified-modal-map"
LABEL = "FD-TVIST ZV, identified modal map"
MAP_FILE = "identified_modal_map.json"
#: Flexible joints of the demo's modal map: base, shoulder, elbow and wrists 1-2 (the fit's
#: default). From the demo campaign the fit keeps wrist 2 (10 200 N m/rad; the twin's gears
#: 15 000) and makes wrist 1 rigid. Checked on poses other than the test motions', the full
#: 208-pose campaign's (true modes): base frequency within 0.24 % RMS (1.4 % max), against
#: 1.05 % (9.6 %) with base, shoulder and elbow only, whose map cannot express the wrists'
#: part in the base mode at folded poses.
DEMO_FLEX_JOINTS = (0, 1, 2, 3, 4)


def fd_tvist_modal(key: str, label: str, modal: ModalMap) -> Method:
    """A ZV FD-TVIST row driven by ``modal`` through :class:`tvist.MapDynamics` (a
    frequency-ranked map shapes the modes each move needs)."""

    def build(ctx: MotionContext) -> Reference:
        provider = tvist.MapDynamics(ctx.robot, modal)
        shaper = tvist.TvShaper(
            provider, ctx.trajectory.dt_s, ctx.trajectory.n_dof, shaper=TVIST_SHAPER
        )
        source = modal.metadata.get("source") or "modal map"
        return _run_tv_shaper(shaper, ctx, f"MapDynamics (modal): {source}", provider)

    # ``dynmap`` only needs ``modes(robot, q)`` (the mode tracks of the report).
    return Method(key=key, label=label, build=build, dynmap=modal)  # type: ignore[arg-type]


def identify_modal_map(
    records: Sequence[dict], out_dir: str | Path, log: Any = None
) -> tuple[Method | None, dict[str, Any]]:
    """Fit the modal map to the demo campaign's ``records``, save it next to them, and return
    its row with a summary (errors against the twin's true modes at the campaign poses), or
    ``(None, {"error": ...})`` if the fit fails."""
    from tvist.ident.modal_fit import fit_modal_map, modal_poses, relative_errors

    try:
        poses = modal_poses(records, "ur5e")
        modal = fit_modal_map(
            poses,
            "ur5e",
            flex_joints=DEMO_FLEX_JOINTS,
            metadata={"source": f"reduced campaign on the twin ({poses.n_poses} poses)"},
        )
        modal.save(Path(out_dir) / MAP_FILE)
        # The real-time provider rejects a map with an overdamped mode at a sampled pose.
        from tvist.demo.motions import PAYLOAD_COM_M, PAYLOAD_KG

        tvist.MapDynamics(
            tvist.robots.ur5e(payload_kg=PAYLOAD_KG, payload_com_m=PAYLOAD_COM_M), modal
        )
    except ValueError as exc:
        if log is not None:
            log(f"identified modal map skipped: {exc}")
        return None, {"error": str(exc)}
    pred = modal.modes_from_mass_matrix_many(
        poses.mass_kg_m2, poses.gravity_torque_nm if modal.uses_gravity else None
    )
    usable = np.isfinite(poses.wn_rad_s)
    truth_wn = np.where(usable, poses.true_wn_rad_s, np.nan)
    truth_zeta = np.where(usable, poses.true_zeta, np.nan)
    summary = {
        "map_file": MAP_FILE,
        "flex_joints": modal.flex_joints,
        "fit_statistics": modal.metadata["fit_statistics"],
        "versus_true_modes": relative_errors(pred, truth_wn, truth_zeta),
    }
    return fd_tvist_modal(KEY, LABEL, modal), summary


def compare_on_variant(variant: str, records_path: str | Path) -> list[tuple[str, str, float]]:
    """Both identified map forms on the twin variant ``variant`` (:mod:`tvist.sim.variants`),
    fitted to that variant's campaign records: ``(motion, row label, reduction %)`` for the
    experiment's three motions, e.g.
    ``compare_on_variant("ur5e-soft-gears", "out/campaign_variant.jsonl")`` (or a family
    variant, ``"family:ur5e:17"``)."""
    from tvist.demo.experiment import run_experiment
    from tvist.demo.methods import default_methods, fd_tvist_map
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
