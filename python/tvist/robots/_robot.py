"""Rigid-body model of a serial revolute arm with a payload (thin wrapper over the Rust core)."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from tvist import _core
from tvist.robots._params import Payload, RobotParams


def _as_q(q: Sequence[float] | np.ndarray, n_dof: int) -> np.ndarray:
    arr = np.ascontiguousarray(q, dtype=float)
    if arr.shape != (n_dof,):
        raise ValueError(f"q must have shape ({n_dof},), got {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise ValueError("q contains NaN or infinite values")
    return arr


def _as_many(q: Sequence[Sequence[float]] | np.ndarray, n_dof: int) -> np.ndarray:
    arr = np.ascontiguousarray(q, dtype=float)
    if arr.ndim != 2 or arr.shape[1] != n_dof:
        raise ValueError(f"Q must have shape (n_samples, {n_dof}), got {arr.shape}")
    if not np.all(np.isfinite(arr)):
        bad = int(np.flatnonzero(~np.all(np.isfinite(arr), axis=1))[0])
        raise ValueError(f"Q row {bad} contains NaN or infinite values")
    return arr


class Robot:
    """Serial revolute arm (DH or URDF joint placement) with link masses and a payload.

    All quantities are link side, without rotor inertia, with gravity 9.81 m/s² along ``-z`` of
    the base frame. Joint vectors have shape ``(n_dof,)``; batches ``(n_samples, n_dof)``.

    Parameters
    ----------
    params
        Kinematic and inertial parameters (see :func:`tvist.robots.params`).
    payload
        Payload on the flange; ``None`` means no payload.

    Raises
    ------
    ValueError
        For non-physical parameters (negative mass, inertia that is not positive
        semi-definite or violates the triangle inequality, NaN, inconsistent lengths).
    """

    def __init__(self, params: RobotParams, payload: Payload | None = None) -> None:
        payload = Payload() if payload is None else payload
        self._params = params
        self._payload = payload
        payload_args = (
            payload.mass_kg,
            np.asarray(payload.com_m),
            None if payload.inertia_kg_m2 is None else np.asarray(payload.inertia_kg_m2),
            params.name,
        )
        links = (
            np.asarray(params.mass_kg),
            np.ascontiguousarray(params.com_m),
            np.ascontiguousarray(params.inertia_kg_m2),
        )
        placed = params.placements
        if placed is None:
            self._core = _core.Robot(
                np.asarray(params.d_m),
                np.asarray(params.a_m),
                np.asarray(params.alpha_rad),
                *links,
                *payload_args,
            )
        else:
            self._core = _core.Robot.placed(
                np.ascontiguousarray(placed.origin_xyz_m),
                np.ascontiguousarray(placed.origin_rpy_rad),
                np.ascontiguousarray(placed.axis),
                np.asarray(placed.flange_xyz_m),
                np.asarray(placed.flange_rpy_rad),
                *links,
                *payload_args,
            )

    @classmethod
    def from_params(cls, params: RobotParams, payload: Payload | None = None) -> Robot:
        """Build a robot from any :class:`RobotParams` (for example a user-defined arm)."""
        return cls(params, payload)

    @property
    def params(self) -> RobotParams:
        """The robot's parameters."""
        return self._params

    @property
    def payload(self) -> Payload:
        """The payload on the flange."""
        return self._payload

    @property
    def n_dof(self) -> int:
        """Number of joints."""
        return self._params.n_dof

    # Single poses go through the batch entry points of the core (one row): one binding per
    # quantity.

    @property
    def core(self) -> _core.Robot:
        """The Rust model (pass-through for :class:`tvist.MapDynamics`)."""
        return self._core

    def joint_inertia(self, q: Sequence[float] | np.ndarray) -> np.ndarray:
        """Diagonal of the joint-space inertia matrix, ``J_i = M[i, i]`` (kg m²), ``(n_dof,)``."""
        return self._core.joint_inertia_many(_as_q(q, self.n_dof)[None])[0]

    def joint_inertia_many(self, q: Sequence[Sequence[float]] | np.ndarray) -> np.ndarray:
        """:meth:`joint_inertia` for every row of ``q`` ``(n_samples, n_dof)``."""
        return self._core.joint_inertia_many(_as_many(q, self.n_dof))

    def mass_matrix(self, q: Sequence[float] | np.ndarray) -> np.ndarray:
        """Joint-space inertia matrix ``M(q)`` (composite rigid body algorithm), ``(n, n)``."""
        return self._core.mass_matrix_many(_as_q(q, self.n_dof)[None])[0]

    def mass_matrix_many(self, q: Sequence[Sequence[float]] | np.ndarray) -> np.ndarray:
        """:meth:`mass_matrix` for every row of ``q``, ``(n_samples, n_dof, n_dof)``."""
        return self._core.mass_matrix_many(_as_many(q, self.n_dof))

    def flange_pose(self, q: Sequence[float] | np.ndarray) -> np.ndarray:
        """Homogeneous transform of the flange (DH frame ``n``) in the base frame, ``(4, 4)``."""
        return self._core.flange_pose_many(_as_q(q, self.n_dof)[None])[0]

    def flange_pose_many(self, q: Sequence[Sequence[float]] | np.ndarray) -> np.ndarray:
        """:meth:`flange_pose` for every row of ``q``, ``(n_samples, 4, 4)``."""
        return self._core.flange_pose_many(_as_many(q, self.n_dof))

    def jacobian(self, q: Sequence[float] | np.ndarray) -> np.ndarray:
        """Geometric Jacobian of the flange origin, base frame, rows ``[linear; angular]``.

        Returns shape ``(6, n_dof)``.
        """
        return self._core.jacobian_many(_as_q(q, self.n_dof)[None])[0]

    def jacobian_many(self, q: Sequence[Sequence[float]] | np.ndarray) -> np.ndarray:
        """:meth:`jacobian` for every row of ``q``, ``(n_samples, 6, n_dof)``."""
        return self._core.jacobian_many(_as_many(q, self.n_dof))

    def gravity_torque(self, q: Sequence[float] | np.ndarray) -> np.ndarray:
        """Joint torques that hold the arm against gravity, ``τ_g(q)`` (N m), ``(n_dof,)``."""
        return self._core.gravity_torque_many(_as_q(q, self.n_dof)[None])[0]

    def gravity_torque_many(self, q: Sequence[Sequence[float]] | np.ndarray) -> np.ndarray:
        """:meth:`gravity_torque` for every row of ``q``, ``(n_samples, n_dof)``."""
        return self._core.gravity_torque_many(_as_many(q, self.n_dof))

    def with_link_hinges(self, hinges: Sequence[tuple[int, float]]) -> HingedArm:
        """The arm with a hinge pair about the two axes perpendicular to each link ``link`` at
        ``at_fraction`` of its length (``hinges``: ``(link, at_fraction)`` pairs): the arm a
        modal map with link hinges evaluates (tvist-core ``Robot::with_link_hinges``)."""
        hinges = sorted((int(link), float(at)) for link, at in hinges)
        core = self._core.with_link_hinges([h[0] for h in hinges], [h[1] for h in hinges])
        return HingedArm(core, self.n_dof, tuple(h[0] for h in hinges))

    def __repr__(self) -> str:
        return (
            f"Robot({self._params.name!r}, n_dof={self.n_dof}, "
            f"payload_kg={self._payload.mass_kg:g})"
        )


