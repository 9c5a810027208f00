"""Tool-space motions: the TCP moves, inverse kinematics turns each tick's TCP pose into joints.

Each motion is a source for :meth:`tvist.urserver.motion.JointMotion.follow`: every tick it
advances the TCP target by ``dt`` and returns the joints reaching it (inverse kinematics seeded
at the present joint target: the continuous branch), or None once it has ended.

- :class:`LinearMove` (``movel``): the TCP position moves on the straight line to the target
  and its orientation rotates about one fixed axis (the slerp between the two orientations),
  both by the same path fraction, which follows a rest-to-rest trapezoidal profile. Neither the
  TCP speed (m/s) nor its angular speed (rad/s) exceeds ``v``, nor their accelerations ``a``
  (a pure rotation moves at ``v`` rad/s, as on a UR).
- :class:`ToolSpeed` (``speedl``): the TCP velocity ``[vx, vy, vz, wx, wy, wz]`` (base frame,
  m/s and rad/s) ramps to the commanded one at ``a`` (m/s², rad/s² for the angular part) and
  keeps it; the TCP pose is integrated from it (never read back from the joints, so it does
  not drift).

Both stop (``stopl``) by decelerating along their path at the given rate. A TCP target without
inverse kinematics solution, mid-way, raises :class:`SafetyViolation` (the arm stops where it
is: a UR protective-stops when a linear move leaves the workspace).
"""

from __future__ import annotations

import numpy as np

from tvist.cartesian import _matrix
from tvist.sim.plant import rotation_vector
from tvist.trajectory.scalar_trapezoid import trapezoid_duration, trapezoid_position
from tvist.urserver.kinematics import Kinematics, pose_matrix, rotation_matrix
from tvist.urserver.motion import CommandRefused, SafetyViolation, positive_value


class _ToolSource:
    """What both motions share: inverse kinematics of the TCP target, and stopping."""

    def __init__(self, kinematics: Kinematics) -> None:
        self._kin = kinematics
        self._stopping = False
        self._decel = 1.0

    def _joints(self, position: np.ndarray, rotation: np.ndarray, q: np.ndarray) -> np.ndarray:
        pose = np.concatenate([position, rotation_vector(rotation.ravel())])
        try:
            return self._kin.inverse(pose, q)
        except CommandRefused:
            raise SafetyViolation(
                f"{self.name}: the TCP path leaves the workspace at "
                f"{np.array2string(pose, precision=4)} (no inverse kinematics solution)"
            ) from None

    def stop(self, decel: float) -> None:
        """``stopl``: decelerate along the path at ``decel`` (m/s², rad/s²) to rest."""
        self._decel = positive_value(decel, "stopl: deceleration")
        self._stopping = True


class Line:
    """The TCP path of a ``movel`` between two TCP transforms ``(4, 4)``: the position on the
    straight line, the orientation rotating about one fixed axis (the slerp), both by the same
    fraction of the way.

    The path parameter ``s`` runs over ``[0, distance]``, ``distance`` the longer of the two
    ways (m of position or rad of rotation, each in its own unit); the other follows in
    proportion (each within ``v`` and ``a``: the shorter moves slower).
    """

    def __init__(self, start: np.ndarray, end: np.ndarray) -> None:
        self.p0 = start[:3, 3].copy()
        self.dp = end[:3, 3] - self.p0
        self.r0 = start[:3, :3].copy()
        self.axis_angle = rotation_vector((end[:3, :3] @ self.r0.T).ravel())
        #: Length of the straight line (m).
        self.length = float(np.linalg.norm(self.dp))
        self.distance = max(self.length, float(np.linalg.norm(self.axis_angle)))

    def at(self, s: float) -> tuple[np.ndarray, np.ndarray]:
        """``(position (m), rotation matrix)`` at ``s`` along the path (``s`` in ``[0,
        distance]``; beyond it the line and the rotation continue)."""
        if self.distance == 0.0:
            return self.p0.copy(), self.r0.copy()
        u = s / self.distance
        return self.p0 + u * self.dp, rotation_matrix(u * self.axis_angle) @ self.r0


