"""The dynamic map (paper eqs. 42-51) as data: build, evaluate, save and load.

The equations live in the Rust core (``tvist-core/src/modes/paper10/dynamic_map.rs``). Per
mode, with ``J_f`` the inertia of the frequency joint, ``J_d`` that of the damping joint,
``τ_f`` the gravity torque of the frequency joint and ``K = k_0 + k_J J_f + k_g |τ_f|_s``::

    ω_n = √(1 + k_p/J_f) · √(K / J_f)
    ζ   = (1 + k_p/J_d)^e_d · (1 + k_p/J_f)^e_f · (c_0 + c_1 √J_d + c_2 J_d)(1 + c_τ J_d)
          / (2 √(K J_f))

The general map (eqs. 42-43) has ``J_f = J_d`` and ``(e_d, e_f) = (1/2, 0)``; the paper's UR5e
base mode (eqs. 47-48) has ``J_f = J_1``, ``J_d = J_0`` and ``(e_d, e_f) = (1, -1/2)``.
``|τ|_s = √(τ² + τ_s²) − τ_s`` with ``τ_s = 1 N m`` stands in for eq. 42's ``|τ|``, which has a
kink where the gravity torque changes sign; it is below ``|τ|`` by less than ``τ_s`` (only
maps with ``k_g != 0`` read it, so the paper's map and its Table 3 are unchanged).

**Validity ranges.** A mode may carry the inertias it was identified on:
``frequency_inertia_range_kg_m2 = [J_min, J_max]`` for ``J_f`` and
``damping_inertia_range_kg_m2`` for ``J_d`` (equal when both read the same joint). Every
evaluation first saturates ``J_f`` and ``J_d`` into them with a C² soft clamp of relative
width ``ε = 0.05``: the identity on ``[J_min (1 + ε), J_max (1 − ε)]``, exactly ``J_min`` at
or below ``J_min (1 − ε)`` and exactly ``J_max`` at or above ``J_max (1 + ε)``, with quartic
blends in between that stay inside ``[J_min, J_max]`` (within ``3ε/16`` of a bound from the
hard clamp). So a map never extrapolates beyond the inertias it was identified on, and the
modes have no kink at a bound (a kink would put a jerk spike into references shaped with
them). A saturated evaluation is normal operation, not an error. A range needs
``J_max / J_min >= (1 + ε)/(1 − ε) ≈ 1.105`` so that the two blends do not overlap.
Missing or ``null`` is unbounded (the paper's map, whose Table 3 values hold at any inertia).
:func:`tvist.ident.fit_map` sets the ranges from its data.

Map files are strict JSON, read, checked and written by the Rust core (one validation for
Python, Rust and C; errors name the field path, e.g. ``modes[1].k_0``)::

    {"schema_version": 1, "kind": "paper10",
     "metadata": {"robot": "ur5e", "payload": {...} | null, "source": "...",
                  "fit_statistics": {...} | null},
     "modes": [{"k_0": ..., "k_j": ..., "k_g": ..., "k_p": ..., "c_0": ..., "c_1": ...,
                "c_2": ..., "c_tau": ..., "frequency_joint": 1, "damping_joint": 0,
                "damping_gain_exponent": 1.0, "frequency_gain_exponent": -0.5,
                "frequency_inertia_range_kg_m2": [0.7, 9.1] | null,     # optional
                "damping_inertia_range_kg_m2": [0.2, 9.3] | null}, ...]} # optional

``schema_version`` is the integer 1. ``kind`` names the form of the map: ``"paper10"`` is the
ten-coefficient map above; files written before (``"tvist.dynamic_map"`` or no ``kind``) read
as ``"paper10"``. ``metadata.robot`` names the robot the map was identified on:
:class:`MapDynamics` refuses the map for another robot unless ``allow_other_robot=True``.
The gain exponents must lie within ±2 (the published forms use −½, 0, ½, 1). Every mode must
be physical at every inertia it reads (its ranges, or ``(0, ∞)`` without them) and every
gravity torque: ``k_g >= 0``, ``k_0 + k_J J_f > 0``, ``1 + k_p/J > 0``,
``c_0 + c_1 √J_d + c_2 J_d >= 0`` and ``1 + c_τ J_d >= 0``, so its modes are finite with
``ω_n > 0`` and ``ζ >= 0`` (``ζ < 1`` over a robot's poses is checked by
:class:`MapDynamics`). At most ``tvist.MAX_MODES`` (64) modes; a file of at most 1 MiB, no
repeated key (a UTF-8 byte-order mark is accepted). No ``NaN`` or
``Infinity`` tokens are read or written: ``null`` means unbounded for a range and "not
available" for metadata (a statistic that could not be computed is written as ``null``).
The range fields are optional, so files written before they existed load unchanged.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from tvist import _core
from tvist.maps.files import MapDocument, RobotModesMixin, plain_metadata
from tvist.robots import Robot

SCHEMA_VERSION: int = _core.MAP_SCHEMA_VERSION
#: ``kind`` of the ten-coefficient map written by this version.
KIND: str = _core.MAP_KIND_PAPER10
#: Fields of one mode, all required in a map file.
MODE_FIELDS: tuple[str, ...] = tuple(_core.MODE_MAP_FIELDS)
#: Optional fields of one mode: ``[J_min, J_max]`` (kg m²) of ``J_f`` and of ``J_d``.
RANGE_FIELDS: tuple[str, ...] = tuple(_core.MODE_MAP_RANGE_FIELDS)


def general_mode(
    joint: int,
    *,
    inertia_range_kg_m2: Sequence[float] | None = None,
    **coefficients: float,
) -> dict[str, Any]:
    """One mode of the general map (eqs. 42-43) driven by ``J = J_joint``.

    ``coefficients`` are ``k_0, k_j, k_g, k_p, c_0, c_1, c_2, c_tau``; ``k_g`` and ``c_1``
    default to 0 (the reduced map, eqs. 44-45), the others are required.
    ``inertia_range_kg_m2`` ``(J_min, J_max)`` limits the map to those inertias (``None``:
    unbounded).
    """
    mode: dict[str, Any] = {"k_g": 0.0, "c_1": 0.0, **coefficients}
    j_range = None if inertia_range_kg_m2 is None else list(inertia_range_kg_m2)
    mode.update(
        frequency_joint=joint,
        damping_joint=joint,
        damping_gain_exponent=0.5,
        frequency_gain_exponent=0.0,
        frequency_inertia_range_kg_m2=j_range,
        damping_inertia_range_kg_m2=j_range,
    )
    _core.DynamicMap([mode])  # the core's validation (ValueError naming the field)
    return mode


class DynamicMap(MapDocument):
    """A dynamic map: modes ``(ω_n, ζ)`` of the arm as functions of its joint inertias.

    Parameters
    ----------
    modes
        One mapping per mode (cascade order) with the fields :data:`MODE_FIELDS` and,
        optionally, the inertia ranges :data:`RANGE_FIELDS` (see the module docstring).
    metadata
        ``robot`` (name), ``payload`` (:class:`~tvist.robots.Payload` or its dict),
        ``source`` (text) and ``fit_statistics`` (mapping); other keys are kept as given.

    Raises
    ------
    ValueError
        Naming the offending field, for missing, unknown or non-finite values, for bad
        ranges (non-finite, ``min <= 0``, ``min >= max``, too narrow for the soft clamp,
        different for one joint), for a mode that is not physical (see the module docstring)
        and for more than ``tvist.MAX_MODES`` modes.
    """

    def __init__(
        self, modes: Sequence[Mapping[str, Any]], metadata: Mapping[str, Any] | None = None
    ) -> None:
        if isinstance(modes, (str, bytes)) or not isinstance(modes, Sequence) or not modes:
            raise ValueError("modes: must be a non-empty list of mode objects")
        document = {
            "schema_version": SCHEMA_VERSION,
            "kind": KIND,
            "metadata": plain_metadata(metadata),
            "modes": [dict(m) if isinstance(m, Mapping) else m for m in modes],
        }
        core, self.metadata = _core.map_from_document(document)
        self._core: _core.DynamicMap = core

    _core_type = _core.DynamicMap
    _other_kind = (
        "kind: a modal map, not a paper10 map: read it with tvist.ModalMap.load or tvist.load_map"
    )

    @classmethod
    def paper_ur5e(cls) -> DynamicMap:
        """The paper's UR5e map: Table 1 (base, eqs. 47-48) and Table 2 (shoulder, eqs. 50-51)."""
        modes = _core.DynamicMap.paper_ur5e().modes  # the core's Tables 1-2
        metadata = {
            "robot": "ur5e",
            "payload": None,
            "source": (
                "Thomsen et al. 2020, Mechanism and Machine Theory: Tables 1-2, eqs. 47-48 "
                "(base mode: frequency from J_1, damping from J_0) and 50-51 (shoulder mode); "
                "identified over payloads 0, 1, 3 and 5 kg"
            ),
            "fit_statistics": None,
        }
        return cls(modes, metadata)

    @property
    def core(self) -> _core.DynamicMap:
        """The Rust map (pass-through for :class:`MapDynamics`)."""
        return self._core

    @property
    def mode_maps(self) -> list[dict[str, Any]]:
        """The coefficients of every mode, with its inertia ranges (``None``: unbounded)."""
        return self._core.modes

    @property
    def inertia_ranges(self) -> list[dict[int, tuple[float, float]]]:
        """Per mode: ``{joint: (J_min, J_max)}`` of the joints whose inertia is saturated."""
        out = []
        for mode in self.mode_maps:
            ranges = {}
            for joint_key, range_key in zip(
                ("frequency_joint", "damping_joint"), RANGE_FIELDS, strict=True
            ):
                if mode[range_key] is not None:
                    ranges[int(mode[joint_key])] = (mode[range_key][0], mode[range_key][1])
            out.append(ranges)
        return out

    def modes_from_inertia(
        self,
        inertia_kg_m2: Sequence[float] | np.ndarray,
        gravity_torque_nm: Sequence[float] | np.ndarray | None = None,
    ) -> list[tuple[float, float]]:
        """Modes ``[(wn_rad_s, zeta), ...]`` for joint inertias ``J_0, J_1, ...`` (kg m²).

        ``gravity_torque_nm`` is needed only when :attr:`uses_gravity`. Inertias are
        saturated into a mode's range (soft clamp, see the module docstring). A mode the map
        cannot give (non-positive stiffness or inertia) is ``(nan, nan)``.
        """
        j = [float(v) for v in np.asarray(inertia_kg_m2, dtype=float).ravel()]
        tau = None
        if gravity_torque_nm is not None:
            tau = [float(v) for v in np.asarray(gravity_torque_nm, dtype=float).ravel()]
        return self._core.modes_from_inertia(j, tau)

    def modes_from_inertia_many(
        self, inertia_kg_m2: np.ndarray, gravity_torque_nm: np.ndarray | None = None
    ) -> np.ndarray:
        """:meth:`modes_from_inertia` for every row of ``inertia_kg_m2`` ``(n_poses, n_j)``.

        ``gravity_torque_nm`` has the same shape (needed only when :attr:`uses_gravity`).
        Returns ``(n_poses, n_modes, 2)``: ``[..., 0]`` is ``wn_rad_s``, ``[..., 1]`` is
        ``zeta``; NaN where the map gives no mode.
        """
        j = np.ascontiguousarray(inertia_kg_m2, dtype=float)
        if j.ndim != 2:
            raise ValueError(f"inertia_kg_m2 must have shape (n_poses, n_j), got {j.shape}")
        tau = None
        if gravity_torque_nm is not None:
            tau = np.ascontiguousarray(gravity_torque_nm, dtype=float)
            if tau.shape != j.shape:
                raise ValueError(
                    f"gravity_torque_nm must have the shape of inertia_kg_m2 {j.shape}, "
                    f"got {tau.shape}"
                )
        return self._core.modes_from_inertia_many(j, tau)

    def outside_range(self, inertia_kg_m2: np.ndarray) -> np.ndarray:
        """Where the map holds a value at a bound: ``(n_samples, n_modes)``, True where an
        inertia the mode reads (``J_f`` or ``J_d``, rows of ``inertia_kg_m2`` ``(n_samples,
        n_j)``) lies outside the range it was identified on."""
        inertia = np.atleast_2d(np.asarray(inertia_kg_m2, dtype=float))
        out = np.zeros((len(inertia), self.n_modes), dtype=bool)
        for m, ranges in enumerate(self.inertia_ranges):
            for joint, (lo, hi) in ranges.items():
                out[:, m] |= (inertia[:, joint] < lo) | (inertia[:, joint] > hi)
        return out

    def range_report(self, robot: Robot, q: np.ndarray) -> str | None:
        """One line on where the map leaves its identified inertia range along the joint
        positions ``q`` ``(n_samples, n_dof)`` of ``robot`` (the first such pose, the inertia
        and the range, and how many samples); ``None`` if it never does."""
        q = np.atleast_2d(np.asarray(q, dtype=float))
        inertia = robot.joint_inertia_many(q)
        outside = self.outside_range(inertia)
        rows = np.flatnonzero(outside.any(axis=1))
        if rows.size == 0:
            return None
        k = int(rows[0])
        mode = int(np.flatnonzero(outside[k])[0])
        joint, (lo, hi) = next(
            (j, (lo, hi))
            for j, (lo, hi) in self.inertia_ranges[mode].items()
            if not lo <= inertia[k, j] <= hi
        )
        pose = ", ".join(f"{v:.3f}" for v in q[k])
        return (
            f"the map holds its mode {mode} at the bound of its identified range at "
            f"{rows.size} of {len(q)} samples: first at sample {k}, q = [{pose}] rad, where "
            f"J_{joint} = {inertia[k, joint]:.3g} kg m² is outside [{lo:.3g}, {hi:.3g}] kg m² "
            "(identify poses that cover it, e.g. the start and end poses of the moves)"
        )

    def modes(self, robot: Robot, q: Sequence[float] | np.ndarray) -> list[tuple[float, float]]:
        """Modes at configuration ``q`` of ``robot`` (its payload included)."""
        j = robot.joint_inertia(q)
        tau = robot.gravity_torque(q) if self.uses_gravity else None
        return self.modes_from_inertia(j, tau)

    @property
    def robot(self) -> str | None:
        """The robot the map was identified on (``metadata["robot"]``), or ``None``."""
        return self.metadata.get("robot")

    def __repr__(self) -> str:
        return f"DynamicMap(n_modes={self.n_modes}, robot={self.metadata.get('robot')!r})"


