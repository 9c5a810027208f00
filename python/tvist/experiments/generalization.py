"""Identification, modal map and shaping on arms tvist has never seen: one variant of the
family (:mod:`tvist.sim.family`) after another, each measured as a user would meet it.

Per variant ``family:<robot>:<seed>``:

1. **Campaign logs**: the plan (:func:`tvist.ident.pose_plan.plan_poses`, which covers the
   workspace's inertias and, as a user gives the poses where their moves stop with ``tvist
   campaign --at``, identifies at the demo's move poses) run on the variant's twin, the
   base, shoulder and elbow excitation of each pose
   (:func:`~tvist.ident.excited.default_excited_joints`) written as ur_rtde CSV logs
   (``<pose>_joint<j>.csv``, one folder per payload; a rerun keeps the logs already written).
2. **Through the CLI** (subprocesses, as a user types them): ``tvist identify`` of each
   payload's logs, then ``tvist fit-map --kind modal``.
3. **Map against the truth** at :data:`EVALUATION_POSES` workspace poses drawn from a stream
   of their own (:func:`evaluation_poses`: not the campaign's poses), with the demo's payload:
   each shaped mode of the map against the variant's true mode of the same name
   (:func:`matching_true_modes`), RMS and largest relative frequency error. The naming is
   the map's own rule applied to the true modes, and one to one (no true mode stands for two
   of the map's modes): a ``shaped_modes: K`` map's ``k``-th lowest mode against the
   ``k``-th lowest true mode; a ``mode_joints`` map's slots in order, each against the true
   mode not taken by an earlier slot that stores the largest share of its strain energy in
   the slot's joint.
4. **The demo's three moves** (:func:`tvist.experiments.motions.demo_motions` of the robot) on the
   variant's twin: unshaped, shaped with the identified map (the demo's modal row: time
   varying, or its stop's modes held where the map predicts less ringing so, marked "held"
   in the table), the identified map's modes at the end pose held over the move, and the ceiling:
   ZV on every true mode below :data:`TRUE_MODE_MAX_HZ` at the end pose; residual vibration
   reduction of each, the shaped move's delay against ZV's analytic delay of the modes it
   shapes.
5. **Wrong and confident**: identifications not flagged low-confidence that lie more than
   :data:`WRONG_TOLERANCE` from every true mode of the pose (:func:`wrong_confident`).

Each variant's result is a JSON file (``<robot>-<seed>/result.json``; a rerun with the same
settings skips finished variants) and ``table.md`` lists them all::

    python -m tvist.experiments.generalization --robot ur5e --seeds 0-4 --out out/generalization

``--seeds nominal`` runs the robot's default twin instead (any robot with a default twin,
e.g. ``--robot fr3``; ``tvist demo --robot fr3`` does this).

At most :data:`MAX_WORKERS` variants run at once, one process each (the CLI steps of a
variant run one after the other in its own process).
"""

from __future__ import annotations

import argparse
import json
import math
import subprocess
import sys
import time
from collections.abc import Mapping, Sequence
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np

from tvist.cli.plan import excited_from_args
from tvist.ident.excited import excited_joints as checked_joints

__all__ = [
    "EVALUATION_POSES",
    "HarnessSettings",
    "FLOOR",
    "Floor",
    "evaluation_poses",
    "floor_misses",
    "floor_summary",
    "frequency_errors",
    "main",
    "map_vs_truth",
    "matching_true_modes",
    "parse_seeds",
    "run_variant",
    "shaped_mode_names",
    "table_markdown",
    "wrong_confident",
]

#: Workspace poses at which each map is compared with its variant's true modes.
EVALUATION_POSES = 20
#: Random stream of the evaluation poses (:func:`tvist.ident.pose_plan.workspace_poses`),
#: apart from the plan's.
EVALUATION_STREAM = 4_000_000
#: The ceiling shapes every true mode below this frequency (Hz).
TRUE_MODE_MAX_HZ = 60.0
#: An identification farther than this (relative, natural frequency) from every true mode
#: of its pose is wrong.
WRONG_TOLERANCE = 0.03
#: True modes an identification may match: up to this frequency (Hz), so that a correct
#: identification of a mode just above :data:`TRUE_MODE_MAX_HZ` does not count as wrong.
MATCH_MAX_HZ = 2 * TRUE_MODE_MAX_HZ
#: Variants running at once (processes).
MAX_WORKERS = 2
RESULT_FILE = "result.json"
TABLE_FILE = "table.md"


