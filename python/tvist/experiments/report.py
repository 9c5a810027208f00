"""``report.md`` of the UR5e experiment: tables, modes, verdict, discussion and figure links;
:func:`write_outputs` writes it with ``results.json`` and the figures."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

from tvist.analysis import peak_acceleration, peak_velocity
from tvist.experiments.experiment import DemoResult, MotionRun
from tvist.experiments.measure import damped_frequency_hz, zv_delay_s
from tvist.experiments.plots import make_figures
from tvist.experiments.report_identification import IDENTIFICATION_CAPTIONS, identification_section
from tvist.experiments.results_json import write_json
from tvist.experiments.settle import CRITERIA, SETTLE_HOLD_S
from tvist.experiments.slow_down import ACCEL_SCALES, JERK_TIMES_S
from tvist.experiments.table import (
    TABLE_HEADER,
    format_reduction,
    markdown_table,
    planned_move_s,
    table_rows,
)
from tvist.experiments.verdict import RANK_CRITERION, recommendation

#: Paper Table 4 (real UR5e, average of 10 repetitions): unshaped RV, shaped RV (m/s²),
#: measured delay (ms) and reduction (%), for comparison in the report.
PAPER_TABLE_4 = {
    "Q1->Q2": {"unshaped_m_s2": 0.99, "shaped_m_s2": 0.09, "delay_ms": 137, "reduction": 89.5},
    "Q1->Q3": {"unshaped_m_s2": 0.77, "shaped_m_s2": 0.20, "delay_ms": 49, "reduction": 73.6},
    "Q3->Q1": {"unshaped_m_s2": 1.24, "shaped_m_s2": 0.12, "delay_ms": 137, "reduction": 90.3},
}


def _slow_down_text(motion: MotionRun) -> str:
    """The move's own duration and the best slow-down profile per band."""
    text = (
        f"The planned move lasts **{planned_move_s(motion):.3f} s** (the limit of every "
        "settle time)."
    )
    if motion.slow_down is None:
        return text
    parts = []
    for c in CRITERIA:
        best = motion.slow_down.best(c.key)
        if best is None:
            parts.append(f"{c.text}: no profile settles within the record")
        else:
            parts.append(
                f"{c.text}: {best.text()} (move {best.settle.move_s:.3f} s, settled "
                f"{best.settle.get(c.key):.3f} s)"
            )
    n = len(motion.slow_down.candidates)
    return f"{text} Slow down instead, best of {n} profiles: " + "; ".join(parts) + "."


def _discussion(result: DemoResult) -> list[str]:
    """Statements computed from the numbers (no claim that the data do not support)."""
    out = []
    for motion in result.motions:
        name = motion.motion.name
        parts = []
        analytic = motion.analytic_zv_delay_s
        for r in motion.runs[1:]:
            parts.append(f"{r.method.label} {format_reduction(r.reduction_percent)} %")
        out.append(f"- **{name.replace('->', ' → ')}**: reduction " + ", ".join(parts) + ".")
        try:
            truth = motion.run("fd-tvist-truth")
            diff_ms = 1e3 * (truth.delay_s - analytic)
            out.append(
                f"  With the true modes the reference stops {1e3 * truth.delay_s:.0f} ms late; "
                f"the analytic two-mode ZV delay at {motion.motion.end} is {1e3 * analytic:.1f} ms "
                f"(difference {diff_ms:+.1f} ms; the stop is measured on the 2 ms grid)."
            )
        except KeyError:
            pass
        true_fd = [damped_frequency_hz(w, z) for w, z in motion.true_end_modes]
        for r in motion.runs[1:]:
            f = r.residual.freq_hz
            if math.isfinite(f) and f > 1.5 * max(true_fd):
                out.append(
                    f"  {r.method.label}: what is left rings at {f:.0f} Hz, above both shaped "
                    f"modes ({', '.join(f'{x:.1f}' for x in true_fd)} Hz): a higher mode of the "
                    "arm that the two-mode shaper does not address."
                )
        paper = PAPER_TABLE_4.get(name)
        try:
            paper_map = motion.run("fd-tvist-paper-map")
        except KeyError:
            paper_map = None
        if paper and paper_map is not None:
            out.append(
                f"  Paper map on the twin: {format_reduction(paper_map.reduction_percent)} % here, "
                f"{paper['reduction']} % on the real UR5e in the paper."
            )
        for label, modes in motion.map_end_modes.items():
            errs = [
                100.0 * (damped_frequency_hz(*m) / damped_frequency_hz(*t) - 1.0)
                for m, t in zip(modes, motion.true_end_modes, strict=False)
            ]
            zetas = ", ".join(
                f"{m[1]:.3f} vs {t[1]:.3f}"
                for m, t in zip(modes, motion.true_end_modes, strict=False)
            )
            out.append(
                f"  {label} at {motion.motion.end}: damped f_d error base {errs[0]:+.1f} %, "
                f"shoulder {errs[1]:+.1f} %; ζ (map vs true) {zetas}; its ZV delay "
                f"{1e3 * zv_delay_s(modes):.1f} ms."
            )
    return out


