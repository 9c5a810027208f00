"""A seeded family of plausible arm variants around a robot's twin, with their true modes.

:func:`sample_variant` draws one arm from a seed (the same seed always gives the same arm);
:func:`nominal_variant` is the default twin in the same form. Each :class:`Variant` builds its
MuJoCo twin (:meth:`Variant.twin`) and knows its true modes at a pose
(:meth:`Variant.true_modes`: eigen-analysis of the twin linearised about its static
equilibrium under gravity, payload included). A variant is named ``family:<robot>:<seed>``
wherever the twin variants of :mod:`tvist.sim.variants` are (``tvist campaign --sim
--variant family:ur5e:17``).

What is drawn, per joint ``j`` (nominal: :func:`tvist.sim.default_flex`):

- **Gear stiffness** ``k1``: base, shoulder and wrist 3 at 0.6-1.6 x nominal (uniform), the
  spread of strain-wave gears of one size and of their mounting. The **elbow** from rigid (the
  twin's stiff elbow, whose flexibility joins the shoulder mode) down to half the shoulder's
  nominal stiffness, log-uniform: softer than the shoulder, so that at folded poses it rings
  as a mode of its own. **Wrists 1-2** 0.25-1.6 x nominal, log-uniform.
- **Gear stiffening with load**: the tangent stiffness ``k1 + 3 k3 δ²`` grows by a factor
  ``g`` of 1 (a linear spring) to 3 (a harmonic drive's curve, ``ur5e-soft-gears``) at the
  gear's rated torque (uniform; the twin's nominal is 1.25). The rated torques are those of
  the nominal gear laws (their ``k3`` is the 1.25 growth at it).
- **Servo in series** with the gear (:class:`~tvist.sim.FlexParams` ``servo_nm_per_rad``):
  ``k_s`` of 2-20 x the joint's nominal gear stiffness (log-uniform): at 2 the joint is a
  third softer than its gear, at 20 under 5 %. A design range: the UR's position-loop
  stiffness is not published.
- **Damping**: every joint's damping law (``c0 (1 + c_load |L|)(1 + c_load2 |L|)``) scaled by
  0.5-2 (log-uniform). The nominal laws put the base and shoulder modes' damping ratios
  where the real UR5e's are (0.08-0.37 at the paper's poses Q1 and Q3, SPEC Table 3; the
  twin 0.05-0.25 over the campaign); the factor of two either way stands for the
  joint-to-joint and arm-to-arm spread of gear friction (temperature, lubricant, wear). Over
  seeds 0-99, with 5 kg at Q1 and Q3, the first three modes' ζ then span 0.029-0.64 on the
  UR5e (5-95 %: 0.054-0.39) and 0.020-0.54 on the UR10e (0.041-0.31): the measured UR5e
  range with some margin on both sides (``tests/integration/test_family.py`` checks every
  one stays within 0.005-0.9).
- **Flexible links** (:mod:`tvist.sim.beams`): half of the variants have a bending upper arm
  and forearm, a tube of 0.85-1.15 x the robot's nominal diameter (UR5e 80 mm, UR10e
  100 mm) with 2.5-4 mm wall and structural loss factor 0.01-0.04 (design choices, as for
  ``ur5e-flex-links``: no measured link sections are published).

The physics time step is the twin's 0.5 ms where no joint is stiffer than nominal, else
halved (a joint's own mode is about ``√k`` faster, and the explicit spring needs ``ω dt`` well
below 2); with bending links it is theirs (0.125 ms).
"""

from __future__ import annotations

import math
import zlib
from collections.abc import Sequence
from dataclasses import dataclass, replace
from typing import NamedTuple

import numpy as np

from tvist.sim.beams import LinkBeams
from tvist.sim.flex import FlexParams, default_flex, stiffening_k3
from tvist.sim.twin import Twin

__all__ = [
    "FAMILY_PREFIX",
    "TrueMode",
    "Variant",
    "nominal_variant",
    "parse_family_name",
    "sample_variant",
]

#: Names of family variants are ``family:<robot>:<seed>``.
FAMILY_PREFIX = "family"
#: The seed part of the nominal variant's name (the robot's default twin).
NOMINAL = "nominal"

#: Robots the family is defined for: nominal tube diameter of the bending links (m).
_TUBE_DIAMETER_M = {"ur5e": 0.080, "ur10e": 0.100}

