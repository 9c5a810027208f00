"""The README's results table, rendered from a committed record of its figures.

Every row of README.md's ``## Results`` table is produced by a command that writes its
figures into a file (:data:`ROWS`: the command, the files, the keys). The record,
``docs/results/headline.json``, holds per row the figures with their source file and key, the
row's text around them, and where the figures came from; the table between
``<!-- results:begin -->`` and ``<!-- results:end -->`` in README.md is rendered from the
record alone, so no number of the table is typed by hand.

``python tools/results_table.py --update`` (``make results-table``) reads the figures of every
row whose outputs exist, replaces that row's record entry (a row whose outputs are missing,
or were made under other conditions than the row states, e.g. a ``--quick`` run, keeps its
entry and is named in the summary), writes the record and renders the table into README.md.
``--check`` (the unit tests run it) fails when the README's table is not the rendering of the
record, or a shown figure is not its recorded value.

In the record a figure is ``{"value", "shown", "unit", "file", "key"}``: ``value`` in the unit
the row shows (a list ``[min, max]`` for a range over repeated runs), ``shown`` its text in
the row, ``key`` where in ``file`` it was read (``× 1000``: scaled to the unit shown).
"""

from __future__ import annotations

import argparse
import json
import math
import re
import subprocess
import sys
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from datetime import datetime, timezone
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parent.parent
README = ROOT / "README.md"
RECORD = ROOT / "docs" / "results" / "headline.json"
BEGIN = "<!-- results:begin -->"
END = "<!-- results:end -->"
HEADER = ("| result | measured | command | details |", "|---|---|---|---|")
#: Provenance of the entries converted from the README's hand-typed table, once.
PUBLISHED = "as published before this record existed (typed into README.md by hand)"
RANGE_DASH = " – "


class MissingOutput(Exception):
    """A row's output file is not there: the row keeps its record entry."""


class UnusableOutput(Exception):
    """A row's output was made under other conditions than the row states (a quick run,
    other folds, a failed arm): the row keeps its record entry."""


# --------------------------------------------------------------------------- formats


def reduction(percent: float) -> str:
    """A reduction in %, as the experiments' tables print it
    (:func:`tvist.experiments.table.format_reduction`: 99.2, 99.98, 99.996)."""
    from tvist.experiments.table import format_reduction

    return format_reduction(percent)


def fixed(decimals: int) -> Callable[[float], str]:
    """``decimals`` digits after the point."""
    return lambda value: f"{value:.{decimals}f}"


def general(value: float) -> str:
    """The shortest text of a setting (5, 2.55, 0.05)."""
    return f"{value:g}"


def two_significant(value: float) -> str:
    """Two significant digits, trailing zeros kept (0.15, 0.70, 9.0, 36; 100 and above to
    the unit)."""
    if abs(value) >= 99.5:
        return f"{value:.0f}"
    return f"{value:#.2g}".rstrip(".")


def scientific(value: float) -> str:
    """One decimal of the mantissa, the exponent without padding (8.2e-3)."""
    mantissa, exponent = f"{value:.1e}".split("e")
    return f"{mantissa}e{int(exponent)}"


def _decimals(text: str) -> int:
    return len(text.split(".")[1]) if "." in text else 0


def shown_matches(value: float, text: str) -> bool:
    """Whether ``text`` is ``value`` rounded to the digits ``text`` shows (fixed point, or
    scientific as :func:`scientific` writes it)."""
    if "e" in text:
        mantissa, exponent = text.split("e")
        return f"{value:.{_decimals(mantissa)}e}" == f"{mantissa}e{int(exponent):+03d}"
    return f"{value:.{_decimals(text)}f}" == text


# --------------------------------------------------------------------------- figures


def figure(
    value: float | list[float],
    fmt: Callable[[float], str],
    unit: str,
    file: str,
    key: str,
) -> dict[str, Any]:
    """A record figure; a ``[min, max]`` value is shown as one number when both ends show
    the same, else as ``min – max``."""
    if isinstance(value, list):
        ends = [fmt(v) for v in value]
        shown = ends[0] if ends[0] == ends[1] else RANGE_DASH.join(ends)
    else:
        shown = fmt(value)
    return {"value": value, "shown": shown, "unit": unit, "file": file, "key": key}