@dataclass(frozen=True)
class Floor:
    """The acceptance floor each variant is held against.

    Attributes
    ----------
    map_rms_percent, map_max_percent
        Largest RMS and largest single-pose error of each shaped mode's frequency against
        the variant's true mode (:func:`map_vs_truth`), %.
    reduction_percent
        Least reduction of residual vibration of each of the demo's moves, %.
    delay_samples
        Largest ``|delay − ZV's analytic delay of the modes shaped|``, control samples.
    wrong_confident
        Most confident identifications farther than :data:`WRONG_TOLERANCE` from every true
        mode (:func:`wrong_confident`).
    """

    map_rms_percent: float = 3.0
    map_max_percent: float = 8.0
    reduction_percent: float = 99.0
    delay_samples: float = 1.0
    wrong_confident: int = 0


FLOOR = Floor()


@dataclass(frozen=True)
class HarnessSettings:
    """What a variant's result depends on besides its seed (kept in its JSON; a result made
    with other settings is recomputed).

    Attributes
    ----------
    robot
        Robot of the family.
    payloads_kg
        Payloads of the plan, kg (centre of mass :data:`~tvist.experiments.motions.PAYLOAD_COM_M`).
    every
        Every ``every``-th of Algorithm 1's poses (the workspace coverage is added to them).
    duration_s
        Excitation length per joint, s.
    accel_noise_std_m_s2
        The twin's accelerometer noise during the campaign.
    plan_seed
        Seed of the plan (wrists, excitations, noise).
    excited_joints
        Joints excited at every pose (:func:`~tvist.ident.excited.excited_joints`; ``None``:
        the robot's base, shoulder and elbow,
        :func:`~tvist.ident.excited.default_excited_joints`). The logs
        folder is shared by reruns: give another ``--out`` for other joints.
    at_move_poses
        Whether the plan identifies at the demo's move poses ``Q1``-``Q3`` too (``tvist
        campaign --at``, as a user gives the poses where their moves stop; every payload).
    """

    robot: str = "ur5e"
    # Cost: 20 variants ran in about 40 minutes on 2 cores with base and shoulder excited.
    # Half of the variants bend their links and need the 0.125 ms physics step (about 1.2 s
    # of CPU per simulated second); every 8th pose of Algorithm 1 with the workspace's
    # extreme poses, two payloads (the modal fit needs two to tell load from inertia) and 4 s
    # excitations are ~23 poses, ~230 simulated seconds per variant with two joints, half
    # again with the elbow (the default, for the modal fit's elbow-dominated modes).
    payloads_kg: tuple[float, ...] = (0.0, 5.0)
    every: int = 8
    duration_s: float = 4.0
    accel_noise_std_m_s2: float = 0.05
    plan_seed: int = 0
    excited_joints: tuple[int, ...] | None = None
    at_move_poses: bool = True

    def __post_init__(self) -> None:
        object.__setattr__(self, "excited_joints", checked_joints(self.excited_joints, self.robot))

    def plan(self) -> list:
        """The campaign poses (payloads above the robot's rated one are left out)."""
        from tvist.experiments.motions import PAYLOAD_COM_M, demo_poses
        from tvist.ident.pose_plan import plan_poses
        from tvist.robots import params

        rated = params(self.robot).max_payload_kg
        payloads = tuple(min(m, rated) for m in self.payloads_kg)
        at_q = np.array(list(demo_poses(self.robot).values())) if self.at_move_poses else None
        return plan_poses(
            self.robot,
            payloads_kg=tuple(dict.fromkeys(payloads)),
            payload_com_m=PAYLOAD_COM_M,
            every=self.every,
            seed=self.plan_seed,
            at_q=at_q,
        )


# --------------------------------------------------------------------------- pieces


def parse_seeds(text: str) -> list[int | None]:
    """``"0-4"``, ``"3"``, ``"0-2,7,9-10"`` → the seeds, in order, each once; ``"nominal"``
    → ``[None]``, the robot's default twin (:func:`tvist.sim.family.nominal_variant`).

    Raises
    ------
    ValueError
        Not such a list of non-negative integers, or a range that runs backwards.
    """
    from tvist.sim.family import NOMINAL

    if text.strip() == NOMINAL:
        return [None]
    seeds: list[int | None] = []
    for part in text.split(","):
        lo, sep, hi = part.strip().partition("-")
        if not lo.isdigit() or (sep and not hi.isdigit()):
            raise ValueError(f"--seeds {text!r}: give seeds like 0-4 or 0,3,7-9")
        first, last = int(lo), int(hi) if sep else int(lo)
        if last < first:
            raise ValueError(f"--seeds {text!r}: the range {part} runs backwards")
        seeds.extend(s for s in range(first, last + 1) if s not in seeds)
    return seeds


def evaluation_poses(robot: str, seed: int | None, n: int = EVALUATION_POSES) -> np.ndarray:
    """``n`` workspace poses ``(n, 6)`` (rad) for variant ``seed``: the plan's workspace
    (:func:`~tvist.ident.pose_plan.workspace_poses`), drawn from :data:`EVALUATION_STREAM`,
    so none is a campaign pose."""
    from tvist.ident.pose_plan import workspace_poses

    return workspace_poses(robot, n, seed=seed or 0, stream=EVALUATION_STREAM)


