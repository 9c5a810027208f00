"""The controller's kinematics services: poses, forward and inverse kinematics, the TCP.

A pose is URScript's ``p[x, y, z, rx, ry, rz]``: position (m) and rotation vector (rad) of a
frame in another (the base, unless said otherwise). The flange is the robot model's DH frame
``n`` (:meth:`tvist.robots.Robot.flange_pose`); the tool centre point (TCP) is the flange
composed with the TCP offset (``set_tcp``), so every TCP pose is ``flange ∘ tcp_offset``.

Inverse kinematics is numerical: damped least squares on the model's geometric Jacobian
(:func:`tvist.cartesian.solve_ik`, converged to 1e-10 m / rad), started at ``qnear``. A UR's
``get_inverse_kin`` returns, of the analytic solutions, the one nearest ``qnear``; Newton's
method started at ``qnear`` converges to the solution whose basin holds ``qnear``, which is
that nearest one whenever ``qnear`` is near a solution (the case of every move along a path and
of a caller giving the present joints). It works for every robot model, not only arms with a
spherical wrist. When it does not converge from ``qnear`` (a seed at a singularity, such as the
stretched arm, or far from every solution) it is tried from the joint target, then from seeds
with the elbow and the wrist bent each way; if none converges the pose has no solution
(``get_inverse_kin`` raises, as on a UR). Joint angles are returned within the joint limits,
the nearest ``2π`` turn to ``qnear``.
"""

from __future__ import annotations

import math

import numpy as np

from tvist.cartesian import solve_ik
from tvist.robots import Robot
from tvist.sim.plant import rotation_vector
from tvist.urserver.motion import CommandRefused, SafetyViolation


def rotation_matrix(rotvec) -> np.ndarray:
    """Rotation matrix of a rotation vector (Rodrigues' formula; plain floats, ~10x faster
    than scipy's ``Rotation`` for one vector, which matters at every 2 ms tick)."""
    x, y, z = (float(v) for v in rotvec)
    angle = math.sqrt(x * x + y * y + z * z)
    if angle < 1e-8:  # second order: the first neglected term is angle³/6 < 1e-24
        return (
            np.array([[1.0, -z, y], [z, 1.0, -x], [-y, x, 1.0]])
            + 0.5 * np.outer([x, y, z], [x, y, z])
            - 0.5 * angle * angle * np.eye(3)
        )
    s, c = math.sin(angle) / angle, (1.0 - math.cos(angle)) / (angle * angle)
    return np.array(
        [
            [1.0 - c * (y * y + z * z), c * x * y - s * z, c * x * z + s * y],
            [c * x * y + s * z, 1.0 - c * (x * x + z * z), c * y * z - s * x],
            [c * x * z - s * y, c * y * z + s * x, 1.0 - c * (x * x + y * y)],
        ]
    )


def pose_matrix(pose) -> np.ndarray:
    """Homogeneous transform ``(4, 4)`` of a pose ``[x, y, z, rx, ry, rz]``."""
    arr = np.asarray(pose, dtype=float)
    out = np.eye(4)
    out[:3, :3] = rotation_matrix(arr[3:6])
    out[:3, 3] = arr[:3]
    return out


def matrix_pose(matrix) -> np.ndarray:
    """Pose ``[x, y, z, rx, ry, rz]`` of a homogeneous transform (rotation angle in [0, π])."""
    m = np.asarray(matrix, dtype=float)
    return np.concatenate([m[:3, 3], rotation_vector(m[:3, :3].ravel())])


def pose_trans(p_from, p_from_to) -> np.ndarray:
    """URScript's ``pose_trans``: ``p_from_to`` (given in frame ``p_from``) in the base."""
    return matrix_pose(pose_matrix(p_from) @ pose_matrix(p_from_to))


def finite_pose(values, what: str) -> np.ndarray:
    """Six finite numbers; :class:`SafetyViolation` naming ``what`` otherwise."""
    arr = np.asarray(values, dtype=float)
    if arr.shape != (6,) or not np.all(np.isfinite(arr)):
        raise SafetyViolation(f"{what} must be 6 finite numbers")
    return arr


