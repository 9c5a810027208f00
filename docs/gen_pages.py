"""Pages generated while the site builds (mkdocs-gen-files runs this file).

Nothing here types a result by hand: every number this file appends is computed now or read
from what `make demo` / `make bench` wrote into out/. (A page's hand-written part may record
an earlier run, under its own heading, with the command that produced it.)

- reference/cli.md: the help of every `tvist` command, from the parser itself.
- results/zero-delay.md: the zero-delay benchmark, computed now (a fraction of a second).
- results/model.md: the robot model's inertias and the paper map's modes at the test poses.
- results/{demo,flexible-payload,pick-place}.md: the report.md of each experiment in out/,
  with its figures; without one, how to produce it.
- results/identification.md: the full twin campaign's agreement with the true modes and the
  map forms' cross-validation (out/campaign_full.jsonl, out/campaign_full_cv.json).
- results/arms.md: `tvist demo --robot fr3` / `iiwa14`'s tables (out/demo-ARM/).
- guides/twin-server.md: the residual vibration of the live runs logged in out/live/.
- benchmarks.md: the output `make bench` saved in out/bench/; without it, how to produce it.
- quickstart.md: what the README's quick start printed and how long each step took, as
  `make quick-start` (tools/quick_start.py) recorded it in out/quick-start/run.json.

The hand-written part of each page stays in docs/ and this file appends to it.
"""

from __future__ import annotations

import os
import re
import sys
from datetime import datetime, timezone
from pathlib import Path

import mkdocs_gen_files

ROOT = Path(__file__).resolve().parent.parent
OUT = ROOT / "out"
TOOLS = ROOT / "tools"

#: Experiment page -> (output folder of its command, the command that writes it).
EXPERIMENTS = {
    "demo": (OUT / "demo", "make demo"),
    "flexible-payload": (
        OUT / "demo-payload",
        "tvist demo --experiment flexible-payload",
    ),
    "pick-place": (OUT / "demo-pick-place", "tvist demo --experiment pick-place"),
}

#: Files `make bench` writes into out/bench/, in the order they are shown: a title, and
#: whether the output is markdown (the cycle harness prints a table) or plain text.
BENCH_OUTPUTS = {
    "cycle.txt": ("Rust core: one control cycle (`cargo bench -p tvist-core --bench cycle`)", True),
    "robot_pass.txt": (
        "Rust core: a map's rigid-body pass (`cargo bench -p tvist-core --bench robot_pass`)",
        True,
    ),
    "modal_step.txt": (
        "Rust core: the modal map's step (`cargo bench -p tvist-core --bench modal_step`)",
        False,
    ),
    "bench_shape.txt": ("Python: `TvShaper.shape` against numpy (`benches/bench_shape.py`)", False),
    "bench_sim.txt": ("The MuJoCo twin against real time (`benches/bench_sim.py`)", False),
}

FIGURE_LINK = re.compile(r"\]\(([^)/:]+\.(?:png|svg))\)")
HEADING = re.compile(r"^(#{1,5}) ", flags=re.MULTILINE)


def missing(what: str, *commands: str) -> str:
    """The note a page shows when the output it is made from has not been produced."""
    run = ", then ".join(f"`{c}`" for c in commands)
    return (
        f'\n!!! note "Not generated yet"\n'
        f"    This part of the page is made from {what}, which this checkout does not have.\n"
        f"    Run {run} and then `make docs` to fill it in.\n"
    )


def results_row_commands(key: str) -> tuple[str, ...]:
    """The commands that write the outputs of the README results table's row ``key``
    (tools/results_table.py holds them once, for the table and for these pages)."""
    import importlib.util

    table = sys.modules.get("results_table")
    if table is None:
        spec = importlib.util.spec_from_file_location("results_table", TOOLS / "results_table.py")
        table = importlib.util.module_from_spec(spec)
        sys.modules["results_table"] = table  # its dataclasses look their module up
        spec.loader.exec_module(table)
    (row,) = (r for r in table.ROWS if r.key == key)
    return row.commands