class MapRangeWarning(UserWarning):
    """A map was evaluated outside the inertia range it was identified on (where it holds
    the value at the bound instead of extrapolating)."""


def range_report_of(dynamics: Any, q: np.ndarray) -> str | None:
    """:meth:`DynamicMap.range_report` of the map a provider reads along ``q``
    ``(n_samples, n_dof)``: ``None`` if it stays in range, or for any provider other than a
    :class:`MapDynamics` with a :class:`DynamicMap`."""
    dynmap = getattr(dynamics, "dynmap", None)
    if not isinstance(dynmap, DynamicMap):
        return None
    return dynmap.range_report(dynamics.robot, q)


def warn_outside_range(dynamics: Any, q: np.ndarray) -> None:
    """One :class:`MapRangeWarning` if ``dynamics`` leaves its map's identified range along
    ``q`` (:func:`range_report_of`). Checked before shaping, not in the real-time path."""
    import warnings

    report = range_report_of(dynamics, q)
    if report is not None:
        warnings.warn(report, MapRangeWarning, stacklevel=3)


class MapDynamics(RobotModesMixin, _core.MapDynamics):
    """Per-cycle dynamics provider for :class:`tvist.TvShaper`: robot inertia + dynamic map.

    Every cycle the joint inertias of ``robot`` are evaluated at the previous shaped output
    and mapped to modes (saturated into the map's inertia ranges, if it has any). Construction
    rejects a map that gives an invalid mode (non-positive stiffness, ``zeta >= 1``) anywhere
    among ``MapDynamics.validation_poses`` sampled configurations, evaluated with the same
    saturation, or reads joints the robot does not have.

    Parameters
    ----------
    robot
        The arm with its payload (:class:`tvist.robots.Robot`).
    dynmap
        The map (:class:`DynamicMap`). A map identified on another robot (its
        ``metadata["robot"]`` differs from the robot's name) raises ``ValueError`` naming both.
        A :class:`tvist.ModalMap` has its own provider, :class:`tvist.ModalDynamics`;
        :func:`tvist.maps.dynamics_for` builds the provider of a map of either kind.
    allow_other_robot
        Accept such a map anyway (research use).
    """

    def __new__(
        cls, robot: Robot, dynmap: DynamicMap, *, allow_other_robot: bool = False
    ) -> MapDynamics:
        if isinstance(dynmap, MapDocument) and not isinstance(dynmap, DynamicMap):
            raise TypeError(
                f"dynmap must be a tvist.DynamicMap, got {type(dynmap).__name__}: "
                "tvist.dynamics_for(robot, map) builds the provider of either kind"
            )
        cls._check(robot, dynmap, DynamicMap, "dynmap")
        return super().__new__(cls, robot.core, dynmap.core, bool(allow_other_robot))
