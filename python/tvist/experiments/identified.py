"""A map identified on the twin: a reduced mapping campaign (Algorithm 1) and the map fit.

The campaign excites the base and the shoulder in turn at every pose (Algorithm 2), fits the
local transfer function to the noisy tool accelerometer (eq. 17) and fits the dynamic map to
the identified modes (section 5.3). The fitted map is limited to the inertias of its poses (it
never extrapolates, see :mod:`tvist.maps.paper10`), so the campaign must cover the inertias the test
motions pass through: its radii reach from the folded pose Q3 (0.25 m from the shoulder axis)
to the stretched pose Q1 (0.92 m), beyond the paper's 0.4-0.9 m. It is reduced to two
payloads (none and the experiment's 5 kg) and 3 angles x 6 radii, 36 poses, so that it fits the
demo's time budget (:data:`DEMO_PLAN` says why these); the published map is fitted to the 5 kg
poses, the modal map (:mod:`tvist.experiments.modal_rows`) to all. The full campaign is
:func:`tvist.ident.campaign.run_campaign` over :func:`tvist.ident.campaign.campaign_poses`.

The campaign's pose records are kept in ``campaign.jsonl`` next to a fingerprint of its
settings and of the code that produced them (``campaign_fingerprint.json``): a second run with
the same fingerprint reuses the records (and resumes an interrupted campaign); any change
starts it afresh.
"""

from __future__ import annotations

import hashlib
import json
import math
import os
import time
from collections.abc import Sequence
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from tvist import robots
from tvist.experiments.method_row import Method
from tvist.experiments.methods import fd_tvist_map
from tvist.experiments.motions import PAYLOAD_COM_M, PAYLOAD_KG
from tvist.maps.paper10 import DynamicMap, MapDynamics

KEY = "fd-tvist-identified-map"
LABEL = "FD-TVIST ZV, identified map"
#: Files of the campaign in the output folder.
CAMPAIGN_FILE = "campaign.jsonl"
FINGERPRINT_FILE = "campaign_fingerprint.json"
MAP_FILE = "identified_map.json"
#: Python sources whose change invalidates cached campaign records (relative to ``tvist``):
#: the twin and the identification chain.
_FINGERPRINT_SOURCES = (
    "sim",
    "ident/campaign.py",
    "ident/excitation.py",
    "ident/local_fit.py",
    "ident/logs.py",
    "ident/preprocess.py",
    "ident/two_mode.py",
    "ident/zoh.py",
    "ident/base_mode.py",
    "ident/pose.py",
    "ident/pose_plan.py",
    "ident/campaign_robots.py",
    "ident/results_store.py",
    "robots",
)


@dataclass(frozen=True)
class CampaignPlan:
    """Settings of a reduced campaign on the twin.

    Attributes
    ----------
    payloads_kg
        Payloads, kg (centre of mass at :data:`~tvist.experiments.motions.PAYLOAD_COM_M`).
    radii_m
        Distances of the flange centre from the shoulder axis, m.
    angles_rad
        Angles of the flange seen from the shoulder (Algorithm 1), rad.
    duration_s
        Excitation length per joint, s (Algorithm 2: about 8 s).
    accel_noise_std_m_s2
        Accelerometer noise of the twin during identification (a real sensor is noisy).
    seed
        Seed of the random wrist angles, excitations and noise.
    """

    payloads_kg: tuple[float, ...] = (PAYLOAD_KG,)
    radii_m: tuple[float, ...] = (0.25, 0.4, 0.55, 0.7, 0.82, 0.92)
    angles_rad: tuple[float, ...] = (0.0, math.pi / 4, math.pi / 2, 3 * math.pi / 4)
    duration_s: float = 8.0
    accel_noise_std_m_s2: float = 0.05
    seed: int = 1

    def poses(self) -> list:
        """The plan's campaign poses (:func:`tvist.ident.campaign.campaign_poses`)."""
        from tvist.ident.campaign import campaign_poses

        return campaign_poses(
            "ur5e",
            payloads_kg=self.payloads_kg,
            payload_com_m=PAYLOAD_COM_M,
            angles_rad=self.angles_rad,
            radii_m=self.radii_m,
            seed=self.seed,
        )

    @property
    def n_poses(self) -> int:
        return len(self.payloads_kg) * len(self.radii_m) * len(self.angles_rad)