def _written(path: Path) -> str:
    """Which output a generated part comes from, and when it was written."""
    written = datetime.fromtimestamp(path.stat().st_mtime, tz=timezone.utc)
    return f"`{path.relative_to(ROOT)}`, written {written:%Y-%m-%d %H:%M} UTC"


def cli_reference() -> str:
    """`tvist --help` and every command's help, as the parser prints them."""
    os.environ["COLUMNS"] = "100"  # argparse wraps to the terminal; fix it for the page
    from tvist.cli import build_parser

    parser = build_parser()
    (subparsers,) = (a for a in parser._actions if a.dest == "command")
    parts = ["```text", parser.format_help().rstrip(), "```"]
    for name, sub in subparsers.choices.items():
        parts += ["", f"## tvist {name}", "", "```text", sub.format_help().rstrip(), "```"]
    return "\n".join(parts) + "\n"


def zero_delay_tables() -> str:
    """The benchmark of `tvist zero-delay`, computed now (at its default --dt-s)."""
    from tvist.cli.demo import ZERO_DELAY_ROBOT
    from tvist.experiments.ztdis_benchmark import format_table, run_benchmark
    from tvist.robots import params

    dt_s = params(ZERO_DELAY_ROBOT).control_period_s
    tables = [format_table(run_benchmark(ref, dt_s=dt_s)) for ref in ("min_jerk", "trapezoid")]
    return "".join(f"\n{table.strip()}\n" for table in tables)  # markdown tables


#: Joint-axis inertias (J_0, J_1) in kg m² the paper printed for its test poses (Table 3 of
#: Thomsen et al. 2020, from Universal Robots' internal model), to compare with the model's.
PAPER_INERTIAS_KG_M2 = {"Q1": (9.73, 9.25), "Q3": (1.12, 1.58)}


def model_inertias() -> str:
    """The UR5e model's joint-axis inertias and the paper map's modes at Q1 and Q3, now."""
    import math

    import tvist
    from tvist.trajectory import PAPER_POSES

    robot = tvist.robots.ur5e(5.0, (0.0, 0.0, 0.05))
    paper_map = tvist.DynamicMap.paper_ur5e()
    rows = [
        "| pose | J_0 (tvist) | J_1 (tvist) | J_0 (paper) | J_1 (paper) "
        "| base mode, paper map | shoulder mode, paper map |",
        "|---|---|---|---|---|---|---|",
    ]
    for pose, (paper_j0, paper_j1) in PAPER_INERTIAS_KG_M2.items():
        q = PAPER_POSES[pose]
        j0, j1 = robot.joint_inertia(q)[:2]
        modes = [
            f"{wn / (2 * math.pi):.2f} Hz, ζ {zeta:.3f}" for wn, zeta in paper_map.modes(robot, q)
        ]
        rows.append(
            f"| {pose} | {j0:.2f} | {j1:.2f} | {paper_j0} | {paper_j1} | {modes[0]} | {modes[1]} |"
        )
    return "\n" + "\n".join(rows) + "\n"


def experiment_report(page: str) -> str:
    """The experiment's report.md with its figures copied beside the page."""
    folder, command = EXPERIMENTS[page]
    report = folder / "report.md"
    if not report.is_file():
        return missing(f"`{report.relative_to(ROOT)}`", command)
    text = report.read_text(encoding="utf-8")
    for name in sorted(set(FIGURE_LINK.findall(text))):
        source = folder / name
        if source.is_file():
            with mkdocs_gen_files.open(f"results/{page}/{name}", "wb") as f:
                f.write(source.read_bytes())
    text = FIGURE_LINK.sub(lambda m: f"]({page}/{m.group(1)})", text)
    text = HEADING.sub(lambda m: "#" + m.group(1) + " ", text)  # below the page's own title
    return f"\n*Generated from `{report.relative_to(ROOT)}`.*\n\n{text}"


