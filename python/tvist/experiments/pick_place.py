"""A pick-and-place cycle on the twin (``tvist demo --experiment pick-place``).

Short, fast moves are where ringing is a large share of the cycle. A cobot cell's cycle here:
:data:`CYCLE`, eight joint-space moves of 0.1-0.6 rad between poses across the workspace
(:data:`CELL_POSES`, from stretched to folded, base turned 0-0.9 rad), 5 kg payload, fast
double-S profile (3 rad/s, 4 rad/s², 20 ms acceleration ramp). At each pose the tool must
be still before it grips or places, so the cycle time is the sum over the moves of the time
from the start of the move until settled (:mod:`tvist.experiments.settle`). Every move starts
from rest (the previous one has settled; what is left under the band is not carried over).

Rows: unshaped; *slow down instead* (per move the profile of the grid
:mod:`tvist.experiments.slow_down` that settles first); fixed shapers tuned per move (two-mode
ZV at its start pose; the shortest robust library shaper over its modes,
:mod:`tvist.experiments.fixed`); FD-TVIST with the identified modal map (the demo's reduced
campaign and fit, :mod:`tvist.experiments.identified`, :mod:`tvist.experiments.modal_rows`);
zero-delay shaping (ZTDIS and modified ZTDIS) with that map's modes at each end pose; and, as
an oracle reference, ZTDIS on the twin's exact end-pose modes. The limit is the sum of the
moves' own durations.
"""

from __future__ import annotations

import math
import re
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from types import MappingProxyType
from typing import Any

import numpy as np

from tvist import robots
from tvist.experiments.experiment import MotionRun, run_motion
from tvist.experiments.method_row import Method
from tvist.experiments.methods import default_methods, fd_tvist_map, zero_delay_row
from tvist.experiments.motions import DT_S, PAYLOAD_COM_M, PAYLOAD_KG, Motion
from tvist.experiments.settle import CRITERIA, SETTLE_HOLD_S, format_settle, settle_config
from tvist.experiments.slow_down import ACCEL_SCALES, JERK_TIMES_S
from tvist.sim import Twin

__all__ = [
    "CELL_POSES",
    "CYCLE",
    "CycleRow",
    "PickPlaceResult",
    "cell_moves",
    "cycle_rows",
    "run_from_args",
    "run_pick_place",
    "write_pick_place",
]

#: Wrist angles of every cell pose (the paper's test poses'), rad.
_WRIST = (-math.pi / 2, 0.0, 0.0)
#: The cell's poses: (base, shoulder, elbow) in rad, stretched (shoulder -2.8, elbow 0.6) to
#: folded (shoulder -2.4, elbow 1.4), base 0-0.9 rad.
CELL_POSES: Mapping[str, tuple[float, ...]] = MappingProxyType(
    {
        name: (*arm, *_WRIST)
        for name, arm in {
            "P0": (0.0, -2.80, 0.60),
            "P1": (0.30, -2.80, 0.60),
            "P2": (0.30, -2.50, 1.20),
            "P3": (0.80, -2.50, 1.20),
            "P4": (0.90, -2.40, 1.40),
            "P5": (0.50, -2.65, 0.95),
            "P6": (0.40, -2.75, 0.75),
            "P7": (0.10, -2.75, 0.75),
        }.items()
    }
)
#: The cycle: P0 -> P1 -> ... -> P7 -> P0; every move changes some joint by 0.1-0.6 rad.
CYCLE = ("P0", "P1", "P2", "P3", "P4", "P5", "P6", "P7", "P0")
#: The fast cobot profile of the moves: speed, acceleration, acceleration ramp.
V_MAX_RAD_S = 3.0
A_MAX_RAD_S2 = 4.0
JERK_TIME_S = 0.02
#: Rest after each move (s): every row of the cycle settles to 0.01 m/s² within 0.96 s after
#: its planned move ends (measured with a 2 s rest), and the record must show the settle
#: hold (0.2 s) after that; a move that has not settled by then is reported as such.
TAIL_S = 1.4
SPECTRUM_WINDOW_S = 1.0
#: The quick run (tests): the first two moves, a shorter tail.
QUICK_MOVES = 2
QUICK_TAIL_S = 1.2


