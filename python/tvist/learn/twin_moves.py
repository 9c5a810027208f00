"""Ordinary moves on the twin to learn from: rest-to-rest double-S moves between random poses
(:func:`tvist.learn.poses.random_poses`) with the demo's limits
(:mod:`tvist.experiments.motions`), unshaped or shaped with a modal map."""

from __future__ import annotations

from collections.abc import Iterator
from typing import TYPE_CHECKING

import numpy as np

import tvist
from tvist.experiments.motions import A_MAX_RAD_S2, JERK_TIME_S, PRE_S, V_MAX_RAD_S
from tvist.maps.modal import ModalMap
from tvist.robots import Robot
from tvist.trajectory import double_s

if TYPE_CHECKING:
    from tvist.learn.learner import MapLearner
    from tvist.sim import SimRecord, Twin

__all__ = ["TAIL_S", "move", "ordinary_moves"]

#: Rest after a move, s: room for the shaper's delay (~0.13 s) and the decay fitted.
TAIL_S = 1.3


def move(
    q_start: np.ndarray,
    q_end: np.ndarray,
    robot: Robot,
    modal_map: ModalMap | None = None,
    tail_s: float = TAIL_S,
) -> np.ndarray:
    """The reference ``(n_samples, 6)`` of a move at the robot's control period
    (:attr:`~tvist.robots.RobotParams.control_period_s`), unshaped, or shaped by the two-mode
    ZV FD-TVIST cascade of ``modal_map``."""
    dt_s = robot.params.sample_period_s()
    traj = double_s(
        q_start,
        q_end,
        dt_s=dt_s,
        v_max=V_MAX_RAD_S,
        a_max=A_MAX_RAD_S2,
        jerk_time_s=JERK_TIME_S,
        t_pre_s=PRE_S,
        t_post_s=tail_s,
    )
    q = np.ascontiguousarray(traj.q)
    if modal_map is None:
        return np.array(q)
    shaper = tvist.TvShaper(tvist.ModalDynamics(robot, modal_map), dt_s, q.shape[1], shaper="zv")
    shaper.reset(np.ascontiguousarray(q[0]))
    return np.array(shaper.shape(q))


def ordinary_moves(
    twin: Twin,
    robot: Robot,
    learner: MapLearner,
    poses: np.ndarray,
    n: int,
    first: int = 0,
    *,
    swap_each_round: bool = False,
) -> Iterator[SimRecord]:
    """The twin's runs of ``n`` moves around ``poses`` (move ``k`` from pose ``k`` to pose
    ``k + 1``, cyclically, from ``k = first``), unshaped and shaped with the learner's current
    map in turn (the map is read when each move starts, so observe each run before the next).

    With an even number of poses the turns fall on the same poses every round, so half of
    them are never reached unshaped; ``swap_each_round`` swaps the turns after each round, so
    that every pose rings unshaped once in two rounds."""
    for k in range(first, first + n):
        a, b = poses[k % len(poses)], poses[(k + 1) % len(poses)]
        turn = k + (k // len(poses) if swap_each_round else 0)
        shaped = learner.map if turn % 2 else None
        yield twin.run(move(a, b, robot, shaped))