def shaped_mode_names(map_document: Mapping[str, Any]) -> list[tuple[str, int]]:
    """How a modal map file names its shaped modes: ``[("joint", j), ...]`` for
    ``mode_joints`` (mode ``m`` is the eigenmode most in joint ``j``), ``[("rank", k), ...]``
    for ``shaped_modes: K`` (the ``k``-th lowest eigenmode, ``k = 0 … K-1``)."""
    if "shaped_modes" in map_document:
        return [("rank", k) for k in range(int(map_document["shaped_modes"]))]
    return [("joint", int(j)) for j in map_document.get("mode_joints", (0, 1))]


def matching_true_modes(names: Sequence[tuple[str, int]], true_modes: Sequence) -> list:
    """For each shaped mode name (:func:`shaped_mode_names`) the true mode it stands for,
    by the map's own rule, one to one: slot by slot in the map's order, the true mode not
    already taken by an earlier slot that stores the largest share of its strain energy in
    joint ``j`` (where one true mode strains both base and shoulder most, the shoulder takes
    the next one, as the map's slots do: ``modal_map.rs``), or the ``k``-th lowest true mode.
    ``None`` where no true mode is left. Each item of ``true_modes`` (lowest first) has
    ``freq_hz`` and ``joint_shares`` (:class:`tvist.sim.family.TrueMode`)."""
    out = []
    taken: set[int] = set()
    for kind, index in names:
        if kind == "joint":
            free = [i for i in range(len(true_modes)) if i not in taken]
            shares = [float(true_modes[i].joint_shares[index]) for i in free]
            pick = free[int(np.argmax(shares))] if free else None
        else:
            pick = index if index < len(true_modes) and index not in taken else None
        if pick is not None:
            taken.add(pick)
        out.append(None if pick is None else true_modes[pick])
    return out


def frequency_errors(predicted_hz: np.ndarray, true_hz: np.ndarray) -> list[dict[str, float]]:
    """Per mode (columns of ``(n_poses, n_modes)`` arrays): RMS and largest ``|f / f_true −
    1|`` over the poses, in %, and the number of poses compared (NaN entries are left
    out)."""
    rel = np.asarray(predicted_hz, dtype=float) / np.asarray(true_hz, dtype=float) - 1.0
    out = []
    for column in rel.T:
        column = column[np.isfinite(column)]
        if column.size == 0:
            out.append({"rms_percent": math.nan, "max_percent": math.nan, "n_poses": 0})
            continue
        out.append(
            {
                "rms_percent": float(100 * np.sqrt(np.mean(column**2))),
                "max_percent": float(100 * np.max(np.abs(column))),
                "n_poses": int(column.size),
            }
        )
    return out


def _confident_identifications(record: Mapping[str, Any]) -> list[dict[str, Any]]:
    """Every identified mode of a pose record not flagged low-confidence: its ``modes`` and,
    where the record has them, its ``ringing`` modes (one entry per log and frequency)."""
    found: dict[tuple[int, float], dict[str, Any]] = {}
    for source, joint_key in (("modes", "joint"), ("ringing", "log_joint")):
        for mode in record.get(source) or []:
            if "wn_rad_s" not in mode or mode.get("low_confidence", True):
                continue
            joint = int(mode.get(joint_key, -1))
            found.setdefault(
                (joint, round(float(mode["wn_rad_s"]), 6)),
                {"log_joint": joint, "wn_rad_s": float(mode["wn_rad_s"]), "source": source},
            )
    return list(found.values())


def wrong_confident(
    records: Sequence[Mapping[str, Any]],
    true_hz: Mapping[str, Sequence[float]],
    tolerance: float = WRONG_TOLERANCE,
) -> list[dict[str, Any]]:
    """Confident identifications (:func:`_confident_identifications`) farther than
    ``tolerance`` (relative) from every true natural frequency of their pose;
    ``true_hz[key]`` lists the pose's true modes (Hz)."""
    wrong = []
    for record in records:
        truth = np.asarray(true_hz.get(record["key"], ()), dtype=float)
        for mode in _confident_identifications(record):
            f_hz = mode["wn_rad_s"] / (2 * math.pi)
            nearest = float(np.min(np.abs(f_hz / truth - 1.0))) if truth.size else math.inf
            if nearest > tolerance:
                wrong.append({"key": record["key"], **mode, "nearest_percent": 100 * nearest})
    return wrong


