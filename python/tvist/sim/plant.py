"""The twin's equations of motion, advanced one control period at a time.

:class:`FlexIntegrator` is the physics of :class:`~tvist.sim.Twin` (the gear springs and
dampers applied to MuJoCo's link-side arm, see :mod:`tvist.sim.twin`): it advances the state by
one control period while the motor angle moves linearly from ``base_ref`` at ``base_ref +
vel_ref dt``. :meth:`Twin.run <tvist.sim.Twin.run>` drives it with a whole reference;
:class:`tvist.sim.twin_plant.TwinPlant` drives it one period at a time for a controller in
the loop (the UR twin server).
"""

from __future__ import annotations

import math

import numpy as np

from tvist.sim.flex import FlexParams


class FlexIntegrator:
    """One control period of the flexible-joint arm (motor prescribed, link side simulated).

    Parameters
    ----------
    mujoco
        The ``mujoco`` module.
    model, data
        MuJoCo model and data of the link-side arm (``data`` is advanced in place).
    flex
        Gear springs and dampers (validated).
    dt_s
        Control period (s), a whole multiple of the model's time step.
    flange, accel_slice
        Site id of the flange and the accelerometer's slice of ``sensordata``.
    arm
        The arm's joints among the model's degrees of freedom: ``slice(0, n_dof)`` when they
        are all of them, else their indices (the other dofs, beam hinges, carry their own
        springs and dampers in the model and are left to MuJoCo).
    """

    def __init__(
        self,
        mujoco,
        model,
        data,
        flex: FlexParams,
        dt_s: float,
        flange: int,
        accel_slice: slice,
        arm: slice | np.ndarray | None = None,
    ) -> None:
        self._mujoco = mujoco
        self.model, self.data = model, data
        self.dt_s = float(dt_s)
        self.n_sub = round(self.dt_s / float(model.opt.timestep))
        self._fractions = np.arange(self.n_sub) / self.n_sub
        self._k1 = np.asarray(flex.k1_nm_per_rad, dtype=float)
        self._k3 = np.asarray(flex.k3_nm_per_rad3, dtype=float)
        self._c0 = np.asarray(flex.c0_nms_per_rad, dtype=float)
        self._c_load = np.asarray(flex.c_load_per_nm, dtype=float)
        self._c_load2 = flex.c_load2()
        self._quadratic = bool(np.any(self._c_load2 != 0.0))  # skip the factor when it is 1
        self._load_index = flex.damper_load_index()
        self._smoothing = flex.load_smoothing_nm
        # With a servo in series the spring law has no closed form (FlexParams solves it).
        self._series = flex if flex.servo_nm_per_rad is not None else None
        self.max_deflection_rad = flex.max_deflection_rad
        self._flange = flange
        self._accel_slice = accel_slice
        self._arm = slice(0, model.nv) if arm is None else arm
        # A slice gives views of qpos and qvel that follow the state in place; indices do not.
        self._views = isinstance(self._arm, slice)
        self._bad_qacc = int(mujoco.mjtWarning.mjWARN_BADQACC)
        n = len(self._k1)
        self._theta = np.empty(n)
        self._delta = np.empty(n)
        self._tau = np.empty(n)
        self._damp = np.empty(n)
        self._growth = np.empty(n)
        self._force = np.empty(n)

    def reset(self, q_link: np.ndarray, qd_link: np.ndarray) -> None:
        """Start from the link-side state ``q_link`` (rad) and velocities ``qd_link`` (rad/s),
        ``(model.nv,)``: joints and any beam hinges."""
        self._mujoco.mj_resetData(self.model, self.data)
        self.data.qpos[:] = q_link
        self.data.qvel[:] = qd_link

    def advance(
        self,
        base_ref: np.ndarray,
        vel_ref: np.ndarray,
        accel_out: np.ndarray,
        flange_pos_out: np.ndarray,
        flange_rot_out: np.ndarray,
    ) -> None:
        """Advance one control period; write the sensors at its start into the ``*_out`` arrays.

        The motor angle is ``base_ref + vel_ref s`` for ``s`` in ``[0, dt_s)`` (rad, rad/s).
        ``accel_out`` (3,) receives the accelerometer (specific force in flange axes, m/s²),
        ``flange_pos_out`` (3,) the flange position (m), ``flange_rot_out`` (9,) its rotation
        matrix, all at the start of the period.
        """
        model, data = self.model, self.data
        k1, k3, c0, c_load, c_load2 = self._k1, self._k3, self._c0, self._c_load, self._c_load2
        quadratic, load_index = self._quadratic, self._load_index
        arm, views = self._arm, self._views
        qpos, qvel = data.qpos[arm], data.qvel[arm]
        step = self._mujoco.mj_step
        smoothing = self._smoothing
        smoothing_sq = smoothing * smoothing
        theta, delta, tau = self._theta, self._delta, self._tau
        damp, growth, force = self._damp, self._growth, self._force
        dt = self.dt_s
        for s in range(self.n_sub):
            if not views:
                qpos, qvel = data.qpos[arm], data.qvel[arm]
            np.multiply(vel_ref, self._fractions[s] * dt, out=theta)
            theta += base_ref
            np.subtract(theta, qpos, out=delta)
            if self._series is None:
                # tau = k1 delta + k3 delta^3
                np.multiply(delta, delta, out=tau)
                tau *= k3
                tau += k1
                tau *= delta
            else:
                tau[:] = self._series.spring_torque_nm(delta)
            # Gear damping c (q_motor' - q_link') with
            # c = c0 (1 + c_load |L|_s) (1 + c_load2 |L|_s) and
            # the trapezoidal link velocity (v_n + v_{n+1}) / 2: c (q_motor' - v_n / 2)
            # is applied, c / 2 is MuJoCo dof damping, which acts on v_{n+1}. This
            # is second-order accurate; fully implicit damping would lower every
            # mode frequency by about zeta wn dt / 2.
            # Load L = tau[load_index], |L|_s = sqrt(L² + s²) - s: the law of
            # FlexParams.damping_nms_per_rad, in place.
            # mode="clip" writes straight into damp (mode="raise" would buffer);
            # the indices were validated with the FlexParams.
            np.take(tau, load_index, out=damp, mode="clip")
            damp *= damp
            damp += smoothing_sq
            np.sqrt(damp, out=damp)
            damp -= smoothing
            if quadratic:
                np.multiply(damp, c_load2, out=growth)
                growth += 1.0
            damp *= c_load
            damp += 1.0
            if quadratic:
                damp *= growth
            damp *= c0
            np.multiply(qvel, -0.5, out=force)
            force += vel_ref
            force *= damp
            force += tau
            damp *= 0.5
            model.dof_damping[arm] = damp
            data.qfrc_applied[arm] = force
            step(model, data)
            if s == 0:
                # mj_step evaluated sensors and kinematics before integrating, so these
                # belong to the start of the period.
                accel_out[:] = data.sensordata[self._accel_slice]
                flange_pos_out[:] = data.site_xpos[self._flange]
                flange_rot_out[:] = data.site_xmat[self._flange]

    def divergence(self, q_motor_end: np.ndarray) -> str | None:
        """Why the state is impossible after a period ending at motor angle ``q_motor_end``.

        ``None`` if the state is finite and every gear deflection is within the limit.
        """
        data = self.data
        if (
            data.warning[self._bad_qacc].number
            or not np.all(np.isfinite(data.qpos))
            or not np.all(np.isfinite(data.qvel))
        ):
            return "non-finite state"
        worst = float(np.max(np.abs(q_motor_end - data.qpos[self._arm])))
        if worst > self.max_deflection_rad:
            return f"gear deflection {worst:.3g} rad exceeds {self.max_deflection_rad:g} rad"
        return None