def _read_json(root: Path, name: str) -> Any:
    path = root / name
    if not path.is_file():
        raise MissingOutput(f"{name} is missing")
    return json.loads(path.read_text(encoding="utf-8"))


def _dig(document: Any, keys: Sequence[str], name: str) -> Any:
    value = document
    for key in keys:
        try:
            value = value[key]
        except (KeyError, IndexError, TypeError):
            raise UnusableOutput(f"{name} has no {'.'.join(keys)}") from None
    if value is None:
        raise UnusableOutput(f"{name}: {'.'.join(keys)} is null (not finite)")
    return value


def _number(document: Any, keys: Sequence[str], name: str) -> float:
    return float(_dig(document, keys, name))


def _not_quick(document: Mapping[str, Any], name: str) -> None:
    if document.get("config", {}).get("quick"):
        raise UnusableOutput(f"{name} is a quick run (--quick)")


#: The UR5e experiment's motions, in the order the rows give them.
MOTIONS = ("Q1->Q2", "Q1->Q3", "Q3->Q1")


def _slug(motion: str) -> str:
    return motion.lower().replace("->", "_")


def demo_figures(root: Path) -> dict[str, Any]:
    """``make demo``: the identified modal map's reduction and delay, and the fixed ZV's
    reduction on the start pose's modes, per motion; the payload."""
    from tvist.experiments.modal_rows import KEY as MODAL_KEY

    name = "out/demo/results.json"
    doc = _read_json(root, name)
    _not_quick(doc, name)
    out = {
        "payload_kg": figure(
            _number(doc, ("config", "payload_kg"), name), general, "kg", name, "config.payload_kg"
        )
    }
    for motion in MOTIONS:
        slug = _slug(motion)
        for label, method, field, fmt, scale, unit in (
            ("modal", MODAL_KEY, "reduction_percent", reduction, 1.0, "%"),
            ("delay", MODAL_KEY, "delay_s", fixed(0), 1e3, "ms"),
            # the fixed two-mode ZV of the start pose's true modes (tvist.experiments.fixed)
            ("fixed", "fixed-start", "reduction_percent", reduction, 1.0, "%"),
        ):
            keys = ("motions", motion, "methods", method, field)
            value = scale * _number(doc, keys, name)
            key = ".".join(keys) + ("" if scale == 1.0 else f" × {scale:g}")
            out[f"{label}_{slug}"] = figure(value, fmt, unit, name, key)
    return out


def pick_place_figures(root: Path) -> dict[str, Any]:
    """``tvist demo --experiment pick-place``: cycle time to settled in the first band of
    unshaped, slowing down and ZTDIS on the identified map's end-pose modes; the moves'
    own time."""
    name = "out/demo-pick-place/results.json"
    doc = _read_json(root, name)
    _not_quick(doc, name)
    band = _dig(doc, ("config", "settle_criteria", "criteria", 0), name)
    out = {
        "band_m_s2": figure(
            float(band["threshold"]),
            general,
            "m/s²",
            name,
            "config.settle_criteria.criteria.0.threshold",
        )
    }
    for label, row in (
        ("unshaped", "unshaped"),
        ("slow_down", "slow-down"),
        ("ztdis", "ztdis-map"),
    ):
        keys = ("cycle", row, "cycle_s", band["key"])
        out[label] = figure(_number(doc, keys, name), fixed(3), "s", name, ".".join(keys))
    out["limit"] = figure(
        _number(doc, ("cycle_limit_s",), name), fixed(3), "s", name, "cycle_limit_s"
    )
    return out


def payload_figures(root: Path) -> dict[str, Any]:
    """``tvist demo --experiment flexible-payload``: reduction and delay of conventional ZVD,
    ZTDIS and modified ZTDIS; the payload's frequency."""
    name = "out/demo-payload/results.json"
    doc = _read_json(root, name)
    out = {
        "payload_hz": figure(
            _number(doc, ("config", "payload", "freq_hz"), name),
            general,
            "Hz",
            name,
            "config.payload.freq_hz",
        )
    }
    for method in ("conventional", "ztdis", "modified"):
        keys = ("methods", method, "reduction_percent")
        out[method] = figure(_number(doc, keys, name), reduction, "%", name, ".".join(keys))
    out["conventional_delay"] = figure(
        1e3 * _number(doc, ("methods", "conventional", "delay_s"), name),
        fixed(0),
        "ms",
        name,
        "methods.conventional.delay_s × 1000",
    )
    delays = [1e3 * _number(doc, ("methods", m, "delay_s"), name) for m in ("ztdis", "modified")]
    out["zero_delay"] = figure(
        [min(delays), max(delays)],
        fixed(0),
        "ms",
        name,
        "methods.ztdis.delay_s, methods.modified.delay_s × 1000 (min, max)",
    )
    return out


