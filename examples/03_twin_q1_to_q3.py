"""Try the whole chain without a robot: plan a move, shape it, run it on the flexible twin.

The simulated UR5e (MuJoCo, flexible joints, 5 kg payload) runs the paper's Q1 -> Q3 move
twice, unshaped and shaped by multi-mode FD-TVIST with the paper's dynamic map evaluated in
Rust every cycle; the tool accelerometer tells how much the arm rings after the stop.
Run: ``python examples/03_twin_q1_to_q3.py``.
"""

from __future__ import annotations

import numpy as np

import tvist
from tvist.analysis import residual_vibration
from tvist.sim import Twin
from tvist.trajectory import PAPER_POSES, double_s

DT_S = tvist.robots.params("ur5e").control_period_s  # the UR5e controller's period, s
PAYLOAD_KG, PAYLOAD_COM_M = 5.0, (0.0, 0.0, 0.05)

move = double_s(PAPER_POSES["Q1"], PAPER_POSES["Q3"], dt_s=DT_S, t_pre_s=0.1, t_post_s=1.0)
robot = tvist.robots.ur5e(PAYLOAD_KG, PAYLOAD_COM_M)
shaper = tvist.TvShaper(
    tvist.MapDynamics(robot, tvist.DynamicMap.paper_ur5e()), dt_s=DT_S, n_dof=6, shaper="zv"
)
shaped = shaper.shape(move.q)
print(f"shaper delay at Q3: {shaper.delay_s * 1e3:.1f} ms")

twin = Twin("ur5e", payload_kg=PAYLOAD_KG, payload_com_m=PAYLOAD_COM_M)
results = {}
for name, reference, t_stop in (
    ("unshaped", move.q, move.t_motion_end_s),
    ("FD-TVIST", shaped, move.t_motion_end_s + shaper.delay_s),
):
    record = twin.run(reference, dt_s=DT_S)
    # The tool is at rest after the stop, so the accelerometer's static level (gravity in the
    # flange frame) is the mean of the record's tail; residual_vibration subtracts it.
    rv = residual_vibration(record.timestamp, record.actual_tool_accelerometer, t_stop)
    results[name] = rv.amplitude
    print(f"{name:>9}: residual vibration {rv.amplitude:.4f} m/s²")

reduction = 100.0 * (1.0 - results["FD-TVIST"] / results["unshaped"])
print(f"reduction: {reduction:.1f} %")
for label, (wn, zeta) in zip(("base", "shoulder"), twin.modes(PAPER_POSES["Q3"]), strict=True):
    print(f"twin's true {label} mode at Q3: {wn / (2 * np.pi):.2f} Hz, zeta {zeta:.3f}")
assert reduction > 80.0, "shaping with the paper's map should remove most of the ringing"
