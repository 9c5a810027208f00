"""The twin as a plant that a servo drives one control period at a time (:class:`TwinPlant`,
the UR twin server's arm): the twin's physics (:class:`~tvist.sim.plant.FlexIntegrator`)
advanced period by period, with the sensors read at the start of each."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from tvist.sim.plant import rotation_vector
from tvist.sim.twin import SimulationDiverged, Twin

__all__ = ["PlantSample", "TwinPlant"]


@dataclass(frozen=True)
class PlantSample:
    """What the arm's sensors read at the start of one control period.

    Attributes
    ----------
    time_s
        Time since the plant started (s).
    q_motor
        Motor-side joint angles (rad), the servo's position, ``(n_dof,)``.
    q_link, qd_link
        Link-side joint angles (rad) and velocities (rad/s), ``(n_dof,)``.
    accelerometer
        Specific force at the flange in flange axes (m/s²), ``(3,)``; ``R^T [0, 0, g]`` at rest.
    flange_pose
        Flange pose in the base frame, ``[x, y, z, rx, ry, rz]`` (m, axis-angle rad).
    """

    time_s: float
    q_motor: np.ndarray
    q_link: np.ndarray
    qd_link: np.ndarray
    accelerometer: np.ndarray
    flange_pose: np.ndarray


class TwinPlant:
    """The twin as a plant that a servo drives one control period at a time.

    Starts at rest in static equilibrium under gravity with the motors at ``q0``. Each
    :meth:`step` moves the motors linearly to the given angles over one period, exactly as
    :meth:`Twin.run <tvist.sim.Twin.run>` does between two reference samples, so stepping
    the rows of a reference reproduces ``Twin.run`` sample for sample.

    Parameters
    ----------
    twin
        The twin (its MuJoCo data is used: run nothing else on it meanwhile).
    q0
        Initial motor angles (rad), ``(n_dof,)``, within the joint limits.
    dt_s
        Control period (s), a whole multiple of the twin's physics step. ``None``: the robot's
        (:attr:`~tvist.robots.RobotParams.control_period_s`; ValueError if it has none).
    """

    def __init__(self, twin: Twin, q0, dt_s: float | None = None) -> None:
        self._twin = twin
        self._integrator = twin.integrator(twin.params.sample_period_s(dt_s))
        q0 = twin.check_pose(np.asarray(q0, dtype=float), "q0")
        self._integrator.reset(twin.equilibrium_state(q0), np.zeros(twin.n_state))
        self._q_motor = q0.copy()
        self._k = 0
        self._accel = np.empty(3)
        self._pos = np.empty(3)
        self._rot = np.empty(9)
        self._noise_std = twin.accel_noise_std

    @property
    def dt_s(self) -> float:
        """Control period (s)."""
        return self._integrator.dt_s

    @property
    def time_s(self) -> float:
        """Time of the next period's start (s)."""
        return self._k * self._integrator.dt_s

    @property
    def q_motor(self) -> np.ndarray:
        """Motor angles now (rad), a copy."""
        return self._q_motor.copy()

    def step(self, q_motor_next) -> PlantSample:
        """Move the motors linearly to ``q_motor_next`` (rad) over one period.

        Returns the sensors at the start of the period.

        Raises
        ------
        SimulationDiverged
            If the state becomes impossible (the plant must not be stepped further then).
        """
        target = np.asarray(q_motor_next, dtype=float)
        dt = self._integrator.dt_s
        base = self._q_motor
        data = self._integrator.data
        twin = self._twin
        arm = twin.arm_dofs if twin.n_state > twin.n_dof else slice(None)
        q_link, qd_link = data.qpos[arm].copy(), data.qvel[arm].copy()
        self._integrator.advance(base, (target - base) / dt, self._accel, self._pos, self._rot)
        reason = self._integrator.divergence(target)
        time_s = self._k * dt
        self._k += 1
        if reason is not None:
            raise SimulationDiverged(self._k * dt, reason)
        accel = self._accel.copy()
        if self._noise_std > 0.0:
            accel += self._twin.noise(self._noise_std, 3)
        rotvec = rotation_vector(self._rot)
        sample = PlantSample(
            time_s=time_s,
            q_motor=base.copy(),
            q_link=q_link,
            qd_link=qd_link,
            accelerometer=accel,
            flange_pose=np.concatenate([self._pos, rotvec]),
        )
        self._q_motor = target.copy()
        return sample
