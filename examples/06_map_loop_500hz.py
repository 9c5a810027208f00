"""Load a map file and shape in a 500 Hz control loop, as a robot controller would.

A map file is what ``tvist fit-map`` writes for your arm; here the paper's UR5e map is saved
to one first so the example has a file to load. The loop then takes one planned joint sample
per 2 ms cycle, shapes it with FD-TVIST (the modes re-evaluated from the pose every cycle, in
Rust) and would send the result to the robot. Paced to the wall clock with ``--realtime``;
by default it runs as fast as it can.

    python examples/06_map_loop_500hz.py [--realtime]
"""

from __future__ import annotations

import sys
import time

import numpy as np

import tvist
from tvist.trajectory import PAPER_POSES, double_s

DT_S = tvist.robots.params("ur5e").control_period_s  # the UR5e controller's: 2 ms, 500 Hz
realtime = "--realtime" in sys.argv[1:]

# Your map file (here: the paper's map, saved so that the loop has a file to load).
tvist.DynamicMap.paper_ur5e().save("ur5e_map.json")
dynmap = tvist.load_map("ur5e_map.json")  # a paper10 or a modal map, by the file's kind

robot = tvist.robots.ur5e(payload_kg=5.0, payload_com_m=(0.0, 0.0, 0.05))
shaper = tvist.TvShaper(tvist.dynamics_for(robot, dynmap), dt_s=DT_S, n_dof=6, shaper="zv")

plan = double_s(PAPER_POSES["Q1"], PAPER_POSES["Q3"], dt_s=DT_S, t_post_s=0.3).q
shaper.reset(plan[0])
worst_step_s, next_tick = 0.0, time.perf_counter()
for q_planned in plan:  # one iteration per control cycle
    t0 = time.perf_counter()
    q_cmd = shaper.step(q_planned)  # robot_io.servo(q_cmd) on a robot
    worst_step_s = max(worst_step_s, time.perf_counter() - t0)
    if shaper.last_status:
        print(f"status: {tvist.Status(shaper.last_status)}")
    if realtime:
        next_tick += DT_S
        time.sleep(max(0.0, next_tick - time.perf_counter()))

print(f"{len(plan)} cycles of {DT_S * 1e3:.0f} ms")
print(f"delay at the end pose {shaper.delay_s * 1e3:.1f} ms")
print(f"final error {np.max(np.abs(q_cmd - plan[-1])):.2e} rad")
print(f"slowest step (Python call included) {worst_step_s * 1e6:.0f} us")
