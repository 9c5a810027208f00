"""The controller's joint motion: what the servo is told to do, one 2 ms tick at a time.

The motion owns the joint target ``q`` (rad) that the motors follow (the twin's motor side
follows it exactly, see :mod:`tvist.sim.twin_plant`), with its velocity ``qd`` (rad/s) and
acceleration ``qdd`` (rad/s²). Modes, as URScript's functions:

- ``movej(q, a, v)``: a trapezoidal speed profile in joint space, all joints starting and
  arriving together; the joint with the longest way moves at most at speed ``v`` and
  acceleration ``a`` (a triangle when the way is too short to reach ``v``).
- ``servoj(q, t, lookahead_time, gain)``: the target moves linearly to ``q`` within ``t``;
  the servo reference follows it through a first-order low-pass of time constant
  ``lookahead_time`` (the smoothing: a longer lookahead is smoother and lags more), and the
  joint target follows the reference with the proportional gain ``gain`` (1/s, i.e. a second
  first-order lag of time constant ``1/gain``). Both lags are discretized exactly (zero-order
  hold), so every gain in UR's range 100-2000 is stable at 2 ms. When servoj commands stop
  arriving, the target stays at the last one: the arm holds.
- ``speedj(qd, a)``: every joint speed ramps to ``qd`` at acceleration ``a`` and keeps it.
- ``stopj(a)``: all joints decelerate together (the fastest at ``a``) and stop.

Every mode clips the joint speed to the robot's limits (``movej`` clips its ``v`` and ``a`` so
that no joint exceeds its speed limit nor reaches it in less than one tick). Every number a
command takes is checked: one that is not finite, or a target outside the joint limits, raises
:class:`SafetyViolation` (a UR protective-stops); a finite one outside the range URScript
allows raises :class:`CommandRefused` (a UR stops the program with a runtime error). The
joint target is finite at every tick (an invariant :meth:`JointMotion.advance` checks).
"""

from __future__ import annotations

import logging
import math

import numpy as np

from tvist.trajectory.scalar_trapezoid import trapezoid_duration, trapezoid_position

log = logging.getLogger("tvist.urserver")

#: servoj's ``lookahead_time`` (s) and ``gain`` (1/s) ranges (URScript manual).
SERVO_LOOKAHEAD_RANGE_S = (0.03, 0.2)
SERVO_GAIN_RANGE = (100.0, 2000.0)


class SafetyViolation(RuntimeError):
    """A commanded motion would leave the joint limits, or a command's number is not finite
    (the controller protective-stops)."""


class CommandRefused(ValueError):
    """A command's argument is outside the range URScript allows (the program stops with a
    runtime error; the arm decelerates as at any program stop)."""


def finite_value(value, what: str) -> float:
    """``value`` as a float; :class:`SafetyViolation` naming ``what`` if it is not finite."""
    number = float(value)
    if not math.isfinite(number):
        raise SafetyViolation(f"{what} is {number} (not a finite number)")
    return number


def value_in_range(value, what: str, lower: float, upper: float) -> float:
    """``value`` as a float within ``[lower, upper]``.

    Raises
    ------
    SafetyViolation
        If it is not finite.
    CommandRefused
        If it is outside the range.
    """
    number = finite_value(value, what)
    if not lower <= number <= upper:
        raise CommandRefused(f"{what} = {number:g} is outside [{lower:g}, {upper:g}]")
    return number


def positive_value(value, what: str) -> float:
    """``value`` as a finite float > 0 (:class:`SafetyViolation` if not finite,
    :class:`CommandRefused` if <= 0)."""
    number = finite_value(value, what)
    if not number > 0.0:
        raise CommandRefused(f"{what} = {number:g} must be > 0")
    return number


