"""The modal fit on every identified mode, over arm variants of the UR5e family.

For each variant: pose records made from its eigen-analysis at the demo's 36-pose plan
(:func:`tvist.sim.ringing_records.ringing_records`), the fit
(:func:`tvist.ident.all_modes_fit.fit_all_modes`), and the shaped modes' frequency errors at
20 held-out poses against the variant's true modes (:mod:`tvist.sim.map_truth`), by
frequency rank and by joint; one markdown row per variant.

    python benches/bench_modal_fit_family.py nominal 14 0 3 [--records-dir /tmp/records]

Development seeds only (0-99); ``nominal`` is the default twin.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np

from tvist.experiments.identified import DEMO_PLAN
from tvist.ident.all_modes_fit import fit_all_modes, fitted_map
from tvist.sim.family import nominal_variant, sample_variant
from tvist.sim.map_truth import held_out_poses, physical_mode_errors, ranked_mode_errors
from tvist.sim.ringing_records import ringing_records


def _text(e: np.ndarray) -> str:
    e = e[np.isfinite(e)]
    if not e.size:
        return "–"
    return f"{100 * np.sqrt(np.mean(e**2)):.2f} / {100 * np.max(np.abs(e)):.1f} %"


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("seeds", nargs="+", help="family seeds (0-99) or 'nominal'")
    p.add_argument("--records-dir", type=Path, help="cache the generated records here")
    args = p.parse_args()
    poses = [
        (q.key, q.q, q.payload_kg, q.payload_com_m) for q in DEMO_PLAN.poses() if q.q is not None
    ]
    held = held_out_poses()
    print("| variant | flexible | shaped (K) | by rank: RMS / max per shaped mode | by joint |")
    print("|---|---|---|---|---|")
    for name in args.seeds:
        variant = (
            nominal_variant("ur5e") if name == "nominal" else sample_variant("ur5e", int(name))
        )
        cache = args.records_dir / f"records_{name}.json" if args.records_dir else None
        if cache is not None and cache.exists():
            records = json.loads(cache.read_text())
        else:
            records = ringing_records(variant, poses, seed=1)
            if cache is not None:
                cache.parent.mkdir(parents=True, exist_ok=True)
                cache.write_text(json.dumps(records))
        fit = fit_all_modes(records, "ur5e")
        modal = fitted_map(fit)
        report = modal.metadata["fit_statistics"]["physical_modes"]
        k = max(m["frequency_rank"] for m in report if m["shaped"])
        ranked = ranked_mode_errors(fit.entries, variant, held, k)
        by_joint = physical_mode_errors(fit.entries, variant, held, modal.mode_joints)
        print(
            f"| {variant.name} | {fit.statistics['flexible_joints']} | {modal.mode_joints} ({k}) "
            f"| {'; '.join(_text(e) for e in ranked)} "
            f"| {'; '.join(f'{j}: {_text(e)}' for j, e in by_joint.items())} |",
            flush=True,
        )


if __name__ == "__main__":
    main()