def rotation_vector(matrix) -> np.ndarray:
    """Axis-angle vector (rad) of a rotation matrix given row-major as 9 numbers.

    Through the unit quaternion (Shepperd's method: the largest of ``w, x, y, z`` is computed
    from the diagonal, the rest from off-diagonal sums), so it is accurate at every angle,
    ``pi`` included; the angle is in ``[0, pi]``. Plain floats: ~10x faster than scipy's
    ``Rotation`` for one matrix, which matters at 500 samples a second.
    """
    r00, r01, r02, r10, r11, r12, r20, r21, r22 = (float(v) for v in matrix)
    trace = r00 + r11 + r22
    if trace >= max(r00, r11, r22):
        w = 0.5 * math.sqrt(1.0 + trace)
        f = 0.25 / w
        x, y, z = (r21 - r12) * f, (r02 - r20) * f, (r10 - r01) * f
    elif r00 >= r11 and r00 >= r22:
        x = 0.5 * math.sqrt(1.0 + r00 - r11 - r22)
        f = 0.25 / x
        w, y, z = (r21 - r12) * f, (r01 + r10) * f, (r02 + r20) * f
    elif r11 >= r22:
        y = 0.5 * math.sqrt(1.0 - r00 + r11 - r22)
        f = 0.25 / y
        w, x, z = (r02 - r20) * f, (r01 + r10) * f, (r12 + r21) * f
    else:
        z = 0.5 * math.sqrt(1.0 - r00 - r11 + r22)
        f = 0.25 / z
        w, x, y = (r10 - r01) * f, (r02 + r20) * f, (r12 + r21) * f
    if w < 0.0:  # the same rotation with the angle in [0, pi]
        w, x, y, z = -w, -x, -y, -z
    norm = math.sqrt(x * x + y * y + z * z)
    if norm < 1e-300:
        return np.zeros(3)
    scale = 2.0 * math.atan2(norm, w) / norm
    return np.array([x * scale, y * scale, z * scale])
