"""``tvist`` subcommands of the identification toolbox: campaign, identify, fit-map, sensitivity.

Each ``add_*_command(sub)`` registers one subparser and sets ``func``; heavy imports happen
inside the command. Library errors (``ValueError``, ``OSError``) propagate to ``tvist.cli.main``,
which reports them on one line; usage problems found here are reported by :func:`_error`.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path

from tvist.cli.args import (
    add_robot_and_payload,
    add_units,
    existing_file,
    kinematic_robot,
    map_from_args,
    map_payload,
    output_file,
    payload_from_args,
)
from tvist.cli.plan import add_plan_options

__all__ = [
    "add_campaign_command",
    "add_fit_map_command",
    "add_identify_command",
    "add_sensitivity_command",
]


def _error(command: str, message: str) -> int:
    """A user error: one line on stderr, exit code 2."""
    print(f"tvist {command}: error: {message}", file=sys.stderr)
    return 2


def _add_payload_args(p: argparse.ArgumentParser) -> None:
    from tvist.cli.args import add_robot_and_payload

    add_robot_and_payload(
        p,
        "payload mass during the logs",
        payload_from="default: the log's payload columns, which 'tvist record' and 'tvist run' "
        "write; required for other logs",
    )


# --------------------------------------------------------------------------- campaign


def _cmd_campaign(args: argparse.Namespace) -> int:
    from tvist.cli.plan import checked_plan, excited_from_args
    from tvist.ident.campaign import URRobot, run_campaign
    from tvist.ident.campaign_robots import new_run_folder
    from tvist.ident.results_store import SettingsMismatch

    if args.variant:
        from tvist.sim.variants import variant_robot

        if args.robot_ip:
            return _error("campaign", "--variant selects a twin: use it with --sim")
        try:
            robot_of = variant_robot(args.variant)
        except ValueError as exc:
            return _error("campaign", f"--variant: {exc}")
        if robot_of != args.robot:
            return _error(
                "campaign", f"--variant {args.variant} is a {robot_of}: add --robot {robot_of}"
            )
    joints = excited_from_args(args)
    output_file(args.out, "--out")
    if args.map:
        output_file(args.map, "--map")
    # A plan the map fit cannot succeed on is refused before a robot moves (on the twin it
    # only matters when a map is asked for).
    fit_check = bool(args.robot_ip or args.map) and not args.no_fit_check
    poses = checked_plan(args, require_fittable=fit_check)
    from tvist.cli.plan import coverage_text

    print(f"plan: {len(poses)} poses; {coverage_text(poses, args)}", flush=True)
    robot = None
    if args.robot_ip:
        log_dir = new_run_folder(Path(args.out).parent / "logs")
        print(f"RTDE logs of this run: {log_dir}", flush=True)
        robot = URRobot(
            args.robot_ip, args.robot, log_dir=log_dir, confirm=None if args.yes else input
        )
    try:
        results = run_campaign(
            poses,
            args.out,
            robot=robot,
            robot_name=args.robot,
            workers=args.workers,
            accel_noise_std=args.accel_noise,
            noise_seed=args.seed,
            duration_s=args.duration,
            separate_modes=not args.single_mode,
            overwrite=args.overwrite,
            variant=args.variant,
            joints=joints,
        )
    except KeyboardInterrupt:
        from tvist.ident.results_store import load_results

        saved = len(load_results(args.out)) if Path(args.out).exists() else 0
        print(
            f"tvist campaign: interrupted; {saved} pose record(s) saved in {args.out}, rerun "
            "the same command to resume",
            file=sys.stderr,
        )
        return 130
    except SettingsMismatch as exc:
        raise SettingsMismatch(str(exc).replace("overwrite it", "pass --overwrite")) from None
    wanted = {p.key for p in poses}
    done = [r for r in results if r["key"] in wanted]
    confident = [
        r for r in done if r["modes"] and all(not m.get("low_confidence", True) for m in r["modes"])
    ]
    print(f"{len(done)}/{len(poses)} poses in {args.out}; {len(confident)} fully confident")
    from tvist.ident.true_mode_agreement import within_tolerance

    for name, (within, compared) in within_tolerance(done).items():
        print(
            f"  {name}: ω_n within 3 % of the twin's modes at {within}/{compared} poses "
            f"({100 * within / compared:.0f} %)"
        )
    print(_ringing_summary(done))
    if args.map:
        from tvist.ident.map_fit import fit_map

        dynmap = fit_map(done, metadata={"robot": args.robot})
        dynmap.save(args.map)
        print(f"map written to {args.map}")
    return 0


def _ringing_summary(records: list[dict]) -> str:
    """One line on the records' ``ringing`` modes: how many are confident, how many rang
    faster while their joint moved than at rest (:func:`tvist.ident.ringing.checked_at_rest`);
    on the twin, how many confident ones are more than 3 % from every true mode
    (:func:`tvist.ident.true_mode_agreement.ringing_agreement`)."""
    import statistics

    from tvist.ident.campaign_robots import TRUE_MODES_MAX_HZ
    from tvist.ident.ringing import AT_REST_REASON
    from tvist.ident.true_mode_agreement import TOLERANCE, ringing_agreement

    modes = [m for r in records for m in r.get("ringing") or ()]
    confident = [m for m in modes if not m.get("low_confidence", True)]
    line = f"  ringing: {len(modes)} modes in the logs, {len(confident)} confident"
    stiffer = [
        m["wn_rad_s"] / m["wn_at_rest_rad_s"] - 1.0
        for m in modes
        if any(r.startswith(AT_REST_REASON) for r in m.get("reasons", ()))
    ]
    if stiffer:
        line += (
            f"; {len(stiffer)} flagged for ringing faster while the joint moved than at rest "
            f"after its stops (median {100 * statistics.median(stiffer):+.1f} %), as a gear that "
            "stiffens under load does"
        )
    truth = ringing_agreement(records, TRUE_MODES_MAX_HZ)
    if truth.modes:
        line += (
            f"; of the {truth.compared} confident ones the twin's true modes up to "
            f"{TRUE_MODES_MAX_HZ:g} Hz can judge, {truth.outside} more than "
            f"{100 * TOLERANCE:g} % from every true mode ({truth.above_band} too near or above "
            f"{TRUE_MODES_MAX_HZ:g} Hz to judge)"
        )
    return line


def add_campaign_command(sub: argparse._SubParsersAction) -> None:
    """``tvist campaign (--sim | --robot-ip IP)``: Algorithm 1 over the workspace."""
    p = sub.add_parser(
        "campaign",
        help="identify the arm's modes over the workspace (paper Algorithm 1)",
        description="Move through the campaign poses payload by payload (on a robot: one "
        "prompt per payload change, or none with --yes; each run's RTDE logs in a new "
        "logs/run-NNN next to --out), excite the --excite joints (base, shoulder, elbow) in "
        "turn, identify the base and shoulder modes and every mode that rings in each log, and "
        "append one JSON line per pose to --out (reruns resume). A plan the map fit cannot "
        "succeed on is refused before the robot moves.",
    )
    target = p.add_mutually_exclusive_group(required=True)
    target.add_argument("--sim", action="store_true", help="use the MuJoCo twin")
    target.add_argument("--robot-ip", help="use a real UR at this address (needs ur-rtde)")
    p.add_argument("--out", default="out/campaign.jsonl", help="results file (JSON lines)")
    add_plan_options(p)
    p.add_argument(
        "--yes",
        action="store_true",
        help="with --robot-ip: do not ask before each payload change (mount the payloads in "
        "the plan's order, lightest first, as the campaign reaches them)",
    )
    p.add_argument(
        "--no-fit-check",
        action="store_true",
        help="run a plan the map fit cannot succeed on (to identify a few poses only)",
    )
    p.add_argument(
        "--variant",
        help="with --sim: a twin variant whose flexibility the maps do not model exactly "
        "(ur5e-soft-gears, ur5e-flex-links, or family:ROBOT:SEED, e.g. family:ur5e:17, "
        "one arm of a seeded family of plausible UR5e/UR10e variants)",
    )
    p.add_argument("--workers", type=int, default=1, help="processes for the twin")
    p.add_argument(
        "--accel-noise", type=float, default=0.05, help="twin accelerometer noise (m/s²)"
    )
    p.add_argument(
        "--single-mode",
        action="store_true",
        help="record the paper's single-mode base fit only (no base/shoulder separation)",
    )
    p.add_argument("--map", help="also fit a dynamic map and write it here (JSON)")
    p.add_argument(
        "--overwrite",
        action="store_true",
        help="start --out afresh (default: resume it; a file made with other settings is refused)",
    )
    p.set_defaults(func=_cmd_campaign)


# --------------------------------------------------------------------------- identify


def _cmd_identify(args: argparse.Namespace) -> int:
    from tvist.ident.batch import expand_logs
    from tvist.units import parse_units

    parse_units(args.units)  # a bad --units is one error, not one per log

    try:
        paths = expand_logs(args.logs)
    except FileNotFoundError as exc:
        raise ValueError(
            f"logs {exc.filename}: no such file (give files, globs or folders)"
        ) from exc
    if args.out or len(paths) > 1:
        if not args.out:
            return _error("identify", f"{len(paths)} logs: name the results file with --out")
        return _identify_batch(args, paths)
    return _identify_one(args, paths[0])


def _identify_batch(args: argparse.Namespace, paths: list[Path]) -> int:
    from collections import Counter

    from tvist.cli.args import payload_from_args
    from tvist.ident.batch import identify_logs
    from tvist.ident.logs import log_payload

    def message(text: str) -> None:
        print(f"tvist identify: warning: {text}", file=sys.stderr)

    if args.payload_kg is not None or args.payload_com is not None:
        payload_from_args(args, needed_for="identification (the joint inertias)")
    else:  # each log's own payload: every log must name one
        found = {path: log_payload(path) for path in paths}
        missing = [path for path, payload in found.items() if payload is None]
        if missing:
            raise ValueError(
                f"no payload: {missing[0]} (and {len(missing) - 1} more logs) has no payload "
                "columns; give --payload-kg KG (and --payload-com X Y Z)"
            )
        counts = Counter(float(p.mass_kg) for p in found.values())
        text = ", ".join(f"{kg:g} kg ({n} logs)" for kg, n in sorted(counts.items()))
        print(f"payload from each log's payload columns: {text}")
    records = identify_logs(
        paths,
        robot_name=args.robot,
        payload_kg=args.payload_kg,
        payload_com_m=args.payload_com,
        accel_frame=args.accel_frame,
        separate_modes=not args.single_mode,
        drop_nan=args.drop_nan,
        resample=not args.no_resample,
        repair=tuple(args.repair or ()),
        units=args.units,
        workers=args.workers,
        on_message=message,
        progress=sys.stderr.isatty(),
    )
    if not records:
        return _error("identify", "no log of an identified joint (0-3) could be read")
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    with out.open("w", encoding="utf-8") as fh:
        for record in records:
            fh.write(json.dumps(record) + "\n")
    confident = sum(
        1
        for r in records
        for m in r["modes"]
        if "wn_rad_s" in m and not m.get("low_confidence", True)
    )
    n_modes = sum(len(r["modes"]) for r in records)
    print(
        f"{len(paths)} logs -> {len(records)} poses in {out}; {confident}/{n_modes} modes "
        "identified with confidence"
    )
    print(_ringing_summary(records))
    return 0


def _identify_one(args: argparse.Namespace, path: Path) -> int:
    import warnings

    from tvist.cli.args import payload_from_args
    from tvist.ident.local_identification import identify_local
    from tvist.ident.logs import LogWarning, log_payload, read_rtde_csv
    from tvist.ident.segment import excitation_segment
    from tvist.robots import Robot, params

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", LogWarning)
        record = read_rtde_csv(
            path,
            repair=tuple(args.repair or ()) or None,
            drop_nan=args.drop_nan,
            resample=not args.no_resample,
            units=args.units,
        )
    for w in caught:
        print(f"tvist identify: warning: {w.message}", file=sys.stderr)
    payload = payload_from_args(
        args,
        ("the log's payload columns", lambda: log_payload(path)),
        needed_for="identification (the joint inertias)",
        out=sys.stderr if args.json else None,
    )
    if args.joint is None:
        segment = excitation_segment(record)
        joint, n_rows = segment.joint, record.n_samples
        record = segment.of(record)
        if segment.trimmed and not args.json:
            print(
                f"{path}: excitation of joint {joint} in rows {segment.start}-"
                f"{segment.stop - 1} of {n_rows} ({segment.n_moves} moves; the rest of the "
                "log is left out, --joint fits the whole log)"
            )
    else:
        joint = args.joint
    robot = Robot(params(args.robot), payload)
    fit = identify_local(
        record,
        joint,
        robot,
        accel_frame=args.accel_frame,
        two_modes=args.two_modes,
        base_mode=not args.single_mode,
    )
    if args.json:
        print(json.dumps(fit.to_dict(), indent=2))
        return 0
    print(f"{path}: joint {joint}, {record.n_samples} samples at {record.dt_s * 1e3:.3f} ms")
    if fit.no_ringing:
        print(f"  NO RINGING ABOVE NOISE (flagged, no mode reported): {fit.reason}")
        return 0
    print(
        f"  f_n = {fit.fn_hz:.3f} Hz ± {fit.wn_se_rad_s / (2 * math.pi):.3f}   "
        f"ω_n = {fit.wn_rad_s:.2f} rad/s   ζ = {fit.zeta:.4f} ± {fit.zeta_se:.4f}"
    )
    print(
        f"  fit {fit.fit_percent:.1f} %   timing offset {fit.delay_s * 1e3:+.2f} ms   "
        f"({fit.method})"
    )
    if fit.two_mode is not None:
        modes = ", ".join(
            f"{m.fn_hz:.2f} Hz / ζ {m.zeta:.3f} ({100 * m.energy_share:.0f} %)"
            for m in fit.two_mode.modes
        )
        verdict = "significant" if fit.two_mode.significant else "not significant"
        print(f"  two-mode fit: {modes}; {verdict}")
    if fit.low_confidence:
        print(f"  LOW CONFIDENCE: {fit.reason}")
    return 0


def add_identify_command(sub: argparse._SubParsersAction) -> None:
    """``tvist identify LOG...``: local fits of RTDE logs, one log or a whole campaign."""
    p = sub.add_parser(
        "identify",
        help="identify modes from RTDE logs of excitations (one log, or many into --out)",
        description="Read UR RTDE logs (ur_rtde or UR's record.py), compute the tangential "
        "acceleration (eqs. 12-13) and fit G(s) (eq. 17). One log: print the fit. Many logs "
        "(files, globs or directories) with --out: find each log's excited joint, group the "
        "logs of each pose (base, shoulder, elbow, wrist 1) by their starting actual_q, "
        "identify every pose (the modes of base and shoulder, every mode that rings in each "
        "log) in parallel and write one pose record per line, the input of 'tvist fit-map'.",
    )
    p.add_argument("logs", nargs="+", metavar="LOG", help="RTDE CSV files, globs or directories")
    p.add_argument(
        "--joint",
        type=int,
        default=None,
        help="excited joint of a single log (0 base, 1 shoulder), fitted over the whole log "
        "(default: the excitation and its joint are found in the log, approach moves and "
        "rests around it left out)",
    )
    _add_payload_args(p)
    p.add_argument(
        "--accel-frame",
        choices=("flange", "base"),
        default="flange",
        help="frame of actual_tool_accelerometer (default flange)",
    )
    p.add_argument("--two-modes", action="store_true", help="also show the two-mode fit")
    p.add_argument(
        "--single-mode",
        action="store_true",
        help="report the paper's single-mode base fit (no base/shoulder separation)",
    )
    p.add_argument("--drop-nan", action="store_true", help="drop rows with NaN (with a warning)")
    p.add_argument(
        "--repair",
        action="append",
        choices=("drop-bad-rows", "keep-first-duplicate"),
        help="repair a malformed log instead of refusing it (repeatable, with a warning): "
        "drop rows with the wrong field count or unreadable cells; use the first of "
        "repeated columns",
    )
    p.add_argument(
        "--no-resample",
        action="store_true",
        help="do not fill skipped samples by interpolation (default: fill, with a warning)",
    )
    p.add_argument("--resample", action="store_true", help=argparse.SUPPRESS)  # the default
    add_units(p, ("q", "qd", "qdd", "acc"))
    p.add_argument("--json", action="store_true", help="print a single log's fit as JSON")
    p.add_argument("--out", help="write one pose record per line here (JSON lines)")
    p.add_argument(
        "--workers", type=int, default=None, help="processes for --out (default: all CPUs)"
    )
    p.set_defaults(func=_cmd_identify)


# --------------------------------------------------------------------------- fit-map

RECORD_FORMAT = """\
input: JSON lines, one pose per line, as written by 'tvist identify --out' and
'tvist campaign':
  key                string      name of the pose
  q                  [6] rad     joint angles of the pose
  payload_kg         kg          payload mass; payload_com_m [3] m: its centre of mass
                                 in the flange frame
  inertia_kg_m2      [6] kg m^2  joint-axis inertias at q (required)
  gravity_torque_nm  [6] N m     gravity torques at q (optional; needed for k_g)
  modes              list        per identified joint:
    joint            0 base, 1 shoulder
    wn_rad_s, zeta   natural frequency (rad/s) and damping ratio
    wn_se_rad_s, zeta_se  standard errors
    low_confidence   true: not used unless --include-low-confidence; reasons: why
    method           single-mode or two-mode (base separated from the shoulder mode)
    ringing_index    the ringing entry that is this mode (the base mode: the base log's
                     mode along the base joint's tangent); null if none
    error            instead of the above if the joint could not be identified
  ringing            list        every mode that rings in each log (1-3 per log):
    log_joint        the log's excited joint: 0 base, 1 shoulder, 2 elbow, 3 wrist 1
    wn_rad_s, zeta   natural frequency (rad/s) and damping ratio; wn_se_rad_s, zeta_se
    amplitude_m_s2   largest flange acceleration of the mode's ringing in the log
    flange_direction [3] unit vector, base frame, largest component positive (null: no
                     3-axis accelerometer)
    low_confidence   true with reasons: below noise, weak, uncertain, merged neighbours,
                     disagrees with another log, jumps against neighbouring poses
  true_modes         (twin only) every true mode below 60 Hz: freq_hz, zeta,
                     joint_shares [6], flange_direction [3], link_share, wn_rad_s, and
                     joint 0 / 1 for the twin's base / shoulder mode (else null)
  error              why the pose has no result (e.g. unreachable)
Records without ringing (older files) are read; their modes are used.
"""


def _cmd_fit_map(args: argparse.Namespace) -> int:
    from tvist.ident.map_fit import fit_map
    from tvist.ident.results_store import load_results

    results = load_results(existing_file(args.results, "results"))
    output_file(args.out, "--out")
    if not results:
        return _error("fit-map", f"{args.results}: no pose records")
    _check_pose_angles(args.results, results)
    print(f"payload from the pose records: {_payload_summary(results)}")
    if args.kind == "modal":
        from tvist.cli.modal_fit import fit_modal_command

        return fit_modal_command(results, args)
    dynmap = fit_map(
        results,
        k_0=args.k0,
        include_low_confidence=args.include_low_confidence,
        metadata={"robot": args.robot, "source": f"tvist fit-map {args.results}"},
    )
    dynmap.save(args.out)
    for stats in dynmap.metadata["fit_statistics"]["modes"]:
        name = "base" if stats["joint"] == 0 else "shoulder"
        coefficients = {
            **stats["frequency"]["coefficients"],
            **stats["damping"]["coefficients"],
        }
        at_bound = stats["frequency"]["at_bound"] + stats["damping"]["at_bound"]

        def coefficient(name: str, value: float, se: float | None, at_bound=at_bound) -> str:
            if name in at_bound:
                return f"{name} = {value:.4g} (at bound >= 0)"
            if se is None:  # a singular fit (stored as null): no standard error exists
                return f"{name} = {value:.4g} (no standard error: not separable)"
            return f"{name} = {value:.4g} ± {se:.2g}"

        text = ", ".join(coefficient(k, v["value"], v["se"]) for k, v in coefficients.items())
        print(
            f"{name} mode ({stats['n_poses']} poses, frequency from J_{stats['frequency_joint']}):"
        )
        print(f"  {text}")
        print(
            f"  RMS relative error: frequency {100 * stats['frequency']['rms_relative_error']:.2f}"
            f" %, damping {100 * stats['damping']['rms_relative_error']:.2f} %"
        )
        dropped = {**stats["frequency"]["dropped"], **stats["damping"]["dropped"]}
        if dropped:
            print(f"  dropped as negligible: {', '.join(dropped)}")
        poor = stats["frequency"]["poorly_determined"] + stats["damping"]["poorly_determined"]
        if poor:
            print(f"  poorly determined (±50 % or worse): {', '.join(poor)}")
    print(f"map written to {args.out}")
    return 0


def _payload_summary(records) -> str:
    """``"0 kg (12 poses), 5 kg (12 poses)"``; records without ``payload_kg`` counted apart."""
    from collections import Counter

    counts = Counter(
        f"{float(r['payload_kg']):g} kg" if "payload_kg" in r else "not recorded" for r in records
    )
    return ", ".join(f"{k} ({n} poses)" for k, n in sorted(counts.items()))


def _check_pose_angles(path: str, results: list[dict]) -> None:
    """Refuse pose records whose joint angles ``q`` are not radians (identified from logs in
    degrees read as radians: their inertias and gravity torques are those of other poses)."""
    import numpy as np

    from tvist.units import UnitError, angle_unit

    for line, record in enumerate(results, start=1):
        q = np.asarray(record.get("q", []), dtype=float)
        if angle_unit(q) != "rad":
            raise UnitError(
                f"{path}: record {line} ({record.get('key', '?')}): q = "
                f"{np.round(q, 3).tolist()} is beyond ±2π rad: a pose in degrees; identify its "
                "logs again with --units q=deg"
            )


def add_fit_map_command(sub: argparse._SubParsersAction) -> None:
    """``tvist fit-map RESULTS.jsonl``: fit the dynamic map to identified poses."""
    p = sub.add_parser(
        "fit-map",
        help="fit the dynamic map's coefficients to identified poses",
        description="Nonlinear least squares of the map coefficients (frequency, then "
        "damping), dropping negligible terms; writes a tvist map file.",
        epilog=RECORD_FORMAT,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument("results", help="pose records (JSON lines, see below)")
    p.add_argument("--out", default="out/map.json", help="map file to write (default out/map.json)")
    p.add_argument(
        "--robot", default="ur5e", help="robot model name stored in the map (default ur5e)"
    )
    p.add_argument(
        "--k0",
        type=float,
        default=None,
        help="fix the stiffness at zero inertia k_0 at this value, N m/rad (the paper's "
        "reduced map uses 10000); default: estimated with k_J and k_p (k_0 is not a scale: "
        "the k_p k_0/J² term of ω_n² determines it)",
    )
    p.add_argument(
        "--kind",
        choices=("paper10", "modal"),
        default="paper10",
        help="map form: the published 10 coefficients (paper10, the default) or the modal "
        "map (modal)",
    )
    p.add_argument(
        "--include-low-confidence", action="store_true", help="also use flagged identifications"
    )
    p.add_argument(
        "--select-folds",
        type=int,
        default=None,
        metavar="K",
        help="modal: fit only the base and shoulder modes named by their excitation joint "
        "(records' 'modes'), keeping a wrist joint or stiffness load term only if it lowers "
        "the K-fold held-out frequency error (default: every identified mode, matched to the "
        "model's eigenmodes by frequency and flange direction, flexible joints by a test)",
    )
    p.set_defaults(func=_cmd_fit_map)


# --------------------------------------------------------------------------- sensitivity


def _cmd_sensitivity(args: argparse.Namespace) -> int:
    from tvist import ModalMap
    from tvist.ident import plots
    from tvist.ident.results_store import load_results
    from tvist.ident.robustness import evaluate_map, summarize

    args.paper_map = not args.map
    dynmap = map_from_args(args)
    # A modal map's modes come from the robot model's mass matrix: --robot (the map's own
    # robot by default), with --payload-kg/--payload-com for the PRV panels at Q1 and Q3;
    # at campaign poses the record's payload.
    map_robot = getattr(dynmap, "robot", None)
    if args.robot is None:
        args.robot = map_robot or "ur5e"
    elif isinstance(dynmap, ModalMap) and map_robot and map_robot != args.robot:
        raise ValueError(
            f"--map {args.map}: a modal map identified on {map_robot}, not on {args.robot} "
            "(--robot)"
        )
    if isinstance(dynmap, ModalMap):  # its panels' modes depend on the payload
        payload_from_args(
            args,
            ("the map file", lambda: map_payload(dynmap)),
            needed_for="a modal map's PRV panels at Q1 and Q3",
        )
    robot = kinematic_robot(args)  # otherwise the records' payloads are used
    results = load_results(existing_file(args.results, "--results")) if args.results else []
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    written = [
        plots.plot_prv_sensitivity(dynmap, out / "prv_sensitivity.png", robot=robot),
        plots.plot_frequency_robustness(
            dynmap, results, out / "base_frequency.png", mode=0, robot=robot
        ),
        plots.plot_frequency_robustness(
            dynmap, results, out / "shoulder_frequency.png", mode=1, robot=robot
        ),
        plots.plot_damping_robustness(
            dynmap, results, out / "shoulder_damping.png", mode=1, robot=robot
        ),
    ]
    if results:
        written.append(plots.plot_map_fit(dynmap, results, out / "map_fit.png", robot=robot))
        summary = summarize(evaluate_map(results, dynmap, robot=robot))
        (out / "robustness.json").write_text(json.dumps(summary, indent=2) + "\n")
        if summary["n_poses"]:
            print(
                f"{summary['within_10_percent_prv']}/{summary['n_poses']} identified poses "
                "have PRV <= 10 % in both modes with the map-designed two-mode ZV shaper"
            )
    for path in written:
        print(f"wrote {path}")
    return 0


def add_sensitivity_command(sub: argparse._SubParsersAction) -> None:
    """``tvist sensitivity``: PRV sensitivity and map robustness figures (paper 5.4)."""
    p = sub.add_parser(
        "sensitivity",
        help="PRV sensitivity and map robustness figures (paper Figs. 27-30)",
        description="Plot the two-mode ZV shaper's PRV around the map's modes and, with "
        "--results, the identified modes against the map's 10 % PRV band.",
    )
    p.add_argument("--map", help="map file, paper10 or modal (default: the paper's UR5e map)")
    p.add_argument("--results", help="campaign results (JSON lines) to overlay and judge")
    p.add_argument("--out", default="out/sensitivity", help="output folder")
    add_robot_and_payload(
        p,
        "payload of a modal map's PRV panels at Q1 and Q3",
        payload_from="modal map: required unless the map file names one",
    )
    p.set_defaults(robot=None)
    for action in p._actions:
        if action.dest == "robot":
            action.help = "robot model of a modal map (default: the map's robot, else ur5e)"
    p.set_defaults(func=_cmd_sensitivity)
