"""A path of moves with blends, as the controller runs ``movePath`` (and ``moveL``/``moveJ``
with a list of waypoints, which ur_rtde sends as a path).

Each waypoint is a segment from the previous one: a ``movel`` (the TCP on a straight line, its
orientation slerped, see :class:`~tvist.urserver.tool_motion.Line`) or a ``movej`` (all joints
linearly in proportion). Each segment has a path parameter ``u`` in ``[0, L]`` in its own unit
(m or rad of the TCP for a ``movel``, rad of the leading joint for a ``movej``).

Blends (UR semantics): a waypoint with blend radius ``r > 0`` (m, a TCP distance, for both
kinds) is passed without stopping. The motion leaves the arriving segment where the TCP comes
within ``r`` of the waypoint and joins the next segment where it is ``r`` from the waypoint.
Blends do not overlap: a radius larger than half of either neighbouring segment (TCP chord)
is reduced to that half, with a warning in the log. The last waypoint is always reached at
rest.

Inside a blend (a parabolic blend) the arriving segment's parameter decelerates linearly to
its end and the next one's accelerates linearly from its start, over the same time ``T``, and
the two displacements from the waypoint add: for two ``movel`` segments in TCP space
(positions add, rotations compose), otherwise in joint space. The speed therefore changes
direction smoothly, never exceeds the segments' speeds, stays away from zero unless the path
reverses, and the TCP stays within ``r`` of the waypoint (for two lines: the distance is at
most the sum of the two parameters' remaining and done ways, which is at most ``r``). Between
blends each segment runs a trapezoidal profile from the blend speed it enters with to the one
it leaves with (0 at a stop); a forward and a backward pass lower the blend speeds until every
segment can make its change of speed at its acceleration, and each blend's speed is also
capped so that neither parameter decelerates faster than its segment's acceleration.
"""

from __future__ import annotations

import logging
import math

import numpy as np

from tvist.sim.plant import rotation_vector
from tvist.urserver.kinematics import Kinematics, pose_matrix
from tvist.urserver.motion import CommandRefused, JointMotion, SafetyViolation, positive_value
from tvist.urserver.move_path import Waypoint
from tvist.urserver.tool_motion import Line

log = logging.getLogger("tvist.urserver")

#: Steps of inverse kinematics along a line to find the joints at its end on the branch the
#: motion follows (each step moves the TCP by a quarter of the line; few, because the path is
#: planned within one controller tick).
_IK_WALK_STEPS = 4
#: Bisection steps for the joint-move parameter at a given TCP distance (resolves L / 2**40).
_BISECTION_STEPS = 40


class _JointSegment:
    """A ``movej`` from ``q0`` to ``q1``: ``u`` is the leading joint's way (rad)."""

    kind = "movej"

    def __init__(self, kin: Kinematics, q0, q1, v: float, a: float) -> None:
        self._kin = kin
        self.q0 = np.asarray(q0, dtype=float)
        self.q1 = np.asarray(q1, dtype=float)
        self.length = float(np.max(np.abs(self.q1 - self.q0)))
        self.v, self.a = v, a

    def joints(self, u: float, seed: np.ndarray) -> np.ndarray:
        if self.length == 0.0 or u >= self.length:
            return self.q1.copy()
        return self.q0 + (u / self.length) * (self.q1 - self.q0)

    def tcp_position(self, u: float) -> np.ndarray:
        return self._kin.forward_matrix(self.joints(u, self.q0))[:3, 3]

    def param_within(self, r: float, at_end: bool) -> float:
        """Way (in ``u``) from the end (``at_end``) or the start to where the TCP is ``r``
        from that end: bisection on the TCP distance."""
        anchor = self.tcp_position(self.length if at_end else 0.0)
        near, far = 0.0, self.length  # way from the anchor: TCP distance < r, >= r
        for _ in range(_BISECTION_STEPS):
            mid = 0.5 * (near + far)
            u = self.length - mid if at_end else mid
            if np.linalg.norm(self.tcp_position(u) - anchor) < r:
                near = mid
            else:
                far = mid
        return 0.5 * (near + far)


class _LinearSegment:
    """A ``movel`` from the TCP pose at ``q0`` to ``pose``: ``u`` runs along its
    :class:`Line` (m, or rad for a rotation-dominated move)."""

    kind = "movel"

    def __init__(self, kin: Kinematics, q0, pose, v: float, a: float) -> None:
        self._kin = kin
        self.line = Line(kin.forward_matrix(q0), pose_matrix(pose))
        self.length = self.line.distance
        self.v, self.a = v, a
        # The joints at the end, on the branch the motion follows: IK walked along the line.
        q = np.asarray(q0, dtype=float)
        for step in range(1, _IK_WALK_STEPS + 1):
            q = self.ik(*self.line.at(self.length * step / _IK_WALK_STEPS), q)
        self.q0 = np.asarray(q0, dtype=float)
        self.q1 = q

    def ik(self, position: np.ndarray, rotation: np.ndarray, seed: np.ndarray) -> np.ndarray:
        pose = np.concatenate([position, rotation_vector(rotation.ravel())])
        try:
            return self._kin.inverse(pose, seed)
        except CommandRefused:
            raise SafetyViolation(
                f"movel: the TCP path leaves the workspace at "
                f"{np.array2string(pose, precision=4)} (no inverse kinematics solution)"
            ) from None

    def joints(self, u: float, seed: np.ndarray) -> np.ndarray:
        return self.ik(*self.line.at(u), seed)

    def param_within(self, r: float, at_end: bool) -> float:
        # The TCP moves on the line in proportion to u.
        return r * self.length / self.line.length


