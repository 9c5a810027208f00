"""Random poses to learn at: the upper arm far enough from vertical and the flange far enough
from the base axis that the base mode shows at the flange (:func:`random_poses`)."""

from __future__ import annotations

import numpy as np

from tvist.robots import Robot

__all__ = ["ELBOW_RANGE", "MIN_RADIUS_M", "SHOULDER_RANGE", "random_poses"]

#: Ranges of the random poses, rad: any base angle; the upper arm from horizontal to 30° short
#: of vertical (pointing up, the base mode is a torsion of the wrists); the elbow from
#: stretched to folded like Q3; the wrists as in the test poses.
SHOULDER_RANGE = (-np.pi, -np.pi / 2 - np.pi / 6)
ELBOW_RANGE = (0.0, 5 * np.pi / 6)
#: Fewest metres of the flange from the base axis (the base mode's tangential direction).
MIN_RADIUS_M = 0.25


def random_poses(robot: Robot, n: int, rng: np.random.Generator) -> np.ndarray:
    """``n`` random poses ``(n, 6)`` in the ranges above, flange at least :data:`MIN_RADIUS_M`
    from the base axis."""
    poses: list[np.ndarray] = []
    while len(poses) < n:
        q = np.array(
            [
                rng.uniform(-np.pi, np.pi),
                rng.uniform(*SHOULDER_RANGE),
                rng.uniform(*ELBOW_RANGE),
                -np.pi / 2,
                0.0,
                0.0,
            ]
        )
        xyz = robot.flange_pose_many(q[None, :])[0, :3, 3]
        if np.hypot(xyz[0], xyz[1]) >= MIN_RADIUS_M:
            poses.append(q)
    return np.array(poses)
