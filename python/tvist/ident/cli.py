"""``tvist`` subcommands of the identification toolbox: campaign, identify, fit-map, sensitivity.

Each ``add_*_command(sub)`` registers one subparser and sets ``func``; heavy imports happen
inside the command.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path

__all__ = [
    "add_campaign_command",
    "add_fit_map_command",
    "add_identify_command",
    "add_sensitivity_command",
]


def _add_payload_args(p: argparse.ArgumentParser) -> None:
    p.add_argument("--robot", default="ur5e", help="robot model (default ur5e)")
    p.add_argument("--payload-kg", type=float, default=0.0, help="payload mass (kg)")
    p.add_argument(
        "--payload-com",
        type=float,
        nargs=3,
        default=(0.0, 0.0, 0.05),
        metavar=("X", "Y", "Z"),
        help="payload centre of mass in the flange frame (m, default 0 0 0.05)",
    )


# --------------------------------------------------------------------------- campaign


def _cmd_campaign(args: argparse.Namespace) -> int:
    from tvist.ident.campaign import URRobot, campaign_poses, run_campaign

    poses = campaign_poses(
        args.robot, payloads_kg=args.payloads, payload_com_m=args.payload_com, seed=args.seed
    )
    poses = poses[:: args.every]
    robot = None
    if args.robot_ip:
        robot = URRobot(args.robot_ip, args.robot, log_dir=Path(args.out).parent / "logs")
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
    )
    wanted = {p.key for p in poses}
    done = [r for r in results if r["key"] in wanted]
    confident = [
        r for r in done if r["modes"] and all(not m.get("low_confidence", True) for m in r["modes"])
    ]
    print(f"{len(done)}/{len(poses)} poses in {args.out}; {len(confident)} fully confident")
    truth = [r for r in done if "true_modes" in r]
    for joint, name in ((0, "base"), (1, "shoulder")):
        errors = []
        for r in truth:
            fit = next((m for m in r["modes"] if m.get("joint") == joint), None)
            true = next(m for m in r["true_modes"] if m["joint"] == joint)
            if fit is not None and "wn_rad_s" in fit:
                errors.append(abs(fit["wn_rad_s"] / true["wn_rad_s"] - 1.0))
        if errors:
            within = sum(e < 0.03 for e in errors)
            print(
                f"  {name}: ω_n within 3 % of the twin's modes at {within}/{len(errors)} poses "
                f"({100 * within / len(errors):.0f} %)"
            )
    if args.map:
        from tvist.ident.map_fit import fit_map

        dynmap = fit_map(done, metadata={"robot": args.robot})
        dynmap.save(args.map)
        print(f"map written to {args.map}")
    return 0


def add_campaign_command(sub: argparse._SubParsersAction) -> None:
    """``tvist campaign (--sim | --robot-ip IP)``: Algorithm 1 over the workspace."""
    p = sub.add_parser(
        "campaign",
        help="identify base and shoulder modes over the workspace (paper Algorithm 1)",
        description="Move through the campaign poses, excite base and shoulder, identify "
        "their modes and append one JSON line per pose to --out (reruns resume).",
    )
    target = p.add_mutually_exclusive_group(required=True)
    target.add_argument("--sim", action="store_true", help="use the MuJoCo twin")
    target.add_argument("--robot-ip", help="use a real UR at this address (needs ur-rtde)")
    p.add_argument("--out", default="out/campaign.jsonl", help="results file (JSON lines)")
    p.add_argument("--robot", default="ur5e", help="robot model (default ur5e)")
    p.add_argument(
        "--payloads", type=float, nargs="+", default=[0.0, 1.0, 3.0, 5.0], help="payloads (kg)"
    )
    p.add_argument(
        "--payload-com",
        type=float,
        nargs=3,
        default=(0.0, 0.0, 0.05),
        metavar=("X", "Y", "Z"),
        help="payload centre of mass in the flange frame (m)",
    )
    p.add_argument("--every", type=int, default=1, help="run every N-th pose only")
    p.add_argument("--workers", type=int, default=1, help="processes for the twin")
    p.add_argument("--seed", type=int, default=0, help="seed of wrists, excitations, noise")
    p.add_argument(
        "--accel-noise", type=float, default=0.05, help="twin accelerometer noise (m/s²)"
    )
    p.add_argument("--duration", type=float, default=8.0, help="excitation length per joint (s)")
    p.add_argument(
        "--single-mode",
        action="store_true",
        help="record the paper's single-mode base fit only (no base/shoulder separation)",
    )
    p.add_argument("--map", help="also fit a dynamic map and write it here (JSON)")
    p.set_defaults(func=_cmd_campaign)


# --------------------------------------------------------------------------- identify


def _cmd_identify(args: argparse.Namespace) -> int:
    from tvist.ident.local_fit import identify_local
    from tvist.ident.logs import read_rtde_csv
    from tvist.robots import Payload, Robot, params

    record = read_rtde_csv(args.log, drop_nan=args.drop_nan, resample=args.resample)
    robot = Robot(params(args.robot), Payload(args.payload_kg, tuple(args.payload_com)))
    fit = identify_local(
        record, args.joint, robot, accel_frame=args.accel_frame, two_modes=args.two_modes
    )
    if args.json:
        print(json.dumps(fit.to_dict(), indent=2))
        return 0
    print(
        f"{args.log}: joint {args.joint}, {record.n_samples} samples at {record.dt_s * 1e3:.3f} ms"
    )
    print(
        f"  f_n = {fit.fn_hz:.3f} Hz ± {fit.wn_se_rad_s / (2 * math.pi):.3f}   "
        f"ω_n = {fit.wn_rad_s:.2f} rad/s   ζ = {fit.zeta:.4f} ± {fit.zeta_se:.4f}"
    )
    print(f"  fit {fit.fit_percent:.1f} %   input delay {fit.delay_s * 1e3:.0f} ms")
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
    """``tvist identify LOG.csv``: local fit (eq. 17) of one RTDE log."""
    p = sub.add_parser(
        "identify",
        help="identify one mode from an RTDE log of an excitation",
        description="Read a UR RTDE log (ur_rtde or UR's record.py), compute the tangential "
        "acceleration (eqs. 12-13) and fit G(s) (eq. 17).",
    )
    p.add_argument("log", help="RTDE CSV file")
    p.add_argument("--joint", type=int, default=0, help="excited joint (0 base, 1 shoulder)")
    _add_payload_args(p)
    p.add_argument(
        "--accel-frame",
        choices=("flange", "base"),
        default="flange",
        help="frame of actual_tool_accelerometer (default flange)",
    )
    p.add_argument("--two-modes", action="store_true", help="also fit two modes")
    p.add_argument("--drop-nan", action="store_true", help="drop rows with NaN (with a warning)")
    p.add_argument("--resample", action="store_true", help="fill skipped samples by interpolation")
    p.add_argument("--json", action="store_true", help="print the result as JSON")
    p.set_defaults(func=_cmd_identify)


# --------------------------------------------------------------------------- fit-map


def _cmd_fit_map(args: argparse.Namespace) -> int:
    from tvist.ident.campaign import load_results
    from tvist.ident.map_fit import fit_map

    results = load_results(args.results)
    if not results:
        print(f"{args.results}: no pose records", file=sys.stderr)
        return 1
    if args.kind == "modal":
        from tvist.ident.modal_fit import fit_map_command

        return fit_map_command(results, args)
    dynmap = fit_map(
        results,
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
        text = ", ".join(f"{k} = {v['value']:.4g} ± {v['se']:.2g}" for k, v in coefficients.items())
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


def add_fit_map_command(sub: argparse._SubParsersAction) -> None:
    """``tvist fit-map RESULTS.jsonl``: fit the dynamic map to a campaign."""
    p = sub.add_parser(
        "fit-map",
        help="fit the dynamic map's coefficients to campaign results",
        description="Nonlinear least squares of the map coefficients (frequency, then "
        "damping), dropping negligible terms; writes a tvist map file.",
    )
    p.add_argument("results", help="campaign results (JSON lines)")
    p.add_argument("--out", default="out/map.json", help="map file to write")
    p.add_argument("--robot", default="ur5e", help="robot model name stored in the map")
    p.add_argument(
        "--kind",
        choices=("paper10", "modal"),
        default="paper10",
        help="map form: the published 10 coefficients (paper10) or the modal map (modal)",
    )
    p.add_argument(
        "--include-low-confidence", action="store_true", help="also use flagged identifications"
    )
    p.set_defaults(func=_cmd_fit_map)


# --------------------------------------------------------------------------- sensitivity


def _cmd_sensitivity(args: argparse.Namespace) -> int:
    import tvist
    from tvist.ident import plots
    from tvist.ident.campaign import load_results
    from tvist.ident.robustness import evaluate_map, summarize

    dynmap = tvist.DynamicMap.load(args.map) if args.map else tvist.DynamicMap.paper_ur5e()
    results = load_results(args.results) if args.results else []
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    written = [
        plots.plot_prv_sensitivity(dynmap, out / "prv_sensitivity.png"),
        plots.plot_frequency_robustness(dynmap, results, out / "base_frequency.png", mode=0),
        plots.plot_frequency_robustness(dynmap, results, out / "shoulder_frequency.png", mode=1),
        plots.plot_damping_robustness(dynmap, results, out / "shoulder_damping.png", mode=1),
    ]
    if results:
        written.append(plots.plot_map_fit(dynmap, results, out / "map_fit.png"))
        summary = summarize(evaluate_map(results, dynmap))
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
    p.add_argument("--map", help="map file (default: the paper's UR5e map)")
    p.add_argument("--results", help="campaign results (JSON lines) to overlay and judge")
    p.add_argument("--out", default="out/sensitivity", help="output folder")
    p.set_defaults(func=_cmd_sensitivity)