class Kinematics:
    """Forward and inverse kinematics of the twin's robot, with the TCP offset.

    Parameters
    ----------
    robot
        The rigid robot model (its DH kinematics).
    joint_limits_rad
        ``(n_dof, 2)`` lower and upper joint limits (rad).
    """

    def __init__(self, robot: Robot, joint_limits_rad: np.ndarray) -> None:
        self.robot = robot
        self.limits = np.asarray(joint_limits_rad, dtype=float)
        #: TCP offset: the TCP pose in the flange frame (``set_tcp``).
        self.tcp_offset = np.zeros(6)
        self._tcp = np.eye(4)
        #: A TCP farther than this from the flange is no tool the arm could carry (m): the
        #: arm's reach (sum of its link lengths).
        self.tcp_limit_m = float(
            np.sum(np.abs(robot.params.a_m)) + np.sum(np.abs(robot.params.d_m))
        )

    def set_tcp(self, offset) -> None:
        """``set_tcp``: the TCP pose in the flange frame.

        Raises
        ------
        SafetyViolation
            A number that is not finite.
        CommandRefused
            A TCP beyond the arm's reach.
        """
        pose = finite_pose(offset, "set_tcp: pose")
        distance = float(np.linalg.norm(pose[:3]))
        if distance > self.tcp_limit_m:
            raise CommandRefused(
                f"set_tcp: TCP {distance:g} m from the flange, beyond the arm's reach "
                f"{self.tcp_limit_m:g} m"
            )
        self.tcp_offset = pose
        self._tcp = pose_matrix(pose)

    def within_limits(self, q) -> bool:
        """Whether every joint angle is within its limits."""
        arr = np.asarray(q, dtype=float)
        lower, upper = self.limits.T
        return bool(np.all(np.isfinite(arr)) and np.all((arr >= lower) & (arr <= upper)))

    def flange_to_tcp(self, flange_pose) -> np.ndarray:
        """The TCP pose of a flange pose (``flange ∘ tcp_offset``)."""
        return matrix_pose(pose_matrix(flange_pose) @ self._tcp)

    def forward(self, q, tcp_offset=None) -> np.ndarray:
        """TCP pose at joints ``q`` (``tcp_offset``: this one instead of the active one)."""
        tcp = self._tcp if tcp_offset is None else pose_matrix(tcp_offset)
        return matrix_pose(self.robot.flange_pose(np.asarray(q, dtype=float)) @ tcp)

    def forward_matrix(self, q) -> np.ndarray:
        """TCP transform ``(4, 4)`` at joints ``q``."""
        return self.robot.flange_pose(np.asarray(q, dtype=float)) @ self._tcp

    def inverse(self, pose, qnear, q_fallback=None) -> np.ndarray:
        """Joints whose TCP is at ``pose``, nearest ``qnear`` (see the module docstring).

        Raises
        ------
        CommandRefused
            If no solution within the joint limits is found.
        """
        target = pose_matrix(pose) @ np.linalg.inv(self._tcp)  # the flange's pose
        near = np.asarray(qnear, dtype=float)
        seeds = [near]
        if q_fallback is not None:
            seeds.append(np.asarray(q_fallback, dtype=float))
        for seed in seeds + self._configuration_seeds(near):
            try:
                q = solve_ik(self.robot, target[:3, 3], target[:3, :3], seed)
            except ValueError:
                continue
            q = self._nearest_turn(q, near)
            if self.within_limits(q):
                return q
        raise CommandRefused(
            "get_inverse_kin: no solution within the joint limits for pose "
            f"{np.array2string(np.asarray(pose), precision=4)}"
        )

    @staticmethod
    def _configuration_seeds(qnear: np.ndarray) -> list[np.ndarray]:
        """Seeds in the arm's elbow-up/down and wrist-flip configurations (the elbow and
        the wrist bent away from their singular straight positions), tried in turn when
        Newton's method does not converge from ``qnear`` (a seed at a singularity, or a
        ``qnear`` far from every solution)."""
        seeds = []
        for elbow in (1.0, -1.0):
            for wrist in (1.0, -1.0):
                seed = qnear.copy()
                if seed.size >= 5:
                    seed[2] = elbow * max(abs(seed[2]), 0.5)
                    seed[4] = wrist * max(abs(seed[4]), 0.5)
                seeds.append(seed)
        return seeds

    def has_solution(self, pose, qnear) -> bool:
        try:
            self.inverse(pose, qnear)
        except CommandRefused:
            return False
        return True

    def _nearest_turn(self, q: np.ndarray, qnear: np.ndarray) -> np.ndarray:
        """``q`` with each angle shifted by whole turns towards ``qnear``, within limits."""
        out = q.copy()
        lower, upper = self.limits.T
        for j in range(out.size):
            turns = round((qnear[j] - out[j]) / (2.0 * math.pi))
            shifted = out[j] + 2.0 * math.pi * turns
            if lower[j] <= shifted <= upper[j]:
                out[j] = shifted
            while out[j] > upper[j] and out[j] - 2.0 * math.pi >= lower[j]:
                out[j] -= 2.0 * math.pi
            while out[j] < lower[j] and out[j] + 2.0 * math.pi <= upper[j]:
                out[j] += 2.0 * math.pi
        return out


class PoseRate:
    """TCP speed ``[vx, vy, vz, wx, wy, wz]`` (m/s, rad/s, base frame) of a pose sampled every
    tick: the backward difference of consecutive poses (the angular part the rotation vector
    of ``R_k R_{k-1}ᵀ`` over the interval). Zero at the first sample."""

    def __init__(self) -> None:
        self._pose: np.ndarray | None = None
        self._time = 0.0

    def velocity(self, pose, time_s: float) -> np.ndarray:
        pose = np.asarray(pose, dtype=float)
        out = np.zeros(6)
        if self._pose is not None and time_s > self._time:
            dt = time_s - self._time
            out[:3] = (pose[:3] - self._pose[:3]) / dt
            turn = rotation_matrix(pose[3:]) @ rotation_matrix(self._pose[3:]).T
            out[3:] = rotation_vector(turn.ravel()) / dt
        self._pose, self._time = pose, float(time_s)
        return out