def write_markdown(result: DemoResult, path: Path, figures: dict[str, list[Path]]) -> Path:
    """Write ``report.md``: tables, modes, discussion and figure links."""
    lines = [
        "# FD-TVIST on the simulated flexible UR5e (paper section 6)",
        "",
        "Test motions Q1→Q2, Q1→Q3, Q3→Q1 with a 5 kg payload (centre of mass 5 cm beyond the "
        "flange), joint-space double-S profile (1.5 rad/s, 2 rad/s², 20 ms jerk ramp), 500 Hz. "
        "Each reference is run on the MuJoCo twin (flexible joints, noise-free accelerometer). "
        "Residual vibration (RV): amplitude of the gravity-free tool acceleration at the stop "
        "of the reference (t_b unshaped, t_b* shaped), from the log decay of the acceleration "
        "peaks after it (refined by a one-mode fit where one mode explains the decay). Delay: "
        "t_b* − t_b, where a reference has stopped at the first sample from which it equals the "
        "end pose (to 1e-9 rad). Reduction: 1 − RV/RV_unshaped of the same motion. Peak jerk: "
        "largest third difference of the reference over all joints.",
        "",
        "Settled: time from the start of the move until the gravity-free tool acceleration "
        "|ψ| stays below 0.05 or 0.01 m/s², or the flange stays within 0.1 mm of where it "
        "comes to rest (the twin's flange at rest under gravity at the end pose), for good "
        f"(the record must show it inside the band for {SETTLE_HOLD_S:g} s); interpolated "
        "between the 2 ms samples. Its physical limit is the move's own duration: a perfect "
        "shaper adds nothing to it. *Slow down instead*: the planned move run unshaped with a "
        f"softer jerk ramp ({', '.join(f'{1e3 * j:g}' for j in JERK_TIMES_S)} ms) and "
        f"acceleration limit (×{', ×'.join(f'{a:g}' for a in ACCEL_SCALES)}), every "
        "profile simulated on the twin; per band the one that settles first. Rows marked "
        "*(oracle)* read what only the twin knows (its exact modes); they are references, "
        "never recommended.",
        "",
        f"Wall time (identification, simulations, analysis): {result.wall_time_s:.1f} s"
        + (" (quick run: first motion only, shorter tail)." if result.config["quick"] else "."),
        "",
    ]
    lines += ["## Which method to use", "", *_recommendation_lines(result), ""]
    for motion in result.motions:
        name = motion.motion.name
        lines += [f"## {name.replace('->', ' → ')}", ""]
        lines.append(markdown_table(TABLE_HEADER, table_rows(motion)))
        lines.append("")
        lines.append(_slow_down_text(motion))
        lines.append("")
        lines.append(
            "Flange path deviation from the planned path (distance to its nearest point; the "
            "planned path is the polyline through its 2 ms samples, whose chords cut its arcs "
            "by up to ~2 µm here): "
            + "; ".join(
                f"{r.method.label} {1e6 * r.path_deviation_m:.1f} µm"
                for r in motion.runs
                if r.method.key != "unshaped"
            )
            + "."
        )
        lines.append("")
        lines.append(
            f"Analytic two-mode ZV delay at {motion.motion.end} from the twin's true modes: "
            f"**{1e3 * motion.analytic_zv_delay_s:.1f} ms**."
        )
        paper = PAPER_TABLE_4.get(name)
        if paper:
            lines.append(
                f"Paper (real UR5e, paper map): unshaped {paper['unshaped_m_s2']} m/s², shaped "
                f"{paper['shaped_m_s2']} m/s², delay {paper['delay_ms']} ms, reduction "
                f"{paper['reduction']} %."
            )
        lines.append("")
        mode_rows = [
            ["twin (true)"]
            + [f"{damped_frequency_hz(w, z):.2f} Hz / {z:.3f}" for w, z in motion.true_end_modes]
        ]
        for label, modes in motion.map_end_modes.items():
            mode_rows.append(
                [label] + [f"{damped_frequency_hz(w, z):.2f} Hz / {z:.3f}" for w, z in modes]
            )
        lines.append(
            markdown_table(
                [
                    f"modes at {motion.motion.end}",
                    "base damped f_d / ζ",
                    "shoulder damped f_d / ζ",
                ],
                mode_rows,
            )
        )
        lines.append("")
        zd = [r for r in motion.runs if "alpha" in r.details]
        if zd:
            lines.append(
                "Zero-delay rows: "
                + "; ".join(
                    f"{r.method.label}: α = {r.details['alpha']:.4f}, removed shaper delay "
                    f"{1e3 * r.details['shaper_delay_removed_s']:.1f} ms, truncation residue "
                    f"{r.details['tail_error_rad']:.1e} rad, peak speed "
                    f"{peak_velocity(r.q, r.dt_s):.2f} rad/s and acceleration "
                    f"{peak_acceleration(r.q, r.dt_s):.2f} rad/s² (planned move: "
                    f"{peak_velocity(motion.runs[0].q, motion.runs[0].dt_s):.2f} and "
                    f"{peak_acceleration(motion.runs[0].q, motion.runs[0].dt_s):.2f})"
                    for r in zd
                )
                + ". A residue above the 1e-9 rad rest tolerance makes the reference stop one "
                "sample (2 ms) after the planned move."
            )
            lines.append("")
    lines += _fixed_section(result)
    lines += identification_section(result)
    lines += ["## Discussion", ""]
    lines += _discussion(result)
    lines += ["", *_NOTES]
    if _jerk_spike(result):
        lines.append(_JERK_NOTE)
    lines += _map_jerk_notes(result)
    lines.append("")
    lines += ["## Figures", ""]
    captions = {
        "acceleration": "Tool acceleration around the stop (like Fig. 35)",
        "spectra": "Residual vibration spectra, eq. 56 (like Fig. 36)",
        "modes": "J_0, J_1, damped frequency f_d and ζ along the move: map vs twin "
        "(like Figs. 32-34)",
    }
    for kind, paths in figures.items():
        for p in paths:
            lines.append(f"- {captions[kind]}: [{p.name}]({p.name})")
            lines.append(f"  ![{p.name}]({p.name})")
    for name in (result.identification or {}).get("figures", []):
        caption = IDENTIFICATION_CAPTIONS.get(name, "Identified map")
        lines.append(f"- {caption}: [{name}]({name})")
        lines.append(f"  ![{name}]({name})")
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return path


