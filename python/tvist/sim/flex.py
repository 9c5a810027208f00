"""Joint flexibility of the simulated arm: strain-wave gear springs and dampers.

Each joint is a flexible joint (paper section 4.3, Fig. 7): the motor side follows the joint
reference, the link side is connected to it through the gear, a nonlinear torsional spring and
a load-dependent damper. With the deflection ``delta = q_motor - q_link`` (rad):

- gear spring, eq. 22: ``tau_spring = k1 * delta + k3 * delta**3`` (N m), tangent stiffness
  ``k1 + 3 k3 delta**2`` (eq. 23);
- gear damping, eq. 35 with constant ``c``: ``tau_damping = c0 * (1 + c_load * |tau_spring|_s) *
  d(delta)/dt`` (N m), i.e. friction that grows with the load the gear carries. ``|x|_s =
  sqrt(x² + s²) − s`` is a smooth absolute value (``s = load_smoothing_nm``): a gear's friction
  has no kink where its load changes sign, and a kink would put one into the true damping
  ratio along a move (and so into references shaped with it).

The stiffness is an *effective* joint stiffness: it lumps the gear with the compliance of the
bearings and the links, which the paper also folds into the joint modes (section 4.1).
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
        Load dependence of the damping (1/(N m)), >= 0: the damping coefficient is
        ``c0 * (1 + c_load * |tau_spring|_s)``.
    load_smoothing_nm
        Width ``s`` of the smooth absolute value ``|x|_s = sqrt(x² + s²) − s`` (N m), > 0.
    max_deflection_rad
        A gear deflection larger than this (rad) means the simulation has diverged; real
        strain-wave gears deflect a few milliradians.
    """

    k1_nm_per_rad: tuple[float, ...]
    k3_nm_per_rad3: tuple[float, ...]
    c0_nms_per_rad: tuple[float, ...]
    c_load_per_nm: tuple[float, ...]
    load_smoothing_nm: float = 5.0
    max_deflection_rad: float = 0.1

    def validate(self, n_dof: int) -> None:
        """Raise ValueError unless every field is finite, has ``n_dof`` entries and a valid sign."""
        per_joint = {
            "k1_nm_per_rad": (self.k1_nm_per_rad, True),
            "k3_nm_per_rad3": (self.k3_nm_per_rad3, False),
            "c0_nms_per_rad": (self.c0_nms_per_rad, False),
            "c_load_per_nm": (self.c_load_per_nm, False),
        }
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

    def spring_torque_nm(self, delta_rad: np.ndarray) -> np.ndarray:
        """Gear spring torque ``k1 delta + k3 delta³`` (N m) for deflections ``(..., n_dof)``."""
        delta = np.asarray(delta_rad, dtype=float)
        return np.asarray(self.k1_nm_per_rad) * delta + np.asarray(self.k3_nm_per_rad3) * delta**3

    def tangent_stiffness_nm_per_rad(self, delta_rad: np.ndarray) -> np.ndarray:
        """Tangent gear stiffness ``k1 + 3 k3 delta²`` (N m/rad), eq. 23."""
        delta = np.asarray(delta_rad, dtype=float)
        return np.asarray(self.k1_nm_per_rad) + 3.0 * np.asarray(self.k3_nm_per_rad3) * delta**2

    def damping_nms_per_rad(self, spring_torque_nm: np.ndarray) -> np.ndarray:
        """Load-dependent gear damping ``c0 (1 + c_load |tau|_s)`` (N m s/rad)."""
        tau = np.asarray(spring_torque_nm, dtype=float)
        s = self.load_smoothing_nm
        load = np.sqrt(tau * tau + s * s) - s
        return np.asarray(self.c0_nms_per_rad) * (1.0 + np.asarray(self.c_load_per_nm) * load)

    def deflection_rad(self, torque_nm: np.ndarray) -> np.ndarray:
        """Deflection that carries ``torque_nm`` (inverse of eq. 22, the real root; Newton)."""
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
        return delta


#: UR5e, effective joint stiffness and damping (chosen so that with a 5 kg payload 5 cm beyond
#: the flange the base and shoulder modes fall where the paper measured them: Q1 about 8 and
#: 7 Hz, Q3 about 22 and 19 Hz; damping ratios 0.1 to 0.25).
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
#: - ``c0``, ``c_load``: gear damping that doubles at 100 N m of gear torque (eq. 35).
UR5E_FLEX = FlexParams(
    k1_nm_per_rad=(22000.0, 18000.0, 120000.0, 15000.0, 15000.0, 2000.0),
    k3_nm_per_rad3=(4.63e7, 2.53e7, 7.51e9, 4.21e8, 4.21e8, 9.98e5),
    c0_nms_per_rad=(90.0, 60.0, 40.0, 5.0, 5.0, 0.2),
    c_load_per_nm=(0.01, 0.01, 0.01, 0.01, 0.01, 0.01),
)

_DEFAULTS: dict[str, FlexParams] = {"ur5e": UR5E_FLEX}


def default_flex(robot_name: str) -> FlexParams:
    """The default :class:`FlexParams` of ``robot_name``.

    Raises
    ------
    ValueError
        If no default is defined for that robot; pass ``flex=FlexParams(...)`` explicitly.
    """
    try:
        return _DEFAULTS[robot_name]
    except KeyError:
        known = ", ".join(_DEFAULTS)
        raise ValueError(
            f"no default FlexParams for robot {robot_name!r} (defaults exist for: {known}); "
            "pass flex=FlexParams(...)"
        ) from None
