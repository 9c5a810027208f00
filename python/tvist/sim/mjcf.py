"""MJCF model of a serial revolute arm, generated from :class:`tvist.robots.RobotParams`.

The numbers come only from the robot parameter file (through ``RobotParams`` and ``Payload``);
this module only translates standard DH frames into MuJoCo bodies.

Body layout (standard DH, frame ``i = frame_{i-1} Rz(q_i) Tz(d_i) Tx(a_i) Rx(alpha_i)``):

- body ``link{i}`` (``i = 1..n``) has its origin and axes at ``frame_{i-1} Rz(q_i)``, i.e. the
  joint frame *before* the fixed part of the DH transform. Its hinge ``joint{i}`` turns about
  the body's z axis through its origin, so the hinge angle is the DH angle ``q_i``.
- body ``link{i+1}`` is placed in ``link{i}`` at ``Tz(d_i) Tx(a_i) Rx(alpha_i)``, that is at
  ``pos = (a_i, 0, d_i)`` with the rotation ``Rx(alpha_i)``.
- the inertial data of link ``i`` (given in DH frame ``i``) is mapped into body ``link{i}`` by
  the same fixed transform.
- site ``flange`` is DH frame ``n`` (the UR tool flange), placed in ``link{n}``. The payload is
  rigidly fixed to the flange, so it is lumped into the inertial of ``link{n}`` (a point-mass
  payload has no inertia of its own, which MuJoCo would reject as a separate body).

The hinges carry no springs, armature or damping here: the flexible-joint model applies the gear
spring and damping itself (:mod:`tvist.sim.twin`), so this model's joint-space inertia matrix is
the rigid link-side ``M(q)`` of the robot.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET

import numpy as np

from tvist.robots import Payload, RobotParams, inertia_tensor
from tvist.robots.inertial import NEGLIGIBLE, Inertial, lump
from tvist.robots.rpy import rpy_matrix, rpy_quat
from tvist.sim.beams import LinkBeams, split_link

#: Gravity along -z of the base frame (m/s²); the same value as :class:`tvist.robots.Robot`.
GRAVITY_M_S2 = 9.81


def _fmt(values: np.ndarray | list[float] | tuple[float, ...]) -> str:
    """Space-separated numbers at full double precision."""
    return " ".join(repr(float(v)) for v in np.ravel(values))


def _rot_x(angle_rad: float) -> np.ndarray:
    c, s = math.cos(angle_rad), math.sin(angle_rad)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def _quat_x(angle_rad: float) -> np.ndarray:
    """Unit quaternion ``[w, x, y, z]`` of a rotation about x."""
    return np.array([math.cos(angle_rad / 2.0), math.sin(angle_rad / 2.0), 0.0, 0.0])


def _inertial(
    parent: ET.Element,
    mass_kg: float,
    com_m: np.ndarray,
    inertia_kg_m2: np.ndarray,
) -> None:
    """Add an ``<inertial>`` with a full tensor (kg m², about the COM, axes of ``parent``)."""
    six = [
        inertia_kg_m2[0, 0],
        inertia_kg_m2[1, 1],
        inertia_kg_m2[2, 2],
        inertia_kg_m2[0, 1],
        inertia_kg_m2[0, 2],
        inertia_kg_m2[1, 2],
    ]
    ET.SubElement(
        parent,
        "inertial",
        pos=_fmt(com_m),
        mass=repr(float(mass_kg)),
        fullinertia=_fmt(six),
    )


def _payload_inertial(payload: Payload) -> Inertial:
    tensor = (
        np.zeros((3, 3))
        if payload.inertia_kg_m2 is None
        else inertia_tensor(np.asarray(payload.inertia_kg_m2))
    )
    return payload.mass_kg, np.asarray(payload.com_m, dtype=float), tensor


def _beam_link(
    body: ET.Element,
    i: int,
    offset: np.ndarray,
    mass: float,
    com: np.ndarray,
    inertia: np.ndarray,
    beams: LinkBeams,
) -> tuple[ET.Element, np.ndarray]:
    """Cut link ``i`` (body ``body``, inertial data in its frame) into hinged segments.

    Returns the last segment's body and the next link's position in it.
    """
    length = float(np.linalg.norm(offset))
    segments, axes = split_link(offset, mass, com, inertia, beams.hinges_per_link)
    stiffness = repr(beams.hinge_stiffness_nm_per_rad(length))
    damping = repr(beams.hinge_damping_nms_per_rad(length))
    origin = np.zeros(3)  # the current segment body's origin in the link body's frame
    ends = [seg.hinge_m for seg in segments[1:]] + [offset]
    for s, segment in enumerate(segments):
        if segment.hinge_m is not None:
            body = ET.SubElement(
                body, "body", name=f"link{i + 1}_seg{s}", pos=_fmt(segment.hinge_m - origin)
            )
            origin = segment.hinge_m
            for tag, axis in zip("ab", axes, strict=True):
                ET.SubElement(
                    body,
                    "joint",
                    name=f"link{i + 1}_bend{s}{tag}",
                    type="hinge",
                    axis=_fmt(axis),
                    stiffness=stiffness,
                    damping=damping,
                )
        _inertial(body, segment.mass_kg, segment.com_m - origin, segment.inertia_kg_m2)
        # Visual segment to the next hinge or joint (no mass, no contact).
        ET.SubElement(
            body, "geom", type="capsule", size="0.03", fromto=_fmt([0, 0, 0, *(ends[s] - origin)])
        )
    return body, offset - origin


def build_mjcf(
    params: RobotParams,
    payload: Payload | None = None,
    *,
    physics_dt_s: float = 0.0005,
    beams: LinkBeams | None = None,
) -> str:
    """MJCF text of the rigid arm ``params`` with ``payload`` on the flange.

    Parameters
    ----------
    params
        Robot parameters (standard DH, link masses, centres of mass and inertia tensors).
    payload
        Payload fixed to the flange (DH frame ``n``); ``None`` or zero mass means none.
    physics_dt_s
        Integration time step (s).
    beams
        Links that bend (:mod:`tvist.sim.beams`): each is cut into rigid segments, bodies
        ``link{i}_seg{s}`` (``s = 1 .. n``) with the hinge joints ``link{i}_bend{s}a`` and
        ``link{i}_bend{s}b`` carrying the beam's spring and damper (MJCF ``stiffness`` and
        ``damping``, ``springref`` 0: straight). ``None``: rigid links.

    Returns
    -------
    str
        The MJCF document. Joints are named ``joint1 .. joint{n}``, bodies ``link1 ..
        link{n}``; the flange is site ``flange`` and carries the sensor ``accelerometer``.
    """
    if not (math.isfinite(physics_dt_s) and physics_dt_s > 0.0):
        raise ValueError(f"physics_dt_s must be finite and > 0, got {physics_dt_s!r}")
    n = params.n_dof
    if beams is not None:
        beams.validate(n)
    root = ET.Element("mujoco", model=params.name)
    ET.SubElement(root, "compiler", angle="radian", inertiafromgeom="false", autolimits="true")
    option = ET.SubElement(
        root,
        "option",
        timestep=repr(float(physics_dt_s)),
        gravity=_fmt([0.0, 0.0, -GRAVITY_M_S2]),
        # Implicit in velocity: the dof damping (half of the gear damping) acts on the new
        # velocity; see tvist.sim.twin.
        integrator="implicitfast",
    )
    # No geometry takes part in contacts; the arm only moves freely in space.
    ET.SubElement(option, "flag", contact="disable")
    visual = ET.SubElement(root, "default")
    ET.SubElement(visual, "geom", contype="0", conaffinity="0", group="1", rgba="0.6 0.7 0.8 1")

    parent = ET.SubElement(root, "worldbody")
    if params.placements is not None:
        if beams is not None:
            raise ValueError(f"{params.name}: bending links need a DH arm")
        body, flange_pos, flange_quat = _placed_arm(parent, params, payload)
        return _finish(root, body, flange_pos, flange_quat)
    inertias = params.inertia_tensors_kg_m2
    pos_in_parent = np.zeros(3)
    quat_in_parent = np.array([1.0, 0.0, 0.0, 0.0])
    body = parent
    for i in range(n):
        body = ET.SubElement(
            parent,
            "body",
            name=f"link{i + 1}",
            pos=_fmt(pos_in_parent),
            quat=_fmt(quat_in_parent),
        )
        ET.SubElement(body, "joint", name=f"joint{i + 1}", type="hinge", axis="0 0 1")
        # Fixed part of DH transform i: frame i = (this body frame) Tz(d) Tx(a) Rx(alpha).
        offset = np.array([params.a_m[i], 0.0, params.d_m[i]])
        rotation = _rot_x(float(params.alpha_rad[i]))
        mass = float(params.mass_kg[i])
        com_frame_i = np.asarray(params.com_m[i], dtype=float)
        inertia_frame_i = inertias[i]
        if i == n - 1 and payload is not None:
            # The flange is DH frame n, so the payload is given in the same frame as link n.
            mass, com_frame_i, inertia_frame_i = lump(
                (mass, com_frame_i, inertia_frame_i), _payload_inertial(payload)
            )
        com_body = offset + rotation @ com_frame_i
        inertia_body = rotation @ inertia_frame_i @ rotation.T
        if beams is not None and i in beams.links:
            body, pos_in_parent = _beam_link(body, i, offset, mass, com_body, inertia_body, beams)
        else:
            if mass > NEGLIGIBLE:
                _inertial(body, mass, com_body, inertia_body)
            # Visual segment from the joint axis to the next frame origin (no mass, no contact).
            if np.linalg.norm(offset) > 1e-6:
                ET.SubElement(
                    body, "geom", type="capsule", size="0.03", fromto=_fmt([0, 0, 0, *offset])
                )
            pos_in_parent = offset
        quat_in_parent = _quat_x(float(params.alpha_rad[i]))
        parent = body

    return _finish(root, body, pos_in_parent, quat_in_parent)


def _placed_arm(parent: ET.Element, params: RobotParams, payload: Payload | None):
    """Bodies ``link1 .. link{n}`` of an arm placed as URDF places it: each body is its URDF
    link frame (placed by the joint's origin, hinge about the joint's axis), the link's inertial
    as given; the payload (flange frame) joins the last link. Returns the last body and the
    flange's position and quaternion in it."""
    placed = params.placements
    inertias = params.inertia_tensors_kg_m2
    n = params.n_dof
    flange_rot = rpy_matrix(placed.flange_rpy_rad)
    body = parent
    for i in range(n):
        origin = placed.origin_xyz_m[i]
        body = ET.SubElement(
            parent,
            "body",
            name=f"link{i + 1}",
            pos=_fmt(origin),
            quat=_fmt(rpy_quat(placed.origin_rpy_rad[i])),
        )
        ET.SubElement(body, "joint", name=f"joint{i + 1}", type="hinge", axis=_fmt(placed.axis[i]))
        inertial = (float(params.mass_kg[i]), np.asarray(params.com_m[i]), inertias[i])
        if i == n - 1 and payload is not None:
            mass, com, tensor = _payload_inertial(payload)
            moved = (
                mass,
                placed.flange_xyz_m + flange_rot @ com,
                flange_rot @ tensor @ flange_rot.T,
            )
            inertial = lump(inertial, moved)
        if inertial[0] > NEGLIGIBLE:
            _inertial(body, *inertial)
        next_origin = placed.flange_xyz_m if i == n - 1 else placed.origin_xyz_m[i + 1]
        if np.linalg.norm(next_origin) > 1e-6:
            ET.SubElement(
                body, "geom", type="capsule", size="0.03", fromto=_fmt([0, 0, 0, *next_origin])
            )
        parent = body
    return body, placed.flange_xyz_m, rpy_quat(placed.flange_rpy_rad)


def _finish(root: ET.Element, body: ET.Element, flange_pos, flange_quat) -> str:
    """The flange site and its accelerometer on ``body``; the document's text."""
    ET.SubElement(body, "site", name="flange", pos=_fmt(flange_pos), quat=_fmt(flange_quat))
    sensor = ET.SubElement(root, "sensor")
    ET.SubElement(sensor, "accelerometer", name="accelerometer", site="flange")
    ET.indent(root)
    return ET.tostring(root, encoding="unicode")
