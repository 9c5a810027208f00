"""Joint flexibility of the simulated arm: strain-wave gear springs and dampers.

Each joint is a flexible joint (paper section 4.3, Fig. 7): the motor side follows the joint
reference, the link side is connected to it through the gear, a nonlinear torsional spring and
a load-dependent damper. With the deflection ``delta = q_motor - q_link`` (rad):

- gear spring, eq. 22: ``tau_spring = k1 * delta + k3 * delta**3`` (N m), tangent stiffness
  ``k1 + 3 k3 delta**2`` (eq. 23);
- gear damping, eq. 35 with constant ``c``: ``tau_damping = c0 * (1 + c_load * |L|_s) *
  (1 + c_load2 * |L|_s) * d(delta)/dt`` (N m), i.e. friction that grows with the load ``L``
  (N m) the joint's gear and bearings carry, linearly (``c_load2 = 0``) or, as the paper's
  measured damping map (eq. 48), faster than linearly. ``L`` is the spring torque of the joint
  named by ``damper_load_joint``: by default the joint's own gear torque; for the base of a UR
  arm, the shoulder's, which is the tilting moment the arm exerts on the base's cross-roller
  bearing (see :data:`UR5E_FLEX`).
  ``|x|_s = sqrt(x² + s²) − s`` is a smooth absolute value (``s = load_smoothing_nm``): a
  gear's friction has no kink where its load changes sign, and a kink would put one into the
  true damping ratio along a move (and so into references shaped with it).

The stiffness is an *effective* joint stiffness: it lumps the gear with the compliance of the
bearings and the links, which the paper also folds into the joint modes (section 4.1).

Servo stiffness (optional, ``servo_nm_per_rad``): a position servo of finite stiffness ``k_s``
in series with the gear. The servo's rotor is taken massless (its reflected inertia is small
beside the link's and its own mode lies far above the arm's), so servo and gear carry the same
torque and the joint's deflection is the sum of theirs,
``delta = tau / k_s + delta_gear(tau)`` with ``tau = k1 delta_gear + k3 delta_gear**3``: a
softer joint whose stiffening is diluted by the linear servo. The damper acts across the
series pair (the gear's friction and the servo's velocity loop lumped into one law). ``None``
is the ideal, infinitely stiff servo of the paper (``q_m / N ≈ q_c``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class FlexParams:
    """Gear spring and damper of every joint of one robot, link side, SI units.

    All per-joint tuples have length ``n_dof`` (joint 1 = base first).

    Attributes
    ----------
    k1_nm_per_rad
        Linear gear stiffness ``k1`` of eq. 22 (N m/rad).
    k3_nm_per_rad3
        Cubic stiffening ``k3`` of eq. 22 (N m/rad³), >= 0.
    c0_nms_per_rad
        Viscous gear damping at zero load (N m s/rad).
    c_load_per_nm
        Load dependence of the damping (1/(N m)), >= 0: the damping coefficient of joint ``j``
        is ``c0 * (1 + c_load * |L|_s) * (1 + c_load2 * |L|_s)`` with the load
        ``L = tau_spring[damper_load_joint[j]]``.
    load_smoothing_nm
        Width ``s`` of the smooth absolute value ``|x|_s = sqrt(x² + s²) − s`` (N m), > 0.
    max_deflection_rad
        A gear deflection larger than this (rad) means the simulation has diverged; real
        strain-wave gears deflect a few milliradians.
    damper_load_joint
        For each joint, the joint whose gear spring torque is the load of its damper
        (0-based indices); ``None``: every damper is loaded by its own gear.
    c_load2_per_nm
        Second load factor (1/(N m)), >= 0, making the damping grow quadratically with the
        load: the coefficient is ``c0 (1 + c_load |L|_s) (1 + c_load2 |L|_s)``, the form of the
        paper's measured damping map (eq. 48, ``(c_0 + c_2 J)(1 + c_τ J)``) with the load in
        place of the inertia. ``None``: zero for every joint (damping linear in the load).
    servo_nm_per_rad
        Stiffness ``k_s`` (N m/rad), > 0, of a position servo in series with each gear (see the
        module docstring). ``None``: an infinitely stiff servo.
    """

    k1_nm_per_rad: tuple[float, ...]
    k3_nm_per_rad3: tuple[float, ...]
    c0_nms_per_rad: tuple[float, ...]
    c_load_per_nm: tuple[float, ...]
    load_smoothing_nm: float = 5.0
    max_deflection_rad: float = 0.1
    damper_load_joint: tuple[int, ...] | None = None
    c_load2_per_nm: tuple[float, ...] | None = None
    servo_nm_per_rad: tuple[float, ...] | None = None

    def validate(self, n_dof: int) -> None:
        """Raise ValueError unless every field is finite, has ``n_dof`` entries and a valid sign."""
        per_joint = {
            "k1_nm_per_rad": (self.k1_nm_per_rad, True),
            "k3_nm_per_rad3": (self.k3_nm_per_rad3, False),
            "c0_nms_per_rad": (self.c0_nms_per_rad, False),
            "c_load_per_nm": (self.c_load_per_nm, False),
        }
        if self.c_load2_per_nm is not None:
            per_joint["c_load2_per_nm"] = (self.c_load2_per_nm, False)
        if self.servo_nm_per_rad is not None:
            per_joint["servo_nm_per_rad"] = (self.servo_nm_per_rad, True)
        for name, (values, strictly_positive) in per_joint.items():
            arr = np.asarray(values, dtype=float)
            if arr.shape != (n_dof,):
                raise ValueError(f"FlexParams.{name}: expected {n_dof} values, got {arr.shape}")
            if not np.all(np.isfinite(arr)):
                raise ValueError(f"FlexParams.{name}: contains NaN or infinite values")
            if strictly_positive and np.any(arr <= 0.0):
                raise ValueError(f"FlexParams.{name}: must be > 0, got {arr.tolist()}")
            if np.any(arr < 0.0):
                raise ValueError(f"FlexParams.{name}: must be >= 0, got {arr.tolist()}")
        for name in ("load_smoothing_nm", "max_deflection_rad"):
            value = float(getattr(self, name))
            if not (math.isfinite(value) and value > 0.0):
                raise ValueError(f"FlexParams.{name} must be > 0, got {value!r}")
        if self.damper_load_joint is not None:
            try:
                joints = tuple(self.damper_load_joint)
            except TypeError:
                joints = ()
            if len(joints) != n_dof or not all(
                isinstance(j, (int, np.integer)) and 0 <= j < n_dof for j in joints
            ):
                raise ValueError(
                    f"FlexParams.damper_load_joint: expected {n_dof} joint indices in "
                    f"[0, {n_dof - 1}], got {self.damper_load_joint!r}"
                )

    def c_load2(self) -> np.ndarray:
        """Second load factors ``(n_dof,)`` (1/(N m)); zeros if ``c_load2_per_nm`` is None."""
        if self.c_load2_per_nm is None:
            return np.zeros(len(self.c0_nms_per_rad))
        return np.asarray(self.c_load2_per_nm, dtype=float)

    def damper_load_index(self) -> np.ndarray:
        """Indices ``idx`` ``(n_dof,)``: joint ``j``'s damper load is spring torque ``idx[j]``."""
        if self.damper_load_joint is None:
            return np.arange(len(self.c0_nms_per_rad))
        return np.asarray(self.damper_load_joint, dtype=np.intp)

    def gear_torque_nm(self, gear_delta_rad: np.ndarray) -> np.ndarray:
        """Gear spring torque ``k1 d + k3 d³`` (N m) for gear deflections ``d`` ``(..., n_dof)``."""
        d = np.asarray(gear_delta_rad, dtype=float)
        return np.asarray(self.k1_nm_per_rad) * d + np.asarray(self.k3_nm_per_rad3) * d**3

    def gear_deflection_rad(self, delta_rad: np.ndarray) -> np.ndarray:
        """The gear's share of the joint deflection ``delta_rad`` ``(..., n_dof)`` (rad).

        Without a servo this is ``delta_rad``; with one, the root of
        ``d + (k1 d + k3 d³) / k_s = delta`` (Newton from the linear guess: the left side is
        odd, monotone and convex for ``d > 0``, so the iterates approach the root from one side).
        """
        delta = np.asarray(delta_rad, dtype=float)
        if self.servo_nm_per_rad is None:
            return delta
        k1 = np.asarray(self.k1_nm_per_rad)
        k3 = np.asarray(self.k3_nm_per_rad3)
        ks = np.asarray(self.servo_nm_per_rad, dtype=float)
        d = delta * ks / (ks + k1)
        for _ in range(60):
            step = (d + (k1 * d + k3 * d**3) / ks - delta) / (1.0 + (k1 + 3.0 * k3 * d * d) / ks)
            d = d - step
            if np.all(np.abs(step) <= 1e-15 * np.maximum(1e-6, np.abs(d))):
                break
        return d

    def spring_torque_nm(self, delta_rad: np.ndarray) -> np.ndarray:
        """Joint spring torque (N m) for joint deflections ``(..., n_dof)``: the gear's
        ``k1 d + k3 d³`` at its share ``d`` of the deflection (all of it without a servo)."""
        return self.gear_torque_nm(self.gear_deflection_rad(delta_rad))

    def tangent_stiffness_nm_per_rad(self, delta_rad: np.ndarray) -> np.ndarray:
        """Tangent joint stiffness (N m/rad): the gear's ``k1 + 3 k3 d²`` (eq. 23), in series
        with the servo's ``k_s`` if there is one."""
        d = self.gear_deflection_rad(delta_rad)
        gear = np.asarray(self.k1_nm_per_rad) + 3.0 * np.asarray(self.k3_nm_per_rad3) * d**2
        if self.servo_nm_per_rad is None:
            return gear
        ks = np.asarray(self.servo_nm_per_rad, dtype=float)
        return gear * ks / (gear + ks)

    def damping_nms_per_rad(self, spring_torque_nm: np.ndarray) -> np.ndarray:
        """Load-dependent gear damping ``c0 (1 + c_load |L|_s) (1 + c_load2 |L|_s)`` (N m s/rad).

        Returns an array ``(..., n_dof)``.

        ``spring_torque_nm`` holds the gear spring torques of all joints ``(..., n_dof)``; the
        load ``L`` of joint ``j`` is entry ``damper_load_joint[j]`` of it. This is the one
        definition of the damping law: the time-stepping loop of :class:`tvist.sim.Twin`
        evaluates the same expression in place.
        """
        tau = np.asarray(spring_torque_nm, dtype=float)[..., self.damper_load_index()]
        s = self.load_smoothing_nm
        load = np.sqrt(tau * tau + s * s) - s
        c0 = np.asarray(self.c0_nms_per_rad)
        return c0 * (1.0 + np.asarray(self.c_load_per_nm) * load) * (1.0 + self.c_load2() * load)

    def deflection_rad(self, torque_nm: np.ndarray) -> np.ndarray:
        """Joint deflection that carries ``torque_nm``: the inverse of eq. 22 (the real root;
        Newton) plus the servo's ``tau / k_s`` if there is one."""
        tau = np.asarray(torque_nm, dtype=float)
        k1 = np.asarray(self.k1_nm_per_rad)
        k3 = np.asarray(self.k3_nm_per_rad3)
        delta = tau / k1
        # The spring law is odd and monotone with a convex branch for delta > 0, so Newton from
        # the linear guess moves monotonically towards the root; 60 steps is far more than the
        # few it takes at gear-size torques.
        for _ in range(60):
            step = (k1 * delta + k3 * delta**3 - tau) / (k1 + 3.0 * k3 * delta**2)
            delta = delta - step
            if np.all(np.abs(step) <= 1e-15 * np.maximum(1.0, np.abs(delta))):
                break
        if self.servo_nm_per_rad is not None:
            delta = delta + tau / np.asarray(self.servo_nm_per_rad, dtype=float)
        return delta


