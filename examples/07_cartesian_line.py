"""Shape a straight Cartesian move so that it stays straight.

A 0.3 m flange line along base X in 0.734 s with a 2.55 Hz payload mode (zeta 0.04), shaped
by a ZVD shaper: once on the TCP reference (``tvist.cartesian``, joints by inverse
kinematics every sample) and once on the joint reference. Joint-space shaping blends points of
a path that is curved in joint space, so the flange leaves the line; Cartesian shaping keeps
it on the line.

    python examples/07_cartesian_line.py
"""

from __future__ import annotations

import numpy as np

import tvist
from tvist import cartesian

DT_S = tvist.robots.params("ur5e").control_period_s  # the UR5e controller's period, s
MODES = [(2 * np.pi * 2.55, 0.04)]  # (wn_rad_s, zeta) of the payload mode

robot = tvist.robots.ur5e()
q_start = np.array([0.0, -2.0, 2.0, -np.pi / 2, -np.pi / 2, 0.0])
line, R0 = cartesian.straight_line(
    robot, q_start, (0.3, 0.0, 0.0), duration_s=0.734, dt_s=DT_S, t_post_s=1.0
)

in_tcp = cartesian.shape_cartesian(robot, q_start, line.q, R0, DT_S, MODES, shaper="zvd")
planned_joints = cartesian.joints_from_tcp(robot, line.q, R0, q_start)
joint_shaper = tvist.TvShaper(tvist.ConstantModes(MODES), dt_s=DT_S, n_dof=6, shaper="zvd")
in_joints = joint_shaper.shape(planned_joints)

for label, Q in (("Cartesian shaping", in_tcp.Q), ("joint shaping", in_joints)):
    deviation_m = np.max(cartesian.tcp_path_deviation_m(robot, planned_joints, Q))
    print(f"{label:>17}: flange leaves the line by {deviation_m:.2e} m")
