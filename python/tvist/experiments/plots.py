"""Figures of the experiments' reports, and :func:`make_figures`, those of the UR5e experiment.
Every figure is a standalone :func:`tvist.figures.new_figure` saved to a file, so plotting
never selects or changes the global pyplot backend (inline plots in Jupyter keep working)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from tvist.experiments.experiment import DemoResult, MotionRun
from tvist.experiments.measure import damped_frequency_hz
from tvist.figures import new_figure


def plot_traces(
    t_s: np.ndarray,
    traces: dict[str, np.ndarray],
    path: str | Path,
    *,
    ylabel: str,
    title: str,
) -> Path:
    """One labelled line per trace against time; saved as PNG at ``path``."""
    fig = new_figure(figsize=(9, 4))
    ax = fig.subplots()
    for label, y in traces.items():
        ax.plot(t_s, y, label=label, lw=1.0)
    ax.set_xlabel("time [s]")
    ax.set_ylabel(ylabel)
    ax.set_title(title)
    ax.grid(True, alpha=0.3)
    ax.legend()
    fig.savefig(path, dpi=120)
    return Path(path)


#: Line colours of the methods in the experiment figures, in row order.
#: The marker lines of the spectra use gray, olive and cyan, so those are left out here. The
#: colours repeat (``_colours``) when there are more rows than colours: no row is dropped.
_COLOURS = (
    "black",
    "tab:blue",
    "tab:orange",
    "tab:green",
    "tab:red",
    "tab:purple",
    "tab:brown",
    "tab:pink",
    "goldenrod",
    "navy",
    "lime",
)


def _colours(start: int = 0):
    """The row colours, endlessly (zip with the rows: every row gets one)."""
    import itertools

    return itertools.islice(itertools.cycle(_COLOURS), start, None)


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
    fig = new_figure(figsize=(10, 7.5))
    top, bottom = fig.subplots(2, 1)
    floor = np.inf
    for (label, (mag, t_stop, rv, decay)), colour in zip(traces.items(), _colours(), strict=False):
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
    top.set_xlabel(
        "time from the planned stop t_b (where the unshaped reference stops) [s];  "
        "dotted lines: each run's own stop"
    )
    top.set_ylabel("|tool acceleration| [m/s²]")
    top.set_title(title)
    top.grid(True, alpha=0.3)
    top.legend(loc="upper left", fontsize=9)
    bottom.set_xlabel("time since the run's own stop (t_b unshaped, t_b* shaped) [s]")
    bottom.set_ylabel("|tool acceleration| [m/s²] (log)")
    bottom.set_title("After the stop: dot = residual vibration, dashed = fitted decay envelope")
    bottom.set_ylim(max(1e-5, 0.05 * floor), None)
    bottom.grid(True, which="both", alpha=0.3)
    bottom.legend(loc="upper right", fontsize=9)
    fig.savefig(path, dpi=120)
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
    fig = new_figure(figsize=(13, 3.2 * len(panels) + 0.6))
    axes = fig.subplots(len(panels), 1)
    axes = np.atleast_1d(axes)
    for ax, (panel_title, spectra, marks) in zip(axes, panels, strict=True):
        peak, lowest_peak = 0.0, np.inf
        for (label, (freq, energy)), colour in zip(spectra.items(), _colours(), strict=False):
            band = (freq > 0.0) & (freq <= f_max_hz)
            ax.semilogy(freq[band], energy[band], color=colour, lw=1.1, label=label)
            peak = max(peak, float(energy[band].max()))
            if energy[band].max() > 0.0:
                lowest_peak = min(lowest_peak, float(energy[band].max()))
        for (mark_label, freqs), style, mark_colour in zip(
            marks.items(), ("--", ":", "-."), ("tab:gray", "tab:olive", "tab:cyan"), strict=False
        ):
            for i, f in enumerate(freqs):
                ax.axvline(
                    f, color=mark_colour, ls=style, lw=1.2, label=mark_label if i == 0 else None
                )
        ax.set_xlim(0.0, f_max_hz)
        # Down to two decades below the weakest curve's peak, so the best methods show their
        # whole spectrum instead of a stub (at most 14 decades below the strongest).
        ax.set_ylim(max(min(peak * 1e-7, lowest_peak * 1e-2), peak * 1e-14), peak * 3.0)
        ax.set_title(panel_title)
        ax.set_xlabel("frequency [Hz]")
        ax.set_ylabel("energy E [(m/s²)²]")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8)
    fig.suptitle(title)
    fig.savefig(path, dpi=120)
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
    fig = new_figure(figsize=(12, 9))
    axes = fig.subplots(3, 1, sharex=True)
    axes[0].plot(t_s, inertia_kg_m2[:, 0], color="tab:blue", label="J_0 (base axis)")
    axes[0].plot(t_s, inertia_kg_m2[:, 1], color="tab:red", ls="--", label="J_1 (shoulder axis)")
    axes[0].set_ylabel("inertia [kg m²]")
    axes[0].set_title(title)
    mode_names, styles = ("base", "shoulder"), ("-", "--")
    for (label, track), colour in zip(modes.items(), _colours(), strict=False):
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
    return Path(path)


def plot_tip_acceleration(
    t_s: np.ndarray,
    runs: dict[str, tuple[np.ndarray, np.ndarray]],
    stops_s: dict[str, float],
    t_planned_stop_s: float,
    path: str | Path,
    *,
    title: str,
) -> Path:
    """One panel per method: measured tip acceleration and the reference's acceleration
    (like the zero-delay paper's Fig. 12).

    Parameters
    ----------
    t_s
        Sample times, s.
    runs
        ``label -> (tip acceleration (n_samples,) m/s², reference acceleration (n_samples,)
        m/s²)``.
    stops_s
        ``label -> when that reference stops``, s.
    t_planned_stop_s
        When the planned (unshaped) move stops, s.
    """
    fig = new_figure(figsize=(10, 2.2 * len(runs) + 0.6))
    axes = np.atleast_1d(fig.subplots(len(runs), 1, sharex=True, sharey=True))
    t_end = max(stops_s.values()) + 2.0
    shown = t_s <= t_end
    for ax, (label, (tip, ref)), colour in zip(axes, runs.items(), _colours(), strict=False):
        ax.plot(t_s[shown], ref[shown], color="0.6", lw=1.0, label="reference acceleration")
        ax.plot(t_s[shown], tip[shown], color=colour, lw=1.1, label="tip acceleration (measured)")
        ax.axvline(t_planned_stop_s, color="k", ls=":", lw=1.0, label="planned stop")
        if stops_s[label] > t_planned_stop_s + 1e-9:
            ax.axvline(stops_s[label], color=colour, ls="--", lw=1.0, label="this reference stops")
        ax.set_title(label, fontsize=10)
        ax.set_ylabel("a_x [m/s²]")
        ax.grid(True, alpha=0.3)
        ax.legend(loc="upper right", fontsize=8)
    axes[-1].set_xlabel("time [s]")
    fig.suptitle(title)
    fig.savefig(path, dpi=120)
    return Path(path)


def plot_velocity_references(
    t_s: np.ndarray,
    velocities: dict[str, np.ndarray],
    t_planned_stop_s: float,
    path: str | Path,
    *,
    title: str,
    ylabel: str,
) -> Path:
    """Velocity references of several methods on one axis (like the zero-delay paper's
    Fig. 13); ``velocities`` maps a label to ``(n_samples,)`` in the unit of ``ylabel``."""
    fig = new_figure(figsize=(9, 4.5))
    ax = fig.subplots()
    moving = np.flatnonzero(np.any(np.abs(np.array(list(velocities.values()))) > 1e-9, axis=0))
    lo = t_s[max(moving[0] - 25, 0)] if moving.size else t_s[0]
    hi = t_s[min(moving[-1] + 50, len(t_s) - 1)] if moving.size else t_s[-1]
    shown = (t_s >= lo) & (t_s <= hi)
    for (label, v), colour in zip(velocities.items(), _colours(), strict=False):
        ax.plot(t_s[shown], v[shown], color=colour, lw=1.3, label=label)
    ax.axvline(t_planned_stop_s, color="k", ls=":", lw=1.0, label="planned stop")
    ax.set_xlabel("time [s]")
    ax.set_ylabel(ylabel)
    ax.set_title(title)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=9)
    fig.savefig(path, dpi=120)
    return Path(path)


def plot_path_deviation(
    t_s: np.ndarray,
    deviations_m: dict[str, np.ndarray],
    path: str | Path,
    *,
    title: str,
) -> Path:
    """Distance of shaped flange paths from the planned path against time, µm (log scale);
    distances below 0.1 nm (the inverse-kinematics tolerance) are drawn at 0.1 nm."""
    fig = new_figure(figsize=(9, 4))
    ax = fig.subplots()
    off = np.flatnonzero(np.max(np.array(list(deviations_m.values())), axis=0) > 0.0)
    shown = (
        (t_s >= t_s[max(off[0] - 50, 0)]) & (t_s <= t_s[min(off[-1] + 100, len(t_s) - 1)])
        if off.size
        else np.ones(len(t_s), dtype=bool)
    )
    for (label, dev), colour in zip(deviations_m.items(), _colours(1), strict=False):
        ax.semilogy(
            t_s[shown],
            np.maximum(1e6 * dev[shown], 1e-4),
            color=colour,
            lw=1.2,
            label=f"{label}: max {np.max(dev):.2g} m",
        )
    ax.set_xlabel("time [s]")
    ax.set_ylabel("distance from the planned path [µm]\n(floor: 0.1 nm)")
    ax.set_title(title)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=9)
    fig.savefig(path, dpi=120)
    return Path(path)


def make_figures(result: DemoResult, out: Path) -> dict[str, list[Path]]:
    """Write the figures; returns ``{"acceleration": [...], "spectra": [...], "modes": [...]}``."""
    figures: dict[str, list[Path]] = {"acceleration": [], "spectra": [], "modes": []}
    panels = []
    for motion in result.motions:
        traces = {
            r.method.label: (
                np.linalg.norm(r.psi, axis=1),
                r.t_stop_s,
                r.residual.amplitude,
                r.residual.decay_rate_1_s,
            )
            for r in motion.runs
        }
        name = motion.motion.name.replace("->", " → ")
        figures["acceleration"].append(
            plot_stop_aligned_acceleration(
                motion.t_s,
                traces,
                motion.t_stop_unshaped_s,
                out / f"acceleration_{motion.motion.slug}.png",
                title=f"{name}: gravity-free tool acceleration |ψ|, 5 kg payload (simulated UR5e)",
            )
        )
        spectra = {r.method.label: (r.spectrum.freq_hz, r.spectrum.energy) for r in motion.runs}
        marks = {
            f"twin (true): damped f_d at {motion.motion.end}": [
                damped_frequency_hz(w, z) for w, z in motion.true_end_modes
            ]
        }
        for label, modes in motion.map_end_modes.items():
            marks[f"{label}: damped f_d at {motion.motion.end}"] = [
                damped_frequency_hz(w, z) for w, z in modes
            ]
        panels.append((f"{name}: residual vibration after the stop", spectra, marks))
        traj_start = float(motion.tracks.t_s[0])
        figures["modes"].append(
            plot_mode_tracks(
                motion.tracks.t_s - traj_start,
                motion.tracks.inertia_kg_m2,
                motion.tracks.modes,
                out / f"modes_{motion.motion.slug}.png",
                title=f"{name}: inertias and modes along the planned move",
                t_marks_s={
                    "planned move starts": _move_start(motion) - traj_start,
                    "planned move stops (t_b)": motion.t_stop_unshaped_s - traj_start,
                },
            )
        )
    window = result.config["spectrum_window_s"]
    figures["spectra"].append(
        plot_energy_spectra(
            panels,
            out / "spectra.png",
            title=f"Energy spectra (eq. 56) of the gravity-free tool acceleration, {window:g} s "
            "after each stop",
        )
    )
    return figures


def _move_start(motion: MotionRun) -> float:
    q = motion.runs[0].q
    moving = np.flatnonzero(np.any(q != q[0], axis=1))
    return float(motion.t_s[moving[0] - 1]) if moving.size else float(motion.t_s[0])
