"""Figures of the identification: PRV sensitivity (Fig. 27), map robustness to frequency and
damping errors (Figs. 28-30) and identified modes against the map (Figs. 23-26).

matplotlib is imported lazily; every figure is a standalone ``Figure`` (no global pyplot
backend is selected). Every function writes one PNG and returns its path.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

import tvist
from tvist.ident.robustness import (
    PRV_LIMIT,
    pose_modes,
    prv_band,
    two_mode_shaper,
    usable_mode,
)

__all__ = [
    "plot_damping_robustness",
    "plot_frequency_robustness",
    "plot_map_fit",
    "plot_prv_sensitivity",
]

#: The paper fixes J_0 at a mid-range value for its 2-D robustness plots, kg m².
J0_FIXED_KG_M2 = 4.5


def _figure(nrows: int, ncols: int, figsize: tuple[float, float], **kwargs):
    """A standalone figure and its axes (no pyplot state)."""
    from tvist.figures import new_figure

    fig = new_figure(figsize=figsize)
    return fig, fig.subplots(nrows, ncols, **kwargs)


def _inertia(j0: float, j1: float, n_dof: int = 6) -> list[float]:
    j = [1.0] * n_dof  # joints the map does not read; positive so nothing is invalid
    j[0], j[1] = j0, j1
    return j


def _modes(dynmap: tvist.DynamicMap, j0: float, j1: float) -> list[tuple[float, float]]:
    """Map modes for ``(J_0, J_1)``; a gravity term, if any, is evaluated at ``τ_g = 0``."""
    tau = [0.0] * 6 if dynmap.uses_gravity else None
    return dynmap.modes_from_inertia(_inertia(j0, j1), tau)


def _save(fig, path: str | Path) -> Path:
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=120)
    return path


def _design_points(
    dynmap: tvist.DynamicMap | tvist.ModalMap,
    j1_values_kg_m2: Sequence[float],
    j0_kg_m2: float,
    robot: tvist.robots.Robot | None,
) -> list[tuple[str, list[tuple[float, float]]]]:
    """``(title, modes)`` of each panel of :func:`plot_prv_sensitivity`: the published form at
    ``(J_0, J_1)``; a modal map (whose modes depend on the whole pose) at the paper's test poses
    Q1 (stretched) and Q3 (folded) of ``robot`` (default: the map's robot, no payload)."""
    if isinstance(dynmap, tvist.ModalMap):
        from tvist.trajectory.poses import PAPER_POSES

        if robot is None:
            robot = tvist.robots.Robot(tvist.robots.params(dynmap.robot or "ur5e"))
        return [
            (
                f"{name}, {robot.payload.mass_kg:g} kg payload",
                dynmap.modes(robot, PAPER_POSES[name]),
            )
            for name in ("Q1", "Q3")
        ]
    return [
        (f"J_0 = {j0_kg_m2:g}, J_1 = {j1:g} kg m²", _modes(dynmap, j0_kg_m2, j1))
        for j1 in j1_values_kg_m2
    ]


def plot_prv_sensitivity(
    dynmap: tvist.DynamicMap | tvist.ModalMap,
    path: str | Path,
    *,
    j1_values_kg_m2: Sequence[float] = (1.0, 3.2, 10.0),
    j0_kg_m2: float = J0_FIXED_KG_M2,
    shaper: str = "zv",
    robot: tvist.robots.Robot | None = None,
) -> Path:
    """Fig. 27: PRV of the two-mode shaper over actual frequency and damping, per ``J_1``
    (published form) or per test pose Q1, Q3 of ``robot`` (modal map).

    The shaper is designed from the map's modes there; the filled region is PRV <= 10 %,
    the markers are the two design modes.
    """
    points = _design_points(dynmap, j1_values_kg_m2, j0_kg_m2, robot)
    fig, axes = _figure(1, len(points), (5 * len(points), 4))
    axes = np.atleast_1d(axes)
    for ax, (title, modes) in zip(axes, points, strict=True):
        impulses = two_mode_shaper(modes, shaper)
        f_max = 2.5 * max(w for w, _ in modes) / (2 * math.pi)
        f = np.linspace(0.2, f_max, 300)
        z = np.linspace(0.0, 0.6, 121)
        ff, zz = np.meshgrid(f, z)
        prv = tvist.prv(impulses, 2 * math.pi * ff, zz)
        ax.contourf(ff, zz, prv, levels=[0.0, PRV_LIMIT], colors=["#9ecae1"])
        cs = ax.contour(ff, zz, prv, levels=[0.05, PRV_LIMIT, 0.25, 0.5], colors="k")
        ax.clabel(cs, fmt=lambda v: f"{100 * v:.0f} %")
        for (w, zeta), name in zip(modes, ("base", "shoulder"), strict=False):
            ax.plot(w / (2 * math.pi), zeta, "o", label=f"{name} {w / (2 * math.pi):.1f} Hz")
        ax.set_title(title)
        ax.set_xlabel("actual natural frequency (Hz)")
        ax.set_ylabel("actual damping ratio")
        ax.legend(loc="upper right", fontsize=8)
    fig.suptitle(f"PRV of the two-mode {shaper.upper()} shaper (shaded: <= 10 %)")
    return _save(fig, path)


#: The paper's mid-range shoulder inertia (Fig. 27's middle panel), kg m².
J1_FIXED_KG_M2 = 3.2


def _map_curve(dynmap, mode: int, j_grid: np.ndarray, vary: str, shaper: str):
    """Map prediction and its 10 % PRV band along the inertia of the mode's frequency joint
    (the other of ``J_0``, ``J_1`` fixed at its mid-range value)."""
    f_joint = dynmap.mode_maps[mode]["frequency_joint"]
    centre, lo, hi = [], [], []
    for j in j_grid:
        j0, j1 = (j, J1_FIXED_KG_M2) if f_joint == 0 else (J0_FIXED_KG_M2, j)
        modes = _modes(dynmap, j0, j1)
        if not all(math.isfinite(wn) and 0.0 <= zeta < 1.0 for wn, zeta in modes):
            centre.append(math.nan)  # outside the map's valid range: leave a gap
            lo.append(math.nan)
            hi.append(math.nan)
            continue
        impulses = two_mode_shaper(modes, shaper)
        w, z = modes[mode]
        band = prv_band(impulses, w, z, vary=vary)
        if vary == "frequency":
            centre.append(w / (2 * math.pi))
            lo.append(band[0] / (2 * math.pi))
            hi.append(band[1] / (2 * math.pi))
        else:
            centre.append(z)
            lo.append(band[0])
            hi.append(band[1])
    return np.array(centre), np.array(lo), np.array(hi)


def _points(results: Sequence[Mapping[str, Any]], joint: int, inertia_joint: int):
    j, f, z = [], [], []
    for record in results:
        for m in record.get("modes", []):
            if m.get("joint") != joint or "error" in m or m.get("low_confidence", False):
                continue
            j.append(record["inertia_kg_m2"][inertia_joint])
            f.append(m["wn_rad_s"] / (2 * math.pi))
            z.append(m["zeta"])
    return np.array(j), np.array(f), np.array(z)


def plot_frequency_robustness(
    dynmap: tvist.DynamicMap | tvist.ModalMap,
    results: Sequence[Mapping[str, Any]],
    path: str | Path,
    *,
    mode: int = 0,
    joint: int | None = None,
    shaper: str = "zv",
    robot: tvist.robots.Robot | None = None,
) -> Path:
    """Figs. 28 (``mode=0``, base) and 29 (``mode=1``, shoulder): frequency vs inertia.

    x: the inertia of the mode's frequency joint (``J_1`` for the paper's map); line: the map
    (the other inertia fixed at mid-range, ``J_0 = 4.5`` as in the paper); shaded: the 10 %
    PRV band of the two-mode shaper designed from the map; dots: identified frequencies. A
    modal map's modes depend on the whole pose, not on one inertia: it is drawn at each
    identified pose (model ``robot``, see :func:`~tvist.ident.robustness.pose_modes`), with
    its 10 % PRV band as an error bar.
    """
    return _plot_robustness(dynmap, results, path, mode, joint, shaper, "frequency", robot)


def plot_damping_robustness(
    dynmap: tvist.DynamicMap | tvist.ModalMap,
    results: Sequence[Mapping[str, Any]],
    path: str | Path,
    *,
    mode: int = 1,
    joint: int | None = None,
    shaper: str = "zv",
    robot: tvist.robots.Robot | None = None,
) -> Path:
    """Fig. 30: damping ratio vs inertia with the 10 % PRV band (default: shoulder mode); a
    modal map as in :func:`plot_frequency_robustness`."""
    return _plot_robustness(dynmap, results, path, mode, joint, shaper, "damping", robot)


def _plot_robustness(
    dynmap: tvist.DynamicMap | tvist.ModalMap,
    results: Sequence[Mapping[str, Any]],
    path: str | Path,
    mode: int,
    joint: int | None,
    shaper: str,
    quantity: str,
    robot: tvist.robots.Robot | None = None,
) -> Path:
    """The map's frequency or damping (``quantity``) against the inertia of its frequency
    joint, with the 10 % PRV band and the identified values."""
    joint = mode if joint is None else joint
    if isinstance(dynmap, tvist.ModalMap):
        return _plot_modal_robustness(dynmap, results, path, mode, joint, shaper, quantity, robot)
    f_joint = dynmap.mode_maps[mode]["frequency_joint"]
    jx, f, z = _points(results, joint, f_joint)
    bottom = min(0.3, float(jx.min()) * 0.9) if jx.size else 0.3
    top = max(10.0, float(jx.max()) * 1.1) if jx.size else 10.0
    grid = np.geomspace(bottom, top, 80)
    centre, lo, hi = _map_curve(dynmap, mode, grid, quantity, shaper)
    fig, ax = _figure(1, 1, (7, 4.5))
    ax.fill_between(grid, lo, hi, color="#9ecae1", label="PRV <= 10 %")
    ax.plot(grid, centre, "k-", label="dynamic map")
    if jx.size:
        ax.plot(
            jx, f if quantity == "frequency" else z, "o", ms=4, color="#d62728", label="identified"
        )
    ax.set_xscale("log")
    ax.set_xlabel(f"J_{f_joint} (kg m²)")
    ax.set_ylabel("natural frequency (Hz)" if quantity == "frequency" else "damping ratio")
    ax.set_title(f"{'base' if mode == 0 else 'shoulder'} mode: robustness to {quantity} errors")
    ax.legend()
    return _save(fig, path)


def _plot_modal_robustness(
    modal: tvist.ModalMap,
    results: Sequence[Mapping[str, Any]],
    path: str | Path,
    mode: int,
    joint: int,
    shaper: str,
    quantity: str,
    robot: tvist.robots.Robot | None,
) -> Path:
    """:func:`_plot_robustness` for a modal map: the map's value and its 10 % PRV band at
    each identified pose, against the inertia of the mode's joint there."""
    jx, ident, centre, lo, hi = [], [], [], [], []
    scale = 1 / (2 * math.pi) if quantity == "frequency" else 1.0
    for record in results:
        m = usable_mode(record, joint)
        if m is None:
            continue
        modes = pose_modes(modal, record, robot)
        if modes is None or not all(math.isfinite(w) and 0.0 <= z < 1.0 for w, z in modes):
            continue
        w, z = modes[mode]
        band = prv_band(two_mode_shaper(modes, shaper), w, z, vary=quantity)
        jx.append(record["inertia_kg_m2"][joint])
        ident.append((m["wn_rad_s"] if quantity == "frequency" else m["zeta"]) * scale)
        centre.append((w if quantity == "frequency" else z) * scale)
        lo.append(band[0] * scale)
        hi.append(band[1] * scale)
    fig, ax = _figure(1, 1, (7, 4.5))
    if jx:
        c, lo_a, hi_a = np.array(centre), np.array(lo), np.array(hi)
        ax.errorbar(
            jx,
            c,
            yerr=[c - lo_a, hi_a - c],
            fmt="s",
            ms=4,
            color="k",
            ecolor="#6baed6",
            label="modal map, PRV <= 10 % band",
        )
        ax.plot(jx, ident, "o", ms=4, color="#d62728", label="identified")
        ax.set_xscale("log")
    ax.set_xlabel(f"J_{joint} at the pose (kg m²)")
    ax.set_ylabel("natural frequency (Hz)" if quantity == "frequency" else "damping ratio")
    ax.set_title(
        f"{'base' if mode == 0 else 'shoulder'} mode: robustness to {quantity} errors "
        f"(modal map, {len(jx)} poses)"
    )
    ax.legend()
    return _save(fig, path)


def plot_map_fit(
    dynmap: tvist.DynamicMap | tvist.ModalMap,
    results: Sequence[Mapping[str, Any]],
    path: str | Path,
    *,
    joints: Sequence[int] = (0, 1),
    robot: tvist.robots.Robot | None = None,
) -> Path:
    """Figs. 23-26: identified against map-predicted frequency and damping, per mode (a
    modal map evaluated with ``robot``'s model, see :func:`~tvist.ident.robustness.pose_modes`)."""
    fig, axes = _figure(2, len(joints), (5 * len(joints), 8), squeeze=False)
    for col, joint in enumerate(joints):
        ident, pred = [], []
        for record in results:
            m = usable_mode(record, joint)
            if m is None:
                continue
            modes = pose_modes(dynmap, record, robot)
            if modes is None:
                continue
            pred.append(modes[col])
            ident.append((m["wn_rad_s"], m["zeta"]))
        if not ident:
            continue
        ident_a, pred_a = np.array(ident), np.array(pred)
        quantities = ((1 / (2 * math.pi), "natural frequency f_n (Hz)"), (1.0, "damping ratio ζ"))
        for row, (scale, label) in enumerate(quantities):
            ax = axes[row, col]
            x, y = pred_a[:, row] * scale, ident_a[:, row] * scale
            ax.plot(x, y, "o", ms=4, label=f"identified at a pose ({len(ident)} poses)")
            lim = [min(x.min(), y.min()), max(x.max(), y.max())]
            ax.plot(lim, lim, "k--", lw=1, label="identified = map")
            ax.set_xlabel(f"map {label}")
            ax.set_ylabel(f"identified {label}")
            mode_name = "base" if joint == 0 else "shoulder"
            ax.set_title(f"{mode_name} mode, {label.split(' (')[0]}: {len(ident)} poses")
            ax.grid(True, alpha=0.3)
            ax.legend(fontsize=8, loc="upper left")
    fig.suptitle(
        "Identified modes against the fitted map at the campaign poses "
        "(low-confidence identifications left out)"
    )
    return _save(fig, path)
