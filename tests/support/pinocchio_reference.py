"""Independent references built with pinocchio, for tests (the library never imports this).

- :func:`pinocchio_model`: the rigid arm from the robot's DH parameters, one revolute-z joint
  per DH row placed by the previous row's fixed transform ``Tz(d) Tx(a) Rx(alpha)``, each
  link's inertia moved into its joint frame by pinocchio's own ``SE3.act``; no tvist
  kinematics or dynamics.
- :func:`flexible_joint_modes`: the vibration modes of the flexible-joint arm (motors held,
  gear springs and dampers of :class:`tvist.sim.FlexParams`) at rest, from pinocchio's mass
  matrix, gravity torque and its analytic derivative, with the gear laws written out here from
  their documentation (eqs. 22, 23 and 35): a path independent of the twin's MuJoCo model,
  its equilibrium solver, its finite-difference gravity stiffness and its modal analysis.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg

import tvist
from tvist.robots import Payload, RobotParams


def _pin():
    import pinocchio

    return pinocchio


def _fixed_dh(d: float, a: float, alpha: float):
    pin = _pin()
    return pin.SE3(pin.utils.rotate("x", alpha), np.array([a, 0.0, d]))


def pinocchio_model(p: RobotParams, payload: Payload):
    """``(model, flange_frame_id)``: the rigid arm with its payload as a pinocchio model."""
    pin = _pin()
    model = pin.Model()
    parent, placement = 0, pin.SE3.Identity()
    for i in range(p.n_dof):
        joint = model.addJoint(parent, pin.JointModelRZ(), placement, f"joint_{i}")
        to_link = _fixed_dh(p.d_m[i], p.a_m[i], p.alpha_rad[i])
        link = pin.Inertia(p.mass_kg[i], p.com_m[i], p.inertia_tensors_kg_m2[i])
        model.appendBodyToJoint(joint, to_link.act(link), pin.SE3.Identity())
        parent, placement = joint, to_link
    if payload.mass_kg > 0:
        six = np.zeros(6) if payload.inertia_kg_m2 is None else payload.inertia_kg_m2
        tensor = tvist.robots.inertia_tensor(six)
        body = pin.Inertia(payload.mass_kg, np.asarray(payload.com_m), tensor)
        model.appendBodyToJoint(parent, placement.act(body), pin.SE3.Identity())
    flange = model.addFrame(pin.Frame("flange", parent, placement, pin.FrameType.OP_FRAME))
    return model, flange


@dataclass(frozen=True)
class ReferenceModes:
    """Modes of the linearised flexible-joint arm, sorted by natural frequency.

    ``wn_rad_s``, ``zeta``: ``(n_modes,)``; ``shapes``: complex link-side deflection shapes
    ``(n_dof, n_modes)``; ``energy``: share of each mode's gear strain energy per joint
    ``(n_dof, n_modes)``; ``q_link``: the static link angles ``(n_dof,)``; ``mass``,
    ``damping``, ``stiffness``: the matrices of ``M x'' + C x' + K x = 0``.
    """

    wn_rad_s: np.ndarray
    zeta: np.ndarray
    shapes: np.ndarray
    energy: np.ndarray
    q_link: np.ndarray
    mass: np.ndarray
    damping: np.ndarray
    stiffness: np.ndarray

    def dominant(self, joint: int, exclude: tuple[int, ...] = ()) -> int:
        """Index of the mode with the largest share of strain energy in ``joint``."""
        share = self.energy[joint].copy()
        share[list(exclude)] = -np.inf
        return int(np.argmax(share))

    def base_and_shoulder(self) -> list[tuple[float, float]]:
        """``[(wn, zeta) base, (wn, zeta) shoulder]``."""
        base = self.dominant(0)
        shoulder = self.dominant(1, exclude=(base,))
        return [(float(self.wn_rad_s[i]), float(self.zeta[i])) for i in (base, shoulder)]


def urdf_pinocchio_model(path, tip_link: str, payload: Payload):
    """pinocchio's model of URDF ``path`` (its own parser, no tvist code) with ``payload`` on
    ``tip_link`` (centre of mass and inertia in that link's frame)."""
    pin = _pin()
    model = pin.buildModelFromUrdf(str(path))
    frame = model.frames[model.getFrameId(tip_link)]
    six = np.zeros(6) if payload.inertia_kg_m2 is None else np.asarray(payload.inertia_kg_m2)
    tensor = tvist.robots.inertia_tensor(six)
    body = pin.Inertia(payload.mass_kg, np.asarray(payload.com_m), tensor)
    model.appendBodyToJoint(frame.parentJoint, frame.placement.act(body), pin.SE3.Identity())
    return model


def flexible_joint_modes(
    p: RobotParams,
    payload: Payload,
    flex,
    q_motor: np.ndarray,
    gravity_m_s2: float = 9.81,
    model=None,
) -> ReferenceModes:
    """Modes at rest with the motors at ``q_motor`` (see the module docstring); ``model``:
    the pinocchio model (default :func:`pinocchio_model` of the DH arm ``p``), e.g.
    :func:`urdf_pinocchio_model` of a URDF arm (revolute joints only).

    Static equilibrium: the gear spring ``k1 δ + k3 δ³`` carries the gravity torque ``g(q)``,
    ``δ = q_motor − q``, solved by Newton with the Jacobian ``−K_gear(δ) − ∂g/∂q``.
    Linearised about it: ``M ẍ + C ẋ + (K_gear + ∂g/∂q) x = 0``, ``C`` the gear damping
    ``c0 (1 + c_load |L|_s)(1 + c_load2 |L|_s)`` at the static spring torques.
    """
    pin = _pin()
    if model is None:
        model, _ = pinocchio_model(p, payload)
    model.gravity.linear = np.array([0.0, 0.0, -gravity_m_s2])
    data = model.createData()
    k1 = np.asarray(flex.k1_nm_per_rad, dtype=float)
    k3 = np.asarray(flex.k3_nm_per_rad3, dtype=float)
    q_motor = np.asarray(q_motor, dtype=float)

    def gravity(q):
        return pin.computeGeneralizedGravity(model, data, q).copy()

    def gravity_stiffness(q):
        return pin.computeGeneralizedGravityDerivatives(model, data, q).copy()

    q = q_motor.copy()
    for _ in range(50):
        delta = q_motor - q
        spring = k1 * delta + k3 * delta**3
        residual = spring - gravity(q)
        jac = -np.diag(k1 + 3.0 * k3 * delta**2) - gravity_stiffness(q)
        step = np.linalg.solve(jac, -residual)
        q = q + step
        if np.max(np.abs(step)) < 1e-15:
            break
    delta = q_motor - q
    tau = k1 * delta + k3 * delta**3
    gear = k1 + 3.0 * k3 * delta**2
    stiffness = np.diag(gear) + gravity_stiffness(q)
    load_joint = (
        np.arange(q.size) if flex.damper_load_joint is None else np.asarray(flex.damper_load_joint)
    )
    s = flex.load_smoothing_nm
    load = np.sqrt(tau[load_joint] ** 2 + s * s) - s
    c_load2 = np.zeros(q.size) if flex.c_load2_per_nm is None else np.asarray(flex.c_load2_per_nm)
    damping = np.diag(
        np.asarray(flex.c0_nms_per_rad)
        * (1.0 + np.asarray(flex.c_load_per_nm) * load)
        * (1.0 + c_load2 * load)
    )
    mass = pin.crba(model, data, q).copy()
    mass = np.triu(mass) + np.triu(mass, 1).T  # crba fills the upper triangle
    n = q.size
    # Generalised eigenproblem of the first-order form, A v = λ B v.
    a = np.block([[np.zeros((n, n)), np.eye(n)], [-stiffness, -damping]])
    b = np.block([[np.eye(n), np.zeros((n, n))], [np.zeros((n, n)), mass]])
    lam, vec = scipy.linalg.eig(a, b)
    keep = lam.imag > 0.0
    lam, shapes = lam[keep], vec[:n, keep]
    order = np.argsort(np.abs(lam))
    lam, shapes = lam[order], shapes[:, order]
    shapes = shapes / shapes[np.argmax(np.abs(shapes), axis=0), np.arange(shapes.shape[1])]
    energy = gear[:, None] * np.abs(shapes) ** 2
    energy /= energy.sum(axis=0, keepdims=True)
    wn = np.abs(lam)
    return ReferenceModes(wn, -lam.real / wn, shapes, energy, q, mass, damping, stiffness)