def floor_misses(result: Mapping[str, Any], floor: Floor = FLOOR) -> list[str]:
    """The lines of ``floor`` a variant's result (:func:`run_variant`) misses, one short
    text each (``"mode 3 RMS 5.83 %"``, ``"Q3->Q1 98.73 %"``); empty where it meets every
    line. A shaped mode without a true mode to compare, or a move the twin refused, is a
    miss: what cannot be checked is not met. A failed variant misses ``["failed"]``."""
    if "error" in result:
        return ["failed"]
    misses = []
    for mode in result["map_vs_truth"]["modes"]:
        rms, largest = mode["rms_percent"], mode["max_percent"]
        if not (math.isfinite(rms) and math.isfinite(largest)):
            misses.append(f"{mode['name']} not compared (no true mode)")
            continue
        if rms > floor.map_rms_percent:
            misses.append(f"{mode['name']} RMS {rms:.2f} %")
        if largest > floor.map_max_percent:
            misses.append(f"{mode['name']} max {largest:.2f} %")
    for name, move in result["moves"].items():
        identified = move["identified"]
        if "error" in identified:
            misses.append(f"{name} refused")
            continue
        if identified["reduction_percent"] < floor.reduction_percent:
            misses.append(f"{name} {identified['reduction_percent']:.2f} %")
        off = identified["delay_minus_zv_samples"]
        if abs(off) > floor.delay_samples:
            misses.append(f"{name} delay {off:+.2f} samples from ZV's")
    wrong = int(result["wrong_confident"]["count"])
    if wrong > floor.wrong_confident:
        misses.append(f"{wrong} wrong & confident")
    return misses


def floor_summary(results: Sequence[Mapping[str, Any]], floor: Floor = FLOOR) -> dict[str, Any]:
    """Counts over the variants: moves at or above ``floor.reduction_percent`` of all moves
    run (a move refused, or of a failed variant, counts as below), the least reduction,
    variants meeting every line, confident identifications that are wrong."""
    from tvist.experiments.motions import MOTIONS

    reductions = []
    for r in results:
        if "error" in r:
            reductions += [math.nan] * len(MOTIONS)  # every robot's demo has these moves
            continue
        reductions += [
            m["identified"].get("reduction_percent", math.nan) for m in r["moves"].values()
        ]
    done = [r for r in results if "error" not in r]
    return {
        "variants": len(results),
        "meeting_every_line": sum(not floor_misses(r, floor) for r in results),
        "moves": len(reductions),
        "moves_at_floor": sum(
            1 for x in reductions if math.isfinite(x) and x >= floor.reduction_percent
        ),
        "least_reduction_percent": min(
            (x for x in reductions if math.isfinite(x)), default=math.nan
        ),
        "wrong_confident": sum(int(r["wrong_confident"]["count"]) for r in done),
        "failed": len(results) - len(done),
    }


# --------------------------------------------------------------------------- table


def _cell(value: float | None, digits: int = 1) -> str:
    if value is None or not math.isfinite(value):
        return "–"
    return f"{value:.{digits}f}"


def table_markdown(results: Sequence[Mapping[str, Any]]) -> str:
    """The markdown table of variant results (:func:`run_variant`), one row per variant."""
    from tvist.experiments.motions import MOTIONS

    names = [m.name for m in MOTIONS]  # every robot's demo moves have these names
    header = (
        "| variant | map frequency error RMS / max, %, per shaped mode | "
        + " | ".join(f"{n} reduction % (ceiling)" for n in names)
        + " | modes shaped | delay − ZV delay, samples (worst) | wrong & confident"
        + " | misses the floor |"
    )
    lines = [header, "|" + "---|" * (6 + len(names))]
    for r in results:
        if "error" in r:
            lines.append(
                f"| {r['variant']} | failed: {r['error']} |" + " |" * (3 + len(names)) + " failed |"
            )
            continue
        cells = [
            r["variant"],
            "; ".join(
                f"{e['name']}: {_cell(e['rms_percent'], 2)} / {_cell(e['max_percent'], 2)}"
                for e in r["map_vs_truth"]["modes"]
            ),
        ]
        for name in names:
            move = r["moves"][name]
            identified = move["identified"]
            tv = "refused" if "error" in identified else _cell(identified["reduction_percent"], 2)
            if identified.get("held_at_end_pose"):
                tv += " held"  # the stop pose's modes held over the move
            end_pose = move.get("end_pose_map")
            fixed = (
                ""
                if end_pose is None
                else f", end-pose map {_cell(end_pose['reduction_percent'], 2)}"
            )
            cells.append(f"{tv} ({_cell(move['ceiling']['reduction_percent'], 2)}{fixed})")
        shaped = sorted({m["identified"]["modes_shaped"] for m in r["moves"].values()})
        cells.append("/".join(str(k) for k in shaped))
        delays = [
            abs(m["identified"]["delay_minus_zv_samples"])
            for m in r["moves"].values()
            if "delay_minus_zv_samples" in m["identified"]
        ]
        cells.append(_cell(max(delays), 2) if delays else "–")
        cells.append(str(r["wrong_confident"]["count"]))
        cells.append("; ".join(floor_misses(r)) or "none")
        lines.append("| " + " | ".join(cells) + " |")
    summary = floor_summary(results)
    lines.append("")
    lines.append(
        f"Moves at {FLOOR.reduction_percent:g} % or more: {summary['moves_at_floor']} of "
        f"{summary['moves']} (least {_cell(summary['least_reduction_percent'], 2)} %); variants "
        f"meeting every line of the floor: {summary['meeting_every_line']} of "
        f"{summary['variants']}."
    )
    return "\n".join(lines) + "\n"


