"""Simulated flexible UR arm (MuJoCo) that produces RTDE-like logs.

Model
-----
A flexible-joint arm (paper section 4.3, Fig. 7; Spong's model). The motor side of every
joint follows the joint reference exactly: an ideal, infinitely stiff position servo, the
paper's assumption ``q_m / N ≈ q_c``. The reference arrives at the control rate (500 Hz) and is
linearly interpolated at the physics rate. The link side is the rigid arm of
:mod:`tvist.sim.mjcf` (link masses, centres of mass and inertia tensors of the robot parameter
file, plus the payload); each hinge carries the gear torque of :class:`~tvist.sim.FlexParams`,

``tau_j = k1 delta_j + k3 delta_j³ + c_j(tau) (d/dt)delta_j``,  ``delta_j = q_motor,j - q_j``,

which acts between link ``j-1`` and link ``j`` and therefore is the generalized force of hinge
``j``. With a servo of finite stiffness in series (``FlexParams.servo_nm_per_rad``), the
spring torque is that of the series pair (:mod:`tvist.sim.flex`). The damping coefficient
``c_j`` grows with the load on joint ``j``'s gear and bearing, a spring torque
(:meth:`~tvist.sim.FlexParams.damping_nms_per_rad`; for the base, the shoulder's, i.e. the
arm's tilting moment on the base bearing). Rotor inertia does not enter: the motor's motion
is prescribed.

With bending links (``beams``, :mod:`tvist.sim.beams`) the link side also has the links'
bending hinges, whose springs and dampers MuJoCo applies itself (MJCF ``stiffness`` and
``damping``); the gear law acts on the arm's joints only.

Integration: semi-implicit Euler of MuJoCo's ``implicitfast`` integrator. The spring torque is
explicit (no numerical damping of the modes); the damping of the link velocity is half explicit,
half implicit (MuJoCo dof damping), i.e. trapezoidal, and ``+c q_motor'`` is an applied force.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np

from tvist import robots
from tvist.sim.beams import LinkBeams
from tvist.sim.flex import FlexParams, default_flex
from tvist.sim.mjcf import GRAVITY_M_S2, build_mjcf
from tvist.sim.modal import ModalAnalysis, modal_analysis
from tvist.sim.plant import FlexIntegrator
from tvist.sim.record import SimRecord

if TYPE_CHECKING:
    import mujoco

#: The twin refuses payloads heavier than this multiple of the rated payload: the gear model
#: (eq. 22 fitted around the rated torque) is not meant far beyond it.
PAYLOAD_LIMIT_FACTOR = 1.5


def check_payload_mass(params: robots.RobotParams, payload_kg, what: str = "payload_kg") -> float:
    """``payload_kg`` as a float if the twin of ``params`` carries it:
    ``0 <= payload_kg <= PAYLOAD_LIMIT_FACTOR * params.max_payload_kg``.

    Raises
    ------
    ValueError
        Naming ``what``, if it is not finite or outside that range.
    """
    mass_kg = _finite_float(payload_kg, what)
    limit_kg = PAYLOAD_LIMIT_FACTOR * params.max_payload_kg
    if not 0.0 <= mass_kg <= limit_kg:
        raise ValueError(
            f"{what} = {mass_kg:g} is outside [0, {limit_kg:g}] kg "
            f"({PAYLOAD_LIMIT_FACTOR:g} x the {params.name} rated payload)"
        )
    return mass_kg


#: A reference may exceed the joint speed limits by this factor (finite differences of a
#: profile that touches the limit overshoot it slightly; a jump in the reference does not).
SPEED_LIMIT_MARGIN = 1.05

#: Joint indices of the two modes the dynamic map describes.
BASE_JOINT = 0
SHOULDER_JOINT = 1


class SimulationDiverged(RuntimeError):
    """The simulation produced NaN or an impossible gear deflection.

    Attributes
    ----------
    time_s
        Simulated time (s) at which the divergence was detected.
    """

    def __init__(self, time_s: float, reason: str) -> None:
        super().__init__(f"simulation diverged at t = {time_s:.4f} s: {reason}")
        self.time_s = time_s


def _finite_float(value: float, what: str) -> float:
    try:
        out = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{what} must be a number, got {value!r}") from None
    if not math.isfinite(out):
        raise ValueError(f"{what} must be finite, got {value!r}")
    return out


class Twin:
    """MuJoCo twin of a UR e-Series arm with flexible joints and a tool-flange accelerometer.

    Parameters
    ----------
    robot_name
        A robot of the parameter file, e.g. ``"ur5e"`` (see :func:`tvist.robots.names`), or
        any arm's :class:`~tvist.robots.RobotParams` (for example from
        :func:`tvist.robots.urdf_params`; then ``flex`` is needed unless its name has a
        default).
    payload_kg
        Payload mass (kg), ``0 <= payload_kg <= 1.5 * max_payload_kg``.
    payload_com_m
        Payload centre of mass in the flange frame (m).
    flex
        Gear springs and dampers; ``None`` takes :func:`~tvist.sim.default_flex` of the robot.
    physics_dt_s
        Physics time step (s); must divide the control period given to :meth:`run`.
        ``None``: 0.5 ms, or the ``physics_dt_s`` of ``beams`` (bending links have faster
        modes).
    accel_noise_std
        Standard deviation of white noise added to each accelerometer axis (m/s²).
    seed
        Seed of the accelerometer noise.
    payload_inertia_kg_m2
        ``[ixx, iyy, izz, ixy, ixz, iyz]`` about the payload's centre of mass, flange axes;
        ``None`` is a point mass.
    beams
        Links that bend (:class:`~tvist.sim.beams.LinkBeams`): their bending hinges are extra
        degrees of freedom of the link side, with their own springs and dampers. ``None``:
        rigid links. The arm's joint angles (``actual_q``, :meth:`equilibrium`) are those of
        the joints ``joint1 .. joint{n}``; the full state (joints and hinges) is
        :meth:`equilibrium_state`.

    Raises
    ------
    ValueError
        Unknown robot, impossible payload, invalid flexibility or time step.
    """

    def __init__(
        self,
        robot_name: str | robots.RobotParams = "ur5e",
        payload_kg: float = 5.0,
        payload_com_m: Sequence[float] = (0.0, 0.0, 0.05),
        flex: FlexParams | None = None,
        physics_dt_s: float | None = None,
        accel_noise_std: float = 0.0,
        seed: int = 0,
        payload_inertia_kg_m2: Sequence[float] | None = None,
        beams: LinkBeams | None = None,
    ) -> None:
        import mujoco

        if isinstance(robot_name, robots.RobotParams):
            self._params = robot_name
        else:
            self._params = robots.params(robot_name)
        mass_kg = check_payload_mass(self._params, payload_kg)
        self._payload = robots.Payload(mass_kg, tuple(payload_com_m), payload_inertia_kg_m2)
        self._flex = default_flex(self._params.name) if flex is None else flex
        self._flex.validate(self._params.n_dof)
        if physics_dt_s is None:
            physics_dt_s = 0.0005 if beams is None else beams.physics_dt_s
        dt = _finite_float(physics_dt_s, "physics_dt_s")
        if not 0.0 < dt <= 0.0005:
            raise ValueError(f"physics_dt_s must be in (0, 0.0005] s, got {dt:g}")
        noise = _finite_float(accel_noise_std, "accel_noise_std")
        if noise < 0.0:
            raise ValueError(f"accel_noise_std must be >= 0, got {noise:g}")
        self._noise_std = noise
        self._rng = np.random.default_rng(seed)

        self._mujoco = mujoco
        self._beams = beams
        self._model = mujoco.MjModel.from_xml_string(
            build_mjcf(self._params, self._payload, physics_dt_s=dt, beams=beams)
        )
        self._data = mujoco.MjData(self._model)
        # The arm's joints among the model's degrees of freedom (hinge joints: one qpos and one
        # dof each, at the same address). Without beams they are all of them, in order.
        arm = [int(self._model.joint(f"joint{i + 1}").dofadr[0]) for i in range(self.n_dof)]
        self._arm_dofs = np.array(arm)
        self._arm: slice | np.ndarray = (
            slice(0, self.n_dof) if arm == list(range(self._model.nv)) else self._arm_dofs
        )
        # Spring stiffness and damping of every dof that is not an arm joint (beam hinges).
        self._passive = np.setdiff1d(np.arange(self._model.nv), self._arm_dofs)
        self._flange = self._model.site("flange").id
        accel = self._model.sensor("accelerometer")
        self._accel_slice = slice(int(accel.adr[0]), int(accel.adr[0]) + 3)

    # ------------------------------------------------------------------ properties

    @property
    def params(self) -> robots.RobotParams:
        """Robot parameters the model was generated from."""
        return self._params

    @property
    def payload(self) -> robots.Payload:
        """The payload on the flange."""
        return self._payload

    @property
    def flex(self) -> FlexParams:
        """Gear springs and dampers."""
        return self._flex

    @property
    def n_dof(self) -> int:
        """Number of joints."""
        return self._params.n_dof

    @property
    def beams(self) -> LinkBeams | None:
        """The bending links, if any."""
        return self._beams

    @property
    def n_state(self) -> int:
        """Degrees of freedom of the link side: the joints plus any beam hinges."""
        return int(self._model.nv)

    @property
    def arm_dofs(self) -> np.ndarray:
        """Indices of the arm's joints in the link-side state ``(n_dof,)``."""
        return self._arm_dofs.copy()

    @property
    def physics_dt_s(self) -> float:
        """Physics time step (s)."""
        return float(self._model.opt.timestep)

    @property
    def gravity_m_s2(self) -> float:
        """Magnitude of gravity (m/s²), acting along ``-z`` of the base frame."""
        return GRAVITY_M_S2

    @property
    def mjcf(self) -> str:
        """MJCF text of the link-side arm (for inspection or rendering)."""
        return build_mjcf(
            self._params, self._payload, physics_dt_s=self.physics_dt_s, beams=self._beams
        )

    def rigid_model(self) -> tuple[mujoco.MjModel, mujoco.MjData]:
        """A fresh ``(mujoco.MjModel, mujoco.MjData)`` pair of the link-side arm."""
        model = self._mujoco.MjModel.from_xml_string(self.mjcf)
        return model, self._mujoco.MjData(model)

    @property
    def accel_noise_std(self) -> float:
        """Standard deviation of the accelerometer noise on each axis (m/s²)."""
        return self._noise_std

    def noise(self, std: float, size: int | tuple[int, ...]) -> np.ndarray:
        """White noise of standard deviation ``std`` from the twin's own generator."""
        return self._rng.normal(0.0, std, size=size)

    def _control_period(self, dt_s: float) -> float:
        """``dt_s`` as a float; ValueError unless a whole multiple of ``physics_dt_s``."""
        dt = _finite_float(dt_s, "dt_s")
        n_sub = round(dt / self.physics_dt_s)
        if n_sub < 1 or abs(n_sub * self.physics_dt_s - dt) > 1e-9 * dt:
            raise ValueError(
                f"dt_s = {dt:g} s must be a whole multiple of "
                f"physics_dt_s = {self.physics_dt_s:g} s"
            )
        return dt

    def integrator(self, dt_s: float) -> FlexIntegrator:
        """The twin's equations of motion, advanced one control period ``dt_s`` (s) at a time.

        Shares the twin's MuJoCo data: one integrator (or run) at a time.

        Raises
        ------
        ValueError
            If ``dt_s`` is not a whole multiple of ``physics_dt_s``.
        """
        dt = self._control_period(dt_s)
        return FlexIntegrator(
            self._mujoco,
            self._model,
            self._data,
            self._flex,
            dt,
            self._flange,
            self._accel_slice,
            self._arm,
        )

    # ------------------------------------------------------------------ statics

    def check_pose(self, q: np.ndarray, what: str) -> np.ndarray:
        """``q`` as a float array ``(n_dof,)``; ValueError naming ``what`` if malformed or
        outside the joint limits."""
        arr = np.asarray(q, dtype=float)
        if arr.shape != (self.n_dof,):
            raise ValueError(f"{what} must have shape ({self.n_dof},), got {arr.shape}")
        if not np.all(np.isfinite(arr)):
            raise ValueError(f"{what} contains NaN or infinite values")
        lower, upper = self._params.joint_limits_rad.T
        bad = np.flatnonzero((arr < lower) | (arr > upper))
        if bad.size:
            j = int(bad[0])
            raise ValueError(
                f"{what}: joint {j} = {arr[j]:.6g} rad is outside its limits "
                f"[{lower[j]:.6g}, {upper[j]:.6g}]"
            )
        return arr

    def _gravity_torque(self, q_link: np.ndarray) -> np.ndarray:
        """Generalized gravity force ``G(q)`` of the link side at rest (N m), ``(n_state,)``;
        ``q_link`` is the full link-side state."""
        d = self._data
        d.qpos[:] = q_link
        d.qvel[:] = 0.0
        self._mujoco.mj_forward(self._model, d)
        return d.qfrc_bias.copy()

    def _gravity_stiffness(self, q_link: np.ndarray, step_rad: float = 1e-6) -> np.ndarray:
        """``dG/dq`` by central differences (N m/rad), ``(n_state, n_state)``.

        ``G`` is smooth (trigonometric) with second derivatives of order ``|G| ~ 1e2 N m``,
        so the truncation error ``~ step² |G'''|`` is ~1e-10 N m/rad and rounding
        ``~ eps |G| / step`` ~1e-8 N m/rad, far below gear stiffnesses of ~1e3 N m/rad.
        """
        n = self.n_state
        out = np.empty((n, n))
        for j in range(n):
            dq = np.zeros(n)
            dq[j] = step_rad
            out[:, j] = (self._gravity_torque(q_link + dq) - self._gravity_torque(q_link - dq)) / (
                2.0 * step_rad
            )
        return out

    def equilibrium(self, q_motor: Sequence[float] | np.ndarray) -> np.ndarray:
        """Link-side joint angles at rest under gravity with the motors held at ``q_motor``
        (rad), ``(n_dof,)``: the arm-joint part of :meth:`equilibrium_state`."""
        return self.equilibrium_state(q_motor)[self._arm]

    def equilibrium_state(self, q_motor: Sequence[float] | np.ndarray) -> np.ndarray:
        """Full link-side state at rest under gravity with the motors at ``q_motor`` (rad),
        ``(n_state,)``: joint angles and beam hinge angles.

        Solves ``k1 delta + k3 delta³ = G_joint(q)`` (``delta = q_motor - q_joint``) and
        ``k_h q_h = -G_hinge(q)`` by Newton's method.
        """
        theta = self.check_pose(np.asarray(q_motor, dtype=float), "q_motor")
        arm, passive = self._arm, self._passive
        k_passive = self._model.jnt_stiffness[self._model.dof_jntid[passive]]
        # Newton in the small offsets from (motor angles, straight links): the joints' -delta
        # and the hinge angles, so that rounding of the state (~1e-16 rad of angles ~3 rad,
        # ~1e-11 N m through the stiffest gear) does not enter the unknowns.
        origin = np.zeros(self.n_state)
        origin[arm] = theta
        offset = np.zeros(self.n_state)
        gravity = self._gravity_torque(origin)
        offset[arm] = -self._flex.deflection_rad(gravity[arm])
        offset[passive] = -gravity[passive] / k_passive
        residual = np.empty(self.n_state)
        spring = np.empty(self.n_state)
        spring[passive] = k_passive
        for _ in range(50):
            state = origin + offset
            gravity = self._gravity_torque(state)
            delta = -offset[arm]
            residual[arm] = self._flex.spring_torque_nm(delta) - gravity[arm]
            residual[passive] = -k_passive * offset[passive] - gravity[passive]
            if np.max(np.abs(residual)) < 1e-11:
                break
            # d(residual)/d(offset) = -(K_spring + dG/dq).
            spring[arm] = self._flex.tangent_stiffness_nm_per_rad(delta)
            jac = np.diag(spring) + self._gravity_stiffness(state)
            offset = offset + np.linalg.solve(jac, residual)
        else:
            raise SimulationDiverged(0.0, "no static equilibrium under gravity at this pose")
        return origin + offset

    # ------------------------------------------------------------------ modes

    def modal_analysis(self, q: Sequence[float] | np.ndarray) -> ModalAnalysis:
        """All vibration modes at rest with the motors held at ``q`` (linearized).

        The arm is linearized about its static equilibrium under gravity:
        ``M dq'' + C dq' + (K_spring + dG/dq) dq = 0`` with the mass matrix ``M`` of the link
        side, the tangent gear stiffness ``K_gear = diag(k1 + 3 k3 delta_g²)`` at the gravity
        deflection ``delta_g``, the gravity stiffness ``dG/dq`` and the gear damping at the
        static load ``C = diag(c(tau_g))`` of :meth:`~tvist.sim.FlexParams.damping_nms_per_rad`
        with the gravity spring torques ``tau_g`` (the damping force ``c(tau) (d/dt)delta``
        has no first-order term in the load: it is multiplied by a velocity that is zero at
        rest). With bending links the state also holds the beam hinges, with their linear
        springs and dampers in ``K_spring`` and ``C``; the mode shapes and strain energies
        are then ``(n_state, n_modes)``, the joints at :attr:`arm_dofs`.
        """
        theta = self.check_pose(np.asarray(q, dtype=float), "q")
        state = self.equilibrium_state(theta)
        arm, passive = self._arm, self._passive
        delta = theta - state[arm]
        tau = self._flex.spring_torque_nm(delta)
        spring = np.empty(self.n_state)
        spring[arm] = self._flex.tangent_stiffness_nm_per_rad(delta)
        spring[passive] = self._model.jnt_stiffness[self._model.dof_jntid[passive]]
        damping = np.empty(self.n_state)
        damping[arm] = self._flex.damping_nms_per_rad(tau)
        damping[passive] = self._model.dof_damping[passive]
        stiffness = np.diag(spring) + self._gravity_stiffness(state)
        return modal_analysis(self.state_mass_matrix(state), np.diag(damping), stiffness, spring)

    def modes(self, q: Sequence[float] | np.ndarray) -> list[tuple[float, float]]:
        """Ground-truth ``[(wn_rad_s, zeta) base, (wn_rad_s, zeta) shoulder]`` at pose ``q``.

        The base (shoulder) mode is the mode that stores the largest share of its gear strain
        energy in the base (shoulder) joint; see :meth:`modal_analysis`.
        """
        analysis = self.modal_analysis(q)
        base = analysis.dominant_mode(int(self._arm_dofs[BASE_JOINT]))
        shoulder = analysis.dominant_mode(int(self._arm_dofs[SHOULDER_JOINT]), exclude=(base,))
        return [
            (float(analysis.wn_rad_s[base]), float(analysis.zeta[base])),
            (float(analysis.wn_rad_s[shoulder]), float(analysis.zeta[shoulder])),
        ]

    def mass_matrix(self, q_link: Sequence[float] | np.ndarray) -> np.ndarray:
        """Joint-space inertia matrix of the arm with straight links (kg m²), ``(n, n)``:
        the rigid link-side ``M(q)`` at joint angles ``q_link``."""
        state = np.zeros(self.n_state)
        state[self._arm] = np.asarray(q_link, dtype=float)
        return self.state_mass_matrix(state)[np.ix_(self._arm_dofs, self._arm_dofs)]

    def state_mass_matrix(self, state: Sequence[float] | np.ndarray) -> np.ndarray:
        """Inertia matrix of the full link-side state (joints and beam hinges) of the MuJoCo
        model (kg m², kg m² per rad), ``(n_state, n_state)``."""
        d = self._data
        d.qpos[:] = np.asarray(state, dtype=float)
        self._mujoco.mj_forward(self._model, d)
        out = np.zeros((self.n_state, self.n_state))
        self._mujoco.mj_fullM(self._model, d, out)
        return out

    def flange_jacobian(self, state: Sequence[float] | np.ndarray) -> np.ndarray:
        """Translational Jacobian of the flange (m/rad) in the base frame at the full
        link-side ``state`` (:meth:`equilibrium_state`), ``(3, n_state)``."""
        d = self._data
        d.qpos[:] = np.asarray(state, dtype=float)
        self._mujoco.mj_forward(self._model, d)
        jac = np.zeros((3, self.n_state))
        self._mujoco.mj_jacSite(self._model, d, jac, None, self._flange)
        return jac

    # ------------------------------------------------------------------ run

    def _check_trajectory(self, q_ref: np.ndarray | Sequence[Sequence[float]]) -> np.ndarray:
        try:
            arr = np.array(q_ref, dtype=float)
        except (TypeError, ValueError):
            raise ValueError("Q_ref must be a numeric array of shape (n_samples, n_dof)") from None
        if arr.ndim != 2 or arr.shape[1] != self.n_dof or arr.shape[0] < 2:
            raise ValueError(
                f"Q_ref must have shape (n_samples >= 2, {self.n_dof}), got {arr.shape}"
            )
        bad_rows = np.flatnonzero(~np.all(np.isfinite(arr), axis=1))
        if bad_rows.size:
            raise ValueError(f"Q_ref has NaN or infinite values in row {int(bad_rows[0])}")
        lower, upper = self._params.joint_limits_rad.T
        outside = np.argwhere((arr < lower) | (arr > upper))
        if outside.size:
            row, j = (int(v) for v in outside[0])
            raise ValueError(
                f"Q_ref row {row}: joint {j} = {arr[row, j]:.6g} rad is outside its limits "
                f"[{lower[j]:.6g}, {upper[j]:.6g}]"
            )
        return arr

    def _check_speed(self, q_ref: np.ndarray, dt_s: float) -> None:
        """Raise ValueError if the reference steps faster than the joint speed limits."""
        speed = np.abs(np.diff(q_ref, axis=0)) / dt_s
        limit = self._params.max_velocity_rad_s * SPEED_LIMIT_MARGIN
        too_fast = np.argwhere(speed > limit)
        if too_fast.size:
            row, j = (int(v) for v in too_fast[0])
            raise ValueError(
                f"Q_ref rows {row}-{row + 1}: joint {j} moves at {speed[row, j]:.4g} rad/s, "
                f"above its speed limit {self._params.max_velocity_rad_s[j]:.4g} rad/s"
            )

    def run(
        self,
        Q_ref: np.ndarray | Sequence[Sequence[float]],  # noqa: N803 (matches the paper's Q)
        dt_s: float | None = None,
        progress: bool = False,
        *,
        initial_dq_rad: Sequence[float] | np.ndarray | None = None,
        initial_qd_rad_s: Sequence[float] | np.ndarray | None = None,
        noise_seed: int | Sequence[int] | None = None,
    ) -> SimRecord:
        """Simulate the joint reference ``Q_ref`` and record it like RTDE at the control rate.

        The arm starts at rest in static equilibrium under gravity at ``Q_ref[0]`` (the gear
        deflection of the gravity load already settled).

        Parameters
        ----------
        Q_ref
            Joint references (rad), one row per control period, ``(n_samples, n_dof)``.
        dt_s
            Control period (s); a whole multiple of ``physics_dt_s``. ``None``: the robot's
            (:attr:`~tvist.robots.RobotParams.control_period_s`; ValueError if it has none).
        progress
            Show a progress bar.
        initial_dq_rad, initial_qd_rad_s
            Optional link-side offsets from the rest state at ``t = 0`` (rad, rad/s), for
            free-decay experiments; ``(n_dof,)`` (the joints) or ``(n_state,)`` (joints and
            beam hinges, in the order of :meth:`equilibrium_state`).
        noise_seed
            Seed of this run's accelerometer noise (an integer or a sequence of integers);
            ``None`` continues the twin's own generator (seeded by ``seed``), so the noise
            then depends on the runs before. A seed makes the run reproducible on its own and
            leaves the twin's generator untouched.

        Returns
        -------
        SimRecord
            ``n_samples`` samples at ``timestamp = k * dt_s``.

        Raises
        ------
        ValueError
            For a malformed trajectory (shape, NaN, joint position or speed limits) or
            control period.
        SimulationDiverged
            If the simulation blows up; nothing is returned then.
        """
        q_ref = self._check_trajectory(Q_ref)
        dt = self._control_period(self._params.sample_period_s(dt_s))
        self._check_speed(q_ref, dt)
        if noise_seed is not None:
            try:
                np.random.SeedSequence(noise_seed)
            except (TypeError, ValueError):
                raise ValueError(
                    f"noise_seed must be a non-negative integer or a sequence of them, "
                    f"got {noise_seed!r}"
                ) from None
        n_samples, n = q_ref.shape
        offsets = []
        for value, what in ((initial_dq_rad, "initial_dq_rad"), (initial_qd_rad_s, "initial_qd")):
            arr = np.zeros(self.n_state)
            if value is not None:
                given = np.asarray(value, dtype=float)
                if given.shape not in ((n,), (self.n_state,)) or not np.all(np.isfinite(given)):
                    raise ValueError(f"{what} must be {n} (or {self.n_state}) finite values")
                if given.shape == (n,):
                    arr[self._arm] = given
                else:
                    arr[:] = given
            offsets.append(arr)

        q_start = self.equilibrium_state(q_ref[0])
        integrator = self.integrator(dt)
        integrator.reset(q_start + offsets[0], offsets[1])
        qpos, qvel, arm = integrator.data.qpos, integrator.data.qvel, self._arm

        # Motor reference: linear interpolation within each control period.
        q_next = np.vstack([q_ref[1:], q_ref[-1:]])
        slope = (q_next - q_ref) / dt  # rad/s, motor velocity within period k

        actual_q = np.empty((n_samples, n))
        actual_qd = np.empty((n_samples, n))
        deflection = np.empty((n_samples, n))
        accel = np.empty((n_samples, 3))
        flange_pos = np.empty((n_samples, 3))
        flange_rot = np.empty((n_samples, 9))

        bar = _ProgressBar(n_samples, dt) if progress else None
        try:
            for k in range(n_samples):
                actual_q[k] = qpos[arm]
                actual_qd[k] = qvel[arm]
                deflection[k] = q_ref[k] - actual_q[k]
                integrator.advance(q_ref[k], slope[k], accel[k], flange_pos[k], flange_rot[k])
                reason = integrator.divergence(q_next[k])
                if reason is not None:
                    raise SimulationDiverged((k + 1) * dt, reason)
                if bar is not None and k % 250 == 0:
                    bar.update(k)
        finally:
            if bar is not None:
                bar.close()

        if self._noise_std > 0.0:
            rng = self._rng if noise_seed is None else np.random.default_rng(noise_seed)
            accel = accel + rng.normal(0.0, self._noise_std, size=accel.shape)
        from scipy.spatial.transform import Rotation

        rotvec = Rotation.from_matrix(flange_rot.reshape(-1, 3, 3)).as_rotvec()
        target_qd = np.gradient(q_ref, dt, axis=0)
        return SimRecord(
            timestamp=np.arange(n_samples) * dt,
            target_q=q_ref,
            target_qd=target_qd,
            target_qdd=np.gradient(target_qd, dt, axis=0),
            actual_q=actual_q,
            actual_qd=actual_qd,
            actual_TCP_pose=np.hstack([flange_pos, rotvec]),
            actual_tool_accelerometer=accel,
            deflection_rad=deflection,
        )


class _ProgressBar:
    """Rich progress bar over simulated samples."""

    def __init__(self, n_samples: int, dt_s: float) -> None:
        from rich.progress import BarColumn, Progress, TextColumn, TimeRemainingColumn

        self._progress = Progress(
            TextColumn("simulating {task.fields[seconds]:.1f} s"),
            BarColumn(),
            TextColumn("{task.percentage:>3.0f}%"),
            TimeRemainingColumn(),
        )
        self._task = self._progress.add_task("sim", total=n_samples, seconds=n_samples * dt_s)
        self._progress.start()

    def update(self, completed: int) -> None:
        self._progress.update(self._task, completed=completed)

    def close(self) -> None:
        self._progress.update(self._task, completed=self._progress.tasks[0].total)
        self._progress.stop()
