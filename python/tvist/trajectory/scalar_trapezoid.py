"""A rest-to-rest trapezoidal speed profile along one scalar way (a joint angle, a path
length): its duration, cruise speed and the way done at a time. The profile of UR's ``movej``
and ``movel`` (the twin controller's :mod:`tvist.urserver.motion`), of a move list's lines
(:mod:`tvist.move_list`) and of a campaign plan's approach moves; units are the way's (rad or
m) and seconds.
"""

from __future__ import annotations

import math

__all__ = ["trapezoid_duration", "trapezoid_position"]


def trapezoid_duration(distance: float, v_max: float, a_max: float) -> tuple[float, float]:
    """``(duration_s, cruise_speed)`` of a rest-to-rest trapezoidal profile over ``distance``."""
    if distance <= 0.0:
        return 0.0, 0.0
    v = min(v_max, math.sqrt(distance * a_max))  # triangle if v_max is not reached
    return distance / v + v / a_max, v


def trapezoid_position(
    t: float, speed: float, accel: float, total: float, distance: float
) -> float:
    """Way done at time ``t`` of a rest-to-rest trapezoidal profile over ``distance`` that
    cruises at ``speed``, accelerates at ``accel`` and lasts ``total`` (see
    :func:`trapezoid_duration`)."""
    t_acc = speed / accel
    if t <= t_acc:
        return 0.5 * accel * t * t
    if t <= total - t_acc:
        return 0.5 * accel * t_acc * t_acc + speed * (t - t_acc)
    rest = max(total - t, 0.0)
    return distance - 0.5 * accel * rest * rest