class LinearMove(_ToolSource):
    """``movel`` from the TCP pose at ``q_start`` to ``target_pose``.

    Raises
    ------
    SafetyViolation
        A target that is not finite.
    CommandRefused
        ``v`` or ``a`` not > 0, or a target with no inverse kinematics solution.
    """

    name = "movel"

    def __init__(self, kinematics: Kinematics, q_start, target_pose, v: float, a: float) -> None:
        super().__init__(kinematics)
        speed = positive_value(v, "movel: speed")
        accel = positive_value(a, "movel: acceleration")
        kinematics.inverse(target_pose, q_start)  # refuse an unreachable target up front
        self._line = Line(kinematics.forward_matrix(q_start), pose_matrix(target_pose))
        self._distance = self._line.distance
        self._duration, self._speed = trapezoid_duration(self._distance, speed, accel)
        self._accel = accel
        self._t = 0.0
        self._s = 0.0
        self._sd = 0.0
        self._done = self._distance == 0.0

    @property
    def progress(self) -> float:
        """Fraction of the way done, in [0, 1]."""
        return 1.0 if self._distance == 0.0 else min(self._s / self._distance, 1.0)

    def next_q(self, q: np.ndarray, dt: float) -> np.ndarray | None:
        if self._done:
            return None
        if self._stopping:
            sd = max(self._sd - self._decel * dt, 0.0)
            s = min(self._s + 0.5 * (self._sd + sd) * dt, self._distance)
            self._done = sd == 0.0 or s >= self._distance
        else:
            self._t = min(self._t + dt, self._duration)
            s = trapezoid_position(
                self._t, self._speed, self._accel, self._duration, self._distance
            )
            sd = (s - self._s) / dt if dt > 0.0 else self._sd
            self._done = self._t >= self._duration
            if self._done:
                s = self._distance
        self._s, self._sd = s, sd
        return self._joints(*self._line.at(s), q)


class ToolSpeed(_ToolSource):
    """``speedl``: the TCP velocity ramps to ``xd`` at ``a`` and keeps it.

    Raises
    ------
    SafetyViolation
        A speed that is not finite.
    CommandRefused
        ``a`` not > 0.
    """

    name = "speedl"

    def __init__(self, kinematics: Kinematics, q_start, xd, a: float, velocity=None) -> None:
        super().__init__(kinematics)
        start = kinematics.forward_matrix(q_start)
        self._p = start[:3, 3].copy()
        self._r = start[:3, :3].copy()
        self._vel = np.zeros(6) if velocity is None else np.array(velocity, dtype=float)
        self.command(xd, a)

    def command(self, xd, a: float) -> None:
        """A new target velocity (the ramp continues from the present one)."""
        target = np.asarray(xd, dtype=float)
        if target.shape != (6,) or not np.all(np.isfinite(target)):
            raise SafetyViolation("speedl: the tool speed must be 6 finite numbers")
        self._accel = positive_value(a, "speedl: acceleration")
        self._target = target
        self._stopping = False

    @property
    def velocity(self) -> np.ndarray:
        return self._vel.copy()

    def next_q(self, q: np.ndarray, dt: float) -> np.ndarray | None:
        target = np.zeros(6) if self._stopping else self._target
        accel = self._decel if self._stopping else self._accel
        # Linear and angular parts ramp as vectors (the direction of the change is kept).
        new = self._vel.copy()
        for part in (slice(0, 3), slice(3, 6)):
            change = target[part] - self._vel[part]
            norm = float(np.linalg.norm(change))
            step = accel * dt
            new[part] = target[part] if norm <= step else self._vel[part] + change * (step / norm)
        mean = 0.5 * (self._vel + new)
        self._vel = new
        if self._stopping and not np.any(new) and not np.any(mean):
            return None
        self._p = self._p + mean[:3] * dt
        angle = float(np.linalg.norm(mean[3:]))
        if angle > 0.0:
            self._r = _matrix(mean[3:] * dt) @ self._r
        return self._joints(self._p, self._r, q)
