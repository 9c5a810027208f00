"""Every ringing mode against the true modes, on arms of the seeded family.

For each ``ROBOT:SEED`` (e.g. ``ur5e:1``): the campaign's excitations at 5 kg, every 4th
radius of the plan at its 4 angles, 6 s per joint, on the variant's twin (0.05 m/s² noise,
logs cached as pickles in ``--cache``), identified by :func:`tvist.ident.pose.identify_pose`,
checked across poses (:func:`tvist.ident.pose_checks.flag_jumps`) and compared with the
variant's true modes below 60 Hz. Prints one table row per arm: confident and flagged
``ringing`` modes, confident ones more than 3 % from every true mode, true modes matched.

    .venv/bin/python benches/ringing_family.py ur5e:0 ur5e:1 ur5e:6 ur10e:0 ur10e:3
"""

from __future__ import annotations

import argparse
import math
import pickle
import warnings
from pathlib import Path

import numpy as np

from tvist.ident.campaign_robots import TRUE_MODES_MAX_HZ, TwinRobot
from tvist.ident.pose import identify_pose
from tvist.ident.pose_checks import flag_jumps
from tvist.ident.pose_plan import PAPER_RADII_M, campaign_poses, pose_excitations
from tvist.robots import Payload, Robot, params


def _logs(robot: str, seed: int, cache: Path) -> list[dict]:
    folder = cache / f"{robot}_{seed}"
    folder.mkdir(parents=True, exist_ok=True)
    twin = TwinRobot(robot, 0.05, seed=0, variant=f"family:{robot}:{seed}")
    items = []
    for pose in campaign_poses(robot, payloads_kg=(5.0,), radii_m=PAPER_RADII_M[::4]):
        if pose.q is None:
            continue
        path = folder / f"{pose.key}.pkl"
        if not path.exists():
            twin.set_payload(pose.payload_kg, pose.payload_com_m)
            logs = {e.joint: twin.record_excitation(e) for e in pose_excitations(pose, 6.0)}
            truth = [m.freq_hz for m in twin.all_true_modes(pose.q, TRUE_MODES_MAX_HZ)]
            with path.open("wb") as fh:
                pickle.dump({"pose": pose, "logs": logs, "truth_hz": truth}, fh)
        with path.open("rb") as fh:
            items.append(pickle.load(fh))
    return items


def evaluate(robot: str, seed: int, cache: Path) -> str:
    records = []
    for item in _logs(robot, seed, cache):
        pose = item["pose"]
        model = Robot(params(robot), Payload(pose.payload_kg, pose.payload_com_m))
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            record = identify_pose(item["logs"][0], item["logs"][1], model, key=pose.key, q=pose.q)
        records.append({**record.to_dict(), "truth_hz": item["truth_hz"]})
    confident = flagged = wrong = matched = n_true = 0
    for r in flag_jumps(records):
        truth = np.array(r["truth_hz"])
        n_true += truth.size
        sure = [m["wn_rad_s"] / (2 * math.pi) for m in r["ringing"] if not m["low_confidence"]]
        flagged += len(r["ringing"]) - len(sure)
        confident += len(sure)
        wrong += sum(float(np.min(np.abs(f / truth - 1.0))) > 0.03 for f in sure)
        matched += sum(any(abs(f / t - 1.0) <= 0.03 for f in sure) for t in truth)
    return (
        f"| `family:{robot}:{seed}` | {len(records)} | {confident} / {flagged} | {wrong} | "
        f"{matched} of {n_true} |"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("arms", nargs="+", help="ROBOT:SEED, development seeds (0-99)")
    parser.add_argument("--cache", type=Path, default=Path("/tmp/tvist-ringing-family"))
    args = parser.parse_args()
    print("| arm | poses | confident / flagged | confident > 3 % off | true modes matched |")
    print("|---|---|---|---|---|")
    for arm in args.arms:
        robot, seed = arm.split(":")
        print(evaluate(robot, int(seed), args.cache), flush=True)


if __name__ == "__main__":
    main()