def bench_outputs() -> str:
    """What `make bench` printed, as saved in out/bench/."""
    parts = []
    for name, (title, is_markdown) in BENCH_OUTPUTS.items():
        path = OUT / "bench" / name
        parts.append(f"\n### {title}\n")
        if not path.is_file():
            parts.append(missing(f"`out/bench/{name}`", "make bench"))
            continue
        parts.append(f"\n*{_written(path)}.*\n\n")
        text = path.read_text(encoding="utf-8").strip()
        if is_markdown:  # "#10 / #14 ..." is a line of text, not a heading
            parts.append(re.sub(r"^#", r"\\#", text, flags=re.MULTILINE) + "\n")
        else:
            parts.append(f"```text\n{text}\n```\n")
    return "".join(parts)


#: The full campaign on the twin and its cross-validation (README results table, rows
#: "campaign" and "cross-validation").
CAMPAIGN = OUT / "campaign_full.jsonl"
CROSS_VALIDATION = OUT / "campaign_full_cv.json"


def full_campaign() -> str:
    """The full twin campaign's identifications against the true modes, and the two map
    forms' cross-validation, as the campaign's and the fit's outputs hold them."""
    import json

    from tvist.ident.campaign_robots import TRUE_MODES_MAX_HZ
    from tvist.ident.modal_fit.cross_validation import format_comparison
    from tvist.ident.results_store import load_results
    from tvist.ident.true_mode_agreement import TOLERANCE, agreement, ringing_agreement

    parts = []
    if not CAMPAIGN.is_file():
        parts.append(missing(f"`{CAMPAIGN.relative_to(ROOT)}`", *results_row_commands("campaign")))
    else:
        records = load_results(CAMPAIGN)
        payloads = sorted({r["payload_kg"] for r in records})
        rows = [
            f"\n*Generated from {_written(CAMPAIGN)}: {len(records)} poses, payloads "
            + ", ".join(f"{p:g}" for p in payloads)
            + " kg.*\n",
            f"\n| joint | ω_n within {100 * TOLERANCE:g} % of the true mode | confident "
            "(not flagged) | confident and not within |",
            "|---|---|---|---|",
        ]
        for name, joint in agreement(records).items():
            share = 100 * joint.within / joint.compared
            rows.append(
                f"| {name} | {joint.within}/{joint.compared} ({share:.0f} %) | "
                f"{joint.confident} | {joint.confident_outside} |"
            )
        ringing = ringing_agreement(records, TRUE_MODES_MAX_HZ)
        rows.append(
            f"\nEvery mode the logs show (the records' `ringing` lists): {ringing.modes}, of "
            f"which {ringing.confident} confident. The records list the twin's true modes up "
            f"to {TRUE_MODES_MAX_HZ:g} Hz: of the {ringing.compared} confident modes they can "
            f"judge, {ringing.outside} lie more than {100 * TOLERANCE:g} % from every true "
            f"mode; {ringing.above_band} lie too near or above {TRUE_MODES_MAX_HZ:g} Hz to be "
            "judged (on the UR5e twin the stiff elbow's mode, which the elbow log shows)."
        )
        parts.append("\n".join(rows) + "\n")
    if not CROSS_VALIDATION.is_file():
        parts.append(
            missing(
                f"`{CROSS_VALIDATION.relative_to(ROOT)}`", *results_row_commands("cross-validation")
            )
        )
    else:
        cv = json.loads(CROSS_VALIDATION.read_text(encoding="utf-8"))
        parts.append(
            f"\n*Cross-validation, generated from {_written(CROSS_VALIDATION)}: "
            f"{cv['n_poses']} poses, {cv['folds']} folds.*\n\n{format_comparison(cv)}\n"
        )
    return "".join(parts)