# --------------------------------------------------------------------------- one variant


def _cli(*args: str, log: Path) -> None:
    """``tvist ARGS`` in a subprocess (its output appended to ``log``).

    Raises
    ------
    RuntimeError
        The command failed; with its last line of error output.
    """
    command = [sys.executable, "-m", "tvist.cli", *args]
    done = subprocess.run(command, capture_output=True, text=True, check=False)
    with log.open("a", encoding="utf-8") as fh:
        fh.write(f"$ tvist {' '.join(args)}\n{done.stdout}{done.stderr}\n")
    if done.returncode != 0:
        last = (done.stderr.strip().splitlines() or ["(no output)"])[-1]
        raise RuntimeError(f"tvist {args[0]} exited with {done.returncode}: {last}")


def _write_logs(variant: str, settings: HarnessSettings, poses: Sequence, folder: Path) -> int:
    """Each excitation of ``poses`` on the variant's twin as a ur_rtde CSV log in
    ``folder/payload-<kg>kg/``; logs already there are kept. Returns the number written."""
    from tvist.ident.campaign_robots import TwinRobot
    from tvist.ident.pose_plan import campaign_order, pose_excitations

    robot = TwinRobot(
        settings.robot,
        settings.accel_noise_std_m_s2,
        seed=settings.plan_seed,
        variant=variant,
    )
    written = 0
    for pose in campaign_order([p for p in poses if p.q is not None]):
        target = folder / f"payload-{pose.payload_kg:g}kg"
        target.mkdir(parents=True, exist_ok=True)
        for excitation in pose_excitations(
            pose, settings.duration_s, settings.excited_joints, robot_name=settings.robot
        ):
            path = target / f"{pose.key}_joint{excitation.joint}.csv"
            if path.exists():
                continue
            robot.set_payload(pose.payload_kg, pose.payload_com_m)
            record = robot.record_excitation(excitation)
            partial = path.with_suffix(".part")
            record.to_csv(partial, "ur_rtde")
            partial.replace(path)
            written += 1
    return written


def _identify_and_fit(settings: HarnessSettings, logs: Path, folder: Path) -> Path:
    """``tvist identify`` per payload folder, the records concatenated, then ``tvist fit-map
    --kind modal``; returns the map file."""
    from tvist.experiments.motions import PAYLOAD_COM_M

    cli_log = folder / "cli.log"
    cli_log.unlink(missing_ok=True)
    records = folder / "poses.jsonl"
    lines = []
    for payload_dir in sorted(logs.glob("payload-*kg")):
        mass = payload_dir.name[len("payload-") : -len("kg")]
        out = folder / f"poses_{payload_dir.name}.jsonl"
        _cli(
            "identify",
            str(payload_dir),
            "--robot",
            settings.robot,
            "--payload-kg",
            mass,
            "--payload-com",
            *(str(v) for v in PAYLOAD_COM_M),
            "--workers",
            "1",
            "--out",
            str(out),
            log=cli_log,
        )
        lines += out.read_text(encoding="utf-8").splitlines()
    records.write_text("\n".join(lines) + "\n", encoding="utf-8")
    map_path = folder / "modal_map.json"
    _cli(
        "fit-map",
        str(records),
        "--kind",
        "modal",
        "--robot",
        settings.robot,
        "--out",
        str(map_path),
        log=cli_log,
    )
    return map_path


def map_vs_truth(variant, modal, robot, q_eval: np.ndarray) -> dict[str, Any]:
    """The shaped modes of the modal map ``modal`` (named by :func:`shaped_mode_names`)
    against the variant's true modes at ``q_eval``, with the demo's payload (``robot``)."""
    from tvist.experiments.motions import PAYLOAD_COM_M, demo_payload_kg
    from tvist.sim.family import modes_of

    names = shaped_mode_names(
        {"shaped_modes": modal.shaped_modes}
        if modal.shaped_modes is not None
        else {"mode_joints": modal.mode_joints}
    )
    twin = variant.twin(demo_payload_kg(variant.robot), PAYLOAD_COM_M)
    predicted = np.asarray(modal.modes_many(robot, q_eval))[:, :, 0] / (2 * math.pi)
    if names and names[0][0] == "rank":
        # A shaped_modes map shapes the K lowest as a set, in slots by joint: compare the
        # k-th lowest of the set with the k-th lowest true mode.
        predicted = np.sort(predicted, axis=1)
    true_hz = np.full(predicted.shape, math.nan)
    for i, q in enumerate(q_eval):
        matched = matching_true_modes(names, modes_of(twin, q, max_freq_hz=TRUE_MODE_MAX_HZ))
        for m, mode in enumerate(matched):
            if mode is not None:
                true_hz[i, m] = mode.freq_hz
    errors = frequency_errors(predicted, true_hz)
    for (kind, index), entry in zip(names, errors, strict=True):
        entry["name"] = f"joint {index}" if kind == "joint" else f"mode {index + 1}"
    return {
        "poses": q_eval.tolist(),
        "predicted_hz": predicted.tolist(),
        "true_hz": true_hz.tolist(),
        "modes": errors,
    }


