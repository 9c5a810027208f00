"""Robot parameter records from the core's robot data (the one source of robot data).

The numbers live in ``crates/tvist-core/data/ur_e_series.json``, embedded in and parsed once
by the Rust core; :func:`tvist.robots.params` reads them through the bindings (no second parser).

Conventions (also stated in the JSON file):

- Joints are placed by standard DH parameters or, for an arm described by a URDF, as URDF
  places them (:class:`JointPlacements`: origin, then a turn about an axis; links in the link
  frame after each joint). The rest of this list is for DH.
- Standard DH: frame ``i = Rz(q_i) Tz(d_i) Tx(a_i) Rx(alpha_i)``; ``q = 0`` is the arm stretched
  out horizontally. The flange frame is DH frame ``n``.
- ``com_m[i]`` is the centre of mass of link ``i`` in DH frame ``i`` (m).
- ``inertia_kg_m2[i] = [ixx, iyy, izz, ixy, ixz, iyz]`` are inertia-tensor elements about the
  centre of mass, axes of DH frame ``i`` (``ixy = -∫ x y dm``, the URDF convention). For a
  robot with an ``inertia_cylinders`` block they are derived from it by
  :mod:`tvist.robots._cylinders`; the loader reads only ``inertia_kg_m2``.
- Link side only, no rotor inertia.
- ``control_period_s`` is the period of the robot controller's control loop (s), the default
  sample period of everything that runs on the robot; optional (a robot file may omit it).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from tvist import _core


def _frozen_array(value: Any, shape: tuple[int, ...], what: str) -> np.ndarray:
    """Convert ``value`` to a read-only float array of ``shape`` with finite entries."""
    try:
        arr = np.array(value, dtype=float)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{what}: not a numeric array ({exc})") from None
    if arr.shape != shape:
        raise ValueError(f"{what}: expected shape {shape}, got {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{what}: contains NaN or infinite values")
    arr.setflags(write=False)
    return arr


def inertia_tensor(six: np.ndarray) -> np.ndarray:
    """3x3 tensor from ``[ixx, iyy, izz, ixy, ixz, iyz]`` (tensor elements, not products)."""
    ixx, iyy, izz, ixy, ixz, iyz = (float(v) for v in six)
    return np.array([[ixx, ixy, ixz], [ixy, iyy, iyz], [ixz, iyz, izz]])


@dataclass(frozen=True)
class JointPlacements:
    """Joints placed as URDF places them (the alternative to DH parameters).

    Joint ``i``'s origin in the frame of the link before it is the translation
    ``origin_xyz_m[i]`` then the rotation ``Rz(yaw) Ry(pitch) Rx(roll)`` of
    ``origin_rpy_rad[i] = (roll, pitch, yaw)``; the joint turns about ``axis[i]`` of that frame.
    Link ``i`` is fixed to the turned frame (its URDF link frame). The flange frame's origin in
    the last link's frame is ``flange_xyz_m``, ``flange_rpy_rad``. Arrays are read-only;
    per-joint arrays have shape ``(n, 3)``.
    """

    origin_xyz_m: np.ndarray
    origin_rpy_rad: np.ndarray
    axis: np.ndarray
    flange_xyz_m: np.ndarray
    flange_rpy_rad: np.ndarray

    def __post_init__(self) -> None:
        n = np.shape(self.axis)[0] if np.ndim(self.axis) == 2 else 0
        if n < 1:
            raise ValueError("joint placements: axis must have shape (n, 3), n >= 1")
        spec = {
            "origin_xyz_m": (n, 3),
            "origin_rpy_rad": (n, 3),
            "axis": (n, 3),
            "flange_xyz_m": (3,),
            "flange_rpy_rad": (3,),
        }
        for attr, shape in spec.items():
            value = _frozen_array(getattr(self, attr), shape, f"joint placements: {attr}")
            object.__setattr__(self, attr, value)

    @property
    def n_dof(self) -> int:
        return int(self.axis.shape[0])


@dataclass(frozen=True)
class RobotParams:
    """Kinematic and rigid-body parameters of a serial revolute arm.

    Joints are placed by standard DH parameters (``d_m``, ``a_m``, ``alpha_rad``) or, for an
    arm read from a URDF, by ``placements`` (then the DH fields are ``None`` and ``com_m``,
    ``inertia_kg_m2`` are in the link frame after each joint). Arrays are read-only.
    ``n_dof`` is the number of joints ``n``.

    Attributes
    ----------
    name, description, source, inertia_source
        Identification and provenance of the numbers.
    d_m, a_m, alpha_rad
        DH parameters, each shape ``(n,)``.
    mass_kg
        Link masses, ``(n,)``.
    com_m
        Centres of mass in DH frame ``i``, ``(n, 3)``.
    inertia_kg_m2
        ``[ixx, iyy, izz, ixy, ixz, iyz]`` about the centre of mass, axes of DH frame ``i``,
        ``(n, 6)``.
    joint_limits_rad
        ``[lower, upper]`` per joint, ``(n, 2)``.
    max_velocity_rad_s
        Joint speed limits, ``(n,)``.
    max_payload_kg
        Rated payload.
    control_period_s
        Period of the robot controller's control loop, s (finite, > 0): the default sample
        period of everything that runs on the robot (:meth:`sample_period_s`). ``None`` where
        the data does not state it (a robot file written from a URDF without one).
    placements
        URDF joint placement (``None`` for a DH arm).
    elbow_joint
        Index of the elbow: the joint whose flexibility bends the arm in the shoulder's
        plane (a UR's 2; 3 on an arm whose joint 2 turns the upper arm about its own axis,
        FR3, iiwa14). ``None`` at construction: :func:`elbow_by_axes` (still ``None`` for an
        arm without one). The identification reads it (:mod:`tvist.ident.excited`).
    """

    name: str
    description: str
    source: str
    d_m: np.ndarray | None
    a_m: np.ndarray | None
    alpha_rad: np.ndarray | None
    mass_kg: np.ndarray
    com_m: np.ndarray
    inertia_kg_m2: np.ndarray
    inertia_source: str
    joint_limits_rad: np.ndarray
    max_velocity_rad_s: np.ndarray
    max_payload_kg: float
    placements: JointPlacements | None = None
    elbow_joint: int | None = None
    control_period_s: float | None = None
    n_dof: int = field(init=False)

    def __post_init__(self) -> None:
        dh = (self.d_m, self.a_m, self.alpha_rad)
        if self.placements is not None:
            if any(v is not None for v in dh):
                raise ValueError(f"{self.name}: give DH parameters or placements, not both")
            n = self.placements.n_dof
        else:
            n = np.asarray(self.d_m).shape[0] if np.ndim(self.d_m) == 1 else -1
            if n < 1:
                raise ValueError(f"{self.name}: dh.d must be a non-empty 1-D array")
        object.__setattr__(self, "n_dof", int(n))
        spec = {} if self.placements is not None else {"d_m": (n,), "a_m": (n,), "alpha_rad": (n,)}
        spec |= {
            "mass_kg": (n,),
            "com_m": (n, 3),
            "inertia_kg_m2": (n, 6),
            "joint_limits_rad": (n, 2),
            "max_velocity_rad_s": (n,),
        }
        for attr, shape in spec.items():
            value = _frozen_array(getattr(self, attr), shape, f"{self.name}: {attr}")
            object.__setattr__(self, attr, value)
        if np.any(self.mass_kg < 0.0):
            raise ValueError(f"{self.name}: mass_kg must be >= 0, got {self.mass_kg.tolist()}")
        if np.any(self.joint_limits_rad[:, 0] >= self.joint_limits_rad[:, 1]):
            raise ValueError(f"{self.name}: joint_limits_rad needs lower < upper for every joint")
        if np.any(self.max_velocity_rad_s <= 0.0):
            raise ValueError(f"{self.name}: max_velocity_rad_s must be > 0")
        payload = float(self.max_payload_kg)
        if not math.isfinite(payload) or payload < 0.0:
            raise ValueError(f"{self.name}: max_payload_kg must be finite and >= 0")
        object.__setattr__(self, "max_payload_kg", payload)
        if self.control_period_s is not None:
            period = float(self.control_period_s)
            if not math.isfinite(period) or period <= 0.0:
                raise ValueError(
                    f"{self.name}: control_period_s must be finite and > 0, "
                    f"got {self.control_period_s!r}"
                )
            object.__setattr__(self, "control_period_s", period)
        elbow = elbow_by_axes(self) if self.elbow_joint is None else self.elbow_joint
        if elbow is not None:
            if isinstance(elbow, bool) or int(elbow) != elbow or not 2 <= int(elbow) < n:
                raise ValueError(
                    f"{self.name}: elbow_joint must be a joint after the shoulder (2 to "
                    f"{n - 1}), got {self.elbow_joint!r}"
                )
            elbow = int(elbow)
        object.__setattr__(self, "elbow_joint", elbow)

    def sample_period_s(self, dt_s: float | None = None) -> float:
        """``dt_s`` if given, else this robot's :attr:`control_period_s` (s): the default of
        every ``dt_s`` of what runs on the robot.

        Raises
        ------
        ValueError
            ``dt_s`` is None and the robot's data states no control period.
        """
        if dt_s is not None:
            return dt_s
        if self.control_period_s is None:
            raise ValueError(
                f"{self.name}: the robot data states no control period (control_period_s); "
                "pass dt_s"
            )
        return self.control_period_s

    @property
    def inertia_tensors_kg_m2(self) -> np.ndarray:
        """Inertia tensors about each centre of mass, axes of DH frame ``i``, ``(n, 3, 3)``."""
        return np.stack([inertia_tensor(row) for row in self.inertia_kg_m2])

    @classmethod
    def from_dict(cls, name: str, entry: dict[str, Any]) -> RobotParams:
        """Build from one ``robots`` entry of the JSON schema; missing fields raise ValueError."""
        try:
            dh = entry["dh"]
            return cls(
                name=name,
                description=str(entry["description"]),
                source=str(entry["source"]),
                d_m=dh["d"],
                a_m=dh["a"],
                alpha_rad=dh["alpha"],
                mass_kg=entry["mass_kg"],
                com_m=entry["com_m"],
                inertia_kg_m2=entry["inertia_kg_m2"],
                inertia_source=str(entry["inertia_source"]),
                joint_limits_rad=entry["joint_limits_rad"],
                max_velocity_rad_s=entry["max_velocity_rad_s"],
                max_payload_kg=entry["max_payload_kg"],
                control_period_s=entry.get("control_period_s"),
            )
        except (KeyError, TypeError) as exc:
            raise ValueError(f"{name}: missing or malformed field {exc}") from None


#: Two joint axes are parallel if they are within this angle of each other (or of opposite
#: directions), rad: room for angles a URDF writes to 4 decimals (1.5708 for π/2 is 4e-6
#: off), far below any skew an arm is built with.
PARALLEL_AXES_RAD = 1e-3


def joint_axes_at_home(robot: RobotParams) -> np.ndarray:
    """``(n, 3)`` unit axes of the joints in the base frame at ``q = 0``: DH joint ``i`` turns
    about ``z`` of DH frame ``i - 1``; a URDF-placed joint about its ``axis`` in the frame of
    its origin."""
    from tvist.robots.rpy import rpy_matrix

    rot = np.eye(3)
    axes = []
    placed = robot.placements
    for i in range(robot.n_dof):
        if placed is None:
            axes.append(rot[:, 2].copy())
            c, s = math.cos(robot.alpha_rad[i]), math.sin(robot.alpha_rad[i])
            rot = rot @ np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])
        else:
            rot = rot @ rpy_matrix(placed.origin_rpy_rad[i])
            axes.append(rot @ placed.axis[i] / np.linalg.norm(placed.axis[i]))
    return np.array(axes)


def elbow_by_axes(robot: RobotParams) -> int | None:
    """The elbow of an arm whose data does not state it: the first joint after the shoulder
    (joint 1) whose axis is parallel to the shoulder's at ``q = 0`` (within
    :data:`PARALLEL_AXES_RAD`, either direction), the next joint that bends the arm in the
    shoulder's plane. A UR: 2; FR3, iiwa14, Gen3 (joint 2 turns the upper arm about its own
    axis): 3. ``None`` if no joint is."""
    if robot.n_dof < 3:
        return None
    axes = joint_axes_at_home(robot)
    for j in range(2, robot.n_dof):
        if abs(float(axes[j] @ axes[1])) >= math.cos(PARALLEL_AXES_RAD):
            return j
    return None


@dataclass(frozen=True)
class Payload:
    """Rigid payload fixed to the flange (DH frame ``n``).

    Parameters
    ----------
    mass_kg
        Payload mass (>= 0).
    com_m
        Centre of mass in the flange frame (m); ``(0, 0, 0.05)`` is 5 cm beyond the flange
        along its z axis.
    inertia_kg_m2
        ``[ixx, iyy, izz, ixy, ixz, iyz]`` about the payload's centre of mass, flange axes, or
        ``None`` for a point mass. Physical consistency (positive semi-definite, triangle
        inequality) is checked when a :class:`~tvist.robots.Robot` is built.
    """

    mass_kg: float = 0.0
    com_m: tuple[float, float, float] | np.ndarray = (0.0, 0.0, 0.0)
    inertia_kg_m2: tuple[float, ...] | np.ndarray | None = None

    def __post_init__(self) -> None:
        mass = float(self.mass_kg)
        if not math.isfinite(mass) or mass < 0.0:
            raise ValueError(f"payload mass_kg must be finite and >= 0, got {self.mass_kg!r}")
        object.__setattr__(self, "mass_kg", mass)
        com = _frozen_array(self.com_m, (3,), "payload com_m")
        object.__setattr__(self, "com_m", com)
        if self.inertia_kg_m2 is not None:
            inertia = _frozen_array(self.inertia_kg_m2, (6,), "payload inertia_kg_m2")
            object.__setattr__(self, "inertia_kg_m2", inertia)

    def to_dict(self) -> dict[str, Any]:
        """JSON-friendly form (used in map-file metadata)."""
        return {
            "mass_kg": self.mass_kg,
            "com_m": [float(v) for v in self.com_m],
            "inertia_kg_m2": None
            if self.inertia_kg_m2 is None
            else [float(v) for v in self.inertia_kg_m2],
        }


def _from_core(entry: dict[str, Any]) -> RobotParams:
    """RobotParams from the core's entry dict (DH or URDF placement keys)."""
    entry = dict(entry)
    entry.pop("inertia_cylinders", None)  # the source of inertia_kg_m2, see _cylinders
    keys = ("origin_xyz_m", "origin_rpy_rad", "axis", "flange_xyz_m", "flange_rpy_rad")
    placed = {k: entry.pop(k) for k in keys}
    if placed["axis"] is not None:
        entry["placements"] = JointPlacements(**placed)
    return RobotParams(**entry)


def robot_file(path: str) -> RobotParams:
    """Parameters of the one robot in robot file ``path`` (as ``tvist robot-file`` writes
    it; read and checked by the core, the same reader the C API uses)."""
    return _from_core(_core.robot_file_params(str(path)))


def names() -> tuple[str, ...]:
    """Names of the robots in the robot data, e.g. ``("ur3e", "ur5e", ...)``."""
    return tuple(_core.robot_names())