_NOTES = [
    "Notes on the method:",
    "",
    "- *True modes* use the twin's eigen-analysis (linearized about the static equilibrium of "
    "the pose the shaper reports, every 2 ms) as the provider: the modes a perfect map "
    "would give. "
    "The *paper map* row runs the real-time path: the Rust robot model evaluates J_0, J_1 at "
    "the previous shaped output and the published coefficients (Tables 1-2) give the modes.",
    "- The zero-delay rows (second paper) compress the planned move and shape it with the "
    "same two-mode ZV shaper, designed for the twin's modes **at the end pose**. Both ZTDIS "
    "and its modified form are derived for a time-invariant plant: the compensator "
    "F(s) = G(α's)/G(s) cancels fixed poles, and a shaper cancels vibration only for the "
    "modes the arm has while it rings. The vibration that remains after the stop rings at "
    "the end pose, so its modes are the ones to cancel; making the compensator time-varying "
    "would break the pole-zero cancellation it relies on. ZV rather than ZVD: with exact "
    "modes the ZVD's robustness buys nothing, while its delay (the time that must be "
    "recovered by compression) doubles; with ZV the zero-delay rows remove exactly the delay "
    "of the FD-TVIST rows and differ from them only in how.",
    "- The paper map was identified on a real UR5e; the twin is a model with its own gear "
    "stiffness and damping. The map's errors here measure how far the twin is from that "
    "robot, not the quality of the published map.",
    "- The *identified map* row is the honest pipeline on the twin: mapping campaign "
    "(excitation, noisy accelerometer, local fits), map fit, and the same real-time path as "
    "the paper map. Its map knows only the inertias of the campaign and holds its modes "
    "constant beyond them.",
    "- The twin's accelerometer has no noise, so small residual vibrations are measured "
    "exactly; on the real robot the paper reports that the shaped vibration reached the "
    "noise level.",
]