#: Sampling ranges (see the module docstring).
STIFFNESS_RANGE = (0.6, 1.6)
WRIST_STIFFNESS_RANGE = (0.25, 1.6)
#: The softest elbow, as a fraction of the shoulder's nominal gear stiffness.
SOFTEST_ELBOW_OF_SHOULDER = 0.5
STIFFENING_RANGE = (1.0, 3.0)
SERVO_RATIO_RANGE = (2.0, 20.0)
DAMPING_RANGE = (0.5, 2.0)
BEAM_PROBABILITY = 0.5
TUBE_DIAMETER_RANGE = (0.85, 1.15)
TUBE_WALL_RANGE_M = (0.0025, 0.004)
LOSS_FACTOR_RANGE = (0.01, 0.04)
#: The growth of the tangent stiffness at rated torque that the nominal gear laws have.
NOMINAL_STIFFENING = 1.25
#: The twin's default time step (s), fine for gears up to their nominal stiffness.
_BASE_PHYSICS_DT_S = 0.0005


class TrueMode(NamedTuple):
    """One vibration mode of a variant at a pose (eigen-analysis, see
    :meth:`Variant.true_modes`).

    Attributes
    ----------
    freq_hz
        Undamped natural frequency ``|λ| / 2π`` (Hz).
    zeta
        Damping ratio ``−Re λ / |λ|``.
    joint_shares
        Share of the mode's strain energy stored in each joint's spring ``(n_dof,)``; with
        ``link_share`` it sums to 1.
    flange_direction
        Unit vector (base frame) of the flange's translation in this mode: the major axis of
        the (generally elliptic, for a complex mode) path of ``J_p φ``, sign such that its
        largest component is positive. ``(3,)``.
    link_share
        Share stored in the bending links (0 for rigid links).
    """

    freq_hz: float
    zeta: float
    joint_shares: np.ndarray
    flange_direction: np.ndarray
    link_share: float


def rated_torque_nm(flex: FlexParams) -> np.ndarray:
    """Rated torque of each joint's gear (N m) implied by a nominal gear law: the torque at
    which its tangent stiffness has grown by :data:`NOMINAL_STIFFENING` (the inverse of
    :func:`~tvist.sim.flex.stiffening_k3`); infinite for a linear spring (``k3 = 0``)."""
    k1 = np.asarray(flex.k1_nm_per_rad, dtype=float)
    k3 = np.asarray(flex.k3_nm_per_rad3, dtype=float)
    with np.errstate(divide="ignore"):
        delta_r = np.sqrt((NOMINAL_STIFFENING - 1.0) * k1 / (3.0 * k3))
    return delta_r * (NOMINAL_STIFFENING + 2.0) * k1 / 3.0