def cell_moves(quick: bool = False) -> list[Motion]:
    """The cycle's moves (the first :data:`QUICK_MOVES` if ``quick``)."""
    moves = [
        Motion(a, b, CELL_POSES, V_MAX_RAD_S, A_MAX_RAD_S2, JERK_TIME_S)
        for a, b in zip(CYCLE[:-1], CYCLE[1:], strict=True)
    ]
    return moves[:QUICK_MOVES] if quick else moves


def pick_place_methods(dynmap: Any | None, map_name: str = "identified modal map") -> list[Method]:
    """The rows: unshaped, fixed shapers, and with ``dynmap`` (a map with
    ``modes(robot, q)``, called ``map_name`` in labels) FD-TVIST and zero-delay shaping on it;
    ZTDIS on the twin's exact end-pose modes as an oracle reference."""
    from tvist.experiments.fixed import fixed_robust_row, fixed_start_row
    from tvist.experiments.methods import fd_tvist_modal
    from tvist.maps.modal import ModalMap

    rows = [default_methods()[0], fixed_start_row(), fixed_robust_row()]
    if dynmap is not None:
        fd_row = fd_tvist_modal if isinstance(dynmap, ModalMap) else fd_tvist_map
        rows.append(fd_row("fd-tvist-map", f"FD-TVIST ZV, {map_name}", dynmap))
        for key, method, name in (
            ("ztdis-map", "ztdis", "ZTDIS"),
            ("modified-map", "modified", "Modified ZTDIS"),
        ):
            label = f"{name} ZV, {map_name} at the end pose"
            rows.append(zero_delay_row(key, label, method, None, dynmap))
    rows.append(zero_delay_row("ztdis", "ZTDIS ZV, true end-pose modes", "ztdis", None))
    return rows


@dataclass(frozen=True)
class CycleRow:
    """One method over the whole cycle.

    Attributes
    ----------
    key, label
        The row (``"slow-down"`` for the best slow-down profile per move).
    oracle
        Why a user cannot run it, or ``None``.
    per_move_s
        Per criterion key: the settle time of every move (``None``: not settled).
    """

    key: str
    label: str
    oracle: str | None
    per_move_s: dict[str, list[float | None]]

    def total_s(self, key: str) -> float | None:
        """Cycle time to settled by criterion ``key``: the sum over the moves, ``None`` if a
        move has not settled."""
        times = self.per_move_s[key]
        return None if any(t is None for t in times) else float(sum(times))

    def to_json(self) -> dict[str, Any]:
        return {
            "label": self.label,
            "oracle": self.oracle,
            "per_move_settle_s": self.per_move_s,
            "cycle_s": {c.key: self.total_s(c.key) for c in CRITERIA},
        }


def cycle_rows(moves: Sequence[MotionRun]) -> list[CycleRow]:
    """The cycle per row, from each move's measured settle times; the slow-down row takes per
    move and criterion the profile that settled first."""
    keys = [r.method.key for r in moves[0].runs]
    rows = []
    for key in keys:
        runs = [m.run(key) for m in moves]
        per_move = {c.key: [r.settle.get(c.key) for r in runs] for c in CRITERIA}
        method = runs[0].method
        rows.append(CycleRow(key, method.label, method.oracle, per_move))
    if all(m.slow_down is not None for m in moves):
        per_move = {}
        for c in CRITERIA:
            best = [m.slow_down.best(c.key) for m in moves]
            per_move[c.key] = [None if b is None else b.settle.get(c.key) for b in best]
        rows.insert(
            1, CycleRow("slow-down", "Slow down instead (best profile per move)", None, per_move)
        )
    return rows


