"""Robot models from URDF: the chain from a base link to a tip link, parsed by ``yourdfpy``.

The chain keeps URDF's joint placement (each revolute joint's origin, then its axis); fixed
joints are merged (the links they carry join the moving link before them, their origins join
the next joint's origin or the flange). The tip link is the flange: a payload is given in its
frame. What the model cannot represent is refused with one line naming the element:
prismatic, planar and floating joints, mimic joints on the chain, a moving link without
``<inertial>`` or with zero mass, a tip link not below the base link. Continuous joints are
revolute joints without limits: their limits are taken as ±2π, with a warning.

Examples
--------
>>> robot = tvist.robots.from_urdf("fr3.urdf", "fr3_link0", "fr3_link8", payload_kg=1.0)
>>> write_robot_file(urdf_params("fr3.urdf", "fr3_link0", "fr3_link8"), "fr3.json")
"""

from __future__ import annotations

import json
import math
import warnings
from collections.abc import Sequence
from functools import cache
from pathlib import Path
from typing import Any

import numpy as np

from tvist.robots._params import JointPlacements, Payload, RobotParams
from tvist.robots._robot import Robot
from tvist.robots.inertial import lump
from tvist.robots.rpy import rpy_angles

__all__ = [
    "PROXIMAL_JOINTS",
    "SHIPPED_URDFS",
    "dh_urdf",
    "from_urdf",
    "robot_file_document",
    "shipped_params",
    "shipped_urdf",
    "urdf_params",
    "write_robot_file",
]

#: Limits given to a continuous joint (URDF gives none), rad.
CONTINUOUS_LIMIT_RAD = 2.0 * math.pi

_MOVING = ("revolute", "continuous")


def _body(link: Any, where: str) -> tuple[float, np.ndarray, np.ndarray] | None:
    """(mass, centre of mass, inertia tensor about it) in the link's frame, or None."""
    inertial = link.inertial
    if inertial is None:
        return None
    origin = np.eye(4) if inertial.origin is None else np.asarray(inertial.origin, dtype=float)
    rot = origin[:3, :3]
    mass = float(inertial.mass) if inertial.mass is not None else 0.0
    tensor = np.zeros((3, 3)) if inertial.inertia is None else np.asarray(inertial.inertia)
    values = np.concatenate([[mass], origin[:3, 3], tensor.ravel()])
    if not np.all(np.isfinite(values)):
        raise ValueError(f"{where}: <inertial> of link '{link.name}' is not finite")
    return mass, origin[:3, 3].copy(), rot @ tensor @ rot.T


def _moved(body: tuple[float, np.ndarray, np.ndarray], pose: np.ndarray) -> tuple:
    """``body`` given in a frame whose pose in the target frame is ``pose`` (4x4)."""
    mass, com, tensor = body
    rot = pose[:3, :3]
    return mass, pose[:3, 3] + rot @ com, rot @ tensor @ rot.T


def _chain(urdf: Any, base_link: str, tip_link: str, where: str) -> list[Any]:
    """The joints from ``base_link`` down to ``tip_link``, base first."""
    links = {link.name for link in urdf.robot.links}
    for name, flag in ((base_link, "base_link"), (tip_link, "tip_link")):
        if name not in links:
            raise ValueError(f"{where}: no link '{name}' ({flag}); links: {sorted(links)}")
    parent_joint = {joint.child: joint for joint in urdf.robot.joints}
    path, link = [], tip_link
    while link != base_link:
        joint = parent_joint.get(link)
        if joint is None:
            raise ValueError(
                f"{where}: tip link '{tip_link}' is not below base link '{base_link}' "
                f"(the chain up from it ends at link '{link}')"
            )
        path.append(joint)
        link = joint.parent
    return path[::-1]


