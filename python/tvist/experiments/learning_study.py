"""Learning from the paper's published map on the twin: what 20 ordinary moves reach on the
demo's three moves, and what limits Q1->Q3.

The converted prior (:mod:`tvist.learn.prior`) knows nothing of the wrists: the published map
reads joint inertias only, so their stiffness is a guess. Where the upper arm points up (Q3)
the base mode is partly a torsion of the wrists and the arm's third mode (elbow and wrists)
lies close above it, so the demo's Q1->Q3 depends on that guess; the ordinary moves end where
it hardly matters (upper arm at least 30° from vertical, :mod:`tvist.learn.poses`). This
study measures both sides of that:

- :func:`learn_from_paper_map`: the learning sequence of
  ``tests/integration/test_learn.py::test_learning_from_the_published_paper10_map_improves_the_demo_moves``,
  optionally with the converted prior's wrist stiffness given (a what-if: e.g. the twin's
  own, an oracle no prior has, or a gear-size scaling), and the three moves' residual
  vibration reduction with the paper map, the prior and the learned map;
- :func:`third_mode_visibility`: how far above the accelerometer noise the third mode rings
  after each unshaped ordinary move (the noise-free twin's spectral peak near the true third
  mode over the noise's expected spectral level), i.e. whether the learner could fit it.

::

    python -m tvist.experiments.learning_study --seed 3
    python -m tvist.experiments.learning_study --seed 3 --wrists-from-twin
    python -m tvist.experiments.learning_study --seed 3 --wrist-stiffness 4000
"""

from __future__ import annotations

import argparse
import math
import sys
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

import tvist
from tvist.experiments.experiment import run_motion
from tvist.experiments.methods import default_methods, fd_tvist_modal
from tvist.experiments.motions import MOTIONS, PAYLOAD_COM_M, PAYLOAD_KG
from tvist.ident.logs import Record
from tvist.learn import MapLearner
from tvist.learn.decay import DECAY_S, stop_index
from tvist.learn.learner import PRIOR_LOG_SIGMA
from tvist.learn.poses import random_poses
from tvist.learn.prior import converted_prior_log_sigma, modal_prior_from_paper10
from tvist.learn.twin_moves import move, ordinary_moves
from tvist.robots import Robot, ur5e
from tvist.sim import Twin

__all__ = ["LearningResult", "learn_from_paper_map", "third_mode_visibility"]

#: Accelerometer noise of the twin the learner observes, m/s² (as in the demo's campaign).
NOISE_M_S2 = 0.05
#: The wrist joints (1 and 2) whose stiffness the study replaces.
WRIST_JOINTS = (3, 4)
#: Ordinary moves and random poses of the learning sequence.
N_MOVES, N_POSES = 20, 10
#: The third mode's spectral peak is looked for within this relative distance of its true
#: frequency.
PEAK_BAND = 0.15


@dataclass(frozen=True)
class LearningResult:
    """Residual vibration reduction (%) of the demo's moves, by motion name: ``paper``,
    ``prior`` and ``learned`` maps; the learned scale factors and load gains by name; how
    many logs were accepted and how many updated the map; the payload reports (messages;
    the payload is the declared one throughout, so every one is a false alarm)."""

    reduction: dict[str, dict[str, float]]
    scales: dict[str, float]
    accepted: int = 0
    updates: int = 0
    payload_reports: tuple[str, ...] = ()


def _robot() -> Robot:
    return ur5e(payload_kg=PAYLOAD_KG, payload_com_m=PAYLOAD_COM_M)


def _twin(seed: int, noise: float = NOISE_M_S2) -> Twin:
    return Twin(
        "ur5e", payload_kg=PAYLOAD_KG, payload_com_m=PAYLOAD_COM_M, accel_noise_std=noise, seed=seed
    )


def learn_from_paper_map(seed: int, wrist_stiffness: float | None = None) -> LearningResult:
    """The learning sequence from the published map on the default twin (seed ``seed`` for
    its noise and the poses), the converted prior's wrists set to ``wrist_stiffness``
    (N m/rad) if given (the base and shoulder laws fitted with them), then the demo's three
    moves on the noise-free twin."""
    robot = _robot()
    paper = tvist.DynamicMap.paper_ur5e()
    if wrist_stiffness is None:
        learner = MapLearner(robot, paper)
    else:
        converted = modal_prior_from_paper10(
            robot, paper, {j: wrist_stiffness for j in WRIST_JOINTS}
        )
        learner = MapLearner(
            robot,
            converted.map,
            prior_log_sigma=converted_prior_log_sigma(converted, PRIOR_LOG_SIGMA),
        )
    twin = _twin(seed)
    poses = random_poses(robot, N_POSES, np.random.default_rng(seed))
    for record in ordinary_moves(twin, robot, learner, poses, N_MOVES, swap_each_round=True):
        learner.observe(record)
    rows = [m for m in default_methods() if m.key in ("unshaped", "fd-tvist-paper-map")]
    rows += [
        fd_tvist_modal("prior", "prior", learner.prior),
        fd_tvist_modal("learned", "learned", learner.map),
    ]
    quiet = _twin(seed, noise=0.0)
    reduction = {}
    for motion in MOTIONS:
        run = run_motion(motion, rows, quiet, robot, with_slow_down=False)
        reduction[motion.name] = {
            name: float(r.reduction_percent)
            for name, r in zip(("paper", "prior", "learned"), run.runs[1:], strict=True)
        }
    history = learner.history
    return LearningResult(
        reduction,
        learner.scales,
        sum(o.accepted for o in history),
        sum(o.map_updated for o in history),
        tuple(o.payload.message for o in history if o.payload is not None),
    )


