"""Identify a mode from an accelerometer log, as from a robot's RTDE recording.

The flexible UR5e twin runs a random base excitation (the paper's Algorithm 2) at the
stretched pose Q1 with a noisy tool accelerometer, and writes the run as a ur_rtde CSV log:
the file a real UR would give with ``tvist record``. The log is read back and the base mode
identified from it (eqs. 12-19), then compared with the twin's own modes.

    python examples/05_identify_from_log.py
"""

from __future__ import annotations

import math

import tvist
from tvist.ident import identify_local, random_excitation, read_rtde_csv
from tvist.sim import Twin
from tvist.trajectory import PAPER_POSES

PAYLOAD_KG, PAYLOAD_COM_M = 5.0, (0.0, 0.0, 0.05)
BASE = 0
q0 = PAPER_POSES["Q1"]

# 1. Excite the base joint on the twin and record it like RTDE (0.05 m/s² sensor noise).
excitation = random_excitation(
    q0, joint=BASE, seed=3, duration_s=4.0, dt_s=tvist.robots.params("ur5e").control_period_s
)
twin = Twin("ur5e", payload_kg=PAYLOAD_KG, payload_com_m=PAYLOAD_COM_M, accel_noise_std=0.05)
log_path = twin.run(excitation.q, noise_seed=3).to_csv("base_excitation.csv")

# 2. Read the log as any RTDE recording and identify the base mode.
record = read_rtde_csv(log_path)
fit = identify_local(record, BASE, tvist.robots.ur5e(PAYLOAD_KG, PAYLOAD_COM_M))
true_wn, true_zeta = twin.modes(q0)[BASE]

print(f"log: {log_path} ({len(record.t_s)} samples)")
print(f"identified: f_n {fit.wn_rad_s / (2 * math.pi):.3f} Hz, zeta {fit.zeta:.4f}")
print(f"twin:       f_n {true_wn / (2 * math.pi):.3f} Hz, zeta {true_zeta:.4f}")
print(f"error:      f_n {fit.wn_rad_s / true_wn - 1:+.2%}, zeta {fit.zeta / true_zeta - 1:+.2%}")
print(f"confident:  {not fit.low_confidence}")
