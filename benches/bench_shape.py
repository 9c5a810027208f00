"""Benchmark: TvShaper.shape against a per-sample Python/numpy FD-TVIST, in the same run.

A 10 s, 500 Hz, 6-DOF move is shaped by the two-mode ZV FD-TVIST of the paper's UR5e modes
(Table 3, pose Q1) with linear fractional delays, once by the Rust core and once by a
straightforward Python implementation of the same algorithm (circular buffer, impulses
designed every cycle, cascade of two filters). Both run in the same interleaved rounds, the
same number of times each, timed in CPU time of this thread (so time the scheduler gives to
other processes is not counted); prints min and median ns per step of each, the median of the
per-round speedups and the largest difference between the two outputs.

Run: ``.venv/bin/python benches/bench_shape.py`` (or ``make bench``).
"""

from __future__ import annotations

import time

import numpy as np

import tvist

DT_S = 0.002
N_DOF = 6
DURATION_S = 10.0
# (wn_rad_s, zeta) of the base and shoulder modes in pose Q1 (SPEC section 3, Table 3).
MODES = [
    (2 * np.pi * 8.018 / np.sqrt(1 - 0.2645**2), 0.2645),
    (2 * np.pi * 6.909 / np.sqrt(1 - 0.3730**2), 0.3730),
]


def move(n_samples: int) -> np.ndarray:
    """Smooth multi-joint back-and-forth motion, (n_samples, N_DOF), rad."""
    t = np.arange(n_samples) * DT_S
    phase = np.arange(N_DOF)[None, :] * 0.4
    return 0.8 * np.sin(2 * np.pi * 0.3 * t[:, None] + phase) * (1 - np.exp(-t[:, None]))


class PythonZvFilter:
    """One FD-TVIST ZV filter (eq. 7) in plain Python/numpy: circular buffer, linear reads."""

    def __init__(self, n_dof: int, max_delay_s: float) -> None:
        self.capacity = int(np.ceil(max_delay_s / DT_S)) + 2
        self.buf = np.zeros((self.capacity, n_dof))
        self.head = 0
        self.started = False

    def step(self, x: np.ndarray, wn: float, zeta: float) -> np.ndarray:
        if not self.started:
            self.buf[:] = x
            self.started = True
        self.head = (self.head + 1) % self.capacity
        self.buf[self.head] = x
        k = np.exp(-zeta * np.pi / np.sqrt(1 - zeta**2))
        amplitudes = (1 / (1 + k), k / (1 + k))
        delays = (0.0, np.pi / (wn * np.sqrt(1 - zeta**2)) / DT_S)
        out = np.zeros_like(x)
        for a, d in zip(amplitudes, delays, strict=True):
            i = int(np.floor(d))
            mu = d - i
            out += a * (1 - mu) * self.buf[(self.head - i) % self.capacity]
            if mu:
                out += a * mu * self.buf[(self.head - i - 1) % self.capacity]
        return out


def shape_python(q: np.ndarray) -> np.ndarray:
    max_delay = [1.5 * tvist.shaper("zv", *m).duration_s for m in MODES]
    filters = [PythonZvFilter(q.shape[1], d) for d in max_delay]
    out = np.empty_like(q)
    for n, x in enumerate(q):
        y = x
        for f, (wn, zeta) in zip(filters, MODES, strict=True):
            y = f.step(y, wn, zeta)
        out[n] = y
    return out


ROUNDS = 15


def cpu_time_s(fn) -> float:
    t0 = time.thread_time()
    fn()
    return time.thread_time() - t0


def main() -> None:
    n = int(round(DURATION_S / DT_S))
    q = move(n)

    def rust() -> np.ndarray:
        return tvist.TvShaper(tvist.ConstantModes(MODES), DT_S, N_DOF, shaper="zv").shape(q)

    def python() -> np.ndarray:
        return shape_python(q)

    diff = float(np.abs(rust() - python()).max())
    t_rust, t_python = [], []
    for r in range(ROUNDS):
        # Alternate which side runs first in a round.
        for fn, times in [(rust, t_rust), (python, t_python)][:: 1 if r % 2 == 0 else -1]:
            times.append(cpu_time_s(fn))
    t_rust, t_python = np.array(t_rust), np.array(t_python)
    speedup = np.median(t_python / t_rust)
    print(f"move: {DURATION_S:.0f} s at {1 / DT_S:.0f} Hz, {N_DOF} DOF, 2 modes ZV, linear")
    print(f"{ROUNDS} interleaved rounds, thread CPU time per step: min / median")
    print(
        f"Rust TvShaper.shape : {t_rust.min() / n * 1e9:9.1f} / "
        f"{np.median(t_rust) / n * 1e9:9.1f} ns"
    )
    print(
        f"Python/numpy loop   : {t_python.min() / n * 1e9:9.1f} / "
        f"{np.median(t_python) / n * 1e9:9.1f} ns"
    )
    print(f"speedup (median of per-round ratios): {speedup:.0f}x")
    print(f"max |difference|    : {diff:.2e} rad")
    if diff > 1e-12:
        raise SystemExit("the two implementations disagree")


if __name__ == "__main__":
    main()