def third_mode_visibility(seed: int) -> list[tuple[str, float, float]]:
    """For each unshaped move of the learning sequence's first round and the demo's Q1->Q3:
    ``(move, third mode Hz, peak over noise)``, the noise-free twin's largest Hann-windowed
    spectral magnitude of the tool acceleration (any axis) within :data:`PEAK_BAND` of the
    true third mode at the end pose, over the expected magnitude of the accelerometer noise
    alone (``σ √(Σ w²)``), over the :data:`~tvist.learn.decay.DECAY_S` after the stop. Below
    about 3 the mode is lost in the noise of one log."""
    robot = _robot()
    quiet = _twin(seed, noise=0.0)
    poses = random_poses(robot, N_POSES, np.random.default_rng(seed))
    moves = [(f"pose {k} -> {k + 1}", poses[k], poses[k + 1]) for k in range(0, N_POSES - 1, 2)]
    q1q3 = MOTIONS[1]
    moves.append((q1q3.name, q1q3.q_start, q1q3.q_end))
    out = []
    for name, a, b in moves:
        record = Record.from_rtde_fields(quiet.run(move(a, b, robot)))
        k0 = stop_index(record.target_q)
        n = int(round(DECAY_S / record.dt_s))
        acc = record.tool_accel[k0 : k0 + n]
        window = np.hanning(n)
        spectrum = np.abs(np.fft.rfft((acc - acc.mean(axis=0)) * window[:, None], axis=0))
        freq = np.fft.rfftfreq(n, record.dt_s)
        analysis = quiet.modal_analysis(b)
        third_hz = float(np.sort(analysis.wn_rad_s)[2] / (2 * math.pi))
        band = np.abs(freq / third_hz - 1.0) < PEAK_BAND
        noise = NOISE_M_S2 * math.sqrt(float(window @ window))
        out.append((name, third_hz, float(spectrum[band].max()) / noise))
    return out


def main(argv: Sequence[str] | None = None) -> int:
    p = argparse.ArgumentParser(
        prog="python -m tvist.experiments.learning_study",
        description="Learning from the published map on the twin, and what limits Q1->Q3.",
    )
    p.add_argument("--seed", type=int, default=3, help="noise and pose seed (default 3)")
    group = p.add_mutually_exclusive_group()
    group.add_argument(
        "--wrist-stiffness", type=float, help="replace the prior's wrists 1-2 (N m/rad)"
    )
    group.add_argument(
        "--wrists-from-twin",
        action="store_true",
        help="replace the prior's wrists 1-2 by the twin's own (an oracle)",
    )
    p.add_argument(
        "--visibility", action="store_true", help="also the third mode's ringing over the noise"
    )
    args = p.parse_args(argv)
    if args.wrist_stiffness is not None and not (
        math.isfinite(args.wrist_stiffness) and args.wrist_stiffness > 0
    ):
        print("--wrist-stiffness: must be a positive number (N m/rad)", file=sys.stderr)
        return 2
    wrists = args.wrist_stiffness
    if args.wrists_from_twin:
        k = {float(_twin(args.seed).flex.k1_nm_per_rad[j]) for j in WRIST_JOINTS}
        if len(k) != 1:
            print("--wrists-from-twin: the twin's wrists differ", file=sys.stderr)
            return 2
        wrists = k.pop()
    result = learn_from_paper_map(args.seed, wrists)
    what = "converted prior" if wrists is None else f"wrists {wrists:g} N m/rad"
    print(f"seed {args.seed}, {what}: residual vibration reduction % (paper / prior / learned)")
    for name, r in result.reduction.items():
        print(f"  {name}: {r['paper']:.2f} / {r['prior']:.2f} / {r['learned']:.2f}")
    print("  learned: " + ", ".join(f"{k} {v:.3f}" for k, v in result.scales.items()))
    print(
        f"  {N_MOVES} logs: {result.accepted} accepted, {result.updates} updated the map, "
        f"{len(result.payload_reports)} payload alarms (the declared payload is the true one)"
    )
    for message in result.payload_reports:
        print(f"    {message}")
    if args.visibility:
        print("third mode after unshaped moves (noise-free peak over the noise level):")
        for name, hz, ratio in third_mode_visibility(args.seed):
            print(f"  {name}: {hz:.1f} Hz, {ratio:.3f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