def _ceiling_row():
    """ZV on every true mode of the twin below :data:`TRUE_MODE_MAX_HZ` at the end pose,
    held over the move (an oracle: it reads the twin's exact modes)."""
    import tvist
    from tvist.experiments.method_row import Method
    from tvist.experiments.methods import TVIST_SHAPER, _run_tv_shaper
    from tvist.sim.family import modes_of

    def build(ctx):
        modes = modes_of(ctx.twin, ctx.motion.q_end, max_freq_hz=TRUE_MODE_MAX_HZ)
        constant = tvist.ConstantModes([(2 * math.pi * m.freq_hz, m.zeta) for m in modes])
        shaper = tvist.TvShaper(
            constant, ctx.trajectory.dt_s, ctx.trajectory.n_dof, shaper=TVIST_SHAPER
        )
        return _run_tv_shaper(shaper, ctx, "true modes below 60 Hz at the end pose")

    return Method(
        key="ceiling",
        label=f"ZV on every true mode below {TRUE_MODE_MAX_HZ:g} Hz at the end pose",
        build=build,
        oracle="reads the twin's exact modes",
    )


def _end_pose_map_row(modal):
    """ZV on the map's shaped modes at the end pose, held over the move: the identified map
    without time variation (what the map gives where its time-varying path cannot run)."""
    import tvist
    from tvist.experiments.method_row import Method
    from tvist.experiments.methods import TVIST_SHAPER, _run_tv_shaper

    def build(ctx):
        modes = [tuple(m) for m in modal.modes(ctx.robot, ctx.motion.q_end)]
        constant = tvist.ConstantModes(modes)
        shaper = tvist.TvShaper(
            constant, ctx.trajectory.dt_s, ctx.trajectory.n_dof, shaper=TVIST_SHAPER
        )
        return _run_tv_shaper(shaper, ctx, "identified map's modes at the end pose")

    return Method(
        key="end-pose",
        label="ZV on the identified map's modes at the end pose",
        build=build,
    )


def _moves(variant, map_path: Path, robot) -> dict[str, Any]:
    """The demo's three moves on the variant's twin: unshaped, identified map, ceiling; and
    the identified map's end-pose modes held over the move (:func:`_end_pose_map_row`). A
    row the twin refuses (a shaped reference over the joint speed limits) is reported with
    its error instead of its reduction."""
    from tvist import load_map
    from tvist.experiments.experiment import run_motion
    from tvist.experiments.measure import zv_delay_s
    from tvist.experiments.methods import default_methods, fd_tvist_modal
    from tvist.experiments.motions import PAYLOAD_COM_M, demo_motions, demo_payload_kg
    from tvist.sim.family import modes_of

    modal = load_map(map_path)
    identified = fd_tvist_modal("identified", "identified modal map", modal)
    rows = [m for m in default_methods() if m.key == "unshaped"] + [identified, _ceiling_row()]
    twin = variant.twin(demo_payload_kg(variant.robot), PAYLOAD_COM_M)
    out = {}
    for motion in demo_motions(variant.robot):
        end_pose = _end_pose_map_row(modal)
        fixed = run_motion(motion, [rows[0], end_pose, rows[2]], twin, robot, with_slow_down=False)
        end_modes = [tuple(m) for m in modal.modes(robot, motion.q_end)]
        entry: dict[str, Any] = {
            "unshaped_residual_m_s2": fixed.run("unshaped").residual.amplitude,
            "end_pose_map": {
                "reduction_percent": fixed.run("end-pose").reduction_percent,
                "modes_hz": [w / (2 * math.pi) for w, _ in end_modes],
            },
            "ceiling": {
                "reduction_percent": fixed.run("ceiling").reduction_percent,
                "true_modes_hz": [
                    m.freq_hz for m in modes_of(twin, motion.q_end, max_freq_hz=TRUE_MODE_MAX_HZ)
                ],
            },
        }
        try:
            run = run_motion(motion, rows[:2], twin, robot, with_slow_down=False)
        except ValueError as exc:
            entry["identified"] = {"error": str(exc), "modes_shaped": len(end_modes)}
        else:
            shaped_modes = run.map_end_modes[identified.label]
            shaped = run.run("identified")
            analytic = zv_delay_s(shaped_modes)
            entry["identified"] = {
                "reduction_percent": shaped.reduction_percent,
                "modes_shaped": len(shaped_modes),
                # The stop pose's modes held over the move (set_modes_for_move), not followed.
                "held_at_end_pose": bool(shaped.details.get("held_at_end_pose", False)),
                "end_pose_modes_hz": [w / (2 * math.pi) for w, _ in shaped_modes],
                "delay_s": shaped.delay_s,
                "zv_delay_s": analytic,
                "delay_minus_zv_samples": (shaped.delay_s - analytic)
                / robot.params.sample_period_s(),
            }
        out[motion.name] = entry
    return out


