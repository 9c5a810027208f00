"""``tvist learn LOG... --map m.json --out m2.json``: refine a modal map from the logs of
ordinary moves (:mod:`tvist.learn`)."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path


def add_learn_command(sub: argparse._SubParsersAction) -> None:
    """``tvist learn``: a new map file learned from move logs, with provenance."""
    from tvist.cli.args import add_robot_and_payload

    p = sub.add_parser(
        "learn",
        help="refine a modal map from the ringing after ordinary moves",
        description="Fits the free decay after each move's stop and refines the map's "
        "per-joint stiffness and damping scale factors (bounded, gated steps; bad logs are "
        "rejected with their reason). Writes a new map file whose metadata.learned says which "
        "logs were used, what changed and by how much.",
    )
    p.add_argument("logs", nargs="+", help="RTDE CSV logs of moves, in the order they were run")
    p.add_argument(
        "--map",
        required=True,
        help="the map file to start from: a modal map, or a paper10 map (converted into the "
        "modal map that fits its modes along the paper's test motions, with a wider prior)",
    )
    p.add_argument("--out", required=True, help="the learned map file to write")
    add_robot_and_payload(
        p,
        "declared payload mass",
        payload_from="default: the map's metadata.payload, else the first log's payload columns",
    )
    p.add_argument("--json", action="store_true", help="print the per-log verdicts as JSON")
    p.set_defaults(func=_cmd_learn)


def modal_prior(path: str, flag: str):
    """The modal map in file ``path`` to learn from; a paper10 map is refused naming ``flag``."""
    from tvist.maps.dynamics import load_map
    from tvist.maps.modal import ModalMap

    prior = load_map(path)
    if not isinstance(prior, ModalMap):
        raise ValueError(f"{flag} {path}: a paper10 map; learning refines a modal map")
    return prior


def _cmd_learn(args: argparse.Namespace) -> int:
    from tvist.cli.args import map_payload, payload_from_args
    from tvist.ident.logs import log_payload
    from tvist.learn import MapLearner
    from tvist.maps.dynamics import load_map
    from tvist.robots import Robot, params

    prior = load_map(args.map)
    out = Path(args.out)
    if out.resolve() == Path(args.map).resolve():
        raise ValueError("--out names the --map file; write the learned map to a new file")
    for log in args.logs:
        if not Path(log).is_file():
            raise ValueError(f"no such log: {log} (give existing RTDE CSV files as LOG)")
    payload = payload_from_args(
        args,
        ("the map's metadata.payload", lambda: map_payload(prior)),
        ("the first log's payload columns", lambda: log_payload(args.logs[0])),
        needed_for="learning (the joint inertias)",
        out=sys.stderr,
    )
    learner = MapLearner(Robot(params(args.robot), payload), prior)
    if learner.converted is not None:
        c = learner.converted
        print(
            f"{args.map}: a paper10 map, converted into a modal map (its frequencies within "
            f"{100 * c.wn_rel_median:.1f} % of the published map's at the median pose of the "
            f"test motions; prior uncertainty {learner.prior_log_sigma:.2f} in log stiffness)",
            file=sys.stderr,
        )
    for log in args.logs:
        obs = learner.observe(log)
        if not args.json:
            verdict = "used" if obs.accepted else "rejected"
            changed = ", map updated" if obs.map_updated else ""
            print(f"{log}: {verdict}{changed}: {obs.reason}")
    learned = learner.learned_map()
    learned.save(out)
    if args.json:
        print(json.dumps([o.to_json() for o in learner.history], indent=1))
    else:
        for name, entry in learned.metadata["learned"]["scale_factors"].items():
            print(f"{name}: {entry['change_percent']:+.1f} %")
        print(f"wrote {out}")
    return 0
