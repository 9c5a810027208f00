"""A campaign plan written out for one's own robot: what ``tvist plan`` writes.

For each pose of the plan (:func:`~tvist.ident.pose_plan.plan_poses`, payload by payload) and
each excited joint (base, shoulder and the robot's elbow by default,
:func:`~tvist.ident.excited.default_excited_joints`; lowest first) the folder gets the excitation as
a URScript program (``NNN_KEY_jointJ.script``, :func:`~tvist.ident.excitation.to_urscript`:
approach, standstill, moves) and as a trajectory CSV (``NNN_KEY_jointJ.csv``), and
``plan.json`` lists them in order with the poses and the time the robot will be busy.
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from tvist.ident.excitation import to_urscript, write_trajectory_csv
from tvist.ident.excited import excited_joints
from tvist.ident.pose_plan import CampaignPose, pose_excitations
from tvist.robots import params
from tvist.trajectory.scalar_trapezoid import trapezoid_duration
from tvist.units import check_trajectory

__all__ = ["APPROACH_ACCEL_RAD_S2", "APPROACH_SPEED_RAD_S", "PlanSummary", "write_plan"]

#: The approach move of each program to its pose: slow, the arm crosses the workspace.
APPROACH_SPEED_RAD_S = 0.3
APPROACH_ACCEL_RAD_S2 = 0.5


@dataclass(frozen=True)
class PlanSummary:
    """What a written plan holds.

    Attributes
    ----------
    path
        ``plan.json``.
    n_poses, n_excitations
        Reachable poses and excitation programs written.
    payloads_kg
        The payloads in the order they are mounted.
    excitation_s, approach_s
        Time the excitations (standstills included) and the approach moves between them
        take, s (the move to the first pose not counted: it depends on where the arm is).
    unreachable
        Keys of the poses left out (no inverse kinematics solution).
    """

    path: Path
    n_poses: int
    n_excitations: int
    payloads_kg: tuple[float, ...]
    excitation_s: float
    approach_s: float
    unreachable: tuple[str, ...]

    @property
    def busy_s(self) -> float:
        return self.excitation_s + self.approach_s


def write_plan(
    poses: Sequence[CampaignPose],
    folder: str | Path,
    *,
    robot_name: str,
    duration_s: float = 8.0,
    approach_speed_rad_s: float = APPROACH_SPEED_RAD_S,
    approach_accel_rad_s2: float = APPROACH_ACCEL_RAD_S2,
    joints: Sequence[int] | None = None,
) -> PlanSummary:
    """Write the programs, trajectories and ``plan.json`` of ``poses`` (in their order) into
    ``folder`` (created; files of an earlier plan with the same names are replaced), an
    excitation of each of ``joints`` per pose (:func:`~tvist.ident.excited.excited_joints`;
    ``None``: the robot's default), each ``duration_s`` (s) long."""
    joints = excited_joints(joints, robot_name)
    robot_params = params(robot_name)
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    entries = []
    excitation_s = approach_s = 0.0
    q_prev: np.ndarray | None = None
    number = 0
    for pose in poses:
        if pose.q is None:
            continue
        excitations = []
        for excitation in pose_excitations(pose, duration_s, joints, robot_name=robot_name):
            number += 1
            stem = f"{number:03d}_{pose.key}_joint{excitation.joint}"
            # As every trajectory written for a robot: inside its joint and speed limits.
            check_trajectory(excitation.q, excitation.dt_s, robot_params, what=f"excitation {stem}")
            script = folder / f"{stem}.script"
            script.write_text(
                to_urscript(
                    excitation,
                    approach_speed_rad_s=approach_speed_rad_s,
                    approach_accel_rad_s2=approach_accel_rad_s2,
                )
            )
            trajectory = write_trajectory_csv(excitation, folder / f"{stem}.csv")
            if q_prev is not None:
                distance = float(np.max(np.abs(excitation.q0 - q_prev)))
                approach_s += trapezoid_duration(
                    distance, approach_speed_rad_s, approach_accel_rad_s2
                )[0]
            excitation_s += excitation.duration_s
            q_prev = excitation.q[-1]
            excitations.append(
                {
                    "joint": excitation.joint,
                    "seed": excitation.seed,
                    "duration_s": excitation.duration_s,
                    "script": script.name,
                    "trajectory": trajectory.name,
                }
            )
        entries.append(
            {
                "key": pose.key,
                "payload_kg": pose.payload_kg,
                "payload_com_m": list(pose.payload_com_m),
                "angle_rad": pose.angle_rad,
                "radius_m": pose.radius_m,
                "q": [float(v) for v in pose.q],
                "excitations": excitations,
            }
        )
    payloads = tuple(dict.fromkeys(e["payload_kg"] for e in entries))
    summary = PlanSummary(
        path=folder / "plan.json",
        n_poses=len(entries),
        n_excitations=number,
        payloads_kg=payloads,
        excitation_s=excitation_s,
        approach_s=approach_s,
        unreachable=tuple(p.key for p in poses if p.q is None),
    )
    plan = {
        "robot": robot_name,
        "duration_s": duration_s,
        "excited_joints": list(joints),
        "approach_speed_rad_s": approach_speed_rad_s,
        "approach_accel_rad_s2": approach_accel_rad_s2,
        "payloads_kg": list(payloads),
        "busy_s": summary.busy_s,
        "unreachable": list(summary.unreachable),
        "poses": entries,
    }
    summary.path.write_text(json.dumps(plan, indent=2) + "\n")
    return summary