def _identification_truth(variant, records: Sequence[Mapping[str, Any]]) -> dict[str, list]:
    """The true natural frequencies (Hz, up to :data:`MATCH_MAX_HZ`) at each record's pose
    with its payload."""
    from tvist.sim.family import modes_of

    twins: dict[tuple, Any] = {}
    truth = {}
    for record in records:
        if record.get("q") is None:
            continue
        payload = (float(record["payload_kg"]), tuple(record["payload_com_m"]))
        if payload not in twins:
            twins[payload] = variant.twin(*payload)
        modes = modes_of(twins[payload], record["q"], max_freq_hz=MATCH_MAX_HZ)
        truth[record["key"]] = [m.freq_hz for m in modes]
    return truth


def run_variant(seed: int | None, out: str | Path, settings: HarnessSettings) -> dict[str, Any]:
    """Everything of variant ``family:<robot>:<seed>`` (``seed`` ``None``: the robot's
    default twin, ``family:<robot>:nominal``; see the module docstring), written to
    ``out/<robot>-<seed>/result.json`` and returned; a result already there with the same
    settings is returned as it is. A failure is a result with ``"error"``."""
    from tvist.experiments.motions import PAYLOAD_COM_M, demo_payload_kg
    from tvist.robots import Payload, Robot, params
    from tvist.sim.family import nominal_variant, sample_variant

    variant = (
        nominal_variant(settings.robot) if seed is None else sample_variant(settings.robot, seed)
    )
    name = variant.name
    folder = Path(out) / f"{settings.robot}-{name.rsplit(':', 1)[1]}"
    result_path = folder / RESULT_FILE
    wanted = json.loads(json.dumps(asdict(settings)))
    if result_path.exists():
        cached = json.loads(result_path.read_text(encoding="utf-8"))
        if cached.get("settings") == wanted and "error" not in cached:
            return cached
    folder.mkdir(parents=True, exist_ok=True)
    robot = Robot(params(settings.robot), Payload(demo_payload_kg(settings.robot), PAYLOAD_COM_M))
    clock = _Clock()
    result: dict[str, Any] = {"variant": name, "seed": seed, "settings": wanted}
    try:
        poses = settings.plan()
        result["plan"] = {"n_poses": sum(p.q is not None for p in poses)}
        result["plan"]["logs_written"] = _write_logs(name, settings, poses, folder / "logs")
        clock.lap("campaign")

        map_path = _identify_and_fit(settings, folder / "logs", folder)
        clock.lap("identify_and_fit")

        from tvist import load_map

        document = json.loads(map_path.read_text(encoding="utf-8"))
        q_eval = evaluation_poses(settings.robot, seed)
        result["map_vs_truth"] = map_vs_truth(variant, load_map(map_path), robot, q_eval)
        result["map"] = {
            "file": str(map_path.relative_to(folder)),
            "flex_joints": [f["joint"] for f in document.get("flex_joints", [])],
            "shaped": [e["name"] for e in result["map_vs_truth"]["modes"]],
        }
        clock.lap("map_vs_truth")

        records = [
            json.loads(line)
            for line in (folder / "poses.jsonl").read_text(encoding="utf-8").splitlines()
            if line.strip()
        ]
        wrong = wrong_confident(records, _identification_truth(variant, records))
        result["wrong_confident"] = {"count": len(wrong), "identifications": wrong}
        clock.lap("wrong_confident")

        result["moves"] = _moves(variant, map_path, robot)
        clock.lap("moves")
    except (RuntimeError, ValueError, OSError) as exc:
        result["error"] = str(exc)
    result["wall_time_s"] = clock.wall_s
    result["cpu_time_s"] = clock.cpu_s
    result_path.write_text(json.dumps(result, indent=1) + "\n", encoding="utf-8")
    return result


class _Clock:
    """Wall-clock and CPU time per stage, s; CPU time of this process and of the
    subprocesses it waited for (the CLI steps): what the run costs on an idle machine."""

    def __init__(self) -> None:
        self.wall_s: dict[str, float] = {}
        self.cpu_s: dict[str, float] = {}
        self._wall, self._cpu = time.perf_counter(), self._cpu_now()

    @staticmethod
    def _cpu_now() -> float:
        import resource

        children = resource.getrusage(resource.RUSAGE_CHILDREN)
        return time.process_time() + children.ru_utime + children.ru_stime

    def lap(self, stage: str) -> None:
        wall, cpu = time.perf_counter(), self._cpu_now()
        self.wall_s[stage], self.cpu_s[stage] = wall - self._wall, cpu - self._cpu
        self._wall, self._cpu = wall, cpu