#: The full campaign on the twin, shared by its two rows.
CAMPAIGN = "out/campaign_full.jsonl"


def campaign_figures(root: Path) -> dict[str, Any]:
    """``tvist campaign --sim``: poses whose identified ω_n is within 3 % of the twin's true
    mode, per joint (:func:`tvist.ident.true_mode_agreement.within_tolerance`)."""
    from tvist.ident.results_store import load_results
    from tvist.ident.true_mode_agreement import within_tolerance

    path = root / CAMPAIGN
    if not path.is_file():
        raise MissingOutput(f"{CAMPAIGN} is missing")
    records = load_results(path)
    counts = within_tolerance(records)
    key = "within_tolerance(records)"
    out = {"n_poses": figure(len(records), general, "poses", CAMPAIGN, "len(records)")}
    for joint in ("shoulder", "base"):
        if joint not in counts:
            raise UnusableOutput(f"{CAMPAIGN}: no {joint} identification with true modes")
        within, compared = counts[joint]
        out[f"{joint}_within"] = figure(within, general, "poses", CAMPAIGN, f"{key}.{joint}[0]")
        out[f"{joint}_compared"] = figure(compared, general, "poses", CAMPAIGN, f"{key}.{joint}[1]")
    return out


#: The cross-validation of the two map forms on the full campaign, and its folds.
CROSS_VALIDATION = "out/campaign_full_cv.json"
FOLDS = 5


def cross_validation_figures(root: Path) -> dict[str, Any]:
    """``python -m tvist.cli.modal_fit ... --out``: held-out base-mode frequency error
    against the twin's true modes, RMS and max, of both map forms."""
    name = CROSS_VALIDATION
    doc = _read_json(root, name)
    if doc.get("folds") != FOLDS:
        raise UnusableOutput(f"{name} is {doc.get('folds')}-fold, the row states {FOLDS}")
    out = {}
    for form in ("modal", "published"):
        for stat in ("rms", "max"):
            keys = (form, "held_out", "versus_true", "base", "frequency", stat)
            out[f"{form}_{stat}"] = figure(
                100 * _number(doc, keys, name),
                two_significant,
                "%",
                name,
                ".".join(keys) + " × 100",
            )
    return out


#: ``tvist demo --robot NAME``'s result: the arm's default twin, ``out/demo-NAME/NAME-nominal``.
ARMS = ("fr3", "iiwa14")


def arm_figures(root: Path) -> dict[str, Any]:
    """``tvist demo --robot fr3`` / ``iiwa14``: the identified map's reduction per move and
    its largest RMS frequency error over its shaped modes."""
    out = {}
    for arm in ARMS:
        name = f"out/demo-{arm}/{arm}-nominal/result.json"
        doc = _read_json(root, name)
        if "error" in doc:
            raise UnusableOutput(f"{name}: the run failed ({doc['error']})")
        for motion in MOTIONS:
            keys = ("moves", motion, "identified", "reduction_percent")
            out[f"{arm}_{_slug(motion)}"] = figure(
                _number(doc, keys, name), fixed(2), "%", name, ".".join(keys)
            )
        modes = _dig(doc, ("map_vs_truth", "modes"), name)
        rms = max(float(m["rms_percent"]) for m in modes)
        out[f"{arm}_rms"] = figure(
            rms, fixed(2), "%", name, "max over map_vs_truth.modes of rms_percent"
        )
    return out


#: The held-out variants of the UR5e family (seeds 1000-1019), run once.
UNSEEN = "out/generalization-heldout"
UNSEEN_SEEDS = "1000-1019"
UNSEEN_COMMAND = (
    f".venv/bin/python -m tvist.experiments.generalization --robot ur5e --seeds {UNSEEN_SEEDS} "
    f"--workers 2 --out {UNSEEN}"
)