#: UR5e, effective joint stiffness and damping (chosen so that with a 5 kg payload 5 cm beyond
#: the flange the base and shoulder modes fall where the paper measured them: Q1 about 8 and
#: 7 Hz, Q3 about 22 and 19 Hz; damping ratios 0.1 to 0.25, the base's higher stretched
#: than folded).
#:
#: - ``k1``: base 22 000, shoulder 18 000 N m/rad, the size-3 strain-wave gears (150 N m
#:   rated) in series with bearings and links (the paper's base gear alone: 42 000 N m/rad).
#:   The elbow is stiff (120 000 N m/rad) so that its flexibility shows up as part of the
#:   shoulder mode, as the paper assumes (section 4.1); with a soft elbow, folded poses such as
#:   Q3 get an elbow mode that mixes with the base mode, because the off-plane offsets of the
#:   forearm, wrist and payload couple base and elbow. Wrists 1-2 (size 1, 28 N m rated):
#:   15 000 N m/rad; wrist 3: 2 000 N m/rad (it carries only the flange and payload inertia
#:   about the tool axis, about 3e-4 kg m², so a stiffer spring would need a shorter time step).
#: - ``k3``: the tangent stiffness ``k1 + 3 k3 delta²`` grows by 25 % at the rated torque
#:   ``tau_r`` (the curve of the paper's Fig. 13 doubles near rated torque):
#:   ``delta_r = 3 tau_r / (3.25 k1)``, ``k3 = 0.25 k1 / (3 delta_r²)``.
#: - ``c0``, ``c_load`` of joints 2-6: gear damping (N m s/rad) that doubles at 100 N m of
#:   the joint's own gear torque (eq. 35, ``c_load`` 0.01 /(N m)).
#: - Base damping, loaded by the shoulder's spring torque (``damper_load_joint[0] = 1``): the
#:   base joint carries no gravity torque, but its cross-roller bearing carries the arm's
#:   tilting moment, and bearing and gear friction grow with that load. The shoulder axis is
#:   horizontal and meets the base axis, so the shoulder gear torque is the moment of all
#:   gravity (and inertial) forces beyond the shoulder about a horizontal axis on the base
#:   axis; at rest the forces are vertical, so this is the tilting moment on the base bearing
#:   in the arm's plane, whatever the height of the bearing. It is evaluated at no extra cost
#:   in the time-stepping loop. Left out are link 1's own moment (its centre of mass lies near
#:   the base axis) and the moment across the arm's plane from the wrist offsets d4-d6, about
#:   13 (no payload) to 30 N m (5 kg) and changing little with the pose, so lumped into ``c0``.
#:   The damping grows faster than linearly with that load, as the real UR5e's measured base
#:   damping does: the paper's map (eq. 48) has the coefficient ``(c_0 + c_2 J_0)(1 + c_τ J_0)``,
#:   about ``J_0^1.3`` over ``J_0 = 1 … 9`` kg m²; at a fixed payload ``J_0`` grows about as
#:   the square of the reach and the tilting moment about linearly (a point mass at reach r:
#:   ``J_0 ∝ r²``, ``L ∝ r``), so in the load that is about ``L^2.6``. The twin uses the same
#:   product form in the load, ``c0 (1 + c_load L)(1 + c_load2 L)``, with ``c0 = 5`` N m s/rad
#:   (unloaded bearing and gear friction) and ``c_load = c_load2 = 0.056`` /(N m): 5, 18, 62
#:   and 200 N m s/rad at 0, 20, 50 and 100 N m. With 5 kg the twin's base ζ is 0.25 at Q1 and
#:   0.053 at Q3 (real UR5e, SPEC Table 3: 0.26 and 0.08), and 0.04-0.25 over the mapping
#:   campaign's poses, within 0.4 (log-rms) of the published map's ζ_0 at the same inertias
#:   (a damping linear in the load: 0.9). A constant base damping (no load) would instead give
#:   ζ = c / (2 √(k J_0)), rising where the arm is folded near the base axis.
UR5E_FLEX = FlexParams(
    k1_nm_per_rad=(22000.0, 18000.0, 120000.0, 15000.0, 15000.0, 2000.0),
    k3_nm_per_rad3=(4.63e7, 2.53e7, 7.51e9, 4.21e8, 4.21e8, 9.98e5),
    c0_nms_per_rad=(5.0, 60.0, 40.0, 5.0, 5.0, 0.2),
    c_load_per_nm=(0.056, 0.01, 0.01, 0.01, 0.01, 0.01),
    damper_load_joint=(1, 1, 2, 3, 4, 5),
    c_load2_per_nm=(0.056, 0.0, 0.0, 0.0, 0.0, 0.0),
)