# --------------------------------------------------------------------------- command


def _run_one(args: tuple[int | None, str, HarnessSettings]) -> dict[str, Any]:
    seed, out, settings = args
    return run_variant(seed, out, settings)


def main(argv: Sequence[str] | None = None) -> int:
    """``python -m tvist.experiments.generalization``: see the module docstring."""
    p = argparse.ArgumentParser(
        prog="python -m tvist.experiments.generalization",
        description="Campaign, identification, modal map and the demo's moves on variants of "
        "the family (family:ROBOT:SEED); one JSON per variant and a markdown table.",
    )
    defaults = HarnessSettings()
    p.add_argument(
        "--robot",
        default=defaults.robot,
        help="ur5e or ur10e; with --seeds nominal also fr3 or iiwa14 (default ur5e)",
    )
    p.add_argument(
        "--seeds",
        required=True,
        help="variant seeds, e.g. 0-4 or 0,3,7-9, or nominal (the robot's default twin)",
    )
    p.add_argument("--out", default="out/generalization", help="output folder")
    p.add_argument(
        "--workers",
        type=int,
        default=MAX_WORKERS,
        help=f"variants at once (1-{MAX_WORKERS}, default {MAX_WORKERS})",
    )
    p.add_argument(
        "--every",
        type=int,
        default=defaults.every,
        help=f"every N-th of Algorithm 1's poses, plus the workspace coverage (default "
        f"{defaults.every})",
    )
    p.add_argument(
        "--payloads",
        type=float,
        nargs="+",
        default=list(defaults.payloads_kg),
        help="payloads of the plan, kg (default 0 5)",
    )
    p.add_argument(
        "--duration", type=float, default=defaults.duration_s, help="excitation length, s"
    )
    p.add_argument(
        "--excite",
        default=None,
        help="joints excited at every pose (default: base, shoulder and the robot's elbow, "
        "0,1,2 on a UR, 0,1,3 on an FR3 or iiwa14)",
    )
    p.add_argument(
        "--no-at-move-poses",
        action="store_true",
        help="do not identify at the demo's move poses Q1-Q3 (tvist campaign --at)",
    )
    args = p.parse_args(argv)
    try:
        seeds = parse_seeds(args.seeds)
    except ValueError as exc:
        p.exit(2, f"{p.prog}: error: {exc}\n")
    try:
        joints = excited_from_args(args)
    except ValueError as exc:
        p.exit(2, f"{p.prog}: error: {exc}\n")
    if not 1 <= args.workers <= MAX_WORKERS:
        p.exit(2, f"{p.prog}: error: --workers {args.workers}: give 1 to {MAX_WORKERS}\n")
    settings = HarnessSettings(
        robot=args.robot,
        payloads_kg=tuple(args.payloads),
        every=args.every,
        duration_s=args.duration,
        excited_joints=joints,
        at_move_poses=not args.no_at_move_poses,
    )
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    jobs = [(seed, str(out), settings) for seed in seeds]
    results: dict[int | None, dict[str, Any]] = {}
    start = time.perf_counter()
    if args.workers == 1 or len(jobs) == 1:
        for job in jobs:
            results[job[0]] = _report(_run_one(job), start)
    else:
        from concurrent.futures import ProcessPoolExecutor, as_completed

        with ProcessPoolExecutor(max_workers=args.workers) as pool:
            futures = {pool.submit(_run_one, job): job[0] for job in jobs}
            for future in as_completed(futures):
                results[futures[future]] = _report(future.result(), start)
    table = table_markdown([results[s] for s in seeds])
    command = "python -m tvist.experiments.generalization " + " ".join(
        argv if argv is not None else sys.argv[1:]
    )
    (out / TABLE_FILE).write_text(f"`{command}`\n\n{table}", encoding="utf-8")
    print(table)
    print(f"table: {out / TABLE_FILE} ({time.perf_counter() - start:.0f} s)")
    return 0


def _report(result: Mapping[str, Any], start: float) -> Mapping[str, Any]:
    wall = sum((result.get("wall_time_s") or {}).values())
    cpu = sum((result.get("cpu_time_s") or {}).values())
    status = f"failed: {result['error']}" if "error" in result else "done"
    print(
        f"{result['variant']}: {status} ({wall:.0f} s, {cpu:.0f} s of CPU; "
        f"{time.perf_counter() - start:.0f} s since start)",
        flush=True,
    )
    return result


if __name__ == "__main__":
    raise SystemExit(main())