def unseen_figures(root: Path) -> dict[str, Any]:
    """The generalization harness on the held-out variants: the floor's summary
    (:func:`tvist.experiments.generalization.floor_summary`) and, per variant, the largest
    RMS frequency error of its map's shaped modes (median and range over the variants)."""
    import statistics

    from tvist.experiments.generalization import (
        FLOOR,
        WRONG_TOLERANCE,
        floor_summary,
        parse_seeds,
    )

    results, largest = [], []
    for seed in parse_seeds(UNSEEN_SEEDS):
        name = f"{UNSEEN}/ur5e-{seed}/result.json"
        doc = _read_json(root, name)
        results.append(doc)
        if "error" not in doc:
            rms = [float(m["rms_percent"]) for m in _dig(doc, ("map_vs_truth", "modes"), name)]
            # A shaped mode without a true mode to compare (NaN) is a miss of the floor,
            # counted there; the error figures are over the compared ones.
            compared = [x for x in rms if math.isfinite(x)]
            if compared:
                largest.append(max(compared))
    summary = floor_summary(results)
    files = f"{UNSEEN}/ur5e-*/result.json"
    out = {
        key: figure(float(summary[key]), general, unit, files, f"floor_summary(results).{key}")
        for key, unit in (
            ("variants", ""),
            ("moves", ""),
            ("moves_at_floor", ""),
            ("meeting_every_line", ""),
            ("wrong_confident", ""),
        )
    }
    out["least"] = figure(
        summary["least_reduction_percent"],
        fixed(2),
        "%",
        files,
        "floor_summary(results).least_reduction_percent",
    )
    # The limits the counts are made against, as the harness holds them.
    module = "tvist.experiments.generalization"
    out["floor"] = figure(
        FLOOR.reduction_percent, general, "%", files, f"{module}.FLOOR.reduction_percent"
    )
    out["tolerance"] = figure(
        100 * WRONG_TOLERANCE, general, "%", files, f"{module}.WRONG_TOLERANCE × 100"
    )
    key = "largest rms_percent of map_vs_truth.modes per variant"
    out["rms_median"] = figure(
        statistics.median(largest), fixed(1), "%", files, f"median of the {key}"
    )
    out["rms_range"] = figure(
        [min(largest), max(largest)], fixed(1), "%", files, f"min, max of the {key}"
    )
    return out


#: The live runs' RTDE logs (``tvist run ... --log``), three repeats each.
LIVE = "out/live"


def live_figures(root: Path) -> dict[str, Any]:
    """``tvist run`` against the twin server: residual vibration (accelerometer RMS over 1 s
    after the move, :func:`tvist.live.residual_vibration`) of the unshaped and the
    paper-map runs, min and max over the repeats."""
    from tvist.live import residual_vibration

    out = {}
    for label, stem in (("unshaped", "unshaped"), ("paper_map", "paper-map")):
        logs = sorted((root / LIVE).glob(f"{stem}-*.csv"))
        if not logs:
            raise MissingOutput(f"{LIVE}/{stem}-*.csv is missing")
        values = [residual_vibration(log) for log in logs]
        names = ", ".join(log.name for log in logs)
        out[label] = figure(
            [min(values), max(values)],
            scientific,
            "m/s²",
            f"{LIVE}/{stem}-*.csv",
            f"tvist.live.residual_vibration of {names} (min, max)",
        )
    return out


BENCH = "out/bench/cycle.txt"
#: The benchmark's cases of the row, by their name in the table it prints: TvShaper with
#: fixed modes (its ratio to the plain fixed convolution of the same shapers, in the same
#: rounds), and with the UR5e's inertia and the paper's map (its ratio to the former).
BENCH_CASES = {
    "fixed": "6 DOF, 2 modes ZV: TvShaper, constant modes",
    "map": "6 DOF, 2 modes ZV: UR5e inertia + paper map + shaping",
}


