"""The per-motion table of the UR5e experiment, shared by the console (``tvist demo``, see
:mod:`tvist.cli.demo_table`) and ``report.md``: one row per method with its cells formatted,
and the markdown table writer the experiments' reports use."""

from __future__ import annotations

import math
from typing import Any

from tvist.experiments.experiment import MotionRun
from tvist.experiments.settle import CRITERIA, format_settle


def format_reduction(percent: float) -> str:
    """A reduction in % with enough decimals that it never rounds to 100: one decimal, and
    one more per decade the remainder ``100 − percent`` falls below 1 (99.2, 99.98, 99.996)."""
    if not math.isfinite(percent):
        return "n/a"
    rest = 100.0 - percent
    decimals = 1 if rest >= 1.0 or rest <= 0.0 else max(1, math.ceil(-math.log10(rest)) + 1)
    return f"{percent:.{min(decimals, 6)}f}"


#: How each residual-vibration estimate is named in tables (see
#: :class:`tvist.analysis.ResidualVibration`).
RV_ESTIMATES = {
    "damped_sine_fit": "one-mode fit",
    "log_decay": "peak decay",
    "max_abs": "largest peak (upper bound)",
}


def row_label(run: Any) -> str:
    """A row's label, marked when a user cannot run it."""
    return run.method.label + (" (oracle)" if run.method.oracle else "")


def _settle_cells(settle: Any) -> list[str]:
    if settle is None:
        return ["-"] * len(CRITERIA)
    return [format_settle(settle.get(c.key), settle.record_s) for c in CRITERIA]


def table_rows(motion: MotionRun) -> list[list[str]]:
    analytic_ms = f"{1e3 * motion.analytic_zv_delay_s:.1f}"
    rows = []
    for r in motion.runs:
        baseline = r.method.key == "unshaped"
        rows.append(
            [
                row_label(r),
                f"{1e3 * r.delay_s:.0f}",
                "-" if baseline else analytic_ms,
                f"{r.residual.amplitude:.4f}",
                "-" if baseline else format_reduction(r.reduction_percent),
                *_settle_cells(r.settle),
                f"{r.peak_jerk_rad_s3:.0f}",
                RV_ESTIMATES.get(r.residual.method, r.residual.method)
                + ("" if r.residual.reliable else " (unreliable)"),
            ]
        )
    if motion.slow_down is not None:
        cells = []
        for c in CRITERIA:
            best = motion.slow_down.best(c.key)
            cells.append("not settled" if best is None else format_settle(best.settle.get(c.key)))
        rows.append(["Slow down instead (best of the grid)", "-", "-", "-", "-", *cells, "-", "-"])
    return rows


_SETTLE_HEADER = [f"Settled, {c.text} [s]" for c in CRITERIA]
TABLE_HEADER = [
    "Method",
    "Delay [ms]",
    "ZV delay at end, true modes [ms]",
    "Res. vibration [m/s²]",
    "Reduction [%]",
    *_SETTLE_HEADER,
    "Peak jerk [rad/s³]",
    "RV estimate",
]


def planned_move_s(motion: MotionRun) -> float:
    """The planned move's duration (the physical limit of every settle time), s."""
    return float(motion.runs[0].settle.move_s)


def markdown_table(header: list[str], rows: list[list[str]]) -> str:
    """A markdown table; a ``|`` inside a cell (``|ψ|``) is escaped, else it splits the cell."""

    def line(cells: list[str]) -> str:
        return "| " + " | ".join(cell.replace("|", "\\|") for cell in cells) + " |"

    lines = [line(header), "|" + "|".join("---" for _ in header) + "|"]
    lines += [line(row) for row in rows]
    return "\n".join(lines)