class HingedArm:
    """A :class:`Robot` with link hinges (:meth:`Robot.with_link_hinges`), evaluated at the
    robot's joint angles with straight hinges.

    Its joints are the robot's, each at :attr:`joint_index`, and after the joint of each
    hinged link that link's two hinges (first about the axis parallel to the link's joint).
    Batches take the robot's ``q`` ``(n_samples, n_robot)``; results are over all
    :attr:`n_dof` joints."""

    def __init__(self, core: _core.Robot, n_robot: int, hinged_links: tuple[int, ...]) -> None:
        self._core = core
        self.hinged_links = hinged_links
        self.n_robot = n_robot
        self.joint_index = np.array(
            [j + 2 * sum(1 for link in hinged_links if link < j) for j in range(n_robot)]
        )
        #: Indices of the hinge coordinates, two per hinged link in link order.
        self.hinge_index = np.array(
            [self.joint_index[link] + k for link in hinged_links for k in (1, 2)], dtype=int
        )

    @property
    def n_dof(self) -> int:
        return self._core.n_dof

    def _q(self, q: Sequence[Sequence[float]] | np.ndarray) -> np.ndarray:
        q = _as_many(q, self.n_robot)
        full = np.zeros((q.shape[0], self.n_dof))
        full[:, self.joint_index] = q
        return full

    def coordinates(self, q: Sequence[Sequence[float]] | np.ndarray) -> np.ndarray:
        """The robot's ``q`` (or joint velocities) ``(n_samples, n_robot)`` as the hinged
        arm's coordinates ``(n_samples, n_dof)``: hinges straight (and at rest)."""
        return self._q(q)

    def mass_matrix_many(self, q: Sequence[Sequence[float]] | np.ndarray) -> np.ndarray:
        """``(n_samples, n_dof, n_dof)`` mass matrices with straight hinges."""
        return self._core.mass_matrix_many(self._q(q))

    def mass_matrix_bent_many(self, q_full: np.ndarray) -> np.ndarray:
        """``(n_samples, n_dof, n_dof)`` mass matrices at the hinged arm's own coordinates
        ``(n_samples, n_dof)`` (rad), hinges bent as given."""
        return self._core.mass_matrix_many(np.ascontiguousarray(q_full, dtype=float))

    def gravity_torque_many(self, q: Sequence[Sequence[float]] | np.ndarray) -> np.ndarray:
        """``(n_samples, n_dof)`` gravity torques with straight hinges."""
        return self._core.gravity_torque_many(self._q(q))

    def jacobian_many(self, q: Sequence[Sequence[float]] | np.ndarray) -> np.ndarray:
        """``(n_samples, 6, n_dof)`` flange Jacobians with straight hinges."""
        return self._core.jacobian_many(self._q(q))