@dataclass(frozen=True)
class Variant:
    """One arm of the family: its drawn parameters and the flexibility they make.

    Attributes
    ----------
    robot
        Robot of the parameter file (``"ur5e"``, ``"ur10e"``).
    seed
        The seed it was drawn from; ``None`` for :func:`nominal_variant`.
    stiffness_factor
        Gear stiffness ``k1`` per joint over the nominal ``(n_dof,)``.
    stiffening
        Growth of the tangent stiffness at rated torque per joint (1: linear spring).
    servo_ratio
        Servo stiffness over the joint's nominal gear stiffness; ``inf``: an ideal servo.
    damping_factor
        Damping law per joint over the nominal.
    beams
        The bending links, ``None`` if rigid.
    physics_dt_s
        The twin's time step (s).
    """

    robot: str
    seed: int | None
    stiffness_factor: tuple[float, ...]
    stiffening: tuple[float, ...]
    servo_ratio: tuple[float, ...]
    damping_factor: tuple[float, ...]
    beams: LinkBeams | None
    physics_dt_s: float

    @property
    def name(self) -> str:
        """``family:<robot>:<seed>`` (``family:<robot>:nominal`` for the nominal variant)."""
        tail = NOMINAL if self.seed is None else str(self.seed)
        return f"{FAMILY_PREFIX}:{self.robot}:{tail}"

    @property
    def flex(self) -> FlexParams:
        """The joints' springs and dampers (:class:`~tvist.sim.FlexParams`)."""
        nominal = default_flex(self.robot)
        k1 = np.asarray(nominal.k1_nm_per_rad) * np.asarray(self.stiffness_factor)
        rated = rated_torque_nm(nominal)
        k3 = [
            stiffening_k3(float(k), float(t), float(g))
            for k, t, g in zip(k1, rated, self.stiffening, strict=True)
        ]
        ratio = np.asarray(self.servo_ratio, dtype=float)
        servo = None
        if np.all(np.isfinite(ratio)):
            servo = tuple(float(v) for v in ratio * np.asarray(nominal.k1_nm_per_rad))
        return replace(
            nominal,
            k1_nm_per_rad=tuple(float(v) for v in k1),
            k3_nm_per_rad3=tuple(k3),
            c0_nms_per_rad=tuple(
                float(c * f)
                for c, f in zip(nominal.c0_nms_per_rad, self.damping_factor, strict=True)
            ),
            servo_nm_per_rad=servo,
        )

    def twin_kwargs(self) -> dict:
        """The :class:`~tvist.sim.Twin` keywords that make this variant (``flex``, ``beams``,
        ``physics_dt_s``)."""
        return {"flex": self.flex, "beams": self.beams, "physics_dt_s": self.physics_dt_s}

    def twin(
        self,
        payload_kg: float = 5.0,
        payload_com_m: Sequence[float] = (0.0, 0.0, 0.05),
        **kwargs,
    ) -> Twin:
        """The variant's MuJoCo twin with a payload (other keywords go to
        :class:`~tvist.sim.Twin`, e.g. ``accel_noise_std``, ``seed``)."""
        return Twin(
            self.robot,
            payload_kg=payload_kg,
            payload_com_m=payload_com_m,
            **self.twin_kwargs(),
            **kwargs,
        )

    def true_modes(
        self,
        q: Sequence[float] | np.ndarray,
        payload_kg: float = 5.0,
        payload_com_m: Sequence[float] = (0.0, 0.0, 0.05),
        *,
        max_freq_hz: float | None = None,
    ) -> list[TrueMode]:
        """The variant's vibration modes with the motors held at ``q`` (rad), lowest first.

        The twin linearised about its static equilibrium under gravity with the payload
        (:meth:`tvist.sim.Twin.modal_analysis`); only oscillating modes, up to ``max_freq_hz``
        if given.
        """
        return modes_of(self.twin(payload_kg, payload_com_m), q, max_freq_hz=max_freq_hz)


def modes_of(
    twin: Twin, q: Sequence[float] | np.ndarray, *, max_freq_hz: float | None = None
) -> list[TrueMode]:
    """:class:`TrueMode` list of ``twin`` at motor angles ``q`` (see
    :meth:`Variant.true_modes`)."""
    analysis = twin.modal_analysis(q)
    state = twin.equilibrium_state(q)
    jac = twin.flange_jacobian(state)
    arm = twin.arm_dofs
    links = np.setdiff1d(np.arange(twin.n_state), arm)
    out = []
    for m in range(len(analysis.wn_rad_s)):
        freq = float(analysis.freq_hz[m])
        if max_freq_hz is not None and freq > max_freq_hz:
            break
        motion = jac @ analysis.shapes[:, m]  # complex flange translation (3,)
        # Major axis of the ellipse traced by Re(motion e^{iωt}).
        u, _, _ = np.linalg.svd(np.column_stack([motion.real, motion.imag]))
        direction = u[:, 0]
        direction = direction * np.sign(direction[np.argmax(np.abs(direction))])
        out.append(
            TrueMode(
                freq_hz=freq,
                zeta=float(analysis.zeta[m]),
                joint_shares=analysis.strain_energy[arm, m].copy(),
                flange_direction=direction,
                link_share=float(analysis.strain_energy[links, m].sum()),
            )
        )
    return out


def _rng(robot: str, seed: int) -> np.random.Generator:
    """The generator of variant ``(robot, seed)``: independent streams per robot."""
    return np.random.default_rng([int(seed), zlib.crc32(robot.encode())])


def _log_uniform(rng: np.random.Generator, lo: float, hi: float, size=None):
    return np.exp(rng.uniform(math.log(lo), math.log(hi), size=size))