def bench_figures(root: Path) -> dict[str, Any]:
    """``make bench``: the median ns per cycle of two cases of the table
    ``cargo bench -p tvist-core --bench cycle`` prints (saved in out/bench/cycle.txt), each
    with its ratio to its reference case (the median over the rounds of the per-round ratio:
    what a shared machine's speed changes cancel out of)."""
    path = root / BENCH
    if not path.is_file():
        raise MissingOutput(f"{BENCH} is missing")
    rows = [
        [cell.strip() for cell in line.strip().strip("|").split("|")]
        for line in path.read_text(encoding="utf-8").splitlines()
        if line.startswith("|")
    ]
    if not rows or not {"case", "median ns", "ratio"} <= set(rows[0]):
        raise UnusableOutput(f"{BENCH} has no table with 'median ns' and 'ratio' columns")
    case, median, ratio = (rows[0].index(c) for c in ("case", "median ns", "ratio"))
    by_case = {row[case]: row for row in rows[2:] if len(row) == len(rows[0])}
    out = {}
    for label, name in BENCH_CASES.items():
        if name not in by_case:
            raise UnusableOutput(f"{BENCH} has no case '{name}'")
        out[label] = figure(
            float(by_case[name][median]), fixed(1), "ns", BENCH, f"median ns of '{name}'"
        )
        out[f"{label}_ratio"] = figure(
            float(by_case[name][ratio]), fixed(2), "", BENCH, f"ratio of '{name}'"
        )
    return out


# --------------------------------------------------------------------------- rows


@dataclass(frozen=True)
class Row:
    """One row of the table.

    Attributes
    ----------
    key
        The row's name in the record.
    result, measured
        The first two cells, with ``{figure}`` where each figure goes.
    command
        The third cell (markdown).
    details
        The fourth cell: the page with the full table.
    commands
        What to run, in order, to produce the outputs :attr:`extract` reads.
    extract
        ``extract(root)``: the figures, read from the outputs under ``root``; raises
        :class:`MissingOutput` or :class:`UnusableOutput`.
    """

    key: str
    result: str
    measured: str
    command: str
    details: str
    commands: tuple[str, ...]
    extract: Callable[[Path], dict[str, Any]]


