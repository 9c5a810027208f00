"""Shape a planner's waypoints: a straight Cartesian line, and how far shaping bends it.

A planner (MoveIt, a Cartesian path) hands out time-stamped waypoints. Here: 13 waypoints
(10 Hz) of a 0.3 m straight flange line on a UR5e with a 5 kg payload, solved by inverse
kinematics (Newton steps with the geometric Jacobian, orientation held). ``shape_waypoints``
resamples them to 500 Hz (C² spline, at rest at both ends) and shapes them with FD-TVIST
(the paper's map) and with modified ZTDIS (end-pose modes). Joint-space shaping moves every
joint along its own curve but blends points of the joint-space path that lie apart in time,
so a path that is curved in joint space (a Cartesian line) is cut short: ``path_deviation``
reports how far the flange leaves the planned line.

    python examples/04_planner_waypoints.py
"""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

import tvist
from tvist.analysis import path_deviation
from tvist.analysis.path import point_to_polyline_distance
from tvist.trajectory import shape_waypoints

robot = tvist.robots.ur5e(payload_kg=5.0, payload_com_m=(0.0, 0.0, 0.05))
q_start = np.array([0.0, -2.0, 2.0, -np.pi / 2, -np.pi / 2, 0.0])
pose0 = robot.flange_pose(q_start)


def inverse_kinematics(target_m: np.ndarray, q: np.ndarray) -> np.ndarray:
    """Joint angles that put the flange at ``target_m`` with the start orientation."""
    for _ in range(50):
        pose = robot.flange_pose(q)
        err = np.concatenate(
            [
                target_m - pose[:3, 3],
                Rotation.from_matrix(pose0[:3, :3] @ pose[:3, :3].T).as_rotvec(),
            ]
        )
        if np.max(np.abs(err)) < 1e-12:
            break
        q = q + np.linalg.lstsq(robot.jacobian(q), err, rcond=None)[0]
    return q


# The line: 0.3 m along the base y axis in 1.2 s, minimum-jerk timing, waypoints every 0.1 s.
times_s = 0.1 * np.arange(13)
s = times_s / times_s[-1]
along = 0.3 * s**3 * (10 - 15 * s + 6 * s**2)
waypoints, q = [], q_start
for d in along:
    q = inverse_kinematics(pose0[:3, 3] + np.array([0.0, d, 0.0]), q)
    waypoints.append(q)
waypoints = np.array(waypoints)

provider = tvist.MapDynamics(robot, tvist.DynamicMap.paper_ur5e())
dt_s = robot.params.control_period_s  # the UR5e controller's period, s
planned = shape_waypoints(times_s, waypoints, dt_s, provider).planned
line = pose0[:3, 3] + np.outer([0.0, 0.3], [0.0, 1.0, 0.0])
sag, _ = point_to_polyline_distance(robot.flange_pose_many(planned)[:, :3, 3], line)
print(f"planned: the resampled waypoints stay within {1e3 * sag.max():.3f} mm of the line")
for method in ("tvist", "modified"):
    out = shape_waypoints(times_s, waypoints, dt_s, provider, method=method)
    dev = path_deviation(robot, out.planned, out.q)
    print(
        f"{method:>6}: {out.q.shape[0]} samples, ends {1e3 * out.added_delay_s:.0f} ms after "
        f"the plan; the flange leaves the planned line by at most {1e3 * dev.max_m:.2f} mm "
        f"(at {100 * dev.path_fraction:.0f} % of the line)"
    )
