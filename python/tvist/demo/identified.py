"""A map identified on the twin: a reduced mapping campaign (Algorithm 1) and the map fit.

The campaign excites the base and the shoulder in turn at every pose (Algorithm 2), fits the
local transfer function to the noisy tool accelerometer (eq. 17) and fits the dynamic map to
the identified modes (section 5.3). It is reduced to the experiment's payload (5 kg) and to 6
of the paper's 13 radii, i.e. 4 angles x 6 radii = 24 poses, so that it runs in the demo's
time budget; the full campaign is :func:`tvist.ident.campaign.run_campaign` over
:func:`tvist.ident.campaign.campaign_poses`.
"""

from __future__ import annotations

import os
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from tvist import robots
from tvist.demo.methods import Method, fd_tvist_map
from tvist.demo.motions import PAYLOAD_COM_M, PAYLOAD_KG
from tvist.dynmap import MapDynamics

#: Radii of the reduced campaign, m: every other one of the paper's 0.4 + k/24 m, plus 0.9.
CAMPAIGN_RADII_M = (0.4, 0.5, 0.6, 0.7, 0.8, 0.9)
#: Accelerometer noise of the twin during identification, m/s² (a real sensor is noisy).
CAMPAIGN_NOISE_STD_M_S2 = 0.05
#: Seed of the campaign's random wrist angles and excitations.
CAMPAIGN_SEED = 1
KEY = "fd-tvist-identified-map"
LABEL = "FD-TVIST ZV, identified map"


@dataclass
class IdentifiedMap:
    """Outcome of the reduced campaign.

    Attributes
    ----------
    method
        The FD-TVIST row driven by the identified map, or ``None`` if identification failed.
    summary
        JSON-ready facts: poses, usable identifications per mode, fit statistics, files, time;
        or ``{"error": ...}``.
    """

    method: Method | None
    summary: dict[str, Any] = field(default_factory=dict)


def identify_map(
    out_dir: str | Path, *, workers: int | None = None, log: Any = None
) -> IdentifiedMap:
    """Run the reduced campaign on the twin, fit the map and save both to ``out_dir``.

    Writes ``campaign.jsonl`` (one identified pose per line, started afresh) and
    ``identified_map.json``. Any failure of the identification is reported in ``summary``
    (``{"error": ...}``) instead of raised, so the rest of the experiment still runs.
    """
    from tvist.ident.campaign import campaign_poses, run_campaign
    from tvist.ident.map_fit import fit_map

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    results_path = out / "campaign.jsonl"
    map_path = out / "identified_map.json"
    start = time.perf_counter()
    n_workers = workers if workers is not None else min(2, os.cpu_count() or 1)
    try:
        results_path.unlink(missing_ok=True)
        poses = campaign_poses(
            "ur5e",
            payloads_kg=(PAYLOAD_KG,),
            payload_com_m=PAYLOAD_COM_M,
            radii_m=CAMPAIGN_RADII_M,
            seed=CAMPAIGN_SEED,
        )
        records = run_campaign(
            poses,
            results_path,
            workers=n_workers,
            accel_noise_std=CAMPAIGN_NOISE_STD_M_S2,
            noise_seed=CAMPAIGN_SEED,
            progress=False,
        )
        dynmap = fit_map(
            records,
            metadata={
                "robot": "ur5e",
                "payload": {"mass_kg": PAYLOAD_KG, "com_m": list(PAYLOAD_COM_M)},
                "source": f"reduced campaign on the twin ({len(records)} poses, 5 kg)",
            },
        )
        dynmap.save(map_path)
        # The real-time provider rejects a map that gives no valid mode somewhere in the
        # workspace (an extrapolation outside the campaign's poses): fail here, with its reason.
        MapDynamics(robots.ur5e(payload_kg=PAYLOAD_KG, payload_com_m=PAYLOAD_COM_M), dynmap)
    except Exception as exc:  # noqa: BLE001 (any failure is reported, not fatal)
        summary = {"error": f"{type(exc).__name__}: {exc}"}
        if log is not None:
            log(f"identified map skipped: {summary['error']}")
        return IdentifiedMap(None, summary)

    usable = {
        f"joint {j}": sum(
            1
            for r in records
            for m in r.get("modes", [])
            if m.get("joint") == j and "wn_rad_s" in m and not m.get("low_confidence", False)
        )
        for j in (0, 1)
    }
    elapsed = time.perf_counter() - start
    summary = {
        "poses": len(records),
        "usable_identifications": usable,
        "payload_kg": PAYLOAD_KG,
        "radii_m": list(CAMPAIGN_RADII_M),
        "accel_noise_std_m_s2": CAMPAIGN_NOISE_STD_M_S2,
        "modes": dynmap.mode_maps,
        "fit_statistics": dynmap.metadata.get("fit_statistics"),
        "map_file": map_path.name,
        "campaign_file": results_path.name,
        "wall_time_s": elapsed,
    }
    if log is not None:
        log(f"identified map from {len(records)} poses ({elapsed:.1f} s)")
    return IdentifiedMap(fd_tvist_map(KEY, LABEL, dynmap), summary)