class _Profile:
    """Speed profile of the way between two blends: from speed ``w0`` to ``w1`` over
    ``length`` (the segment's unit), accelerating at ``a``, cruising at most at ``v``
    (``|w1² - w0²| <= 2 a length`` and ``w0, w1 <= v`` hold by construction)."""

    def __init__(self, length: float, w0: float, w1: float, v: float, a: float) -> None:
        self.length, self.w0, self.w1, self.a = length, w0, w1, a
        peak = min(v, math.sqrt(max(a * length + 0.5 * (w0 * w0 + w1 * w1), 0.0)))
        self.peak = max(peak, w0, w1)
        self.t1 = (self.peak - w0) / a
        self.d1 = (self.peak**2 - w0 * w0) / (2.0 * a)
        t3 = (self.peak - w1) / a
        d3 = (self.peak**2 - w1 * w1) / (2.0 * a)
        cruise = max(length - self.d1 - d3, 0.0)
        self.t2 = cruise / self.peak if self.peak > 0.0 else 0.0
        self.duration = self.t1 + self.t2 + t3

    def at(self, t: float) -> tuple[float, float]:
        """``(way done, speed)`` at time ``t`` into the profile."""
        if t >= self.duration:
            return self.length, self.w1
        if t <= self.t1:
            return self.w0 * t + 0.5 * self.a * t * t, self.w0 + self.a * t
        if t <= self.t1 + self.t2:
            return self.d1 + self.peak * (t - self.t1), self.peak
        rest = self.duration - t  # decelerating to w1: mirror from the end
        return self.length - (self.w1 * rest + 0.5 * self.a * rest * rest), self.w1 + self.a * rest


