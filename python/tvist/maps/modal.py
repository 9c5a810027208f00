"""The modal map as data: flexible joints, their load laws, save and load.

The physics lives in the Rust core (``tvist-core/src/modes/modal/modal_map.rs``): every
flexible joint ``j`` is a torsional spring ``k_j`` and damper ``c_j`` between its motor (held
rigidly by the servo) and its link, each with its own load law (below), so ``K = diag(k_j)`` and
``C = diag(c_j)``. At each pose the modes are the roots ``λ`` of the damped eigenproblem
``det(λ² M_ff(q) + λ C + K) = 0``, with ``M_ff`` the block of the link-side mass matrix on the
flexible joints: ``ω_n = |λ|``, ``ζ = −Re λ / |λ|``. The core solves it exactly (from the
undamped modes of ``K φ = ω² M_ff φ``), so the damping coupling of close modes is kept, not
the joint dampers projected onto the undamped modes; only a pose with a mode at or beyond
critical damping falls back to that projection, where the overdamped mode has ``ζ >= 1`` and
the shaper holds its last valid modes. The shaped modes are named in one of two ways:

- ``mode_joints`` (e.g. ``[0, 1]``): mode ``m`` is the eigenmode that stores the largest share
  of its strain energy in joint ``mode_joints[m]``, so "base" and "shoulder" keep their meaning
  when their frequencies cross.
- ``shaped_modes`` (an integer K): the K lowest-frequency eigenmodes as a set, whatever
  joint they strain most, shaped in slots ordered by the joint each strains most.
  :func:`tvist.maps.modes_to_shape` picks K for a move.

Each shaped mode is an eigenmode as it is. That rule picks the eigenmodes at a pose; along a
motion the streaming shaper keeps each member of the rule's set in the filter whose eigenmode
it continues (same mode shape, nearby frequency), so a filter keeps its mode and damping where
two modes cross, and where the rule's pick for a filter becomes another eigenmode (dominance
swaps, or the K-th and the next cross) the filter hands over gradually (0.004 in ln ω and ζ
per cycle) instead of jumping (module docs of ``modal_map.rs``).
:meth:`ModalMap.modes_many` evaluates the rule at each pose alone (for checks at independent
poses: a map against measured modes); ``tracked=True`` evaluates a path of poses as the
shaper does. Once the shaper rests at the end of a move its modes (and delay) are the rule's
at the end pose.

**Bending links** (``link_hinges``, optional): a link that bends is a lumped hinge pair about
the two axes perpendicular to it, at ``at_fraction`` of its length, with a spring
``stiffness_nm_per_rad`` and a damper ``damping_nms_per_rad`` about each axis; the link's
inertia is split between its halves so that with straight hinges the arm is the rigid one.
The flexible coordinates are then the joints plus two per hinge (at most 9 in all) and
``M_ff`` is the mass-matrix block of the hinged arm (:meth:`tvist.Robot.with_link_hinges`).

**Load laws.** A flexible joint's stiffness and damping grow with a static load ``L``
(gravity torque, N m): ``v(L) = v_0 + v_1 |L|_s + v_2 L²``; the stiffness of joint ``j`` reads
its own gravity torque, its damping that of ``damping_load_joint``. The laws are the joints'
(a hinge's spring and damper are constant); a mode's damping ratio follows from them through
the eigenproblem above.

Map files are strict JSON, read, checked and written by the Rust core (one validation for
Python, Rust and C; errors name the field path, e.g. ``flex_joints[1].stiffness_nm_per_rad``),
``"kind": "modal"``::

    {"schema_version": 1, "kind": "modal",
     "metadata": {"robot": "ur5e", "payload": null, "source": "...",
                  "fit_statistics": {...} | null},
     "mode_joints": [0, 1],          (or "shaped_modes": 3: exactly one of the two)
     "flex_joints": [{"joint": 0, "stiffness_nm_per_rad": [k_0, k_1, k_2],
                      "damping_nms_per_rad": [c_0, c_1, c_2], "damping_load_joint": 1},
                     ...],
     "link_hinges": [{"link": 1, "at_fraction": 0.5, "stiffness_nm_per_rad": k_h,
                      "damping_nms_per_rad": c_h}, ...]}       (optional; rigid links without)

``metadata`` is as in a paper10 map file (:mod:`tvist.maps.paper10`): ``metadata.robot``
names the robot the map was identified on, and :class:`ModalDynamics` refuses the map for
another robot unless ``allow_other_robot=True``. :func:`tvist.load_map` reads a map file of
either kind.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from tvist import _core
from tvist.maps.files import MapDocument, RobotModesMixin
from tvist.robots import Robot
from tvist.robots._robot import HingedArm

__all__ = [
    "KIND",
    "SCHEMA_VERSION",
    "ModalDynamics",
    "ModalMap",
    "modal_map_from_flex",
]

SCHEMA_VERSION: int = _core.MAP_SCHEMA_VERSION
#: The ``kind`` of a modal map file.
KIND: str = _core.MAP_KIND_MODAL
#: Fields of one flexible joint.
FLEX_JOINT_FIELDS: tuple[str, ...] = tuple(_core.FLEX_JOINT_FIELDS)


def _plain(value: Any) -> Any:
    """``value`` with numpy scalars and arrays as Python numbers and lists (the core reads
    JSON-like Python objects)."""
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, Mapping):
        return {k: _plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    return value


class ModalMap(MapDocument):
    """Modes from the mass matrix and identified joint flexibility.

    Parameters
    ----------
    flex_joints
        One mapping per flexible joint with :data:`FLEX_JOINT_FIELDS`: ``joint``,
        ``stiffness_nm_per_rad`` and ``damping_nms_per_rad`` as ``[v_0, v_1, v_2]`` (value
        at zero load, per N m, per (N m)²; ``v_0 > 0`` for the stiffness, all ``>= 0``), and
        ``damping_load_joint``.
    mode_joints
        The joints naming the shaped modes, in cascade order (default base, shoulder, unless
        ``shaped_modes`` is given).
    metadata
        ``robot``, ``source``, ``fit_statistics`` and anything else JSON-ready.
    shaped_modes
        Instead of ``mode_joints``: the number K of lowest-frequency modes shaped, in
        frequency order (1 to the number of flexible coordinates).
    link_hinges
        Bending links: one mapping per hinged link with ``link``, ``at_fraction``,
        ``stiffness_nm_per_rad`` and ``damping_nms_per_rad`` (module docstring); none by
        default.

    Raises
    ------
    ValueError
        Naming the field: missing, unknown, non-finite or negative values, a joint listed
        twice, a mode joint that is not flexible, both ``mode_joints`` and ``shaped_modes``, a
        ``shaped_modes`` outside 1 to the number of flexible joints.
    """

    def __init__(
        self,
        flex_joints: Sequence[Mapping[str, Any]],
        mode_joints: Sequence[int] | None = None,
        metadata: Mapping[str, Any] | None = None,
        *,
        shaped_modes: int | None = None,
        link_hinges: Sequence[Mapping[str, Any]] | None = None,
    ) -> None:
        if isinstance(flex_joints, (str, bytes)) or not isinstance(flex_joints, Sequence):
            raise ValueError("flex_joints: must be a list of flexible-joint objects")
        if mode_joints is not None and shaped_modes is not None:
            raise ValueError("shaped_modes: give either mode_joints or shaped_modes, not both")
        if mode_joints is None and shaped_modes is None:
            mode_joints = (0, 1)
        if mode_joints is not None and (
            isinstance(mode_joints, (str, bytes)) or not isinstance(mode_joints, Sequence)
        ):
            raise ValueError("mode_joints: must be a list of joint indices")
        if metadata is not None and not isinstance(metadata, Mapping):
            raise ValueError("metadata: must be an object")
        selection = (
            {"mode_joints": _plain(mode_joints)}
            if mode_joints is not None
            else {"shaped_modes": _plain(shaped_modes)}
        )
        document = {
            "schema_version": SCHEMA_VERSION,
            "kind": KIND,
            "metadata": _plain(metadata),
            **selection,
            "flex_joints": _plain(flex_joints),
        }
        if link_hinges:
            document["link_hinges"] = _plain(link_hinges)
        core, self.metadata = _core.map_from_document(document)
        self._core: _core.ModalMap = core

    _core_type = _core.ModalMap
    _other_kind = (
        "kind: a paper10 map, not a modal map: read it with tvist.DynamicMap.load or tvist.load_map"
    )

    @property
    def core(self) -> _core.ModalMap:
        """The Rust map (pass-through for :class:`ModalDynamics`)."""
        return self._core

    @property
    def link_hinges(self) -> list[dict[str, Any]]:
        """The bending links (see the constructor), in link order; empty for rigid links."""
        return self._core.link_hinges

    def evaluated_arm(self, robot: Robot) -> Robot | HingedArm:
        """The arm whose mass matrix the map reads: ``robot`` itself, or with link hinges
        the hinged arm (:meth:`tvist.Robot.with_link_hinges`)."""
        hinges = self.link_hinges
        if not hinges:
            return robot
        return robot.with_link_hinges([(h["link"], h["at_fraction"]) for h in hinges])

    @property
    def flex_joints(self) -> list[dict[str, Any]]:
        """The flexible joints (see the constructor)."""
        return self._core.flex_joints

    @property
    def mode_joints(self) -> list[int] | None:
        """The joints naming the shaped modes, in cascade order; ``None`` for a map shaping
        its lowest-frequency modes (:attr:`shaped_modes`)."""
        return self._core.mode_joints

    @property
    def shaped_modes(self) -> int | None:
        """The number of lowest-frequency modes shaped; ``None`` for a map naming its modes
        by joint (:attr:`mode_joints`)."""
        return self._core.shaped_modes

    def joint_laws(self, robot: Robot, q: Sequence[float] | np.ndarray) -> np.ndarray:
        """Stiffness (N m/rad) and damping (N m s/rad) of every flexible joint at pose ``q``
        of ``robot`` (the laws at its gravity torques), in the order of :attr:`flex_joints`:
        ``(n_flex, 2)``."""
        tau = robot.gravity_torque_many(np.asarray(q, dtype=float)[None, :])
        return self._core.joint_laws_many(np.ascontiguousarray(tau))[0]

    def modes_from_mass_matrix_many(
        self,
        mass_kg_m2: np.ndarray,
        gravity_torque_nm: np.ndarray | None = None,
        *,
        tracked: bool = False,
    ) -> np.ndarray:
        """Shaped modes for mass matrices ``(n_poses, n_dof, n_dof)`` (kg m²) and gravity
        torques ``(n_poses, n_dof)`` (N m; needed when :attr:`uses_gravity`).

        ``tracked``: the poses are a path (e.g. the samples of a move), each mode following its
        eigenmode branch from the first pose on, as the streaming shaper does; otherwise the
        rule at each pose alone (module docs).

        Returns ``(n_poses, n_modes, 2)``: ``[..., 0]`` ``wn_rad_s``, ``[..., 1]`` ``zeta``;
        NaN where the mass block is not positive definite or not finite.
        """
        m = np.asarray(mass_kg_m2, dtype=float)
        if m.ndim != 3 or m.shape[1] != m.shape[2]:
            raise ValueError(f"mass_kg_m2 must have shape (n_poses, n, n), got {m.shape}")
        n_dof = m.shape[1]
        flat = np.ascontiguousarray(m.reshape(m.shape[0], n_dof * n_dof))
        tau = None
        if gravity_torque_nm is not None:
            tau = np.ascontiguousarray(gravity_torque_nm, dtype=float)
            if tau.shape != (m.shape[0], n_dof):
                raise ValueError(
                    f"gravity_torque_nm must have shape {(m.shape[0], n_dof)}, got {tau.shape}"
                )
        return self._core.modes_from_mass_matrix_many(flat, n_dof, tau, bool(tracked))

    def modes_many(self, robot: Robot, q: np.ndarray, *, tracked: bool = False) -> np.ndarray:
        """Shaped modes at every configuration ``q`` ``(n_poses, n_dof)`` of ``robot``
        (payload included): ``(n_poses, n_modes, 2)``; ``tracked`` as in
        :meth:`modes_from_mass_matrix_many` (``q`` a path)."""
        q = np.ascontiguousarray(np.atleast_2d(q), dtype=float)
        arm = self.evaluated_arm(robot)
        tau = arm.gravity_torque_many(q) if self.uses_gravity else None
        return self.modes_from_mass_matrix_many(arm.mass_matrix_many(q), tau, tracked=tracked)

    def modes(self, robot: Robot, q: Sequence[float] | np.ndarray) -> list[tuple[float, float]]:
        """Shaped modes ``[(wn_rad_s, zeta), ...]`` at configuration ``q`` of ``robot``."""
        out = self.modes_many(robot, np.asarray(q, dtype=float)[None, :])[0]
        return [(float(wn), float(z)) for wn, z in out]

    @property
    def robot(self) -> str | None:
        """The robot the map was identified on (``metadata["robot"]``), or ``None``."""
        return self._core.robot

    def __repr__(self) -> str:
        joints = [f["joint"] for f in self.flex_joints]
        shaped = (
            f"mode_joints={self.mode_joints}"
            if self.mode_joints is not None
            else f"shaped_modes={self.shaped_modes}"
        )
        return f"ModalMap(flex_joints={joints}, {shaped}, robot={self.metadata.get('robot')!r})"


class ModalDynamics(RobotModesMixin, _core.ModalDynamics):
    """Per-cycle dynamics provider for :class:`tvist.TvShaper`: robot mass matrix + modal map.

    Every cycle the mass matrix (and the gravity torques, if the map's laws read them) of
    ``robot`` are evaluated at the previous shaped output and the modal eigenproblem is
    solved, in Rust, allocation-free. :func:`tvist.maps.dynamics_for` builds it for a modal map.
    Construction rejects a map that gives an overdamped mode at any of
    ``ModalDynamics.validation_poses`` sampled configurations or reads joints the robot
    does not have. A map identified on another robot (its ``metadata["robot"]`` differs from
    the robot's name) raises ``ValueError`` naming both, unless ``allow_other_robot=True``
    (research use).
    """

    def __new__(
        cls, robot: Robot, modal_map: ModalMap, *, allow_other_robot: bool = False
    ) -> ModalDynamics:
        cls._check(robot, modal_map, ModalMap, "modal_map")
        return super().__new__(cls, robot.core, modal_map.core, bool(allow_other_robot))


def modal_map_from_flex(
    flex: Any,
    joints: Sequence[int] = (0, 1, 2),
    mode_joints: Sequence[int] = (0, 1),
    metadata: Mapping[str, Any] | None = None,
) -> ModalMap:
    """The modal map of a flexible-joint twin's gear laws (:class:`tvist.sim.FlexParams`).

    The twin's spring ``k1 δ + k3 δ³`` has the tangent stiffness ``k1 + 3 k3 δ²``; with the
    static deflection ``δ ≈ L / k1`` that is ``k1 + (3 k3 / k1²) L²``. Its damper
    ``c0 (1 + a |L|)(1 + b |L|)`` expands to ``c0 + c0 (a + b) |L| + c0 a b L²``. Both are
    first-order approximations (the twin's smoothing width of ``|L|`` also differs), so this
    is a physically derived prior, not an exact copy of the twin. With a servo ``k_s`` in
    series (``servo_nm_per_rad``) the joint's stiffness is ``1 / (1/k_gear + 1/k_s)``, to the
    same order ``k_e + (k_e / k1)² (3 k3 / k1²) L²`` with ``k_e = k1 k_s / (k1 + k_s)``.
    """
    c_load2 = flex.c_load2()
    load_joint = flex.damper_load_index()
    servo = getattr(flex, "servo_nm_per_rad", None)
    entries = []
    for j in joints:
        k1, k3 = float(flex.k1_nm_per_rad[j]), float(flex.k3_nm_per_rad3[j])
        series = 1.0 if servo is None else float(servo[j]) / (k1 + float(servo[j]))  # k_e / k1
        c0, a, b = float(flex.c0_nms_per_rad[j]), float(flex.c_load_per_nm[j]), float(c_load2[j])
        entries.append(
            {
                "joint": int(j),
                "stiffness_nm_per_rad": [k1 * series, 0.0, series**2 * 3.0 * k3 / (k1 * k1)],
                "damping_nms_per_rad": [c0, c0 * (a + b), c0 * a * b],
                "damping_load_joint": int(load_joint[j]),
            }
        )
    meta = {"source": "gear laws of a flexible-joint twin (FlexParams)", **(metadata or {})}
    return ModalMap(entries, mode_joints, meta)