def _physics_dt_s(stiffness_factor: np.ndarray, beams: LinkBeams | None) -> float:
    """0.5 ms halved as many times as the stiffest joint's mode speeds up over nominal."""
    speedup = math.sqrt(max(1.0, float(np.max(stiffness_factor))))
    dt = _BASE_PHYSICS_DT_S / math.ceil(speedup - 1e-12)
    return dt if beams is None else min(dt, beams.physics_dt_s)


def _check_robot(robot: str) -> None:
    if robot not in _TUBE_DIAMETER_M:
        raise ValueError(
            f"the variant family is defined for {', '.join(_TUBE_DIAMETER_M)}, not {robot!r}"
        )


def sample_variant(robot: str, seed: int) -> Variant:
    """Draw variant ``seed`` of ``robot``'s family (see the module docstring for the ranges).

    Deterministic: the same ``(robot, seed)`` gives the same variant on every run.

    Raises
    ------
    ValueError
        A robot the family is not defined for, or a negative seed.
    """
    _check_robot(robot)
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise ValueError(f"seed must be a non-negative integer, got {seed!r}")
    nominal = default_flex(robot)
    n = len(nominal.k1_nm_per_rad)
    rng = _rng(robot, int(seed))
    stiffness = rng.uniform(*STIFFNESS_RANGE, size=n)
    # Elbow: from the nominal (rigid) elbow down to half the shoulder's nominal stiffness.
    softest = SOFTEST_ELBOW_OF_SHOULDER * nominal.k1_nm_per_rad[1] / nominal.k1_nm_per_rad[2]
    stiffness[2] = _log_uniform(rng, softest, 1.0)
    stiffness[3:5] = _log_uniform(rng, *WRIST_STIFFNESS_RANGE, size=2)
    stiffening = rng.uniform(*STIFFENING_RANGE, size=n)
    servo = _log_uniform(rng, *SERVO_RATIO_RANGE, size=n)
    damping = _log_uniform(rng, *DAMPING_RANGE, size=n)
    beams = None
    if rng.uniform() < BEAM_PROBABILITY:
        beams = LinkBeams(
            links=(1, 2),
            outer_diameter_m=float(_TUBE_DIAMETER_M[robot] * rng.uniform(*TUBE_DIAMETER_RANGE)),
            wall_m=float(rng.uniform(*TUBE_WALL_RANGE_M)),
            loss_factor=float(rng.uniform(*LOSS_FACTOR_RANGE)),
        )
    return Variant(
        robot=robot,
        seed=int(seed),
        stiffness_factor=tuple(float(v) for v in stiffness),
        stiffening=tuple(float(v) for v in stiffening),
        servo_ratio=tuple(float(v) for v in servo),
        damping_factor=tuple(float(v) for v in damping),
        beams=beams,
        physics_dt_s=_physics_dt_s(stiffness, beams),
    )


def nominal_variant(robot: str) -> Variant:
    """The default twin of ``robot`` as a :class:`Variant`: every factor 1, nominal stiffening,
    an ideal servo, rigid links. Defined for every robot with a
    :func:`~tvist.sim.default_flex` (the family's draws only for :data:`_TUBE_DIAMETER_M`'s).

    Raises
    ------
    ValueError
        A robot without default flexibility.
    """
    n = len(default_flex(robot).k1_nm_per_rad)
    return Variant(
        robot=robot,
        seed=None,
        stiffness_factor=(1.0,) * n,
        stiffening=(NOMINAL_STIFFENING,) * n,
        servo_ratio=(math.inf,) * n,
        damping_factor=(1.0,) * n,
        beams=None,
        physics_dt_s=_BASE_PHYSICS_DT_S,
    )


def parse_family_name(name: str) -> Variant | None:
    """The variant named ``family:<robot>:<seed>``; ``None`` if ``name`` is not a family name.

    Raises
    ------
    ValueError
        A family name with an unknown robot or a seed that is not a non-negative integer.
    """
    parts = name.split(":")
    if parts[0] != FAMILY_PREFIX:
        return None
    if len(parts) == 3 and parts[2] == NOMINAL:
        return nominal_variant(parts[1])
    if len(parts) != 3 or not parts[2].isdigit():
        raise ValueError(
            f"twin variant {name!r}: a family variant is named {FAMILY_PREFIX}:<robot>:<seed> "
            f"or {FAMILY_PREFIX}:<robot>:{NOMINAL}, e.g. {FAMILY_PREFIX}:ur5e:17"
        )
    return sample_variant(parts[1], int(parts[2]))