_JERK_NOTE = (
    "- Peak jerk is the largest third difference of the sent reference. A true-modes row "
    "above the unshaped value comes from a sharp turn of the true damping: the twin's gear "
    "damping grows with the magnitude of the gear torque (tvist.sim.flex), so ζ turns sharply "
    "where a gravity torque changes sign (visible in the ζ panel of the mode figures). The ZV "
    "amplitudes follow it, which turns the reference velocity's slope quickly; the third "
    "difference shows that as a spike."
)


def _map_jerk_notes(result: DemoResult) -> list[str]:
    """Why a map row's reference is jerkier than the planned one, from how the map was used
    along it (:func:`tvist.experiments.methods.map_use`).

    The map has no kink (tvist-core ``dynmap``: inertias are saturated into their ranges by a
    C² soft clamp, the gravity term uses a smoothed ``|τ|``), so what is left are places where
    the modes bend sharply: a clamp's blend zones and a gravity torque passing through zero.
    """
    notes = []
    for motion in result.motions:
        try:
            plain = motion.run("unshaped")
        except KeyError:
            continue
        for r in motion.runs:
            use = r.details.get("map_use")
            if not use or r.peak_jerk_rad_s3 <= plain.peak_jerk_rad_s3:
                continue
            causes = []
            changes = sum(use["gravity_sign_changes"])
            if changes:
                causes.append(
                    "its smoothed stiffness term k_g (√(τ² + τ_s²) − τ_s) bends sharply where the "
                    f"gravity torque it reads changes sign ({changes} "
                    f"time{'s' if changes > 1 else ''} along the move)"
                )
            if any(0.0 < c < 100.0 for c in use["inertia_clamped_percent"]):
                causes.append(
                    "an inertia crosses a bound of the identified range, through the soft "
                    "clamp's blend zone (continuous slope and curvature, but a sharp bend)"
                )
            why = "; ".join(causes) if causes else "no bend of the map explains it"
            notes.append(
                f"- {r.method.label} on {motion.motion.name.replace('->', ' → ')}: peak jerk "
                f"{r.peak_jerk_rad_s3:.0f} rad/s³ (planned move "
                f"{plain.peak_jerk_rad_s3:.0f}): {why}. The shaper's amplitudes and delays "
                "follow the modes, so a sharp bend of the modes becomes a quick change of the "
                "reference acceleration, which the third difference shows as a spike."
            )
    return notes


def _jerk_spike(result: DemoResult) -> bool:
    """Whether some true-modes row is jerkier than its unshaped reference."""
    for motion in result.motions:
        try:
            truth, plain = motion.run("fd-tvist-truth"), motion.run("unshaped")
        except KeyError:
            continue
        if truth.peak_jerk_rad_s3 > plain.peak_jerk_rad_s3:
            return True
    return False


def _recommendation_lines(result: DemoResult) -> list[str]:
    lines = [f"- {recommendation(m)}" for m in result.motions]
    lines.append(
        f"- (Rule: among the rows a user can run, the unshaped move and the best slow-down "
        f"profile included, the one that settles first to {RANK_CRITERION.text}; within one "
        f"2 ms sample of it, the faster to {CRITERIA[1].text}, then the higher reduction. "
        "Rows marked *(oracle)* read what only the twin knows and are references only.)"
    )
    return lines


