"""Joint-space rest-to-rest reference trajectories sampled on a uniform grid.

All arrays are ``(n_samples, n_dof)`` with time along rows; SI units, radians.

- :func:`double_s`: synchronized jerk-limited move (ruckig), the paper's test motion profile.
- :func:`min_jerk`: quintic minimum-jerk move of a given duration.
- :func:`trapezoid`: trapezoidal velocity profile (acceleration-limited, unbounded jerk).
- :func:`resample`, :func:`interpolant`: planner waypoints (times, positions, optional
  velocities and accelerations) on the control grid.
- :func:`shape_waypoints`: waypoints in, shaped time-stamped trajectory out (FD-TVIST, ZTDIS,
  modified ZTDIS); :func:`shape_samples` for samples already on the grid.
- :func:`validate_reference`, :func:`check_uniform_time`: checks of references and time stamps.
- :data:`PAPER_POSES`: the UR5e test poses Q1, Q2, Q3.
"""

from __future__ import annotations

from tvist.trajectory._types import Trajectory
from tvist.trajectory.double_s import double_s
from tvist.trajectory.poses import PAPER_POSES
from tvist.trajectory.profiles import min_jerk, trapezoid
from tvist.trajectory.resample import interpolant, resample
from tvist.trajectory.shaping import ShapedTrajectory, shape_samples, shape_waypoints
from tvist.trajectory.validation import check_uniform_time, validate_reference

__all__ = [
    "PAPER_POSES",
    "ShapedTrajectory",
    "Trajectory",
    "check_uniform_time",
    "double_s",
    "interpolant",
    "min_jerk",
    "resample",
    "shape_samples",
    "shape_waypoints",
    "trapezoid",
    "validate_reference",
]