def urdf_params(
    path: str | Path,
    base_link: str,
    tip_link: str,
    name: str | None = None,
    max_payload_kg: float = 0.0,
    elbow_joint: int | None = None,
    control_period_s: float | None = None,
) -> RobotParams:
    """Parameters of the serial chain from ``base_link`` to ``tip_link`` of URDF ``path``.

    Parameters
    ----------
    path
        URDF file (meshes are not read).
    base_link, tip_link
        The fixed base (gravity along its ``-z``) and the flange (payload frame).
    name
        Robot name (default: the URDF's robot name); maps identified on it carry it.
    max_payload_kg
        Rated payload (URDF does not give one).
    elbow_joint
        Index of the elbow (URDF does not name one); ``None``: the first joint after the
        shoulder whose axis is parallel to the shoulder's at ``q = 0``
        (:func:`tvist.robots.elbow_by_axes`).
    control_period_s
        Period of the arm controller's control loop, s (URDF does not give one); ``None``:
        unknown, and whatever runs on the arm must be given its ``dt_s``.

    Raises
    ------
    ValueError
        One line naming the element the model cannot represent (see the module docstring).
    """
    import yourdfpy

    where = str(path)
    try:
        urdf = yourdfpy.URDF.load(
            str(path),
            build_scene_graph=False,
            build_collision_scene_graph=False,
            load_meshes=False,
            load_collision_meshes=False,
        )
    except Exception as exc:  # yourdfpy raises assorted errors for malformed XML
        if isinstance(exc, OSError):
            raise
        raise ValueError(f"{where}: not a readable URDF ({exc})") from None
    link_by_name = {link.name: link for link in urdf.robot.links}
    origin_xyz, origin_rpy, axes, limits, speeds = [], [], [], [], []
    bodies: list[tuple] = []
    to_current = np.eye(4)  # pose of the frame reached so far in the last moving link's frame
    for joint in _chain(urdf, base_link, tip_link, where):
        origin = np.eye(4) if joint.origin is None else np.asarray(joint.origin, dtype=float)
        child = link_by_name[joint.child]
        if joint.type == "fixed":
            to_current = to_current @ origin
            body = _body(child, where)
            if bodies and body is not None:  # links fixed to the base do not move
                bodies[-1] = lump(bodies[-1], _moved(body, to_current))
            continue
        if joint.type not in _MOVING:
            raise ValueError(
                f"{where}: joint '{joint.name}' is {joint.type}: only revolute, continuous and "
                "fixed joints are supported"
            )
        if joint.mimic is not None:
            raise ValueError(
                f"{where}: joint '{joint.name}' mimics joint '{joint.mimic.joint}': mimic "
                "joints are not supported"
            )
        pose = to_current @ origin
        to_current = np.eye(4)
        axis = np.asarray(joint.axis if joint.axis is not None else (1.0, 0.0, 0.0), float)
        if not (np.all(np.isfinite(axis)) and np.linalg.norm(axis) > 0.0):
            raise ValueError(f"{where}: joint '{joint.name}' has axis {axis.tolist()}")
        body = _body(child, where)
        if body is None:
            raise ValueError(f"{where}: link '{child.name}' has no <inertial>")
        if not body[0] > 0.0:
            raise ValueError(f"{where}: link '{child.name}' has mass {body[0]} kg (must be > 0)")
        origin_xyz.append(pose[:3, 3])
        origin_rpy.append(rpy_angles(pose[:3, :3]))
        axes.append(axis / np.linalg.norm(axis))
        bodies.append(body)
        limits.append(_limits(joint, where))
        speeds.append(_speed(joint, where))
    if not bodies:
        raise ValueError(f"{where}: no revolute joint between '{base_link}' and '{tip_link}'")
    placements = JointPlacements(
        origin_xyz_m=np.array(origin_xyz),
        origin_rpy_rad=np.array(origin_rpy),
        axis=np.array(axes),
        flange_xyz_m=to_current[:3, 3],
        flange_rpy_rad=np.array(rpy_angles(to_current[:3, :3])),
    )
    six = [[t[0, 0], t[1, 1], t[2, 2], t[0, 1], t[0, 2], t[1, 2]] for _, _, t in bodies]
    robot_name = name or urdf.robot.name or Path(path).stem
    return RobotParams(
        name=robot_name,
        description=f"{robot_name}: chain {base_link} -> {tip_link} of {Path(path).name}",
        source=f"URDF {Path(path).name} (joint origins, axes, limits)",
        d_m=None,
        a_m=None,
        alpha_rad=None,
        mass_kg=np.array([b[0] for b in bodies]),
        com_m=np.array([b[1] for b in bodies]),
        inertia_kg_m2=np.array(six),
        inertia_source=f"URDF {Path(path).name} <inertial> (fixed links merged)",
        joint_limits_rad=np.array(limits),
        max_velocity_rad_s=np.array(speeds),
        max_payload_kg=max_payload_kg,
        placements=placements,
        elbow_joint=elbow_joint,
        control_period_s=control_period_s,
    )


def _limits(joint: Any, where: str) -> tuple[float, float]:
    if joint.type == "continuous":
        warnings.warn(
            f"{where}: joint '{joint.name}' is continuous: its limits are taken as "
            f"±{CONTINUOUS_LIMIT_RAD:.4f} rad",
            stacklevel=3,
        )
        return -CONTINUOUS_LIMIT_RAD, CONTINUOUS_LIMIT_RAD
    limit = joint.limit
    lower = None if limit is None else limit.lower
    upper = None if limit is None else limit.upper
    if lower is None or upper is None or not lower < upper:
        raise ValueError(
            f"{where}: joint '{joint.name}' needs <limit lower upper> with lower < upper, got "
            f"{lower}, {upper}"
        )
    return float(lower), float(upper)