@dataclass(frozen=True)
class PickPlaceResult:
    """The cycle: every move's runs, the rows over the cycle, settings and wall time."""

    moves: list[MotionRun]
    rows: list[CycleRow]
    config: dict[str, Any]
    wall_time_s: float
    identification: dict[str, Any] | None = None

    @property
    def limit_s(self) -> float:
        """The sum of the moves' own durations: the cycle no shaper can beat, s."""
        return float(sum(m.runs[0].settle.move_s for m in self.moves))

    def row(self, key: str) -> CycleRow:
        for r in self.rows:
            if r.key == key:
                return r
        raise KeyError(key)

    def to_json(self) -> dict[str, Any]:
        return {
            "config": self.config,
            "wall_time_s": self.wall_time_s,
            "cycle_limit_s": self.limit_s,
            "moves": {m.motion.name: m.to_json() for m in self.moves},
            "cycle": {r.key: r.to_json() for r in self.rows},
            **({} if self.identification is None else {"identified_map": self.identification}),
        }


def run_pick_place(
    *,
    quick: bool = False,
    dynmap: Any | None = None,
    map_name: str = "identified modal map",
    log: Any = None,
    with_slow_down: bool = True,
) -> PickPlaceResult:
    """Run the cycle on the twin without writing anything.

    Parameters
    ----------
    quick
        The first :data:`QUICK_MOVES` moves with a shorter tail (tests).
    dynmap
        The map of the FD-TVIST and zero-delay rows (any map with ``modes(robot, q)``);
        ``None`` leaves those rows out.
    map_name
        How the rows name ``dynmap``.
    log
        Optional ``log(text)`` for progress lines.
    with_slow_down
        Run the slow-down grid on every move.
    """
    start = time.perf_counter()
    rows = pick_place_methods(dynmap, map_name)
    twin = Twin("ur5e", payload_kg=PAYLOAD_KG, payload_com_m=PAYLOAD_COM_M)
    robot = robots.ur5e(payload_kg=PAYLOAD_KG, payload_com_m=PAYLOAD_COM_M)
    tail_s = QUICK_TAIL_S if quick else TAIL_S
    window_s = min(SPECTRUM_WINDOW_S, tail_s - 0.2)
    moves = [
        run_motion(
            move,
            rows,
            twin,
            robot,
            tail_s=tail_s,
            spectrum_window_s=window_s,
            log=log,
            with_slow_down=with_slow_down,
        )
        for move in cell_moves(quick)
    ]
    config = {
        "robot": "ur5e",
        "payload_kg": PAYLOAD_KG,
        "payload_com_m": list(PAYLOAD_COM_M),
        "dt_s": DT_S,
        "profile": {
            "v_max_rad_s": V_MAX_RAD_S,
            "a_max_rad_s2": A_MAX_RAD_S2,
            "jerk_time_s": JERK_TIME_S,
        },
        "poses_rad": {k: list(v) for k, v in CELL_POSES.items()},
        "cycle": [m.motion.name for m in moves],
        "tail_s": tail_s,
        "quick": quick,
        "settle_criteria": settle_config(),
        "slow_down_grid": {"jerk_times_s": list(JERK_TIMES_S), "accel_scales": list(ACCEL_SCALES)}
        if with_slow_down
        else None,
        "methods": {m.key: m.label for m in rows},
    }
    return PickPlaceResult(
        moves=moves,
        rows=cycle_rows(moves),
        config=config,
        wall_time_s=time.perf_counter() - start,
    )


def _total_text(row: CycleRow, key: str, limit_s: float) -> str:
    total = row.total_s(key)
    if total is None:
        n = sum(t is None for t in row.per_move_s[key])
        return f"not settled ({n} move{'s' if n > 1 else ''})"
    return f"{total:.3f} ({100 * (total / limit_s - 1):+.0f} %)"