class JointMotion:
    """Joint target generator of the twin's controller.

    Parameters
    ----------
    q0
        Initial joint target (rad), ``(n_dof,)``.
    dt_s
        Controller tick (s).
    max_speed_rad_s
        Joint speed limits (rad/s), ``(n_dof,)``.
    joint_limits_rad
        ``(n_dof, 2)`` lower and upper joint limits (rad).
    """

    def __init__(
        self,
        q0: np.ndarray,
        dt_s: float,
        max_speed_rad_s: np.ndarray,
        joint_limits_rad: np.ndarray,
    ) -> None:
        self.dt_s = float(dt_s)
        self.q = np.array(q0, dtype=float)
        self.qd = np.zeros_like(self.q)
        self.qdd = np.zeros_like(self.q)
        self._max_speed = np.asarray(max_speed_rad_s, dtype=float)
        self._limits = np.asarray(joint_limits_rad, dtype=float)
        self.mode = "hold"
        #: Speed slider (0..1): moves (movej, tool-space motions) advance their time by this
        #: fraction of each tick, so the whole profile slows down in proportion.
        self.time_scale = 1.0
        # movej
        self._move_from = self.q.copy()
        self._move_to = self.q.copy()
        self._move_t = 0.0
        self._move_duration = 0.0
        self._move_speed = 0.0
        self._move_accel = 0.0
        # servoj: target ramp, low-passed reference
        self._servo_from = self.q.copy()
        self._servo_to = self.q.copy()
        self._servo_ramp_s = self.dt_s
        self._servo_elapsed = 0.0
        self._servo_ref = self.q.copy()
        self._lookahead_s = 0.1
        self._gain = 300.0
        # speedj / stop
        self._speed_target = np.zeros_like(self.q)
        self._vel = np.zeros_like(self.q)  # speed state of speedj / stop (rad/s)
        self._accel = 1.0

    @property
    def moving(self) -> bool:
        """Whether a movej is under way or the joint target is still moving or decelerating
        (a move has ended once the target stands still with zero acceleration)."""
        return self.mode in ("movej", "follow") or bool(
            np.any(self.qd != 0.0) or np.any(self.qdd != 0.0)
        )

    # ----------------------------------------------------------------- commands

    def _check_target(self, q: np.ndarray, what: str) -> np.ndarray:
        arr = np.asarray(q, dtype=float)
        if arr.shape != self.q.shape or not np.all(np.isfinite(arr)):
            raise SafetyViolation(f"{what}: target must be {self.q.size} finite joint angles")
        lower, upper = self._limits.T
        bad = np.flatnonzero((arr < lower) | (arr > upper))
        if bad.size:
            j = int(bad[0])
            raise SafetyViolation(
                f"{what}: joint {j} target {arr[j]:.4f} rad is outside its limits"
            )
        return arr

    def check_target(self, q, what: str) -> np.ndarray:
        """``q`` as joint angles within the limits (:class:`SafetyViolation` otherwise)."""
        return self._check_target(q, what)

    @property
    def source(self):
        """The source a ``follow`` motion takes its targets from (None before the first)."""
        return getattr(self, "_source", None)

    def movej(self, q, speed_rad_s: float, accel_rad_s2: float) -> None:
        """Start a movej from the current target (a UR blends nothing here: from rest or not,
        the profile starts at the current target).

        The leading joint's ``speed_rad_s`` and ``accel_rad_s2`` are clipped (with a warning
        in the log) so that every joint, moving in proportion, stays within its speed limit
        and takes at least one tick to reach it.
        """
        target = self._check_target(q, "movej")
        speed = positive_value(speed_rad_s, "movej: speed")
        accel = positive_value(accel_rad_s2, "movej: acceleration")
        way = np.abs(target - self.q)
        distance = float(np.max(way))
        speed, accel = self.joint_move_limits(way, speed, accel, "movej")
        self._move_from = self.q.copy()
        self._move_to = target
        self._move_duration, self._move_speed = trapezoid_duration(distance, speed, accel)
        self._move_accel = accel
        self._move_distance = distance
        self._move_t = 0.0
        self.mode = "movej"

    def joint_move_limits(
        self, way: np.ndarray, speed: float, accel: float, what: str
    ) -> tuple[float, float]:
        """The leading joint's ``speed`` and ``accel`` of a joint move whose joints travel
        ``way`` (rad, absolute, in proportion), clipped (with a warning in the log) so that
        every joint stays within its speed limit and takes at least one tick to reach it."""
        distance = float(np.max(way))
        if distance <= 0.0:
            return speed, accel
        # Joint j moves way[j] / distance of the leading joint's way: its speed limit
        # bounds the leading joint's speed by max_speed[j] * distance / way[j].
        moving = way > 0.0
        speed_limit = float(np.min(self._max_speed[moving] * distance / way[moving]))
        accel_limit = speed_limit / self.dt_s
        if speed > speed_limit or accel > accel_limit:
            log.warning(
                "%s: speed %g rad/s, acceleration %g rad/s² clipped to the joint "
                "limits (%g rad/s, %g rad/s²)",
                what,
                speed,
                accel,
                min(speed, speed_limit),
                min(accel, accel_limit),
            )
        return min(speed, speed_limit), min(accel, accel_limit)

    def servoj(self, q, time_s: float, lookahead_s: float, gain: float) -> None:
        """New servo target ``q`` (rad), reached by the target ramp within ``time_s`` (at
        least one tick); ``lookahead_s`` and ``gain`` in URScript's ranges."""
        target = self._check_target(q, "servoj")
        ramp_s = finite_value(time_s, "servoj: time")
        if ramp_s < 0.0:
            raise CommandRefused(f"servoj: time = {ramp_s:g} s must be >= 0")
        lookahead = value_in_range(lookahead_s, "servoj: lookahead_time", *SERVO_LOOKAHEAD_RANGE_S)
        gain = value_in_range(gain, "servoj: gain", *SERVO_GAIN_RANGE)
        if self.mode != "servoj":
            self._servo_ref = self.q.copy()
            self._servo_to = self.q.copy()
        ramp_now = self._servo_ramp_value()
        self._servo_from = ramp_now
        self._servo_to = target
        self._servo_ramp_s = max(ramp_s, self.dt_s)
        self._servo_elapsed = 0.0
        self._lookahead_s = lookahead
        self._gain = gain
        self.mode = "servoj"

    def speedj(self, qd, accel_rad_s2: float) -> None:
        """Ramp every joint speed to ``qd`` (rad/s) at ``accel_rad_s2`` and keep it."""
        target = np.asarray(qd, dtype=float)
        if target.shape != self.q.shape or not np.all(np.isfinite(target)):
            raise SafetyViolation(f"speedj: speeds must be {self.q.size} finite values")
        accel = positive_value(accel_rad_s2, "speedj: acceleration")
        if self.mode not in ("speedj", "stop"):
            self._vel = self.qd.copy()
        self._speed_target = np.clip(target, -self._max_speed, self._max_speed)
        self._accel = accel
        self.mode = "speedj"

    def stop(self, accel_rad_s2: float) -> None:
        """Decelerate all joints together to rest (the fastest at ``accel_rad_s2``)."""
        accel = positive_value(accel_rad_s2, "stop: deceleration")
        if self.mode not in ("speedj", "stop"):
            self._vel = self.qd.copy()  # stop from the target's current speed
        self._speed_target = np.zeros_like(self.q)
        self._accel = accel
        self.mode = "stop"

    def follow(self, source) -> None:
        """Take the joint target from ``source`` every tick (a tool-space motion: moveL,
        speedL). ``source.next_q(q, dt)`` returns the next target (rad), or None once the
        motion has ended (the arm then holds). Each target is checked like any other: within
        the joint limits, and no joint faster than its speed limit (the path would need it
        near a singularity; a UR protective-stops there too)."""
        self._source = source
        self.mode = "follow"

    def hold(self) -> None:
        """Stand still at the current target (only from rest; otherwise use :meth:`stop`)."""
        self.qd[:] = 0.0
        self.qdd[:] = 0.0
        self.mode = "hold"

    def hold_at(self, q: np.ndarray) -> None:
        """Stand still at ``q`` (rad, finite): the state after a fault left it unknown."""
        self.q = np.array(q, dtype=float)
        self.hold()

    # ----------------------------------------------------------------- tick

    def _servo_ramp_value(self) -> np.ndarray:
        frac = min(self._servo_elapsed / self._servo_ramp_s, 1.0)
        return self._servo_from + frac * (self._servo_to - self._servo_from)

    def advance(self) -> np.ndarray:
        """Advance one tick; the new joint target (rad), a copy.

        Raises
        ------
        SafetyViolation
            If the target would leave the joint limits.
        """
        dt = self.dt_s
        q_old = self.q.copy()
        qd_old = self.qd.copy()
        if self.mode == "movej":
            self._move_t = min(self._move_t + dt * self.time_scale, self._move_duration)
            self.q = self._move_from + self._movej_fraction(self._move_t) * (
                self._move_to - self._move_from
            )
            if self._move_t >= self._move_duration:
                self.q = self._move_to.copy()
                self.mode = "hold"
        elif self.mode == "servoj":
            self._servo_elapsed += dt
            ramp = self._servo_ramp_value()
            alpha_ref = 1.0 - math.exp(-dt / self._lookahead_s)
            self._servo_ref += alpha_ref * (ramp - self._servo_ref)
            alpha_gain = 1.0 - math.exp(-dt * self._gain)
            step = alpha_gain * (self._servo_ref - self.q)
            self.q = self.q + np.clip(step, -self._max_speed * dt, self._max_speed * dt)
        elif self.mode == "follow":
            q_next = self._source.next_q(self.q.copy(), dt * self.time_scale)
            if q_next is None:
                self.mode = "hold"
            else:
                q_next = np.asarray(q_next, dtype=float)
                fast = np.flatnonzero(np.abs(q_next - self.q) > self._max_speed * dt * 1.0001)
                if fast.size:
                    j = int(fast[0])
                    self.hold_at(q_old)
                    raise SafetyViolation(
                        f"tool-space motion: joint {j} would exceed its speed limit "
                        f"{self._max_speed[j]:g} rad/s (a singularity on the path)"
                    )
                self.q = q_next
        elif self.mode in ("speedj", "stop"):
            vel = self._vel
            dv = self._speed_target - vel
            if self.mode == "stop":
                # All joints reach rest together: the fastest decelerates at the given rate.
                fastest = float(np.max(np.abs(vel)))
                scale = 1.0 if fastest == 0.0 else np.abs(vel) / fastest
                limit = self._accel * dt * scale
            else:
                limit = np.full_like(vel, self._accel * dt)
            vel_new = vel + np.clip(dv, -limit, limit)
            if self.mode == "stop" and np.all(np.abs(vel_new) <= 1e-12):
                vel_new[:] = 0.0
            self.q = self.q + 0.5 * (vel + vel_new) * dt
            self._vel = vel_new
            if self.mode == "stop" and not np.any(vel_new):
                self.mode = "hold"
        if not np.all(np.isfinite(self.q)):
            mode = self.mode
            self.hold_at(q_old)
            raise SafetyViolation(f"{mode}: the joint target is not finite")
        lower, upper = self._limits.T
        outside = np.flatnonzero((self.q < lower) | (self.q > upper))
        if outside.size:
            j = int(outside[0])
            self.hold_at(q_old)
            raise SafetyViolation(f"joint {j} reached its position limit")
        self.qd = (self.q - q_old) / dt
        self.qdd = (self.qd - qd_old) / dt
        return self.q.copy()

    def _movej_fraction(self, t: float) -> float:
        """Fraction of the movej's way done at time ``t`` into it (trapezoid in the leading
        joint's distance, scaled to [0, 1])."""
        distance = self._move_distance
        if distance <= 0.0 or self._move_duration <= 0.0:
            return 1.0
        s = trapezoid_position(t, self._move_speed, self._move_accel, self._move_duration, distance)
        return min(max(s / distance, 0.0), 1.0)
