"""Shape a move cycle by cycle, as a 500 Hz robot controller would.

The two vibration modes are fixed here (the base and shoulder modes of a UR5e in an
outstretched pose); every control cycle, the next target joint position goes in and the shaped
one comes out. Run: ``python examples/01_shape_a_move.py``.
"""

from __future__ import annotations

import numpy as np

import tvist

DT_S = 0.002  # 500 Hz control period
N_DOF = 6

# (wn_rad_s, zeta) per mode: base ~8.3 Hz and shoulder ~7.4 Hz undamped.
modes = tvist.ConstantModes([(2 * np.pi * 8.31, 0.26), (2 * np.pi * 7.45, 0.37)])
shaper = tvist.TvShaper(modes, dt_s=DT_S, n_dof=N_DOF, shaper="zv")

# A 1 s smooth (cosine) move of 0.5 rad on joints 1 and 2, then 0.5 s at rest.
q_start = np.zeros(N_DOF)
q_end = np.array([0.0, 0.5, -0.5, 0.0, 0.0, 0.0])
n_move, n_rest = int(1.0 / DT_S), int(0.5 / DT_S)

for i in range(n_move + n_rest):
    s = min(i / n_move, 1.0)
    q_target = q_start + (q_end - q_start) * 0.5 * (1 - np.cos(np.pi * s))
    q_shaped = shaper.step(q_target)  # send q_shaped to the robot
    if shaper.last_status != tvist.Status.OK:
        print(f"cycle {i}: {tvist.Status(shaper.last_status)!r}")
    if i % 100 == 0:
        lag_mrad = (q_target[1] - q_shaped[1]) * 1e3
        print(
            f"t = {i * DT_S:4.2f} s   target {q_target[1]:+.4f}   shaped {q_shaped[1]:+.4f}   "
            f"lag {lag_mrad:+6.2f} mrad   shaper delay {shaper.delay_s * 1e3:.1f} ms"
        )

print(f"final shaped pose: {np.round(q_shaped, 6)}  (target {q_end})")
assert np.allclose(q_shaped, q_end, atol=1e-12), "the shaped move must end at the target"