def _table(result: PickPlaceResult) -> tuple[list[str], list[list[str]]]:
    header = ["method", *[f"cycle to settled, {c.text} [s]" for c in CRITERIA]]
    rows = [
        [
            r.label + (" (oracle)" if r.oracle else ""),
            *[_total_text(r, c.key, result.limit_s) for c in CRITERIA],
        ]
        for r in result.rows
    ]
    rows.append(["the moves themselves (the limit)", *[f"{result.limit_s:.3f}"] * len(CRITERIA)])
    return header, rows


def fastest_runnable(result: PickPlaceResult, key: str = CRITERIA[0].key) -> CycleRow | None:
    """The runnable row (no oracle) with the shortest cycle by criterion ``key``."""
    done = [r for r in result.rows if r.oracle is None and r.total_s(key) is not None]
    return min(done, key=lambda r: r.total_s(key)) if done else None


def findings(result: PickPlaceResult) -> list[str]:
    """Statements computed from the numbers."""
    out = []
    for c in CRITERIA:
        best = fastest_runnable(result, c.key)
        if best is None:
            out.append(f"{c.text}: no runnable row settles on every move.")
            continue
        parts = [f"{c.text}: fastest runnable cycle **{best.label}**, {best.total_s(c.key):.3f} s"]
        for ref_key, ref_name in (("unshaped", "unshaped"), ("slow-down", "the best slow-down")):
            try:
                ref = result.row(ref_key).total_s(c.key)
            except KeyError:
                continue
            if ref is not None and best.key != ref_key:
                saved = 100 * (1 - best.total_s(c.key) / ref)
                parts.append(f"{saved:.0f} % shorter than {ref_name} ({ref:.3f} s)")
        over = 100 * (best.total_s(c.key) / result.limit_s - 1)
        parts.append(f"{over:+.0f} % against the moves' own {result.limit_s:.3f} s")
        out.append("; ".join(parts) + ".")
    return out


