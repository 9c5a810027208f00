"""A self-contained end-to-end example: two-mode ZV FD-TVIST on a two-mode linear plant.

A joint-space double-S move drives a plant whose tool acceleration is the sum of two
base-excited second-order modes. The reference is shaped by ``TvShaper`` with the plant's own
(constant) modes, and the residual vibration of both runs is compared. This needs no robot
model and no simulator; :mod:`tvist.experiments.experiment` on the MuJoCo twin is the full
experiment.
"""

from __future__ import annotations

import json
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np
from scipy import signal

import tvist
from tvist.analysis import peak_jerk, residual_vibration
from tvist.trajectory import double_s

#: Plant modes (Hz, zeta): roughly the UR5e base and shoulder modes at the stretched pose Q1.
PLANT_MODES_HZ = ((8.0, 0.26), (6.9, 0.37))
#: Control period, s: the UR5e's (its robot data), whose modes the plant has.
DT_S = tvist.robots.params("ur5e").control_period_s


def mode_acceleration(t_s: np.ndarray, u: np.ndarray, freq_hz: float, zeta: float) -> np.ndarray:
    """Absolute acceleration of a base-excited mode ``x'' + 2ζω(x'−u') + ω²(x−u) = 0``.

    With the deflection ``e = x − u``: ``e'' + 2ζωe' + ω²e = −u''`` and
    ``x'' = −2ζωe' − ω²e``. ``u''`` is the reference's second difference (exact for the
    piecewise-linear acceleration of a jerk-limited move), linearly interpolated by ``lsim``.
    """
    w = 2.0 * np.pi * freq_hz
    plant = signal.StateSpace(
        [[0.0, 1.0], [-w * w, -2.0 * zeta * w]], [[0.0], [-1.0]], [[-w * w, -2.0 * zeta * w]], 0.0
    )
    u_dd = np.gradient(np.gradient(u, t_s), t_s)
    _, y, _ = signal.lsim(plant, u_dd, t_s)
    return y


@dataclass
class LinearDemoRow:
    method: str
    delay_s: float
    residual_vibration_m_s2: float
    reduction_percent: float
    peak_jerk_rad_s3: float


def run_linear_demo(
    out_dir: str | Path = "out/demo-linear", quick: bool = False
) -> list[LinearDemoRow]:
    """Run the example, print a table, write ``results.json`` and a figure to ``out_dir``."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    q0, q1 = np.zeros(1), np.array([np.pi / 2 if not quick else 0.5])
    traj = double_s(q0, q1, dt_s=DT_S, t_pre_s=0.1, t_post_s=1.0 if quick else 2.0)
    modes = [(2 * np.pi * f, z) for f, z in PLANT_MODES_HZ]
    shaper = tvist.TvShaper(tvist.ConstantModes(modes), dt_s=DT_S, n_dof=1, shaper="zv")
    shaped = shaper.shape(traj.q)
    delay_s = shaper.delay_s

    rows, traces = [], {}
    for method, ref, t_stop in (
        ("unshaped", traj.q, traj.t_motion_end_s),
        ("fd-tvist zv", shaped, traj.t_motion_end_s + delay_s),
    ):
        acc = sum(mode_acceleration(traj.t_s, ref[:, 0], f, z) for f, z in PLANT_MODES_HZ)
        rv = residual_vibration(traj.t_s, acc, t_stop)
        traces[method] = acc
        rows.append((method, ref, rv.amplitude))
    base = rows[0][2]
    table = [
        LinearDemoRow(
            method=m,
            delay_s=0.0 if m == "unshaped" else delay_s,
            residual_vibration_m_s2=amp,
            reduction_percent=100.0 * (1.0 - amp / base),
            peak_jerk_rad_s3=peak_jerk(ref, DT_S),
        )
        for m, ref, amp in rows
    ]
    print(f"{'method':<14}{'delay [ms]':>12}{'RV':>12}{'reduction':>12}{'peak jerk':>12}")
    for r in table:
        print(
            f"{r.method:<14}{1e3 * r.delay_s:>12.1f}{r.residual_vibration_m_s2:>12.4g}"
            f"{r.reduction_percent:>11.1f}%{r.peak_jerk_rad_s3:>12.1f}"
        )
    (out / "results.json").write_text(json.dumps([asdict(r) for r in table], indent=2))
    from tvist.experiments.plots import plot_traces

    plot_traces(
        traj.t_s,
        traces,
        out / "linear_demo_acceleration.png",
        ylabel="plant acceleration [rad/s²]",
        title="Two-mode linear plant: unshaped vs FD-TVIST (ZV, 2 modes)",
    )
    return table
