"""The test motions of the UR5e experiment (paper section 6.1, Table 3) on the UR5e's control
grid, and the :class:`Motion` every experiment's moves are made of."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from functools import cache
from types import MappingProxyType

import numpy as np

from tvist.robots import params
from tvist.trajectory import PAPER_POSES, Trajectory, double_s

#: The arm of the paper's experiments.
PAPER_ROBOT = "ur5e"
#: Control period of the paper's experiments, s: the UR5e's (its robot data). An experiment
#: on another arm runs at that arm's period (:func:`tvist.experiments.experiment.run_motion`).
DT_S = params(PAPER_ROBOT).control_period_s
#: Double-S limits of the test motions (section 6.1): speed, acceleration, acceleration ramp.
V_MAX_RAD_S = 1.5
A_MAX_RAD_S2 = 2.0
JERK_TIME_S = 0.02
#: Payload of the test motions; its centre of mass 5 cm beyond the flange along flange z.
PAYLOAD_KG = 5.0
PAYLOAD_COM_M = (0.0, 0.0, 0.05)
#: Rest before the move starts, s.
PRE_S = 0.2


@dataclass(frozen=True)
class Motion:
    """A rest-to-rest joint-space double-S move between two named poses.

    Attributes
    ----------
    start, end
        Names of the poses in ``poses``.
    poses
        Where the names are looked up (default :data:`PAPER_POSES`), rad.
    v_max_rad_s, a_max_rad_s2, jerk_time_s
        The double-S limits: speed, acceleration and acceleration ramp (default: the paper's
        test motions).
    """

    start: str
    end: str
    poses: Mapping[str, Sequence[float]] = field(
        default_factory=lambda: PAPER_POSES, compare=False, repr=False
    )
    v_max_rad_s: float = V_MAX_RAD_S
    a_max_rad_s2: float = A_MAX_RAD_S2
    jerk_time_s: float = JERK_TIME_S

    @property
    def name(self) -> str:
        """``"Q1->Q2"`` style name (the key in ``results.json``)."""
        return f"{self.start}->{self.end}"

    @property
    def slug(self) -> str:
        """File-name friendly name, ``"Q1-Q2"``."""
        return f"{self.start}-{self.end}"

    @property
    def q_start(self) -> np.ndarray:
        """Start pose, rad, ``(6,)``."""
        return np.array(self.poses[self.start], dtype=float)

    @property
    def q_end(self) -> np.ndarray:
        """End pose, rad, ``(6,)``."""
        return np.array(self.poses[self.end], dtype=float)

    def reference(self, tail_s: float, dt_s: float) -> Trajectory:
        """The unshaped double-S reference with :data:`PRE_S` rest before and ``tail_s`` after,
        sampled every ``dt_s`` (s: the control period of the arm it runs on).

        The move is joint-space linear (phase-synchronized) and ends exactly on a sample.
        """
        return double_s(
            self.q_start,
            self.q_end,
            dt_s=dt_s,
            v_max=self.v_max_rad_s,
            a_max=self.a_max_rad_s2,
            jerk_time_s=self.jerk_time_s,
            t_pre_s=PRE_S,
            t_post_s=tail_s,
        )


#: The three test motions: constant frequencies, low to high, high to low.
MOTIONS: tuple[Motion, ...] = (Motion("Q1", "Q2"), Motion("Q1", "Q3"), Motion("Q3", "Q1"))


def motion_by_name(name: str) -> Motion:
    """The motion of :data:`MOTIONS` called ``name`` (``"Q1->Q2"``)."""
    for motion in MOTIONS:
        if motion.name == name:
            return motion
    known = ", ".join(m.name for m in MOTIONS)
    raise ValueError(f"unknown motion {name!r}; expected one of {known}")


def demo_payload_kg(robot_name: str) -> float:
    """The test motions' payload on ``robot_name``: :data:`PAYLOAD_KG`, or the arm's rated
    payload if that is smaller (a lighter arm carries what it is rated for)."""
    return min(PAYLOAD_KG, params(robot_name).max_payload_kg)


@cache
def demo_poses(robot_name: str) -> Mapping[str, np.ndarray]:
    """Poses ``Q1``, ``Q2``, ``Q3`` (rad) of the three test moves on ``robot_name``.

    The paper's poses (:data:`PAPER_POSES`) for a DH arm (UR). For a URDF-placed arm the same
    roles, from its own workspace (:func:`tvist.ident.pose_plan.workspace_extremes` with the
    demo payload): ``Q1`` the pose of the largest shoulder inertia ``J_1`` (stretched out,
    lowest modes), ``Q2`` the same pose with the base turned by a quarter turn (same inertias,
    a long base move), ``Q3`` the pose of the smallest ``J_1`` (folded, highest modes) with
    the base turned as in ``Q2``.
    """
    from tvist.ident.pose_plan import workspace_extremes

    p = params(robot_name)
    if p.placements is None:
        return PAPER_POSES
    extremes = workspace_extremes(
        robot_name, demo_payload_kg(robot_name), PAYLOAD_COM_M, joints=[1]
    )
    folded, stretched = extremes  # smallest, then largest J_1
    lower, upper = p.joint_limits_rad[0]
    turn = np.pi / 2 if upper >= np.pi / 2 else -np.pi / 2
    if not lower <= turn <= upper:
        raise ValueError(f"{robot_name}: the base cannot turn a quarter turn within its limits")
    q2, q3 = stretched.copy(), folded.copy()
    q2[0] = q3[0] = turn
    return MappingProxyType({"Q1": stretched, "Q2": q2, "Q3": q3})


def demo_motions(robot_name: str) -> tuple[Motion, ...]:
    """The three test moves of :data:`MOTIONS` between :func:`demo_poses` of ``robot_name``,
    at the paper's double-S limits capped by the arm's slowest joint speed limit."""
    poses = demo_poses(robot_name)
    v_max = min(V_MAX_RAD_S, float(np.min(params(robot_name).max_velocity_rad_s)))
    return tuple(Motion(m.start, m.end, poses, v_max_rad_s=v_max) for m in MOTIONS)