def _speed(joint: Any, where: str) -> float:
    speed = None if joint.limit is None else joint.limit.velocity
    if speed is None or not speed > 0.0:
        raise ValueError(f"{where}: joint '{joint.name}' needs <limit velocity> > 0, got {speed}")
    return float(speed)


def from_urdf(
    path: str | Path,
    base_link: str,
    tip_link: str,
    payload_kg: float = 0.0,
    payload_com_m: Sequence[float] = (0.0, 0.0, 0.0),
    payload_inertia_kg_m2: Sequence[float] | None = None,
    name: str | None = None,
) -> Robot:
    """The rigid-body model of the chain ``base_link`` → ``tip_link`` of URDF ``path`` with a
    payload on the tip link (centre of mass and inertia in its frame). See
    :func:`urdf_params`."""
    params = urdf_params(path, base_link, tip_link, name=name)
    return Robot(params, Payload(payload_kg, tuple(payload_com_m), payload_inertia_kg_m2))


def robot_file_document(params: RobotParams) -> dict[str, Any]:
    """The robot-data document (one robot) of ``params`` placed by URDF joints: what the core
    reads (``tvist_shaper_new_map`` with a ``.json`` robot, :func:`tvist.robots.robot_file`)."""
    placed = params.placements
    if placed is None:
        raise ValueError(f"{params.name}: a robot file is written for URDF-placed joints")

    def rows(a: np.ndarray) -> list:
        return np.asarray(a, dtype=float).tolist()

    entry = {
        "description": params.description,
        "source": params.source,
        "inertia_source": params.inertia_source,
        "joints": [
            {"origin_xyz_m": xyz, "origin_rpy_rad": rpy, "axis": axis}
            for xyz, rpy, axis in zip(
                rows(placed.origin_xyz_m),
                rows(placed.origin_rpy_rad),
                rows(placed.axis),
                strict=True,
            )
        ],
        "flange": {
            "origin_xyz_m": rows(placed.flange_xyz_m),
            "origin_rpy_rad": rows(placed.flange_rpy_rad),
        },
        "mass_kg": rows(params.mass_kg),
        "com_m": rows(params.com_m),
        "inertia_kg_m2": rows(params.inertia_kg_m2),
        "joint_limits_rad": rows(params.joint_limits_rad),
        "max_velocity_rad_s": rows(params.max_velocity_rad_s),
        "max_payload_kg": params.max_payload_kg,
    }
    if params.control_period_s is not None:  # optional in the schema: written when known
        entry["control_period_s"] = params.control_period_s
    return {
        "schema_version": 1,
        "conventions": (
            "Joints placed as URDF places them: joint i's origin (origin_xyz_m, then "
            "origin_rpy_rad = roll, pitch, yaw about fixed axes) in the frame of the link "
            "before it, then the turn about axis; link i (mass_kg, com_m, inertia_kg_m2 = "
            "[ixx, iyy, izz, ixy, ixz, iyz] about the centre of mass) in the link frame after "
            "joint i; the flange frame's origin in the last link's frame. Gravity along -z of "
            "the base. Link side only, no rotor inertia. control_period_s (optional): the "
            "period of the arm controller's control loop, s."
        ),
        "robots": {params.name: entry},
    }


def write_robot_file(params: RobotParams, out: str | Path) -> None:
    """Write :func:`robot_file_document` to ``out`` (doubles written to round-trip)."""
    Path(out).write_text(json.dumps(robot_file_document(params), indent=2) + "\n")


