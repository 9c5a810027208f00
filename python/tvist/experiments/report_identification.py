"""The identified-map section of the UR5e experiment's ``report.md``: the reduced campaign on
the twin, the fitted map's coefficients and inertia ranges, its errors against the twin's true
modes, and the captions of the identification figures."""

from __future__ import annotations

import math
from typing import Any

from tvist.experiments.experiment import DemoResult
from tvist.experiments.table import markdown_table


def _range_text(value: Any) -> str:
    return "unbounded" if value is None else f"{value[0]:.3g} - {value[1]:.3g}"


def _pct(entry: dict[str, Any], key: str) -> str:
    return f"{entry[f'{key}_rms_percent']:.1f} / {entry[f'{key}_max_percent']:.1f}"


#: Map coefficients as the paper writes them (eqs. 42-51), by their keys in the map file.
_COEFFICIENT_NAMES = {
    "k_0": "k_0",
    "k_j": "k_J",
    "k_p": "k_p",
    "k_g": "k_g",
    "c_0": "c_0",
    "c_1": "c_1",
    "c_2": "c_2",
    "c_tau": "c_τ",
}


def identification_section(result: DemoResult) -> list[str]:
    info = result.identification
    if info is None:
        return []
    lines = ["## Identified map (reduced campaign on the twin)", ""]
    if "error" in info:
        return [*lines, f"Identification failed, so the row is missing: `{info['error']}`.", ""]
    plan = info["plan"]
    usable = ", ".join(f"{k}: {v}" for k, v in info["usable_identifications"].items())
    angles = ", ".join(f"{math.degrees(a):g}°" for a in plan["angles_rad"])
    if info["poses_reused"]:
        cache = (
            f"{info['poses_reused']} of the {info['poses']} pose records were reused from "
            f"[{info['campaign_file']}]({info['campaign_file']}) (same settings and code; "
            "delete it to rerun the campaign)"
        )
    else:
        cache = (
            f"all {info['poses']} poses were run now; their records are kept in "
            f"[{info['campaign_file']}]({info['campaign_file']}), so the next run with the same "
            "settings and code reuses them"
        )
    lines.append(
        f"{info['poses']} poses: payload {', '.join(f'{m:g}' for m in plan['payloads_kg'])} kg, "
        f"angles {angles} × radii {', '.join(f'{r:g}' for r in plan['radii_m'])} m (Algorithm "
        f"1; the radii reach from Q3 to Q1 so that the map covers the inertias of the test "
        f"motions). Base and shoulder excited in turn for {plan['duration_s']:g} s each "
        f"(Algorithm 2), local fits (eq. 17) on the accelerometer with "
        f"{plan['accel_noise_std_m_s2']:g} m/s² noise, then the map fit (section 5.3) to the "
        f"{info.get('map_poses', info['poses'])} poses with the experiment's payload (the "
        f"modal map's fit uses every pose). "
        f"Identifications used (not low-confidence): {usable}. Campaign "
        f"{info['campaign_wall_time_s']:.1f} s ({cache}); identification in total "
        f"{info['wall_time_s']:.1f} s. Map file: [{info['map_file']}]({info['map_file']})."
    )
    lines.append("")
    rows = []
    stats = (info.get("fit_statistics") or {}).get("modes", [])
    for i, mode in enumerate(info["modes"]):
        stat = stats[i] if i < len(stats) else {}
        freq_err = stat.get("frequency", {}).get("rms_relative_error")
        damp_err = stat.get("damping", {}).get("rms_relative_error")
        coeffs = ", ".join(f"{shown} {mode[k]:.4g}" for k, shown in _COEFFICIENT_NAMES.items())
        f_range = mode["frequency_inertia_range_kg_m2"]
        d_range = mode["damping_inertia_range_kg_m2"]
        rows.append(
            [
                ("base", "shoulder")[i] if i < 2 else str(i),
                f"J_{mode['frequency_joint']}: {_range_text(f_range)}",
                f"J_{mode['damping_joint']}: {_range_text(d_range)}",
                coeffs,
                "-" if freq_err is None else f"{100 * freq_err:.1f}",
                "-" if damp_err is None else f"{100 * damp_err:.1f}",
            ]
        )
    header = [
        "mode",
        "frequency from, range [kg m²]",
        "damping from, range [kg m²]",
        "coefficients (N m/rad, kg m², N m s)",
        "f fit rms err [%]",
        "ζ fit rms err [%]",
    ]
    lines += [markdown_table(header, rows), ""]
    lines.append(
        "The map is evaluated only inside these inertia ranges (the inertias of the poses it "
        "was fitted to): an inertia is saturated smoothly into its range (a 5 % blend at "
        "each bound, so the modes stay differentiable along a move) and beyond it the map "
        "holds the value at the bound instead of extrapolating. " + _clamp_summary(result)
    )
    lines.append("")
    versus = info.get("versus_true_modes") or {}
    if versus:
        vrows = [
            [
                name,
                str(entry["n_poses"]),
                _pct(entry["identified"], "f_n"),
                _pct(entry["identified"], "zeta"),
                _pct(entry["map"], "f_n"),
                _pct(entry["map"], "zeta"),
            ]
            for name, entry in versus.items()
        ]
        lines.append(
            "Against the twin's true modes (eigen-analysis) at the campaign poses, relative "
            "errors RMS / max in %:"
        )
        lines.append("")
        lines.append(
            markdown_table(
                [
                    "mode",
                    "poses",
                    "identified f_n",
                    "identified ζ",
                    "fitted map f_n",
                    "fitted map ζ",
                ],
                vrows,
            )
        )
        lines.append("")
    return lines


def _clamp_summary(result: DemoResult) -> str:
    """Share of each motion's reference on which the identified map clamped an inertia."""
    from tvist.experiments.identified import KEY

    parts = []
    for motion in result.motions:
        try:
            use = motion.run(KEY).details.get("map_use")
        except KeyError:
            continue
        if use:
            shares = ", ".join(
                f"{name} {v:.0f} %"
                for name, v in zip(
                    ("base", "shoulder"), use["inertia_clamped_percent"], strict=False
                )
            )
            parts.append(f"{motion.motion.name.replace('->', ' → ')}: {shares}")
    if not parts:
        return ""
    return (
        "Share of each shaped reference at which an inertia was outside its range: "
        + "; ".join(parts)
        + "."
    )


IDENTIFICATION_CAPTIONS = {
    "identified_map_fit.png": "Identified map: f_n and ζ against inertia; identified, true and "
    "fitted modes at the campaign poses and the map curve with its range (like Figs. 23-26)",
    "identified_vs_map.png": "Identified against fitted modes at the campaign poses",
}
