"""``tvist demo``'s console table: per motion of the UR5e experiment a Table-4-style table
with the analytic ZV delay and the end-pose modes, and the verdict under it
(:func:`tvist.experiments.verdict.recommendation`)."""

from __future__ import annotations

from typing import Any

from tvist.experiments.experiment import DemoResult
from tvist.experiments.measure import damped_frequency_hz
from tvist.experiments.table import planned_move_s, table_rows
from tvist.experiments.verdict import recommendation

#: Shorter headers for the console.
_CONSOLE_HEADER = [
    "Method",
    "Delay\n[ms]",
    "Analytic ZV\ndelay [ms]",
    "RV\n[m/s²]",
    "Reduction\n[%]",
    "Settled\n0.05 m/s²\n[s]",
    "Settled\n0.01 m/s²\n[s]",
    "Settled\n0.1 mm\n[s]",
    "Peak jerk\n[rad/s³]",
    "RV estimate",
]


def print_table(result: DemoResult, console: Any = None) -> None:
    """Print a Table-4-style table per motion, with the analytic ZV delay and end-pose modes."""
    from rich.console import Console
    from rich.table import Table
    from rich.text import Text

    if console is None:
        console = Console()
    if not console.is_terminal and console.width < 160:
        console.width = 160  # a log file or pipe: keep each row on one line
    for motion in result.motions:
        modes = ", ".join(
            f"{name} damped f_d {damped_frequency_hz(w, z):.2f} Hz ζ {z:.3f}"
            for name, (w, z) in zip(("base", "shoulder"), motion.true_end_modes, strict=False)
        )
        table = Table(
            title=f"{motion.motion.name}: analytic two-mode ZV delay at {motion.motion.end} "
            f"(true modes) = {1e3 * motion.analytic_zv_delay_s:.1f} ms; settle times from the "
            f"start of the move, which itself lasts {planned_move_s(motion):.3f} s (the limit)",
            caption=f"true modes at {motion.motion.end}: {modes}",
        )
        for i, name in enumerate(_CONSOLE_HEADER):
            last = len(_CONSOLE_HEADER) - 1
            table.add_column(
                Text(name), justify="left" if i in (0, last) else "right", no_wrap=i == 0
            )
        for row in table_rows(motion):
            table.add_row(*(Text(cell) for cell in row))
        console.print(table)
        console.print(recommendation(motion))
    console.print(f"simulation and analysis wall time: {result.wall_time_s:.1f} s")
