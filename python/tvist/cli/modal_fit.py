"""``tvist fit-map --kind modal``: fit a modal map, print what was found, write the map file.

By default the fit uses every identified mode (:mod:`tvist.ident.all_modes_fit`);
``--select-folds K`` runs the label-based fit of the base and shoulder modes with its held-out
term selection (:mod:`tvist.ident.modal_fit`).

``python -m tvist.cli.modal_fit RESULTS.jsonl``: the label-based fit against the published
form on held-out poses (:func:`main`).
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Mapping, Sequence
from typing import Any

__all__ = ["fit_modal_command", "main"]

_UNITS = {"stiffness": "N m/rad", "damping": "N m s/rad"}
_PER = {"at_zero": "", "per_nm": " per N m", "per_nm2": " per (N m)²"}


def _error(message: str) -> int:
    print(f"tvist fit-map: error: {message}", file=sys.stderr)
    return 2


def _what(entry: Mapping[str, Any]) -> str:
    """``joint j`` or ``link l bending`` of a test, coefficient or mode entry."""
    return f"link {entry['link']} bending" if "link" in entry else f"joint {entry['joint']}"


def _se(se: float | None) -> str:
    return "?" if se is None else f"{se:.2g}"


def _coverage(mode: Mapping[str, Any]) -> str:
    """What shaping the map's ``K`` lowest does to a physical mode of the report
    (:func:`tvist.ident.shaped_modes.with_coverage`): nothing to add when it is what the mode
    asks (a shaped mode among the ``K`` lowest at every pose, an unshaped one at none)."""
    among = mode.get("among_shaped_at_poses")
    if among is None:
        return ""
    if mode["shaped"] and among < 1.0:
        return (
            f", among the shaped lowest at {100 * among:.0f} % of the poses (elsewhere left "
            f"unshaped: participation up to {100 * mode['participation_outside']:.0f} %)"
        )
    if not mode["shaped"] and among > 0.0:
        return (
            f", among the shaped lowest at {100 * among:.0f} % of the poses (there shaped at "
            "the model's extrapolated frequency when a move makes it ring)"
        )
    return ""


def fit_modal_command(records: Sequence[Mapping[str, Any]], args: argparse.Namespace) -> int:
    """Fit, print, save (``args``: ``results``, ``out``, ``robot``, ``include_low_confidence``,
    ``select_folds``)."""
    if args.select_folds is not None:
        return _labelled_fit(records, args)
    from tvist.ident.all_modes_fit import fit_all_modes, fitted_map, unmatched_warning

    try:
        fit = fit_all_modes(records, args.robot, include_low_confidence=args.include_low_confidence)
    except ValueError as exc:
        return _error(str(exc))
    # After the fit: a refusal stays the one line of its error.
    if not any("ringing" in r for r in records):
        print(
            f"tvist fit-map: warning: {args.results}: no record lists its ringing modes; "
            "using each log's one mode, matched by frequency alone (no flange direction): "
            "a mode the base log mistook for another is then fitted as what it is closest to",
            file=sys.stderr,
        )
    modal = fitted_map(fit, {"source": f"tvist fit-map --kind modal {args.results}"})
    stats = modal.metadata["fit_statistics"]
    print(
        f"modal map of {args.robot}: {stats['n_poses']} poses, {stats['identified_modes']} "
        f"identified modes, {stats['matched_modes']} matched to the model's eigenmodes "
        f"(frequency error {100 * stats['frequency_error_matched']['rms']:.2f} % RMS, damping "
        f"ratio {100 * stats['damping_error_matched']['rms']:.1f} % RMS)"
    )
    doubt = unmatched_warning(stats)
    if doubt is not None:
        print(f"tvist fit-map: warning: {args.results}: {doubt}", file=sys.stderr)
    level = stats["joint_test_level"]
    print(
        f"  flexible joints {stats['flexible_joints']}, bending links "
        f"{stats.get('bending_links', [])} (kept at p < {level:g})"
    )
    for test in stats["joint_tests"]:
        verdict = "made rigid" if test.get("made_rigid") else "flexible"
        if "refit_chi2" in test:
            before, after = test["refit_chi2"]
            verdict = f"better without it: refitted from there (χ² {before:.1f} -> {after:.1f})"
        print(
            f"    {_what(test)}: χ² gain {test['chi2_gain']:.1f} on {test['dof']} "
            f"parameter(s), p = {test['p_value']:.2g}: {verdict}"
        )
    for c in stats["coefficients"]:
        print(
            f"  {_what(c)} {c['what']} {c['term']}: {c['value']:.5g} ± {_se(c['se'])} "
            f"({_UNITS[c['what']]}{_PER[c['term']]})"
        )
    dropped = [d for d in stats["dropped"] if not d.startswith("joint ")]
    if dropped:
        print(f"  dropped as negligible: {', '.join(dropped)}")
    print("  physical modes (frequency min/median/max over the poses, flange participation):")
    for m in stats["physical_modes"]:
        f = m["freq_hz"]
        print(
            f"    {m.get('name', _what(m))}: {f[0]:.1f} / {f[1]:.1f} / {f[2]:.1f} Hz, "
            f"participation median {100 * m['flange_participation'][0]:.0f} %, max "
            f"{100 * m['flange_participation'][1]:.0f} %, identified at "
            f"{100 * m['identified_at_poses']:.0f} % of the poses "
            f"({100 * m['identified_where_it_rings']:.0f} % of those where it rings): "
            f"{'shaped' if m['shaped'] else 'not shaped'}{_coverage(m)}"
        )
    shaped = (
        f"mode_joints {modal.mode_joints}"
        if modal.mode_joints is not None
        else f"the {modal.shaped_modes} lowest (shaped_modes; per move the lowest it needs)"
    )
    print(f"  shaped modes: {shaped}")
    modal.save(args.out)
    print(f"modal map written to {args.out}")
    return 0


def _labelled_fit(records: Sequence[Mapping[str, Any]], args: argparse.Namespace) -> int:
    from tvist.ident.modal_fit import fit_modal_map

    try:
        modal = fit_modal_map(
            records,
            args.robot,
            include_low_confidence=args.include_low_confidence,
            select_folds=args.select_folds,
            metadata={"source": f"tvist fit-map --kind modal {args.results}"},
        )
    except ValueError as exc:
        return _error(str(exc))
    stats = modal.metadata["fit_statistics"]
    print(
        f"modal map of {args.robot} (base and shoulder modes by label): {stats['n_poses']} "
        f"poses, usable identifications base {stats['usable_identifications']['base']}, "
        f"shoulder {stats['usable_identifications']['shoulder']}"
    )
    for what in ("stiffness_nm_per_rad", "damping_nms_per_rad"):
        name = what.split("_")[0]
        for t in stats[what]:
            print(
                f"  joint {t['joint']} {name} {t['term']}: {t['value']:.5g} ± {_se(t['se'])} "
                f"({_UNITS[name]}{_PER[t['term']]})"
            )
    if stats["dropped"]:
        print(f"  dropped as negligible: {', '.join(stats['dropped'])}")
    selection = stats.get("term_selection")
    if selection:
        made = ", ".join(m["move"] for m in selection["moves"]) or "none"
        print(
            f"  held-out selection ({selection['folds']} folds): moves {made}; held-out "
            f"frequency error {100 * selection['held_out_rms']:.2f} % RMS"
        )
    for name, entry in stats["versus_identified"].items():
        print(
            f"  {name}: RMS relative error frequency {100 * entry['frequency']['rms']:.2f} %, "
            f"damping {100 * entry['damping']['rms']:.1f} %"
        )
    modal.save(args.out)
    print(f"modal map written to {args.out}")
    return 0


def main(argv: Sequence[str] | None = None) -> int:
    """``python -m tvist.cli.modal_fit RESULTS.jsonl [--robot R] [--folds K] [--out FILE]``:
    both map forms' errors, in-sample and on held-out poses, as a markdown table
    (:func:`tvist.ident.modal_fit.cross_validation.cross_validate`); ``--out`` also writes
    them as JSON."""
    from tvist.ident.campaign import load_results
    from tvist.ident.modal_fit.cross_validation import cross_validate, format_comparison

    p = argparse.ArgumentParser(prog="python -m tvist.cli.modal_fit", description=main.__doc__)
    p.add_argument("results", help="campaign results (JSON lines)")
    p.add_argument("--robot", default="ur5e", help="robot model (default ur5e)")
    p.add_argument("--folds", type=int, default=5, help="folds over poses (default 5)")
    p.add_argument(
        "--out",
        metavar="FILE",
        help="also write the errors as JSON (cross_validate's result, relative errors as "
        "fractions, NaN as null) to FILE",
    )
    args = p.parse_args(argv)
    if args.out:
        from tvist.cli.args import output_file

        try:
            output_file(args.out, "--out")
        except ValueError as exc:
            print(f"python -m tvist.cli.modal_fit: error: {exc}", file=sys.stderr)
            return 2
    records = load_results(args.results)
    try:
        cv = cross_validate(records, args.robot, folds=args.folds)
    except ValueError as exc:
        print(f"python -m tvist.cli.modal_fit: error: {exc}", file=sys.stderr)
        return 2
    print(f"{cv['n_poses']} poses, {cv['folds']}-fold over poses (seed {cv['seed']})")
    print(format_comparison(cv))
    if args.out:
        _write_comparison(cv, args.results, args.robot, args.out)
        print(f"written to {args.out}")
    return 0


def _write_comparison(cv: Mapping[str, Any], results: str, robot: str, path: str) -> None:
    """``cross_validate``'s result as JSON, with the records file and robot it was run on."""
    import json
    from pathlib import Path

    from tvist.experiments.results_json import json_safe

    document = {"results": results, "robot": robot, **json_safe(dict(cv))}
    Path(path).write_text(json.dumps(document, indent=2) + "\n", encoding="utf-8")


if __name__ == "__main__":
    raise SystemExit(main())