ROWS: tuple[Row, ...] = (
    Row(
        "demo",
        "residual vibration after the paper's three test moves (Q1→Q2 / Q1→Q3 / Q3→Q1), "
        "{payload_kg} kg, FD-TVIST with the identified modal map",
        "{modal_q1_q2} / {modal_q1_q3} / {modal_q3_q1} % less, delay {delay_q1_q2} / "
        "{delay_q1_q3} / {delay_q3_q1} ms (fixed ZV on the start pose's modes: {fixed_q1_q2} / "
        "{fixed_q1_q3} / {fixed_q3_q1} % less)",
        "`make demo`",
        "[demo](docs/results/demo.md)",
        ("make demo",),
        demo_figures,
    ),
    Row(
        "pick-place",
        "pick-and-place cycle of eight moves, time to settled at {band_m_s2} m/s²",
        "{unshaped} s unshaped, {slow_down} s slowing down, {ztdis} s ZTDIS on the identified "
        "modal map's end-pose modes (the moves: {limit} s)",
        "`tvist demo --experiment pick-place`",
        "[pick-place](docs/results/pick-place.md)",
        (".venv/bin/tvist demo --experiment pick-place",),
        pick_place_figures,
    ),
    Row(
        "flexible-payload",
        "flexible payload at {payload_hz} Hz, residual vibration and added delay",
        "conventional ZVD {conventional} % less at {conventional_delay} ms; ZTDIS {ztdis} % and "
        "modified ZTDIS {modified} % less at {zero_delay} ms",
        "`tvist demo --experiment flexible-payload`",
        "[flexible payload](docs/results/flexible-payload.md)",
        (".venv/bin/tvist demo --experiment flexible-payload",),
        payload_figures,
    ),
    Row(
        "campaign",
        "identified ω_n within 3 % of the twin's true modes, full {n_poses}-pose campaign",
        "shoulder {shoulder_within}/{shoulder_compared}, base {base_within}/{base_compared} poses",
        f"`tvist campaign --sim --workers 2 --out {CAMPAIGN}`",
        "[identification](docs/results/identification.md#full-campaign-on-the-twin)",
        (f".venv/bin/tvist campaign --sim --workers 2 --out {CAMPAIGN}",),
        campaign_figures,
    ),
    Row(
        "cross-validation",
        "map frequency error on held-out poses, base mode, RMS / max",
        "modal map {modal_rms} / {modal_max} %, published form {published_rms} / {published_max} %",
        f"`python -m tvist.cli.modal_fit {CAMPAIGN} --folds {FOLDS} --out {CROSS_VALIDATION}`",
        "[identification](docs/results/identification.md#full-campaign-on-the-twin)",
        (
            f".venv/bin/tvist campaign --sim --workers 2 --out {CAMPAIGN}",
            f".venv/bin/python -m tvist.cli.modal_fit {CAMPAIGN} --folds {FOLDS} "
            f"--out {CROSS_VALIDATION}",
        ),
        cross_validation_figures,
    ),
    Row(
        "arms",
        "arms from their URDF (FR3 / iiwa14 twins), the three moves shaped with a modal map "
        "identified on each",
        "FR3 {fr3_q1_q2} / {fr3_q1_q3} / {fr3_q3_q1} %, iiwa14 {iiwa14_q1_q2} / {iiwa14_q1_q3} / "
        "{iiwa14_q3_q1} % less; map within {fr3_rms} % (FR3) and {iiwa14_rms} % (iiwa14) RMS of "
        "the twins' true modes",
        "`tvist demo --robot fr3` (`--robot iiwa14`)",
        "[arms from URDF](docs/results/arms.md)",
        (".venv/bin/tvist demo --robot fr3", ".venv/bin/tvist demo --robot iiwa14"),
        arm_figures,
    ),
    Row(
        "unseen-arms",
        "arms tvist has not seen: {variants} held-out variants of the UR5e family (seeds "
        f"{UNSEEN_SEEDS}), each identified from its own ur_rtde CSV logs through the CLI, the "
        "three moves shaped with its map",
        "{moves_at_floor} of {moves} moves {floor} % less or more (least {least} %); "
        "{meeting_every_line} of {variants} variants meet every line of the floor; largest map "
        "error of a shaped mode {rms_median} % RMS (median over the variants; {rms_range} %); "
        "{wrong_confident} confident identifications more than {tolerance} % from every true "
        "mode",
        f"`python -m tvist.experiments.generalization --seeds {UNSEEN_SEEDS}`",
        "[on arms tvist has not seen](#on-arms-tvist-has-not-seen)",
        (UNSEEN_COMMAND,),
        unseen_figures,
    ),
    Row(
        "live",
        "live through ur_rtde, Q1→Q2, residual vibration",
        "{unshaped} m/s² unshaped, {paper_map} m/s² with the paper's map",
        "`tvist run q1-q2.csv --robot-ip 127.0.0.1 --paper-map`",
        "[twin server](docs/guides/twin-server.md#measured)",
        (
            ".venv/bin/tvist twin-server --payload-kg 5 --payload-com 0 0 0.05 &",
            '.venv/bin/python -c "import numpy as np; from tvist.experiments.motions import '
            "motion_by_name; from tvist.robots import params; np.savetxt('q1-q2.csv', "
            "motion_by_name('Q1->Q2').reference(0.0, params('ur5e').control_period_s).q, "
            "delimiter=',')\"",
            "for n in 1 2 3; do .venv/bin/tvist run q1-q2.csv --robot-ip 127.0.0.1 --unshaped "
            f"--log {LIVE}/unshaped-$n.csv; done",
            "for n in 1 2 3; do .venv/bin/tvist run q1-q2.csv --robot-ip 127.0.0.1 --paper-map "
            f"--log {LIVE}/paper-map-$n.csv; done",
        ),
        live_figures,
    ),
    Row(
        "bench",
        "one control cycle, 6 DOF, two ZV modes (median)",
        "{fixed} ns with fixed modes ({fixed_ratio} × a plain fixed convolution in the same "
        "rounds), {map} ns with the UR5e's inertia and the paper's map ({map_ratio} × fixed "
        "modes); absolute times vary with the shared machine, the ratios less",
        "`cargo bench -p tvist-core --bench cycle` (`make bench`)",
        "[benchmarks](docs/benchmarks.md)",
        ("make bench",),
        bench_figures,
    ),
)


# --------------------------------------------------------------------------- record


