"""Independent reference for the twin's bending links: a continuous Euler-Bernoulli beam.

:func:`clamped_link_frequencies_hz` models one link of the arm as a cantilever beam clamped at
its proximal joint (every joint and every other link held rigid), finite elements with cubic
Hermite shape functions (consistent mass, the exact static stiffness of each element), the
link's mass spread along the beam with a linear density that has the link's mass and centre of
mass, and everything beyond the link (the next links and the payload, with the joints held) a
rigid body fixed to the beam's tip, its mass, centre of mass and inertia from pinocchio's
composite rigid-body inertia. No tvist code (segments, hinges, MuJoCo) takes part; the beam's
rotary inertia and shear are neglected (a slender tube: radius over length ~0.1).
"""

from __future__ import annotations

import numpy as np
import scipy.linalg

from pinocchio_reference import pinocchio_model
from tvist.robots import Payload, RobotParams


def _element_stiffness(h: float) -> np.ndarray:
    return (
        np.array(
            [
                [12.0, 6.0 * h, -12.0, 6.0 * h],
                [6.0 * h, 4.0 * h * h, -6.0 * h, 2.0 * h * h],
                [-12.0, -6.0 * h, 12.0, -6.0 * h],
                [6.0 * h, 2.0 * h * h, -6.0 * h, 4.0 * h * h],
            ]
        )
        / h**3
    )


def _element_mass(h: float) -> np.ndarray:
    return (
        h
        / 420.0
        * np.array(
            [
                [156.0, 22.0 * h, 54.0, -13.0 * h],
                [22.0 * h, 4.0 * h * h, 13.0 * h, -3.0 * h * h],
                [54.0, 13.0 * h, 156.0, -22.0 * h],
                [-13.0 * h, -3.0 * h * h, -22.0 * h, 4.0 * h * h],
            ]
        )
    )


def clamped_link_frequencies_hz(
    p: RobotParams,
    payload: Payload,
    q: np.ndarray,
    link: int,
    bending_stiffness_nm2: float,
    n_elements: int = 40,
) -> np.ndarray:
    """Bending frequencies (Hz, ascending) of link ``link`` (0-based) clamped at its joint.

    The beam runs parallel to the line from joint ``link`` to joint ``link + 1`` through the
    link's centre of mass, from the proximal to the distal joint's plane.
    """
    import pinocchio as pin

    model, _ = pinocchio_model(p, payload)
    data = model.createData()
    pin.forwardKinematics(model, data, np.asarray(q, dtype=float))
    proximal, distal = data.oMi[link + 1], data.oMi[link + 2]
    start, end = proximal.translation, distal.translation
    length = float(np.linalg.norm(end - start))
    axis = (end - start) / length
    # The link's own inertia (the body appended to joint link+1) in the world frame.
    own = proximal.act(model.inertias[link + 1])
    com = own.lever
    sideways = (com - start) - float((com - start) @ axis) * axis
    root = start + sideways
    tip = root + length * axis
    x_com = float((com - root) @ axis)
    # Linear density rho(x) = a + b x with integral m and first moment m x_com.
    m = own.mass
    b = m * (x_com - length / 2.0) * 12.0 / length**3
    a = m / length - b * length / 2.0
    # Everything beyond the link with its joints held (a serial chain: joints link+2 ...,
    # the payload is part of the last joint's body), world frame.
    beyond = pin.Inertia.Zero()
    for j in range(link + 2, model.njoints):
        beyond = beyond + data.oMi[j].act(model.inertias[j])
    r = beyond.lever - tip

    helper = np.array([0.0, 0.0, 1.0]) if abs(axis[2]) < 0.9 else np.array([1.0, 0.0, 0.0])
    a1 = np.cross(axis, helper)
    a1 /= np.linalg.norm(a1)
    a2 = np.cross(axis, a1)
    bending = [(a1, np.cross(a1, axis)), (a2, np.cross(a2, axis))]

    n_nodes = n_elements + 1
    size = 4 * n_nodes  # per node: (w, theta) in plane 1, then plane 2
    stiffness = np.zeros((size, size))
    mass = np.zeros((size, size))
    h = length / n_elements
    k_e, m_e = bending_stiffness_nm2 * _element_stiffness(h), _element_mass(h)
    for e in range(n_elements):
        rho = a + b * (e + 0.5) * h
        for plane in range(2):
            dofs = [4 * e + 2 * plane, 4 * e + 2 * plane + 1]
            dofs += [4 * (e + 1) + 2 * plane, 4 * (e + 1) + 2 * plane + 1]
            stiffness[np.ix_(dofs, dofs)] += k_e
            mass[np.ix_(dofs, dofs)] += rho * m_e
    # Tip body: COM velocity = u' + phi' x r, angular velocity = phi'; the tip node's
    # (w1, theta1, w2, theta2) move the tip by w d and turn it by theta about a.
    velocity = np.zeros((3, 4))
    spin = np.zeros((3, 4))
    for plane, (turn_axis, deflection) in enumerate(bending):
        velocity[:, 2 * plane] = deflection
        velocity[:, 2 * plane + 1] = np.cross(turn_axis, r)
        spin[:, 2 * plane + 1] = turn_axis
    tip_dofs = list(range(4 * n_elements, size))
    mass[np.ix_(tip_dofs, tip_dofs)] += beyond.mass * velocity.T @ velocity
    mass[np.ix_(tip_dofs, tip_dofs)] += spin.T @ beyond.inertia @ spin
    free = slice(4, size)  # node 0 clamped
    omega_sq = scipy.linalg.eigh(stiffness[free, free], mass[free, free], eigvals_only=True)
    return np.sqrt(omega_sq) / (2.0 * np.pi)
