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


#: Line colours of the methods in the experiment figures, in row order.
_COLOURS = ("black", "tab:blue", "tab:orange", "tab:green", "tab:red", "tab:purple", "tab:brown")


def plot_stop_aligned_acceleration(
    t_s: np.ndarray,
    traces: dict[str, tuple[np.ndarray, float, float, float]],
    t_ref_s: float,
    path: str | Path,
    *,
    title: str,
    before_s: float = 0.8,
    after_s: float = 1.2,
) -> Path:
    """Tool acceleration of several runs of one motion around their stops (like paper Fig. 35).

    Top: ``|ψ|`` against time from the reference stop ``t_ref_s`` (the unshaped ``t_b``), with
    every run's own stop marked, so the delay shows. Bottom: the same on a log scale against
    time since each run's own stop, with the residual vibration (extrapolated amplitude at
    the stop) as a dot and its decay envelope as a dashed line.

    Parameters
    ----------
    t_s
        Sample times, s, ``(n_samples,)``.
    traces
        ``label -> (magnitude (n_samples,) m/s², t_stop_s, rv_amplitude_m_s2, decay_rate_1_s)``;
        a NaN decay rate draws no envelope.
    t_ref_s
        Time origin of the top panel (the unshaped stop), s.
    path
        Output PNG.
    title
        Figure title.
    before_s, after_s
        Time shown before and after the stops, s.
    """
    plt = _pyplot()
    fig, (top, bottom) = plt.subplots(2, 1, figsize=(10, 7.5), constrained_layout=True)
    floor = np.inf
    for (label, (mag, t_stop, rv, decay)), colour in zip(traces.items(), _COLOURS, strict=False):
        width = 1.4 if label == next(iter(traces)) else 1.1
        x = t_s - t_ref_s
        shown = (x >= -before_s) & (x <= after_s + 0.2)
        top.plot(x[shown], mag[shown], color=colour, lw=width, label=label)
        top.axvline(t_stop - t_ref_s, color=colour, ls=":", lw=1.0)
        since = t_s - t_stop
        post = (since >= 0.0) & (since <= after_s)
        bottom.semilogy(since[post], np.maximum(mag[post], 1e-9), color=colour, lw=width)
        bottom.plot([0.0], [rv], "o", color=colour, ms=6, label=f"{label}: RV {rv:.3g} m/s²")
        if np.isfinite(decay):
            tau = np.linspace(0.0, after_s, 200)
            bottom.plot(tau, rv * np.exp(-decay * tau), color=colour, ls="--", lw=0.9)
        floor = min(floor, rv)
    top.set_xlabel("time from the unshaped stop t_b [s]  (dotted lines: each run's stop)")
    top.set_ylabel("|tool acceleration| [m/s²]")
    top.set_title(title)
    top.grid(True, alpha=0.3)
    top.legend(loc="upper left", fontsize=9)
    bottom.set_xlabel("time since the run's own stop (t_b or t_b*) [s]")
    bottom.set_ylabel("|tool acceleration| [m/s²] (log)")
    bottom.set_title("After the stop: dot = residual vibration, dashed = fitted decay envelope")
    bottom.set_ylim(max(1e-5, 0.05 * floor), None)
    bottom.grid(True, which="both", alpha=0.3)
    bottom.legend(loc="upper right", fontsize=9)
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return Path(path)


def plot_energy_spectra(
    panels: list[tuple[str, dict[str, tuple[np.ndarray, np.ndarray]], dict[str, list[float]]]],
    path: str | Path,
    *,
    title: str,
    f_max_hz: float = 60.0,
) -> Path:
    """Residual vibration energy spectra (eq. 56), one panel per motion (like paper Fig. 36).

    Parameters
    ----------
    panels
        ``(panel title, {label: (freq_hz, energy)}, {marker label: [freq_hz, ...]})`` per
        panel. The first marker set is drawn dashed, the others dotted.
    path
        Output PNG.
    title
        Figure title.
    f_max_hz
        Upper end of the frequency axis, Hz.
    """
    plt = _pyplot()
    fig, axes = plt.subplots(
        len(panels), 1, figsize=(13, 3.2 * len(panels) + 0.6), constrained_layout=True
    )
    axes = np.atleast_1d(axes)
    for ax, (panel_title, spectra, marks) in zip(axes, panels, strict=True):
        peak = 0.0
        for (label, (freq, energy)), colour in zip(spectra.items(), _COLOURS, strict=False):
            band = (freq > 0.0) & (freq <= f_max_hz)
            ax.semilogy(freq[band], energy[band], color=colour, lw=1.1, label=label)
            peak = max(peak, float(energy[band].max()))
        for (mark_label, freqs), style, mark_colour in zip(
            marks.items(), ("--", ":", "-."), ("tab:gray", "tab:olive", "tab:cyan"), strict=False
        ):
            for i, f in enumerate(freqs):
                ax.axvline(
                    f, color=mark_colour, ls=style, lw=1.2, label=mark_label if i == 0 else None
                )
        ax.set_xlim(0.0, f_max_hz)
        ax.set_ylim(peak * 1e-7, peak * 3.0)
        ax.set_title(panel_title)
        ax.set_xlabel("frequency [Hz]")
        ax.set_ylabel("energy E [(m/s²)²]")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8)
    fig.suptitle(title)
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return Path(path)


def plot_mode_tracks(
    t_s: np.ndarray,
    inertia_kg_m2: np.ndarray,
    modes: dict[str, np.ndarray],
    path: str | Path,
    *,
    title: str,
    t_marks_s: dict[str, float] | None = None,
) -> Path:
    """Inertias, damped frequencies and damping ratios along a motion (like Figs. 32-34).

    Parameters
    ----------
    t_s
        Sample times, s, ``(m,)``.
    inertia_kg_m2
        ``J_0, J_1`` per sample, kg m², ``(m, 2)``.
    modes
        ``source label -> (m, n_modes, 2)`` of ``(f_d_hz, zeta)``, base mode first.
    path
        Output PNG.
    title
        Figure title.
    t_marks_s
        Vertical markers ``label -> time`` (start and end of the move), s.
    """
    plt = _pyplot()
    fig, axes = plt.subplots(3, 1, figsize=(12, 9), sharex=True, constrained_layout=True)
    axes[0].plot(t_s, inertia_kg_m2[:, 0], color="tab:blue", label="J_0 (base axis)")
    axes[0].plot(t_s, inertia_kg_m2[:, 1], color="tab:red", ls="--", label="J_1 (shoulder axis)")
    axes[0].set_ylabel("inertia [kg m²]")
    axes[0].set_title(title)
    mode_names, styles = ("base", "shoulder"), ("-", "--")
    for (label, track), colour in zip(modes.items(), _COLOURS, strict=False):
        for i in range(track.shape[1]):
            name = mode_names[i] if i < len(mode_names) else f"mode {i}"
            style = styles[i % len(styles)]
            axes[1].plot(t_s, track[:, i, 0], color=colour, ls=style, label=f"{label}: {name}")
            axes[2].plot(t_s, track[:, i, 1], color=colour, ls=style, label=f"{label}: {name}")
    axes[1].set_ylabel("damped frequency f_d [Hz]")
    axes[2].set_ylabel("damping ratio ζ [-]")
    axes[2].set_xlabel("time [s]")
    for ax in axes:
        marks = (t_marks_s or {}).items()
        for (mark, t), style in zip(marks, (":", "-.", "--"), strict=False):
            ax.axvline(t, color="gray", ls=style, lw=1.1, label=mark if ax is axes[0] else None)
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return Path(path)