#: The arms of `tvist demo --robot NAME` (docs/results/arms.md).
ARMS = ("fr3", "iiwa14")


def arm_demos() -> str:
    """`tvist demo --robot NAME`'s table and CPU times, per arm, as it wrote them."""
    import json

    parts = []
    for arm in ARMS:
        folder = OUT / f"demo-{arm}"
        table, result = folder / "table.md", folder / f"{arm}-nominal" / "result.json"
        parts.append(f"\n### {arm}\n")
        if not (table.is_file() and result.is_file()):
            parts.append(missing(f"`out/demo-{arm}/`", f"tvist demo --robot {arm}"))
            continue
        cpu = json.loads(result.read_text(encoding="utf-8")).get("cpu_time_s") or {}
        cpu_text = ", ".join(f"{k} {v:.0f}" for k, v in cpu.items())
        parts.append(
            f"\n*Generated from {_written(table)}.*\n\n"
            f"{table.read_text(encoding='utf-8').strip()}\n\nCPU time, s: {cpu_text}.\n"
        )
    return "".join(parts)


#: The live runs of the README's live row: `tvist run ... --log out/live/STEM-N.csv`.
LIVE = OUT / "live"
LIVE_RUNS = {"unshaped": "unshaped", "paper-map": "the paper's map"}


def live_runs() -> str:
    """Residual vibration of each logged live run against the twin server."""
    from tvist.live import residual_vibration

    rows = ["| run | log | residual vibration, m/s² |", "|---|---|---|"]
    written = []
    for stem, label in LIVE_RUNS.items():
        for log in sorted(LIVE.glob(f"{stem}-*.csv")):
            rows.append(f"| {label} | `{log.name}` | {residual_vibration(log):.2e} |")
            written.append(log)
    if not written:
        return missing("`out/live/*.csv`", *results_row_commands("live"))
    newest = max(written, key=lambda p: p.stat().st_mtime)
    return f"\n*Generated from the logs in `out/live/` (newest: {_written(newest)}).*\n\n" + (
        "\n".join(rows) + "\n"
    )


#: Lines of each quick-start step's output the page shows (the last ones: the results).
QUICK_START_LINES = 6


def quick_start_run() -> str:
    """The README's quick start as tools/quick_start.py ran it: each command, its time and
    the last lines it printed."""
    import json

    path = OUT / "quick-start" / "run.json"
    if not path.is_file():
        return missing("`out/quick-start/run.json`", "make quick-start")
    run = json.loads(path.read_text(encoding="utf-8"))
    parts = [
        f"\n*Generated from `out/quick-start/run.json`: commit {run['commit']}, started "
        f"{run['started_utc']} on {run['cpus']} CPUs at a load average of "
        f"{run['load_average_1min']:.1f}. The server was ready after "
        f"{run['server_ready_s']:.0f} s; the first shaped move ended "
        f"{run.get('ready_to_first_shaped_move_s', float('nan')):.0f} s later; the whole run "
        f"took {run['total_s'] / 60:.1f} min.*\n"
    ]
    for step in run["steps"]:
        shown = "\n".join(step["printed"][-QUICK_START_LINES:])
        parts.append(f"\n`{step['command']}`: {step['seconds']:.1f} s\n\n```text\n{shown}\n```\n")
    return "".join(parts)


#: Page -> what is appended to it (computed when the site builds).
APPENDED = {
    "reference/cli.md": cli_reference,
    "results/model.md": model_inertias,
    "results/zero-delay.md": zero_delay_tables,
    **{f"results/{page}.md": (lambda page=page: experiment_report(page)) for page in EXPERIMENTS},
    "results/identification.md": full_campaign,
    "results/arms.md": arm_demos,
    "guides/twin-server.md": live_runs,
    "benchmarks.md": bench_outputs,
    "quickstart.md": quick_start_run,
}
for page, generate in APPENDED.items():
    with mkdocs_gen_files.open(page, "a") as f:
        f.write(generate())
