"""A flexible payload on the flexible arm: a mass on a compliant mount with a tip accelerometer.

The zero-delay paper's experiment mounts a flexible payload (one mode at 2.55 Hz, ζ 0.04) on
the robot's flange and measures the acceleration at its tip. Here the payload is a point mass
on a linear spring-damper mount at the flange, free to deflect along the three flange axes
(MuJoCo slide joints) and tuned *on a rigid flange*: stiffness ``k = m ω²`` and damping
``c = 2 ζ m ω`` per axis, so that alone it rings at ``freq_hz`` with damping ``zeta``. On the
flexible arm the mode couples with the joint modes and shifts slightly (the experiment measures
where it rings).

The arm is the twin's flexible-joint arm (:mod:`tvist.sim.twin`): the motors follow the
reference exactly (linear interpolation at the physics rate), each gear is the spring and
load-dependent damper of :class:`~tvist.sim.FlexParams`, with the same semi-implicit
(trapezoidal) treatment of the gear damping. The MJCF is the twin's arm
(:func:`~tvist.sim.build_mjcf`) with the payload body appended below the flange.

Arrays are ``(n_samples, ...)`` with time along rows; SI units.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from tvist import robots
from tvist.sim.flex import FlexParams, default_flex
from tvist.sim.mjcf import GRAVITY_M_S2, build_mjcf

__all__ = ["FlexiblePayload", "PayloadRecord", "PayloadTwin"]


@dataclass(frozen=True)
class FlexiblePayload:
    """A point mass on a compliant mount at the flange.

    Attributes
    ----------
    freq_hz
        Natural (undamped) frequency of the mount on a rigid flange, Hz.
    zeta
        Damping ratio of the mount on a rigid flange.
    mass_kg
        The mass at the tip.
    offset_m
        Rest position of the mass (and of its accelerometer) in the flange frame, m; the
        mount deflects it along the three flange axes.
    """

    freq_hz: float = 2.55
    zeta: float = 0.04
    mass_kg: float = 2.0
    offset_m: tuple[float, float, float] = (0.0, 0.0, 0.15)

    def __post_init__(self) -> None:
        for name in ("freq_hz", "mass_kg"):
            value = float(getattr(self, name))
            if not (math.isfinite(value) and value > 0.0):
                raise ValueError(f"FlexiblePayload.{name} must be finite and > 0, got {value!r}")
        if not (math.isfinite(self.zeta) and 0.0 <= self.zeta < 1.0):
            raise ValueError(f"FlexiblePayload.zeta must be in [0, 1), got {self.zeta!r}")
        if len(self.offset_m) != 3 or not all(math.isfinite(v) for v in self.offset_m):
            raise ValueError(
                f"FlexiblePayload.offset_m must be 3 finite values, got {self.offset_m!r}"
            )

    @property
    def wn_rad_s(self) -> float:
        """Natural frequency on a rigid flange, rad/s."""
        return 2.0 * math.pi * self.freq_hz

    @property
    def stiffness_n_per_m(self) -> float:
        """Mount stiffness per axis ``m ω²``, N/m."""
        return self.mass_kg * self.wn_rad_s**2

    @property
    def damping_ns_per_m(self) -> float:
        """Mount damping per axis ``2 ζ m ω``, N s/m."""
        return 2.0 * self.zeta * self.mass_kg * self.wn_rad_s


#: Radius of the sphere whose inertia the payload mass gets (m); the mount has no rotational
#: freedom, so this only keeps MuJoCo's body inertia valid.
_MASS_RADIUS_M = 0.03


def build_payload_mjcf(
    params: robots.RobotParams, payload: FlexiblePayload, physics_dt_s: float
) -> str:
    """MJCF of the arm ``params`` with ``payload`` hanging on its flange.

    Adds body ``payload`` with slide joints ``payload_x/y/z`` (flange axes) and site
    ``payload_tip`` carrying the sensor ``payload_accelerometer``.
    """
    root = ET.fromstring(build_mjcf(params, None, physics_dt_s=physics_dt_s))
    last_link = root.find(f".//body[@name='link{params.n_dof}']")
    flange = root.find(".//site[@name='flange']")
    if last_link is None or flange is None:
        raise ValueError("the arm model has no flange site")
    mount = ET.SubElement(
        last_link, "body", name="payload_mount", pos=flange.get("pos"), quat=flange.get("quat")
    )
    mass = ET.SubElement(mount, "body", name="payload", pos=" ".join(map(repr, payload.offset_m)))
    inertia = 0.4 * payload.mass_kg * _MASS_RADIUS_M**2
    ET.SubElement(
        mass, "inertial", pos="0 0 0", mass=repr(payload.mass_kg), diaginertia=f"{inertia!r} " * 3
    )
    for axis, name in (("1 0 0", "x"), ("0 1 0", "y"), ("0 0 1", "z")):
        ET.SubElement(
            mass,
            "joint",
            name=f"payload_{name}",
            type="slide",
            axis=axis,
            stiffness=repr(payload.stiffness_n_per_m),
            damping=repr(payload.damping_ns_per_m),
        )
    ET.SubElement(mass, "site", name="payload_tip")
    ET.SubElement(
        root.find("sensor"), "accelerometer", name="payload_accelerometer", site="payload_tip"
    )
    return ET.tostring(root, encoding="unicode")


@dataclass(frozen=True)
class PayloadRecord:
    """One simulated run at the control rate.

    Attributes
    ----------
    t_s
        Sample times ``k dt_s``, s, ``(n_samples,)``.
    tip_acceleration_m_s2
        Acceleration of the payload tip in the base frame with gravity removed (the tip
        accelerometer's specific force rotated into the base frame, plus gravity), m/s²,
        ``(n_samples, 3)``.
    tip_position_m, flange_position_m
        Positions in the base frame, m, ``(n_samples, 3)``.
    mount_deflection_m
        Deflection of the mount along the flange axes, m, ``(n_samples, 3)``.
    """

    t_s: np.ndarray
    tip_acceleration_m_s2: np.ndarray
    tip_position_m: np.ndarray
    flange_position_m: np.ndarray
    mount_deflection_m: np.ndarray


class PayloadTwin:
    """The flexible arm with a :class:`FlexiblePayload` on its flange (MuJoCo).

    Parameters
    ----------
    robot_name
        A robot of the parameter file with default gear flexibility (``"ur5e"``).
    payload
        The flexible payload.
    flex
        Gear springs and dampers; ``None`` takes the robot's default.
    physics_dt_s
        Physics time step, s; divides the control period.
    """

    def __init__(
        self,
        robot_name: str = "ur5e",
        payload: FlexiblePayload | None = None,
        flex: FlexParams | None = None,
        physics_dt_s: float = 0.0005,
    ) -> None:
        import mujoco

        self._mujoco = mujoco
        self.params = robots.params(robot_name)
        self.payload = FlexiblePayload() if payload is None else payload
        self.flex = default_flex(robot_name) if flex is None else flex
        self.flex.validate(self.params.n_dof)
        self.model = mujoco.MjModel.from_xml_string(
            build_payload_mjcf(self.params, self.payload, physics_dt_s)
        )
        self.data = mujoco.MjData(self.model)
        self._n = self.params.n_dof
        self._payload_damping = self.model.dof_damping[self._n :].copy()
        self._tip = self.model.site("payload_tip").id
        self._flange = self.model.site("flange").id
        adr = int(self.model.sensor("payload_accelerometer").adr[0])
        self._accel = slice(adr, adr + 3)

    @property
    def physics_dt_s(self) -> float:
        """Physics time step, s."""
        return float(self.model.opt.timestep)

    def equilibrium(self, q_motor: Sequence[float] | np.ndarray) -> np.ndarray:
        """Joint positions ``(n_dof + 3,)`` (link angles, mount deflections) at rest under
        gravity with the motors held at ``q_motor``: the root of the accelerations."""
        from scipy.optimize import root

        theta = np.asarray(q_motor, dtype=float)
        d, n = self.data, self._n

        def acceleration(x: np.ndarray) -> np.ndarray:
            d.qpos[:] = x
            d.qvel[:] = 0.0
            d.qfrc_applied[:n] = self.flex.spring_torque_nm(theta - x[:n])
            d.qfrc_applied[n:] = 0.0
            self._mujoco.mj_forward(self.model, d)
            return d.qacc.copy()

        guess = np.concatenate([theta, np.zeros(3)])
        sol = root(acceleration, guess, method="hybr", tol=1e-13)
        if not sol.success or np.max(np.abs(acceleration(sol.x))) > 1e-6:
            raise RuntimeError(f"no static equilibrium of the payload arm: {sol.message}")
        return sol.x

    def run(self, Q_ref: np.ndarray, dt_s: float | None = None) -> PayloadRecord:  # noqa: N803
        """Simulate the joint reference ``Q_ref`` ``(n_samples, n_dof)``, starting at rest in
        equilibrium at ``Q_ref[0]``, one row per control period ``dt_s`` (s; ``None``: the
        robot's :attr:`~tvist.robots.RobotParams.control_period_s`)."""
        dt_s = self.params.sample_period_s(dt_s)
        q_ref = np.asarray(Q_ref, dtype=float)
        if q_ref.ndim != 2 or q_ref.shape[1] != self._n or not np.all(np.isfinite(q_ref)):
            raise ValueError(f"Q_ref must be a finite (n_samples, {self._n}) array")
        n_sub = round(dt_s / self.physics_dt_s)
        if n_sub < 1 or abs(n_sub * self.physics_dt_s - dt_s) > 1e-9 * dt_s:
            raise ValueError(f"dt_s = {dt_s:g} s must be a whole multiple of the physics step")
        mujoco, model, data, n = self._mujoco, self.model, self.data, self._n
        mujoco.mj_resetData(model, data)
        data.qpos[:] = self.equilibrium(q_ref[0])
        slope = (np.vstack([q_ref[1:], q_ref[-1:]]) - q_ref) / dt_s
        n_samples = q_ref.shape[0]
        accel = np.empty((n_samples, 3))
        tip = np.empty((n_samples, 3))
        flange = np.empty((n_samples, 3))
        deflection = np.empty((n_samples, 3))
        gravity = np.array([0.0, 0.0, -GRAVITY_M_S2])
        for k in range(n_samples):
            for s in range(n_sub):
                theta = q_ref[k] + slope[k] * (s / n_sub) * dt_s
                tau = self.flex.spring_torque_nm(theta - data.qpos[:n])
                damp = self.flex.damping_nms_per_rad(tau)
                # Trapezoidal gear damping as in the twin: c (q_motor' − v_n/2) applied,
                # c/2 as MuJoCo dof damping acting on the new velocity.
                data.qfrc_applied[:n] = tau + damp * (slope[k] - 0.5 * data.qvel[:n])
                model.dof_damping[:n] = 0.5 * damp
                mujoco.mj_step(model, data)
                if s == 0:  # sensors and kinematics of the sample instant t_k
                    rot = data.site_xmat[self._tip].reshape(3, 3)
                    accel[k] = rot @ data.sensordata[self._accel] + gravity
                    tip[k] = data.site_xpos[self._tip]
                    flange[k] = data.site_xpos[self._flange]
                    deflection[k] = data.qpos[n:]
            if not np.all(np.isfinite(data.qpos)):
                raise RuntimeError(f"simulation diverged at t = {(k + 1) * dt_s:.4f} s")
        return PayloadRecord(
            t_s=dt_s * np.arange(n_samples),
            tip_acceleration_m_s2=accel,
            tip_position_m=tip,
            flange_position_m=flange,
            mount_deflection_m=deflection,
        )
