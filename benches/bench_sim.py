"""Benchmark: simulated time per wall-clock time of the MuJoCo twin (tvist.sim.Twin.run).

Simulates the paper's test motions Q1 -> Q3 -> Q1 (UR5e, 5 kg payload, joint-space smoothstep
moves, 2 s holds) at 500 Hz with the default 0.5 ms physics step, several times, and prints the
real-time factor (simulated seconds per wall-clock second, best of the repetitions) and the
ground-truth modes at the three test poses.

Run: ``.venv/bin/python benches/bench_sim.py``.
"""

from __future__ import annotations

import time

import numpy as np

from tvist.robots import params
from tvist.sim import Twin

#: The twin's control period: the UR5e's (its robot data), s.
DT_S = params("ur5e").control_period_s
Q1 = np.array([0.0, -np.pi, 0.0, -np.pi / 2, 0.0, 0.0])
Q2 = np.array([np.pi / 2, -np.pi, 0.0, -np.pi / 2, 0.0, 0.0])
Q3 = np.array([np.pi / 2, -np.pi / 2, 5 * np.pi / 6, -np.pi / 2, 0.0, 0.0])


def smooth_move(q_from: np.ndarray, q_to: np.ndarray, move_s: float, hold_s: float) -> np.ndarray:
    """Smoothstep move followed by a hold, (n_samples, 6) rad at 500 Hz."""
    blend = np.clip(np.arange(0.0, move_s + hold_s, DT_S) / move_s, 0.0, 1.0)
    return q_from + np.outer(blend**2 * (3.0 - 2.0 * blend), q_to - q_from)


def main() -> None:
    twin = Twin("ur5e", payload_kg=5.0, payload_com_m=(0.0, 0.0, 0.05))
    for name, q in (("Q1", Q1), ("Q2", Q2), ("Q3", Q3)):
        (wb, zb), (ws, zs) = twin.modes(q)
        print(
            f"{name}: base {wb / 2 / np.pi:6.2f} Hz zeta {zb:.3f} | "
            f"shoulder {ws / 2 / np.pi:6.2f} Hz zeta {zs:.3f}"
        )
    q_ref = np.vstack([smooth_move(Q1, Q3, 2.0, 2.0), smooth_move(Q3, Q1, 2.0, 2.0)])
    simulated_s = len(q_ref) * DT_S
    best_s = np.inf
    for _ in range(5):
        start = time.perf_counter()
        twin.run(q_ref)
        best_s = min(best_s, time.perf_counter() - start)
    print(
        f"{simulated_s:.1f} s simulated in {best_s:.3f} s (physics step "
        f"{twin.physics_dt_s * 1e3:.2f} ms): {simulated_s / best_s:.1f}x real time"
    )


if __name__ == "__main__":
    main()