def _git(root: Path, *args: str) -> str | None:
    try:
        done = subprocess.run(
            ["git", *args], cwd=root, capture_output=True, text=True, check=True, timeout=30
        )
    except (OSError, subprocess.SubprocessError):
        return None
    return done.stdout.strip()


def _utc(timestamp: float) -> str:
    return datetime.fromtimestamp(timestamp, tz=timezone.utc).strftime("%Y-%m-%d %H:%M UTC")


def provenance(
    root: Path, figures: Mapping[str, Any], made_with: str | None = None
) -> dict[str, Any]:
    """Where an entry's figures came from: its output files and when each was written; the
    commit that made them: ``made_with`` (stated by whoever ran the commands, e.g. a
    checkout of an earlier commit; it must be an ancestor of the checked-out commit) or else
    the checked-out one, when every output was written after it was made (else the run's
    commit is unknown: no output records it)."""
    # A figure's file may be a pattern (the live runs' logs): every file it names.
    files = sorted({path for f in figures.values() for path in root.glob(f["file"])})
    written = {str(p.relative_to(root)): p.stat().st_mtime for p in files}
    commit = _git(root, "rev-parse", made_with or "HEAD")
    if made_with is not None and (
        commit is None or _git(root, "merge-base", "--is-ancestor", commit, "HEAD") is None
    ):
        raise ValueError(f"--made-with {made_with}: not a commit of this checkout's history")
    commit_time = _git(root, "show", "-s", "--format=%ct", commit) if commit else None
    after = commit_time is not None and min(written.values()) >= float(commit_time)
    dirty = _git(root, "status", "--porcelain", "--untracked-files=no")
    if made_with is not None:
        note = "the commit the outputs were made with (stated at the update)"
    else:
        note = "the commit checked out when the record was updated" + (
            " (the tree had changes)" if dirty else ""
        )
    return {
        "source": "outputs",
        "outputs": {name: _utc(t) for name, t in written.items()},
        "tvist_commit": commit if after else None,
        "commit_note": (
            note + "; every output was written after it was made"
            if after
            else "unknown: an output is older than the commit "
            + ("stated" if made_with else "checked out at the update")
        ),
        "updated": _utc(datetime.now(timezone.utc).timestamp()),
    }


def entry(row: Row, figures: dict[str, Any], source: dict[str, Any]) -> dict[str, Any]:
    """The record entry of ``row`` with ``figures``."""
    return {
        "key": row.key,
        "result": row.result,
        "measured": row.measured,
        "command": row.command,
        "details": row.details,
        "commands": list(row.commands),
        "figures": figures,
        "provenance": source,
    }


def load_record(path: Path = RECORD) -> dict[str, Any]:
    return json.loads(path.read_text(encoding="utf-8"))


def write_record(record: Mapping[str, Any], path: Path = RECORD) -> None:
    path.write_text(json.dumps(record, indent=1, ensure_ascii=False) + "\n", encoding="utf-8")


# --------------------------------------------------------------------------- rendering


def render_row(item: Mapping[str, Any]) -> str:
    """One table line of a record entry."""
    shown = {name: f["shown"] for name, f in item["figures"].items()}
    cells = [
        item["result"].format_map(shown),
        item["measured"].format_map(shown),
        item["command"],
        item["details"],
    ]
    return "| " + " | ".join(cells) + " |"


def render_table(record: Mapping[str, Any]) -> str:
    """The table between the markers, from the record alone."""
    return "\n".join([*HEADER, *(render_row(item) for item in record["rows"])])


def _section(readme: str) -> tuple[int, int]:
    begin, end = readme.find(BEGIN), readme.find(END)
    if begin < 0 or end < begin:
        raise ValueError(f"README.md has no {BEGIN} ... {END} section")
    return begin + len(BEGIN), end


def with_table(readme: str, table: str) -> str:
    """``readme`` with the text between the markers replaced by ``table``."""
    start, stop = _section(readme)
    return readme[:start] + "\n" + table + "\n" + readme[stop:]


