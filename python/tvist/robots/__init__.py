"""Robot models: UR e-Series parameter data, payloads and the rigid-body inertia model.

The numbers live in one file, ``crates/tvist-core/data/ur_e_series.json``, embedded in the
Rust core; :func:`params` reads them from there. :class:`Robot` evaluates the joint-space
inertia, kinematics and gravity torques in the Rust core.

Examples
--------
>>> import tvist
>>> robot = tvist.robots.ur5e(payload_kg=5.0, payload_com_m=(0.0, 0.0, 0.05))
>>> j = robot.joint_inertia([0.0, -3.14159, 0.0, -1.5708, 0.0, 0.0])  # J_0 ... J_5, kg m^2
"""

from __future__ import annotations

from tvist.robots._named import params, ur3e, ur5e, ur10e, ur16e, ur20
from tvist.robots._params import (
    JointPlacements,
    Payload,
    RobotParams,
    elbow_by_axes,
    inertia_tensor,
    names,
    robot_file,
)
from tvist.robots._robot import Robot
from tvist.robots.urdf import (
    SHIPPED_URDFS,
    dh_urdf,
    from_urdf,
    shipped_params,
    shipped_urdf,
    urdf_params,
    write_robot_file,
)

__all__ = [
    "JointPlacements",
    "Payload",
    "Robot",
    "RobotParams",
    "elbow_by_axes",
    "inertia_tensor",
    "names",
    "params",
    "robot_file",
    "dh_urdf",
    "from_urdf",
    "shipped_params",
    "shipped_urdf",
    "SHIPPED_URDFS",
    "urdf_params",
    "write_robot_file",
    "ur3e",
    "ur5e",
    "ur10e",
    "ur16e",
    "ur20",
]