#: UR10e, effective joint stiffness and damping, scaled from :data:`UR5E_FLEX` by gear size
#: (no measured UR10e modes are published; these put its modes where a stiffer, larger arm
#: would ring: about 4-6 Hz stretched with 5 kg, 12-20 Hz folded).
#:
#: - ``k1``: base 45 000, shoulder 38 000 N m/rad (size-4 gears, 330 N m rated), elbow
#:   200 000 (stiff, as for the UR5e, so that its flexibility joins the shoulder mode), wrists
#:   1-2 20 000 (size 2, 56 N m rated), wrist 3 3 000 (the tool-axis inertia is small; see the
#:   UR5e note on the time step).
#: - ``k3``: the same 25 % stiffening at rated torque, ``k3 = 0.25 k1 / (3 delta_r²)`` with
#:   ``delta_r = 3 tau_r / (3.25 k1)``.
#: - Damping: the UR5e's laws with the load factors scaled by the ratio of rated torques
#:   (150/330 for the base and shoulder), so that the damping doubles at the same fraction of
#:   the rated load; ``c0`` of the shoulder and elbow scaled by ``sqrt(k J)``.
UR10E_FLEX = FlexParams(
    k1_nm_per_rad=(45000.0, 38000.0, 200000.0, 20000.0, 20000.0, 3000.0),
    k3_nm_per_rad3=(8.18e7, 4.93e7, 3.48e10, 2.49e8, 2.49e8, 8.42e5),
    c0_nms_per_rad=(8.0, 150.0, 80.0, 8.0, 8.0, 0.3),
    c_load_per_nm=(0.025, 0.0045, 0.0045, 0.005, 0.005, 0.005),
    damper_load_joint=(1, 1, 2, 3, 4, 5),
    c_load2_per_nm=(0.025, 0.0, 0.0, 0.0, 0.0, 0.0),
)


