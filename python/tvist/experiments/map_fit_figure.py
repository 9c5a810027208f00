"""Figure of an identified map (like the paper's Figs. 23-26): modes against inertia.

Per mode, ``f_n`` against the inertia of its frequency joint and ``ζ`` against the inertia of
its damping joint: the identified modes, the twin's true modes at the same poses, the fitted
map at those poses, and the map as a curve (the other inputs at their median over the poses)
with its identified inertia range shaded; outside the range the curve is flat, because the map
clamps the inertia.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from tvist.maps.paper10 import RANGE_FIELDS, DynamicMap

_MODE_NAMES = ("base", "shoulder")


def _usable(records: Sequence[dict], index: int) -> list[tuple[dict, dict, dict | None]]:
    """(record, identified mode, true mode or None) of the usable identifications of mode
    ``index``."""
    out = []
    for r in records:
        mode = next((m for m in r.get("modes", []) if m.get("joint") == index), None)
        if mode is None or "wn_rad_s" not in mode or mode.get("low_confidence", False):
            continue
        truth = {m["joint"]: m for m in r.get("true_modes") or []}.get(index)
        out.append((r, mode, truth))
    return out


def plot_identified_map(dynmap: DynamicMap, records: Sequence[dict], path: str | Path) -> Path:
    """Write the figure to ``path`` (PNG) and return the path."""
    from tvist.figures import new_figure

    n_modes = min(dynmap.n_modes, len(_MODE_NAMES))
    fig = new_figure(figsize=(12, 4.2 * n_modes))
    axes = fig.subplots(n_modes, 2, squeeze=False)
    for index in range(n_modes):
        mode_map = dynmap.mode_maps[index]
        rows = _usable(records, index)
        if not rows:
            for ax in axes[index]:
                ax.set_title(f"{_MODE_NAMES[index]} mode: no usable identification")
            continue
        inertia = np.array([r["inertia_kg_m2"] for r, _, _ in rows])
        tau = np.abs(
            np.array([r.get("gravity_torque_nm") or [0.0] * inertia.shape[1] for r, _, _ in rows])
        )
        fitted = dynmap.modes_from_inertia_many(inertia, tau if dynmap.uses_gravity else None)
        ident = np.array([(m["wn_rad_s"], m["zeta"]) for _, m, _ in rows])
        true = np.array(
            [(t["wn_rad_s"], t["zeta"]) if t else (math.nan, math.nan) for _, _, t in rows]
        )
        panels = (
            (
                "frequency_joint",
                RANGE_FIELDS[0],
                0,
                1 / (2 * math.pi),
                "natural frequency f_n (Hz)",
            ),
            ("damping_joint", RANGE_FIELDS[1], 1, 1.0, "damping ratio ζ"),
        )
        for ax, (joint_key, range_key, column, scale, ylabel) in zip(
            axes[index], panels, strict=True
        ):
            joint = int(mode_map[joint_key])
            x = inertia[:, joint]
            j_range = mode_map[range_key]
            lo, hi = j_range if j_range is not None else (x.min(), x.max())
            grid = np.geomspace(0.6 * min(lo, x.min()), 1.4 * max(hi, x.max()), 200)
            base_row = np.median(inertia, axis=0)
            curve_j = np.tile(base_row, (grid.size, 1))
            curve_j[:, joint] = grid
            curve_tau = np.tile(np.median(tau, axis=0), (grid.size, 1))
            curve = dynmap.modes_from_inertia_many(
                curve_j, curve_tau if dynmap.uses_gravity else None
            )[:, index, column]
            if j_range is not None:
                ax.axvspan(lo, hi, color="#deebf7", label="identified inertia range")
            ax.plot(grid, curve * scale, "-", color="#1f77b4", label="map (other inputs at median)")
            ax.plot(
                x,
                fitted[:, index, column] * scale,
                "o",
                mfc="none",
                color="#1f77b4",
                ms=7,
                label="map at the poses",
            )
            ax.plot(x, ident[:, column] * scale, "o", color="#d62728", ms=4, label="identified")
            ax.plot(x, true[:, column] * scale, "x", color="k", ms=5, label="twin (true)")
            ax.set_xscale("log")
            ax.set_xlabel(f"J_{joint} (kg m²)")
            ax.set_ylabel(ylabel)
            ax.set_title(
                f"{_MODE_NAMES[index]} mode: {ylabel.split(' (')[0]} from J_{joint} "
                f"({len(rows)} poses)"
            )
            ax.grid(True, alpha=0.3)
            ax.legend(fontsize=8)
    fig.suptitle(
        f"Identified dynamic map: campaign on the twin ({len(records)} poses, local fits; "
        "low-confidence identifications left out) and the fitted map"
    )
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    return path