def _fixed_section(result: DemoResult) -> list[str]:
    """Fixed shapers (tune once at the start pose; robust over the move) against FD-TVIST
    with the identified map, per motion, with what the time variation buys."""
    from tvist.experiments.identified import KEY

    lines: list[str] = []
    for motion in result.motions:
        try:
            start, robust = motion.run("fixed-start"), motion.run("fixed-robust")
        except KeyError:
            continue
        try:
            tv = motion.run(KEY)
        except KeyError:
            tv = None
        name = motion.motion.name.replace("->", " → ")
        parts = [
            f"- **{name}**: fixed ZV at the start pose ({start.details['design']}): "
            f"{format_reduction(start.reduction_percent)} % for {1e3 * start.delay_s:.0f} ms; "
            f"fixed robust shaper ({robust.details['design']}): "
            f"{format_reduction(robust.reduction_percent)} % for {1e3 * robust.delay_s:.0f} ms"
        ]
        if not robust.details["robust_design"]["feasible"]:
            parts.append(
                " (no design of the library reaches the 5 % PRV over this range; this is the "
                "one with the lowest PRV)"
            )
        if tv is None:
            lines.append("".join(parts) + ".")
            continue
        parts.append(
            f"; FD-TVIST with the identified map: {format_reduction(tv.reduction_percent)} % "
            f"for {1e3 * tv.delay_s:.0f} ms. "
        )
        parts.append(_time_variation_buys(tv, start, robust))
        parts.append(_why_fixed_wins(motion, tv, start, robust))
        lines.append("".join(parts))
    if not lines:
        return []
    return [
        "## Fixed shapers against FD-TVIST",
        "",
        "What a user would run instead of a time-varying shaper: a two-mode ZV tuned once at "
        "the start pose and held for the whole move, or the shortest time-invariant shaper of "
        "tvist's library (one registry shaper, or two convolved, each designed for one mode) "
        "that keeps every mode the twin has along the planned move (both modes, every 20 ms) "
        "within 5 % residual vibration (PRV, eqs. 52-55).",
        "",
        *lines,
        "",
    ]


def _why_fixed_wins(motion: MotionRun, tv: Any, start: Any, robust: Any) -> str:
    """Where a fixed shaper beats FD-TVIST, the reason the numbers show."""
    notes = []
    start_modes = [tuple(m) for m in start.details["modes"]]
    change = max(
        abs(damped_frequency_hz(*a) / damped_frequency_hz(*b) - 1.0)
        for a, b in zip(start_modes, motion.true_end_modes, strict=False)
    )
    if tv.reduction_percent < start.reduction_percent and change < 0.02:
        notes.append(
            f" The modes do not change along this move (start and end within "
            f"{100 * change:.1f} %), so the start-pose ZV is exactly tuned and the identified "
            "map's errors are all FD-TVIST can add."
        )
    stages = robust.details["robust_design"]["stages"]
    if robust.delay_s < tv.delay_s and len(stages) == 1:
        f_end = [damped_frequency_hz(*m) for m in motion.true_end_modes]
        notes.append(
            f" Both modes ring at nearly the same frequency here (damped {f_end[0]:.2f} and "
            f"{f_end[1]:.2f} Hz), so one robust shaper covers both, while the two-mode ZV "
            "cascade pays a half period for each."
        )
    return "".join(notes)


def _time_variation_buys(tv: Any, start: Any, robust: Any) -> str:
    """One sentence from the numbers: reduction against the start-pose ZV and delay against
    the robust shaper, said plainly either way."""
    d_red = tv.reduction_percent - start.reduction_percent
    d_delay_ms = 1e3 * (robust.delay_s - tv.delay_s)
    if d_red >= 0.0:
        first = (
            f"Retuning along the move buys {d_red:.1f} points of reduction over the start-pose ZV"
        )
    else:
        first = (
            f"FD-TVIST with the identified map does **not** reach the start-pose ZV's "
            f"reduction here ({-d_red:.1f} points less)"
        )
    if d_delay_ms >= 0.0:
        second = f"and {d_delay_ms:.0f} ms less delay than the robust shaper"
    else:
        second = (
            f"and it is **not** faster than the robust shaper ({-d_delay_ms:.0f} ms more delay)"
        )
    return f"{first}, {second}."


def write_outputs(result: DemoResult, out_dir: str | Path) -> dict[str, Any]:
    """Write ``results.json``, the figures and ``report.md`` to ``out_dir``."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    figures = make_figures(result, out)
    return {
        "results": write_json(result, out / "results.json"),
        "report": write_markdown(result, out / "report.md", figures),
        "figures": figures,
    }
