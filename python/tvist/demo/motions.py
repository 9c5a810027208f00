"""The test motions of the UR5e experiment (paper section 6.1, Table 3) on the 500 Hz grid,
and the :class:`Motion` every experiment's moves are made of."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np

from tvist.trajectory import PAPER_POSES, Trajectory, double_s

#: Control period of the UR e-Series controller, s.
DT_S = 0.002
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

    def reference(self, tail_s: float, dt_s: float = DT_S) -> Trajectory:
        """The unshaped double-S reference with :data:`PRE_S` rest before and ``tail_s`` after.

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