def figure_problems(record: Mapping[str, Any]) -> list[str]:
    """Record entries whose shown text is not their value (or misses a placeholder)."""
    problems = []
    for item in record["rows"]:
        for name, f in item["figures"].items():
            values = f["value"] if isinstance(f["value"], list) else [f["value"]]
            texts = f["shown"].split(RANGE_DASH)
            if len(texts) == 1:
                texts = texts * len(values)
            if len(texts) != len(values) or not all(
                isinstance(v, (int, float)) and math.isfinite(v) and shown_matches(v, t)
                for v, t in zip(values, texts, strict=True)
            ):
                problems.append(f"{item['key']}: {name} shows {f['shown']!r}, value {f['value']}")
        for cell in ("result", "measured"):
            wanted = set(re.findall(r"\{(\w+)\}", item[cell]))
            if wanted - set(item["figures"]):
                problems.append(f"{item['key']}: no figure {sorted(wanted - set(item['figures']))}")
    return problems


def check(readme: str, record: Mapping[str, Any]) -> list[str]:
    """What is wrong with README.md's table against the record (empty: nothing)."""
    problems = figure_problems(record)
    if problems:
        return problems
    start, stop = _section(readme)
    have = readme[start:stop].strip("\n").splitlines()
    want = render_table(record).splitlines()
    for i, (line, expected) in enumerate(zip(have, want, strict=False)):
        if line != expected:
            problems.append(
                f"README.md table line {i + 1} is not the record's rendering "
                f"(docs/results/headline.json; run `make results-table`):\n"
                f"  README: {line}\n  record: {expected}"
            )
    if len(have) != len(want):
        problems.append(f"README.md's table has {len(have)} lines, the record renders {len(want)}")
    return problems


def update(
    root: Path, record: dict[str, Any], made_with: Mapping[str, str] | None = None
) -> tuple[dict[str, Any], list[str]]:
    """The record with every row whose outputs exist read again (``made_with``: row key ->
    the commit its outputs were made with, see :func:`provenance`); and one line per row on
    what was done."""
    made_with = made_with or {}
    unknown = set(made_with) - {row.key for row in ROWS}
    if unknown:
        raise ValueError(f"--made-with: no row {', '.join(sorted(unknown))}")
    entries = {item["key"]: item for item in record["rows"]}
    lines = []
    for row in ROWS:
        try:
            figures = row.extract(root)
        except (MissingOutput, UnusableOutput) as exc:
            lines.append(f"{row.key}: kept the record's entry ({exc})")
            continue
        entries[row.key] = entry(row, figures, provenance(root, figures, made_with.get(row.key)))
        lines.append(
            f"{row.key}: updated from {', '.join(entries[row.key]['provenance']['outputs'])}"
        )
    rows = [entries[row.key] for row in ROWS if row.key in entries]
    return {**record, "rows": rows}, lines


def main(argv: Sequence[str] | None = None) -> int:
    p = argparse.ArgumentParser(
        prog="tools/results_table.py",
        description="README.md's results table from docs/results/headline.json (see the "
        "module docstring).",
    )
    mode = p.add_mutually_exclusive_group(required=True)
    mode.add_argument(
        "--update",
        action="store_true",
        help="read the rows' outputs in out/, write the record and README.md",
    )
    mode.add_argument(
        "--check",
        action="store_true",
        help="fail if README.md's table is not the rendering of the record",
    )
    p.add_argument(
        "--made-with",
        metavar="ROW=COMMIT",
        action="append",
        default=[],
        help="with --update: the commit a row's outputs were made with, when it is not the "
        "checked-out one (repeat per row)",
    )
    args = p.parse_args(argv)
    record = load_record()
    readme = README.read_text(encoding="utf-8")
    if args.update:
        pairs = [item.partition("=") for item in args.made_with]
        if any(not key or not sep or not commit for key, sep, commit in pairs):
            p.error("--made-with takes ROW=COMMIT")
        try:
            record, lines = update(ROOT, record, {key: commit for key, _, commit in pairs})
        except ValueError as exc:
            p.error(str(exc))
        problems = figure_problems(record)
        if problems:
            print("\n".join(problems), file=sys.stderr)
            return 1
        write_record(record)
        README.write_text(with_table(readme, render_table(record)), encoding="utf-8")
        print("\n".join(lines))
        print(f"wrote {RECORD.relative_to(ROOT)} and the table in README.md")
        return 0
    problems = check(readme, record)
    if problems:
        print("\n".join(problems), file=sys.stderr)
        return 1
    print("README.md's results table is the rendering of docs/results/headline.json")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