#: The demo's campaign: 36 poses, two payloads (none and the experiment's 5 kg), radii covering
#: the test motions' Q3 ... Q1, three angles. Two payloads because at one payload the gravity
#: load and the inertia of a joint grow together with the reach, so the modal map's load laws
#: and the elbow's stiffness cannot be told apart (from the former 5 kg-only, 24-pose campaign
#: the modal fit makes the elbow rigid); no pose at V = π/2 (arm pointing up),
#: where the base mode is a torsion of the wrists that the base excitation does not identify
#: (every such base identification is flagged low-confidence).
DEMO_PLAN = CampaignPlan(
    payloads_kg=(0.0, PAYLOAD_KG), angles_rad=(0.0, math.pi / 4, 3 * math.pi / 4)
)
#: The quick run's campaign (tests): 12 poses and 4 s excitations; enough to exercise the
#: pipeline, too little for a map one would use.
QUICK_PLAN = CampaignPlan(radii_m=(0.25, 0.55, 0.92), duration_s=4.0)


@dataclass
class IdentifiedMap:
    """Outcome of the reduced campaign.

    Attributes
    ----------
    method
        The FD-TVIST row driven by the identified map, or ``None`` if identification failed.
    summary
        JSON-ready facts: plan, poses, usable identifications per mode, identified and fitted
        modes against the twin's true modes, coefficients with ranges, files, time; or
        ``{"error": ...}``.
    dynmap
        The fitted map (``None`` on failure).
    records
        The campaign's pose records.
    """

    method: Method | None
    summary: dict[str, Any] = field(default_factory=dict)
    dynmap: DynamicMap | None = None
    records: list[dict] = field(default_factory=list)


def _source_digest() -> str:
    """SHA-256 over the sources that produce campaign records."""
    import tvist

    root = Path(tvist.__file__).parent
    digest = hashlib.sha256()
    for rel in _FINGERPRINT_SOURCES:
        path = root / rel
        files = sorted(path.rglob("*")) if path.is_dir() else [path]
        for f in files:
            if f.is_file() and f.suffix in (".py", ".json"):
                digest.update(str(f.relative_to(root)).encode())
                digest.update(f.read_bytes())
    return digest.hexdigest()


def _fingerprint(plan: CampaignPlan, poses: Sequence[Any]) -> dict[str, Any]:
    """What the campaign records depend on, in its JSON form (so that it compares equal to
    the stored file)."""
    fingerprint = {
        "plan": asdict(plan),
        "payload_com_m": list(PAYLOAD_COM_M),
        "poses": [[p.key, None if p.q is None else [float(v) for v in p.q]] for p in poses],
        "sources_sha256": _source_digest(),
    }
    return json.loads(json.dumps(fingerprint))


def _prepare_cache(out: Path, fingerprint: dict[str, Any]) -> int:
    """Keep ``campaign.jsonl`` only if it was made with ``fingerprint``; returns the number of
    records kept."""
    from tvist.ident.campaign import load_results

    results_path, fp_path = out / CAMPAIGN_FILE, out / FINGERPRINT_FILE
    try:
        same = json.loads(fp_path.read_text(encoding="utf-8")) == fingerprint
    except (OSError, ValueError):
        same = False
    if not same:
        results_path.unlink(missing_ok=True)
        fp_path.write_text(json.dumps(fingerprint, indent=1) + "\n", encoding="utf-8")
        return 0
    try:
        return len(load_results(results_path))
    except ValueError:  # a damaged file: start afresh
        results_path.unlink(missing_ok=True)
        return 0


def _relative_errors(records: Sequence[dict], dynmap: DynamicMap) -> dict[str, Any]:
    """Per mode: the identified and the fitted map's ``f_n`` and ``ζ`` against the twin's
    true modes at the campaign poses (usable identifications only)."""
    out: dict[str, Any] = {}
    for index, name in enumerate(("base", "shoulder")):
        ident, fitted, true = [], [], []
        for r in records:
            truth = {m["joint"]: m for m in r.get("true_modes") or []}
            mode = next((m for m in r.get("modes", []) if m.get("joint") == index), None)
            if mode is None or "wn_rad_s" not in mode or mode.get("low_confidence", False):
                continue
            if index not in truth:
                continue
            tau = r.get("gravity_torque_nm") if dynmap.uses_gravity else None
            fitted.append(dynmap.modes_from_inertia(r["inertia_kg_m2"], tau)[index])
            ident.append((mode["wn_rad_s"], mode["zeta"]))
            true.append((truth[index]["wn_rad_s"], truth[index]["zeta"]))
        if not true:
            continue
        t = np.array(true)
        entry: dict[str, Any] = {"n_poses": len(true)}
        for source, values in (("identified", ident), ("map", fitted)):
            rel = np.array(values) / t - 1.0
            entry[source] = {
                "f_n_rms_percent": float(100 * np.sqrt(np.mean(rel[:, 0] ** 2))),
                "f_n_max_percent": float(100 * np.max(np.abs(rel[:, 0]))),
                "zeta_rms_percent": float(100 * np.sqrt(np.mean(rel[:, 1] ** 2))),
                "zeta_max_percent": float(100 * np.max(np.abs(rel[:, 1]))),
            }
        out[name] = entry
    return out