class PathMotion:
    """The motion of a whole path from the joints ``q_start``: a source for
    :meth:`tvist.urserver.motion.JointMotion.follow`.

    Raises
    ------
    CommandRefused
        A speed or acceleration not > 0, or a pose target with no inverse kinematics solution
        (naming the waypoint).
    SafetyViolation
        A joint target outside the limits, a line leaving the workspace.
    """

    name = "movePath"

    def __init__(
        self, kin: Kinematics, motion: JointMotion, q_start, waypoints: tuple[Waypoint, ...]
    ) -> None:
        self._kin = kin
        self._segments = []
        q = np.asarray(q_start, dtype=float)
        for i, point in enumerate(waypoints):
            what = f"movePath waypoint {i} ({point.kind})"
            try:
                v = positive_value(point.v, f"{what}: speed")
                a = positive_value(point.a, f"{what}: acceleration")
                if point.kind == "movej":
                    target = kin.inverse(point.target, q) if point.is_pose else point.target
                    target = motion.check_target(target, what)
                    v, a = motion.joint_move_limits(np.abs(target - q), v, a, what)
                    segment = _JointSegment(kin, q, target, v, a)
                else:
                    pose = point.target if point.is_pose else kin.forward(point.target)
                    kin.inverse(pose, q)  # refuse an unreachable target up front
                    segment = _LinearSegment(kin, q, pose, v, a)
            except CommandRefused as exc:
                raise CommandRefused(f"{what}: {exc}") from None
            self._segments.append(segment)
            q = segment.q1
        self._plan([point.r for point in waypoints])
        self._piece = 0
        self._t = 0.0
        self._rate = 1.0  # time rate (1: as planned; falls to 0 when stopping)
        self._rate_decay = 0.0
        self._done = not self._pieces

    # ------------------------------------------------------------------ planning

    def _plan(self, radii: list[float]) -> None:
        segs = self._segments
        n = len(segs)
        corners = [segs[0].q0] + [s.q1 for s in segs]
        tcp = [self._kin.forward_matrix(q)[:3, 3] for q in corners]
        chords = [float(np.linalg.norm(tcp[k + 1] - tcp[k])) for k in range(n)]
        # Blend k is at the end of segment k (the waypoint k); the last one is a stop.
        blend = [0.0] * n
        for k in range(n - 1):
            fit = 0.5 * min(chords[k], chords[k + 1])
            if radii[k] > fit:
                log.warning(
                    "movePath waypoint %d: blend radius %g m reduced to %g m (half the "
                    "shorter neighbouring segment: blends do not overlap)",
                    k,
                    radii[k],
                    fit,
                )
            blend[k] = min(max(radii[k], 0.0), fit)
        # Ways (in each segment's u) inside the blend zone at its end and at its start.
        out = [segs[k].param_within(blend[k], True) if blend[k] > 0 else 0.0 for k in range(n)]
        inn = [0.0] + [
            segs[k + 1].param_within(blend[k], False) if blend[k] > 0 else 0.0 for k in range(n - 1)
        ]
        for k in range(n):
            total = inn[k] + out[k]
            if total > segs[k].length > 0.0:  # a curved joint move: keep the zones apart
                inn[k] *= segs[k].length / total
                out[k] *= segs[k].length / total
        free = [max(segs[k].length - inn[k] - out[k], 0.0) for k in range(n)]
        # Blend rate lam[k] = 2 / T_k: the arriving segment leaves at speed lam * out[k], the
        # next one joins at lam * inn[k + 1] (each parameter covers its way in T at half the
        # speed on average).
        lam = [0.0] * n
        for k in range(n - 1):
            if blend[k] <= 0.0 or out[k] <= 0.0 or inn[k + 1] <= 0.0:
                continue
            a, b = segs[k], segs[k + 1]
            lam[k] = min(
                a.v / out[k],
                b.v / inn[k + 1],
                math.sqrt(2.0 * a.a / out[k]),
                math.sqrt(2.0 * b.a / inn[k + 1]),
            )
        for k in range(n - 1):  # forward: each segment can speed up to the next blend
            if lam[k] > 0.0:
                w_in = lam[k - 1] * inn[k] if k > 0 else 0.0
                reach = math.sqrt(w_in * w_in + 2.0 * segs[k].a * free[k])
                lam[k] = min(lam[k], reach / out[k])
        for k in range(n - 2, -1, -1):  # backward: and slow down to the one after
            if lam[k] > 0.0:
                w_out = lam[k + 1] * out[k + 1] if k + 1 < n - 1 else 0.0
                reach = math.sqrt(w_out * w_out + 2.0 * segs[k + 1].a * free[k + 1])
                lam[k] = min(lam[k], reach / inn[k + 1])
        self._inn, self._out, self._lam = inn, out, lam
        self._tcp = tcp
        self._pieces: list[tuple[str, int, float, _Profile | None]] = []
        for k, seg in enumerate(segs):
            w0 = lam[k - 1] * inn[k] if k > 0 else 0.0
            w1 = lam[k] * out[k]
            profile = _Profile(free[k], w0, w1, seg.v, seg.a)
            self._pieces.append(("segment", k, profile.duration, profile))
            if lam[k] > 0.0:
                self._pieces.append(("blend", k, 2.0 / lam[k], None))

    # ------------------------------------------------------------------ running

    @property
    def waypoint(self) -> int:
        """Index of the waypoint the motion is heading for (the next one once in its blend:
        a UR's program moves on to the next move when the blend starts)."""
        kind, k, _, _ = self._pieces[min(self._piece, len(self._pieces) - 1)]
        return k + 1 if kind == "blend" else k

    def _speed(self) -> float:
        """Parameter speed now (the faster of the two in a blend)."""
        kind, k, duration, profile = self._pieces[self._piece]
        if kind == "segment":
            return profile.at(self._t)[1]
        x = self._t / duration
        return max(self._lam[k] * self._out[k] * (1.0 - x), self._lam[k] * self._inn[k + 1] * x)

    def stop(self, decel: float) -> None:
        """``stopl``/``stopj``: slow down along the path to rest at about ``decel``."""
        decel = positive_value(decel, "stop: deceleration")
        if self._done:
            return
        self._rate_decay = decel / max(self._speed(), 1e-9)

    def next_q(self, q: np.ndarray, dt: float) -> np.ndarray | None:
        if self._done:
            return None
        if self._rate_decay > 0.0:
            rate = max(self._rate - self._rate_decay * dt, 0.0)
            step = 0.5 * (self._rate + rate) * dt
            self._rate = rate
            if rate == 0.0:
                self._done = True
        else:
            step = dt
        self._t += step
        while self._t >= self._pieces[self._piece][2] and self._piece + 1 < len(self._pieces):
            self._t -= self._pieces[self._piece][2]
            self._piece += 1
        kind, k, duration, profile = self._pieces[self._piece]
        if self._piece + 1 == len(self._pieces) and self._t >= duration:
            self._done = True
        if kind == "segment":
            seg = self._segments[k]
            return seg.joints(self._inn[k] + profile.at(self._t)[0], q)
        return self._blend(k, min(self._t, duration), duration, q)

    def _blend(self, k: int, t: float, duration: float, q: np.ndarray) -> np.ndarray:
        a, b = self._segments[k], self._segments[k + 1]
        lam = self._lam[k]
        w_out, w_in = lam * self._out[k], lam * self._inn[k + 1]
        # Linear speed ramps over the blend: the arriving parameter from w_out to 0, the
        # next one from 0 to w_in.
        ua = a.length - self._out[k] + w_out * t - w_out * t * t / (2.0 * duration)
        ub = w_in * t * t / (2.0 * duration)
        if a.kind == b.kind == "movel":
            pa, ra = a.line.at(ua)
            pb, rb = b.line.at(ub)
            position = pa + pb - self._tcp[k + 1]
            rotation = rb @ b.line.r0.T @ ra  # both rotations from the waypoint's, composed
            return a.ik(position, rotation, q)
        return a.joints(ua, q) + b.joints(ub, q) - a.q1