def plot_cycle(result: PickPlaceResult, path: Path, key: str = CRITERIA[0].key) -> Path:
    """The cycle on a time line: per row, each planned move (dark) and the time after it until
    settled (light); a shaped reference moves on during part of the light segment."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    criterion = next(c for c in CRITERIA if c.key == key)
    rows = result.rows
    fig, ax = plt.subplots(figsize=(11, 0.55 * len(rows) + 1.6))
    moves_s = [m.runs[0].settle.move_s for m in result.moves]
    slow_moves = {}
    if any(r.key == "slow-down" for r in rows):
        slow_moves = {
            i: (m.slow_down.best(key).settle.move_s if m.slow_down.best(key) else None)
            for i, m in enumerate(result.moves)
        }
    colors = plt.get_cmap("tab10")
    for y, row in enumerate(reversed(rows)):
        t = 0.0
        for i, settle in enumerate(row.per_move_s[key]):
            move = slow_moves.get(i) if row.key == "slow-down" else moves_s[i]
            if settle is None or move is None:
                ax.text(t, y, "  not settled", va="center", fontsize=8)
                break
            color = colors(i % 10)
            ax.broken_barh([(t, min(move, settle))], (y - 0.3, 0.6), color=color, alpha=0.9)
            if settle > move:
                ax.broken_barh([(t + move, settle - move)], (y - 0.3, 0.6), color=color, alpha=0.3)
            t += settle
        else:
            ax.text(t + 0.03, y, f"{t:.2f} s", va="center", fontsize=8)
    ax.axvline(result.limit_s, color="k", ls="--", lw=1)
    ax.text(result.limit_s, len(rows) - 0.4, " moves alone", fontsize=8)
    ax.set_yticks(range(len(rows)))
    ax.set_yticklabels(
        [r.label + (" (oracle)" if r.oracle else "") for r in reversed(rows)], fontsize=8
    )
    ax.set_xlabel("time [s]")
    ax.set_title(
        f"Pick-and-place cycle, {len(result.moves)} moves, 5 kg: each planned move (dark) and "
        f"the time after it until {criterion.text} (light)",
        fontsize=10,
    )
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def write_pick_place(result: PickPlaceResult, out_dir: str | Path) -> dict[str, Any]:
    """Write ``results.json``, ``report.md`` and ``cycle.png`` to ``out_dir``."""
    from tvist.experiments.results_json import write_document
    from tvist.experiments.table import markdown_table

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    results = write_document(result.to_json(), out / "results.json")
    figure = plot_cycle(result, out / "cycle.png")
    header, rows = _table(result)
    per_move_header = ["move", "move [s]", *[r.label for r in result.rows]]
    key = CRITERIA[0].key
    per_move = []
    for i, m in enumerate(result.moves):
        delta = np.abs(m.motion.q_end - m.motion.q_start)
        per_move.append(
            [
                f"{m.motion.start} → {m.motion.end} ({delta.max():.2f} rad)",
                f"{m.runs[0].settle.move_s:.3f}",
                *[format_settle(r.per_move_s[key][i]) for r in result.rows],
            ]
        )
    lines = [
        "# Pick-and-place cycle on the simulated UR5e",
        "",
        re.sub(r":\w+:`~?([^`]*)`", r"`\1`", __doc__.split("\n\n", 1)[1].strip()),
        "",
        f"Settled: from the start of each move until the tool stays in the band for good (the "
        f"record must show {SETTLE_HOLD_S:g} s inside it). Slow-down grid: acceleration ramps "
        f"{', '.join(f'{1e3 * j:g}' for j in JERK_TIMES_S)} ms × acceleration "
        f"×{', ×'.join(f'{a:g}' for a in ACCEL_SCALES)} (speed limit unchanged), every profile "
        "simulated. Rows marked *(oracle)* read what only the twin knows.",
        "",
        f"Wall time: {result.wall_time_s:.1f} s"
        + (" (quick run)." if result.config["quick"] else "."),
        "",
        "## Cycle time to settled",
        "",
        markdown_table(header, rows),
        "",
        *[f"- {line}" for line in findings(result)],
        "",
        f"## Per move, settled to {CRITERIA[0].text} [s]",
        "",
        markdown_table(per_move_header, per_move),
        "",
        f"![cycle]({figure.name})",
        "",
    ]
    report = out / "report.md"
    report.write_text("\n".join(lines), encoding="utf-8")
    return {"results": results, "report": report, "figures": [figure]}


def run_from_args(args: Any) -> int:
    """``tvist demo --experiment pick-place``: identify the map (the demo's reduced campaign,
    cached in the output folder), run the cycle, print the table, write the report."""
    from rich.console import Console
    from rich.table import Table

    from tvist.experiments.identified import DEMO_PLAN, QUICK_PLAN, identify_map
    from tvist.experiments.modal_rows import identify_modal_map

    console = Console()
    if not console.is_terminal and console.width < 160:
        console.width = 160
    start = time.perf_counter()
    out = Path(args.out or "out/demo-pick-place")
    dynmap, identification = None, None
    if args.identify:
        plan = QUICK_PLAN if args.quick else DEMO_PLAN
        console.print(
            f"identifying a modal map on the twin (reduced campaign, {plan.n_poses} poses) ..."
        )
        identified = identify_map(out, plan=plan, log=console.print)
        identification = identified.summary
        if identified.records:
            row, summary = identify_modal_map(identified.records, out, console.print)
            identification = {**identification, "modal_map": summary}
            if row is not None:
                dynmap = row.dynmap
    result = run_pick_place(quick=args.quick, dynmap=dynmap, log=console.print)
    from dataclasses import replace

    result = replace(result, identification=identification, wall_time_s=time.perf_counter() - start)
    outputs = write_pick_place(result, out)
    header, rows = _table(result)
    table = Table(title=f"pick-and-place cycle, {len(result.moves)} moves, 5 kg")
    for name in header:
        table.add_column(name)
    for row in rows:
        table.add_row(*row)
    console.print(table)
    for line in findings(result):
        console.print(f"- {line}")
    console.print(
        f"wrote {outputs['results']}, {outputs['report']} and {outputs['figures'][0]} "
        f"(total {time.perf_counter() - start:.1f} s)"
    )
    return 0