def stiffening_k3(k1_nm_per_rad: float, rated_nm: float, growth: float = 1.25) -> float:
    """``k3`` (N m/rad³) such that the tangent stiffness ``k1 + 3 k3 δ²`` is ``growth`` x
    ``k1`` at the deflection carrying ``rated_nm``: ``δ_r = 3 τ_r / ((growth + 2) k1)``,
    ``k3 = (growth − 1) k1 / (3 δ_r²)`` (the UR defaults' 25 % at rated torque)."""
    delta_r = 3.0 * rated_nm / ((growth + 2.0) * k1_nm_per_rad)
    return (growth - 1.0) * k1_nm_per_rad / (3.0 * delta_r * delta_r)


#: Franka Research 3, design values (Franka publishes no joint stiffness or damping). Joints
#: 1-4 are flexible (:data:`tvist.robots.urdf.PROXIMAL_JOINTS`: base, shoulder, upper-arm
#: roll, elbow, the joints a modal map of the arm models), joints 5-7 stiff.
#:
#: - ``k1`` of the flexible joints 1-4 (87 N m rated torque, Franka's data sheet): the UR5e's
#:   base stiffness scaled by rated torque, ``22 000 x 87 / 150 = 12 800`` N m/rad (the
#:   torsional stiffness of strain-wave gears of one series grows about in proportion to
#:   their rated torque). With 3 kg 5 cm beyond the flange this puts the base and shoulder
#:   modes at about 7-8 Hz stretched out and 25-35 Hz folded, the roll and elbow modes at
#:   12-45 Hz: the band where a cobot of this size rings.
#: - ``k3``: 25 % stiffening at rated torque, as the UR defaults (:func:`stiffening_k3`).
#: - Joints 5-7 (12 N m) are stiff and linear (``k3 = 0``): each one's own mode lies at
#:   100-250 Hz over the workspace, far above the four modeled modes (the stiffness that
#:   takes the joint's largest axis inertia, 0.14 kg m² for joints 5-6 and 1e-4 kg m² for
#:   the flange joint 7, to 100-150 Hz) and below what the 0.5 ms physics step integrates
#:   stably (``ω dt < 2``, 640 Hz).
#: - Damping: the UR5e's laws (base loaded by the shoulder's torque, growing with the
#:   square of that load; the others doubling at 100 N m of their own) with ``c0`` set for
#:   damping ratios of about 0.05-0.2 over the workspace, as the UR defaults have
#:   (``c0 ≈ 2 ζ √(k J)`` at a mid-workspace inertia); joints 5-7 at about ζ = 0.1 of their
#:   own mode.
FR3_FLEX = FlexParams(
    k1_nm_per_rad=(12800.0, 12800.0, 12800.0, 12800.0, 55000.0, 55000.0, 100.0),
    k3_nm_per_rad3=(*(stiffening_k3(12800.0, 87.0) for _ in range(4)), 0.0, 0.0, 0.0),
    c0_nms_per_rad=(3.0, 30.0, 10.0, 15.0, 13.0, 13.0, 0.02),
    c_load_per_nm=(0.056, 0.01, 0.01, 0.01, 0.01, 0.01, 0.01),
    damper_load_joint=(1, 1, 2, 3, 4, 5, 6),
    c_load2_per_nm=(0.056, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0),
)