def dh_urdf(params: RobotParams) -> str:
    """A URDF of a DH arm (meshes left out), from its parameters: link ``link_k`` is DH frame
    ``k - 1`` turned by joint ``k - 1`` (``base_link`` the base), so joint ``k``'s origin is the
    DH step ``Tz(d) Tx(a) Rx(α)`` of the joint before it and every axis is ``z``; each link's
    ``<inertial>`` frame is the DH frame it is given in; a fixed joint carries the ``flange``
    link (DH frame ``n``)."""
    import xml.etree.ElementTree as ET

    if params.placements is not None:
        raise ValueError(f"{params.name}: not a DH arm")

    def f(values: Sequence[float]) -> str:
        return " ".join(repr(float(v)) for v in values)

    def step(k: int) -> dict[str, str]:
        return {
            "xyz": f((params.a_m[k], 0.0, params.d_m[k])),
            "rpy": f((params.alpha_rad[k], 0.0, 0.0)),
        }

    robot = ET.Element("robot", name=params.name)
    ET.SubElement(robot, "link", name="base_link")
    n = params.n_dof
    for k in range(n):
        link = ET.SubElement(robot, "link", name=f"link_{k + 1}")
        inertial = ET.SubElement(link, "inertial")
        alpha = float(params.alpha_rad[k])
        c, s = math.cos(alpha), math.sin(alpha)
        com = np.asarray(params.com_m[k])
        rot_com = np.array([com[0], c * com[1] - s * com[2], s * com[1] + c * com[2]])
        offset = np.array([params.a_m[k], 0.0, params.d_m[k]]) + rot_com
        ET.SubElement(inertial, "origin", xyz=f(offset), rpy=f((alpha, 0.0, 0.0)))
        ET.SubElement(inertial, "mass", value=repr(float(params.mass_kg[k])))
        ixx, iyy, izz, ixy, ixz, iyz = (repr(float(v)) for v in params.inertia_kg_m2[k])
        ET.SubElement(inertial, "inertia", ixx=ixx, iyy=iyy, izz=izz, ixy=ixy, ixz=ixz, iyz=iyz)
        joint = ET.SubElement(robot, "joint", name=f"joint_{k + 1}", type="revolute")
        ET.SubElement(joint, "parent", link="base_link" if k == 0 else f"link_{k}")
        ET.SubElement(joint, "child", link=f"link_{k + 1}")
        origin = {"xyz": "0 0 0", "rpy": "0 0 0"} if k == 0 else step(k - 1)
        ET.SubElement(joint, "origin", **origin)
        ET.SubElement(joint, "axis", xyz="0 0 1")
        lower, upper = params.joint_limits_rad[k]
        ET.SubElement(
            joint,
            "limit",
            lower=repr(float(lower)),
            upper=repr(float(upper)),
            velocity=repr(float(params.max_velocity_rad_s[k])),
            effort="0",
        )
    ET.SubElement(robot, "link", name="flange")
    flange = ET.SubElement(robot, "joint", name="flange_joint", type="fixed")
    ET.SubElement(flange, "parent", link=f"link_{n}")
    ET.SubElement(flange, "child", link="flange")
    ET.SubElement(flange, "origin", **step(n - 1))
    ET.indent(robot)
    return ET.tostring(robot, encoding="unicode") + "\n"


#: The joints of a URDF-placed arm that may be flexible (a modal map's candidates, the
#: joints a twin of it makes flexible): the proximal joints up to the elbow, which carry
#: the big gears and most of the arm's inertia (joints 1-4 of a 7-joint arm). The wrist's
#: small gears ring far above them; and the modal core solves at most 6 flexible joints.
PROXIMAL_JOINTS: tuple[int, ...] = (0, 1, 2, 3)

#: The arms shipped as URDF data (``urdf_data/``, provenance and license in each file):
#: name → (file, base link, tip link, rated payload in kg, elbow joint, control period in s).
#: URDF gives no rated payload; the makers' data sheets do: Franka Research 3 3 kg, KUKA LBR
#: iiwa 14 R820 14 kg, Kinova Gen3 (7 DOF) 4 kg at mid-range. Nor does it name the elbow: on
#: all three joint 2 turns the upper arm about its own axis and joint 3 is the elbow (the
#: makers' "joint 4"). Nor the control period; the makers' real-time interfaces do:
#: FR3 1 ms (libfranka's 1 kHz control loop), iiwa14 1 ms (FRI, the Fast Robot Interface: its
#: send period is configurable, 1 ms the fastest and the one used here), Gen3 1 ms (the Kortex
#: API's 1 kHz low-level servoing).
SHIPPED_URDFS: dict[str, tuple[str, str, str, float, int, float]] = {
    "fr3": ("fr3.urdf", "fr3_link0", "fr3_link8", 3.0, 3, 0.001),
    "iiwa14": ("iiwa14.urdf", "iiwa_link_0", "iiwa_link_ee", 14.0, 3, 0.001),
    "gen3": ("gen3.urdf", "base_link", "end_effector_link", 4.0, 3, 0.001),
}


def shipped_urdf(name: str) -> tuple[Path, str, str]:
    """``(path, base_link, tip_link)`` of shipped arm ``name`` (one of :data:`SHIPPED_URDFS`)."""
    if name not in SHIPPED_URDFS:
        raise ValueError(f"unknown shipped arm {name!r}; known: {', '.join(SHIPPED_URDFS)}")
    file, base, tip, *_ = SHIPPED_URDFS[name]
    return Path(__file__).parent / "urdf_data" / file, base, tip


@cache
def shipped_params(name: str) -> RobotParams:
    """Parameters of shipped arm ``name`` (its chain, rated payload, elbow and control
    period), read once; :func:`tvist.robots.params` serves them under the same names."""
    path, base, tip = shipped_urdf(name)
    *_, payload_kg, elbow, period_s = SHIPPED_URDFS[name]
    with warnings.catch_warnings():
        # Gen3's continuous joints get ±2π limits: stated in the module docstring.
        warnings.simplefilter("ignore")
        return urdf_params(
            path,
            base,
            tip,
            name=name,
            max_payload_kg=payload_kg,
            elbow_joint=elbow,
            control_period_s=period_s,
        )