def identify_map(
    out_dir: str | Path,
    *,
    plan: CampaignPlan = DEMO_PLAN,
    workers: int | None = None,
    log: Any = None,
) -> IdentifiedMap:
    """Run (or reuse) the reduced campaign on the twin, fit the map and save both to
    ``out_dir``.

    Writes ``campaign.jsonl`` (one identified pose per line), ``campaign_fingerprint.json``,
    ``identified_map.json`` and the identification figures. Records of an earlier run with the
    same fingerprint are reused. Any failure of the identification is reported in ``summary``
    (``{"error": ...}``) instead of raised, so the rest of the experiment still runs.
    """
    from tvist.ident.campaign import run_campaign
    from tvist.ident.map_fit import fit_map

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    start = time.perf_counter()
    n_workers = workers if workers is not None else min(2, os.cpu_count() or 1)
    records: list[dict] = []
    try:
        poses = plan.poses()
        reused = _prepare_cache(out, _fingerprint(plan, poses))
        records = run_campaign(
            poses,
            out / CAMPAIGN_FILE,
            workers=n_workers,
            accel_noise_std=plan.accel_noise_std_m_s2,
            noise_seed=plan.seed,
            duration_s=plan.duration_s,
            progress=False,
            # Base and shoulder only: the demo's maps use their entries, and an elbow
            # excitation per pose would add half again to the demo's run time.
            joints=(0, 1),
        )
        campaign_s = time.perf_counter() - start
        # The published form is a law in the joint inertias of one payload's arm (the UR5e's
        # map was measured with one payload): it is fitted to the experiment's payload's poses;
        # the modal map (modal_rows) uses every payload.
        published = [r for r in records if r.get("payload_kg") == PAYLOAD_KG]
        dynmap = fit_map(
            published,
            metadata={
                "robot": "ur5e",
                "payload": {"mass_kg": PAYLOAD_KG, "com_m": list(PAYLOAD_COM_M)},
                "source": f"reduced campaign on the twin ({len(published)} poses, "
                f"{PAYLOAD_KG:g} kg)",
            },
        )
        dynmap.save(out / MAP_FILE)
        # The real-time provider rejects a map that gives no valid mode at some reachable pose
        # (evaluated as it runs: saturated into the identified inertia ranges); fail here.
        MapDynamics(robots.ur5e(payload_kg=PAYLOAD_KG, payload_com_m=PAYLOAD_COM_M), dynmap)
    except Exception as exc:  # noqa: BLE001 (any failure is reported, not fatal)
        summary = {"error": f"{type(exc).__name__}: {exc}"}
        if log is not None:
            log(f"identified map skipped: {summary['error']}")
        return IdentifiedMap(None, summary, None, records)

    usable = {
        f"joint {j}": sum(
            1
            for r in published
            for m in r.get("modes", [])
            if m.get("joint") == j and "wn_rad_s" in m and not m.get("low_confidence", False)
        )
        for j in (0, 1)
    }
    figures = _figures(dynmap, published, out)
    elapsed = time.perf_counter() - start
    summary = {
        "poses": len(records),
        "poses_reused": reused,
        "poses_run": len(records) - reused,
        "usable_identifications": usable,
        "plan": asdict(plan),
        "payload_kg": PAYLOAD_KG,
        "radii_m": list(plan.radii_m),
        "accel_noise_std_m_s2": plan.accel_noise_std_m_s2,
        "modes": dynmap.mode_maps,
        "fit_statistics": dynmap.metadata.get("fit_statistics"),
        "versus_true_modes": _relative_errors(published, dynmap),
        "map_poses": len(published),
        "map_file": MAP_FILE,
        "campaign_file": CAMPAIGN_FILE,
        "figures": [p.name for p in figures],
        "campaign_wall_time_s": campaign_s,
        "wall_time_s": elapsed,
    }
    if log is not None:
        cached = f", {reused} reused from {CAMPAIGN_FILE}" if reused else ""
        log(f"identified map from {len(records)} poses{cached} ({elapsed:.1f} s)")
    return IdentifiedMap(fd_tvist_map(KEY, LABEL, dynmap), summary, dynmap, records)


def _figures(dynmap: DynamicMap, records: Sequence[dict], out: Path) -> list[Path]:
    """The map-fit figures (like Figs. 23-26): modes against inertia, and identified against
    fitted."""
    from tvist.experiments.map_fit_figure import plot_identified_map
    from tvist.ident.plots import plot_map_fit

    paths = [plot_identified_map(dynmap, records, out / "identified_map_fit.png")]
    paths.append(plot_map_fit(dynmap, records, out / "identified_vs_map.png"))
    return paths