#: KUKA LBR iiwa 14 R820, design values (KUKA publishes no joint stiffness or damping).
#:
#: - ``k1`` of the flexible joints 1-4 (rated 320, 320, 176, 176 N m, KUKA's data sheet):
#:   the UR5e's base stiffness scaled by rated torque (see :data:`FR3_FLEX`), 47 000 and
#:   26 000 N m/rad; with 5 kg 5 cm beyond the flange the base and shoulder modes lie at
#:   about 6-7 Hz stretched out and 20-30 Hz folded.
#: - ``k3``: 25 % stiffening at rated torque.
#: - Joints 5-7 (110, 40, 40 N m) stiff and linear, each one's own mode at 100-350 Hz over
#:   the workspace (axis inertias up to 0.11, 0.10 and 0.014 kg m²; see :data:`FR3_FLEX`).
#: - Damping: as :data:`FR3_FLEX`, the load factors scaled by the ratio of rated torques
#:   (150/320 for base and shoulder, 150/176 for roll and elbow) so that the damping doubles
#:   at the same fraction of the rated load, as :data:`UR10E_FLEX` does.
IIWA14_FLEX = FlexParams(
    k1_nm_per_rad=(47000.0, 47000.0, 26000.0, 26000.0, 45000.0, 40000.0, 5000.0),
    k3_nm_per_rad3=(
        stiffening_k3(47000.0, 320.0),
        stiffening_k3(47000.0, 320.0),
        stiffening_k3(26000.0, 176.0),
        stiffening_k3(26000.0, 176.0),
        0.0,
        0.0,
        0.0,
    ),
    c0_nms_per_rad=(10.0, 60.0, 15.0, 25.0, 10.0, 9.0, 1.2),
    c_load_per_nm=(0.026, 0.0047, 0.0085, 0.0085, 0.01, 0.01, 0.01),
    damper_load_joint=(1, 1, 2, 3, 4, 5, 6),
    c_load2_per_nm=(0.026, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0),
)

_DEFAULTS: dict[str, FlexParams] = {
    "ur5e": UR5E_FLEX,
    "ur10e": UR10E_FLEX,
    "fr3": FR3_FLEX,
    "iiwa14": IIWA14_FLEX,
}


class NoTwinError(ValueError):
    """A robot tvist has no twin of (no default :class:`FlexParams`)."""


def default_flex(robot_name: str) -> FlexParams:
    """The default :class:`FlexParams` of ``robot_name``.

    Raises
    ------
    NoTwinError
        If no default is defined for that robot (a ``ValueError``); pass
        ``flex=FlexParams(...)`` explicitly.
    """
    try:
        return _DEFAULTS[robot_name]
    except KeyError:
        known = ", ".join(_DEFAULTS)
        raise NoTwinError(
            f"tvist has no twin of robot {robot_name!r}: its joint flexibility has no default "
            f"(twins: {known}; in Python, pass flex=FlexParams(...))"
        ) from None
