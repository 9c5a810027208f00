"""Figures for reports. matplotlib is imported lazily and uses the non-interactive Agg backend."""

from __future__ import annotations

from pathlib import Path

import numpy as np


def _pyplot():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def plot_traces(
    t_s: np.ndarray,
    traces: dict[str, np.ndarray],
    path: str | Path,
    *,
    ylabel: str,
    title: str,
) -> Path:
    """One labelled line per trace against time; saved as PNG at ``path``."""
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(9, 4), constrained_layout=True)
    for label, y in traces.items():
        ax.plot(t_s, y, label=label, lw=1.0)
    ax.set_xlabel("time [s]")
    ax.set_ylabel(ylabel)
    ax.set_title(title)
    ax.grid(True, alpha=0.3)
    ax.legend()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return Path(path)
