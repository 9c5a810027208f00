"""The modified-ZTDIS paper's benchmark: unshaped vs conventional IS vs ZTDIS vs modified ZTDIS.

Setup (Zhao and Tomizuka, experiment section): a flexible payload with one mode at 2.55 Hz,
ζ = 0.04, a ZVD shaper (Δ_n = 0.3925 s) and a rapid rest-to-rest move of T = 0.734 s. The
paper's own reference is only shown as a figure, so two standard references of length T are
used: a minimum-jerk quintic and a trapezoidal velocity profile.

Plant. The payload tip ``x`` hangs on the commanded (stiff, position-controlled) flange ``u``
through a spring-damper: ``x'' = ω²(u − x) + 2ζω(u' − x')``, i.e.
``X/U = (2ζωs + ω²)/(s² + 2ζωs + ω²)``. Its deflection ``e = x − u`` obeys
``e'' + 2ζωe' + ω²e = −u''``: the paper's second-order plant (eq. 1) driven by the reference
acceleration, which is how the tip accelerometer sees it. Both views have the same poles, so
residual vibration (the deflection after the reference has stopped) is the same quantity. The
plant is simulated with :func:`scipy.signal.lsim` on the piecewise-linear reference.

Metrics per method: completion time of the reference, residual vibration (peak deflection
after completion) absolute and relative to the unshaped move, the same with the mode 10 %
off (model error), peak velocity, acceleration and jerk of the sampled reference (finite
differences: for references with acceleration steps the jerk is ~Δa/dt and grows with the
control rate), and the number of velocity peaks.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from tvist import _core
from tvist.analysis import metrics
from tvist.ztdis import zero_delay

__all__ = [
    "METHOD_LABELS",
    "Benchmark",
    "MethodMetrics",
    "count_velocity_peaks",
    "format_table",
    "plot_benchmark",
    "reference_move",
    "run_benchmark",
    "simulate_tip",
]

#: Methods in display order with their labels.
METHOD_LABELS: dict[str, str] = {
    "unshaped": "unshaped",
    "is": "conventional IS",
    "ztdis": "ZTDIS",
    "modified": "modified ZTDIS",
}

#: Velocity peaks count only with a prominence of at least this fraction of the peak speed
#: (ignores rounding ripple; any visible second hump in a plot is far above 1 %).
PEAK_PROMINENCE = 0.01

#: The reference has "completed" once it stays within this fraction of the move distance of
#: its end pose (far below any residual vibration of interest, above the filters' rounding).
COMPLETION_TOLERANCE = 1e-6

#: Simulated time after a reference completes, s: several periods of the 2.55 Hz mode, which
#: is where the residual peak is (it only decays afterwards).
SETTLE_WINDOW_S = 3.0


@dataclass(frozen=True)
class MethodMetrics:
    """What one method does to the benchmark move (units of the move: m or rad)."""

    completion_s: float
    residual: float
    residual_ratio: float
    residual_ratio_low: float
    residual_ratio_high: float
    peak_velocity: float
    peak_acceleration: float
    peak_jerk: float
    velocity_peaks: int


@dataclass(frozen=True)
class Benchmark:
    """One run of the benchmark: parameters, time scales, metrics and the signals to plot."""

    reference: str
    dt_s: float
    freq_hz: float
    zeta: float
    move_s: float
    distance: float
    shaper: str
    model_error: float
    rest_s: tuple[float, float]
    delay_s: float
    alpha: float
    alpha_modified: float
    metrics: dict[str, MethodMetrics]
    t_s: np.ndarray = field(repr=False)
    references: dict[str, np.ndarray] = field(repr=False)
    tip_velocity: dict[str, np.ndarray] = field(repr=False)


def reference_move(kind: str, move_s: float, dt_s: float, distance: float) -> np.ndarray:
    """A rest-to-rest move of length ``move_s`` over ``distance``, shape ``(n_samples,)``.

    ``"min_jerk"``: quintic. ``"trapezoid"``: trapezoidal velocity, a quarter of the move
    accelerating and a quarter braking (peak speed ``distance / (0.75 move_s)``).
    """
    from tvist.trajectory import min_jerk, trapezoid

    if kind == "min_jerk":
        traj = min_jerk([0.0], [distance], move_s, dt_s)
    elif kind == "trapezoid":
        t_acc = 0.25 * move_s
        v_peak = distance / (move_s - t_acc)
        traj = trapezoid([0.0], [distance], v_max=v_peak, a_max=v_peak / t_acc, dt_s=dt_s)
    else:
        raise ValueError(f"unknown reference {kind!r}; expected 'min_jerk' or 'trapezoid'")
    q = np.array(traj.q[:, 0])
    expected = int(round(move_s / dt_s)) + 1
    if q.shape[0] != expected:
        raise ValueError(
            f"move_s = {move_s} s is not a whole number of samples of dt_s = {dt_s} s "
            f"({q.shape[0]} samples generated, {expected} expected)"
        )
    return q


def simulate_tip(
    u: np.ndarray, dt_s: float, wn_rad_s: float, zeta: float
) -> tuple[np.ndarray, np.ndarray]:
    """Tip position and velocity of ``x'' = ω²(u − x) + 2ζω(u' − x')``, at rest at ``u[0]``.

    ``u`` is sampled every ``dt_s`` and linearly interpolated between samples.
    """
    from scipy import signal

    w, z = wn_rad_s, zeta
    den = [1.0, 2.0 * z * w, w * w]
    t = dt_s * np.arange(u.shape[0])
    u0 = u - u[0]
    _, x, _ = signal.lsim(([2.0 * z * w, w * w], den), u0, t)
    _, xd, _ = signal.lsim(([2.0 * z * w, w * w, 0.0], den), u0, t)
    return x + u[0], xd


def count_velocity_peaks(v: np.ndarray) -> int:
    """Humps of the speed ``|v|`` rising and falling by :data:`PEAK_PROMINENCE` of its top."""
    return int(metrics.count_velocity_peaks(v, rel_threshold=PEAK_PROMINENCE))


def _completion_s(q: np.ndarray, dt_s: float, distance: float) -> float:
    away = np.nonzero(np.abs(q - q[-1]) > COMPLETION_TOLERANCE * abs(distance))[0]
    return 0.0 if away.size == 0 else float((away[-1] + 1) * dt_s)


def _residual(q: np.ndarray, dt_s: float, wn_rad_s: float, zeta: float, done_s: float) -> float:
    x, _ = simulate_tip(q, dt_s, wn_rad_s, zeta)
    k = int(round(done_s / dt_s))
    return float(np.max(np.abs(x[k:] - q[-1])))


def run_benchmark(
    reference: str = "min_jerk",
    *,
    dt_s: float,
    freq_hz: float = 2.55,
    zeta: float = 0.04,
    move_s: float = 0.734,
    distance: float = 0.3,
    shaper: str = "zvd",
    model_error: float = 0.1,
    rest_s: tuple[float, float] = (0.0, 0.0),
) -> Benchmark:
    """Run the four methods on one reference and measure them on the simulated payload.

    Parameters
    ----------
    reference
        ``"min_jerk"`` or ``"trapezoid"`` (see :func:`reference_move`).
    dt_s
        Control period, s.
    freq_hz, zeta
        The payload mode the shapers are designed for (and the exact plant).
    move_s
        Length ``T`` of the move, s (a whole number of samples).
    distance
        Length of the move (m or rad); the metrics scale with it, the ratios do not.
    shaper
        Registry shaper.
    model_error
        Relative frequency error of the plant for the robustness columns (``±model_error``).
    rest_s
        Rest before and after the move, s, as a planner pads it. The zero-delay methods
        compress only the move (:func:`tvist.zero_delay`); completion times are counted from
        the start of the move.
    """
    wn = 2.0 * np.pi * freq_hz
    modes = [(wn, zeta)]
    q = reference_move(reference, move_s, dt_s, distance)
    before, after = (int(round(max(0.0, float(r)) / dt_s)) for r in rest_s)
    q = np.concatenate([np.full(before, q[0]), q, np.full(after, q[-1])])
    n = q.shape[0]
    delay_s = _core.design_shaper(shaper, wn, zeta).duration_s

    # Conventional shaping: the same move, extended by the delay and shaped.
    n_is = n + int(np.ceil(delay_s / dt_s)) + 1
    padded = np.concatenate([q, np.full(n_is - n, q[-1])])
    conventional = _core.TvShaper(
        _core.ConstantModes(modes), dt_s, 1, shaper=shaper, interp="cubic"
    )
    conventional.reset(np.array([q[0]]))
    shaped_is = conventional.shape(padded[:, None])[:, 0]

    ztdis = zero_delay(q, dt_s, modes, shaper, method="ztdis")
    modified = zero_delay(q, dt_s, modes, shaper, method="modified")
    refs = {"unshaped": q, "is": shaped_is, "ztdis": ztdis.Q, "modified": modified.Q}

    # Every reference is simulated on one common grid, long enough to settle after the last.
    n_total = n_is + int(round(SETTLE_WINDOW_S / dt_s))
    refs = {k: np.concatenate([r, np.full(n_total - r.shape[0], r[-1])]) for k, r in refs.items()}

    metrics: dict[str, MethodMetrics] = {}
    tip_velocity: dict[str, np.ndarray] = {}
    base: dict[str, float] = {}
    for key, r in refs.items():
        done_in_array = _completion_s(r, dt_s, distance)
        done = done_in_array - before * dt_s  # counted from the start of the move
        residuals = [
            _residual(r, dt_s, wn * f, zeta, done_in_array)
            for f in (1.0, 1.0 - model_error, 1.0 + model_error)
        ]
        if key == "unshaped":
            base = {"exact": residuals[0], "low": residuals[1], "high": residuals[2]}
        _, xd = simulate_tip(r, dt_s, wn, zeta)
        tip_velocity[key] = xd
        v = np.gradient(r, dt_s)
        metrics[key] = MethodMetrics(
            completion_s=done,
            residual=residuals[0],
            residual_ratio=residuals[0] / base["exact"],
            residual_ratio_low=residuals[1] / base["low"],
            residual_ratio_high=residuals[2] / base["high"],
            peak_velocity=float(np.max(np.abs(v))),
            peak_acceleration=float(np.max(np.abs(np.diff(r, 2)))) / dt_s**2,
            peak_jerk=float(np.max(np.abs(np.diff(r, 3)))) / dt_s**3,
            velocity_peaks=count_velocity_peaks(v),
        )
    return Benchmark(
        reference=reference,
        dt_s=dt_s,
        freq_hz=freq_hz,
        zeta=zeta,
        move_s=move_s,
        distance=distance,
        shaper=shaper,
        model_error=model_error,
        rest_s=(before * dt_s, after * dt_s),
        delay_s=delay_s,
        alpha=ztdis.alpha,
        alpha_modified=modified.alpha,
        metrics=metrics,
        t_s=dt_s * np.arange(n_total),
        references=refs,
        tip_velocity=tip_velocity,
    )


def format_table(bench: Benchmark) -> str:
    """The metrics of one run as a Markdown table."""
    e = 100.0 * bench.model_error
    lines = [
        f"Reference `{bench.reference}`, T = {bench.move_s} s, distance {bench.distance}, "
        f"{bench.freq_hz} Hz / zeta {bench.zeta}, {bench.shaper.upper()} "
        f"(delay {bench.delay_s:.4f} s), alpha = {bench.alpha:.4f}, "
        f"alpha' = {bench.alpha_modified:.4f}, dt = {bench.dt_s} s; unshaped residual "
        f"{bench.metrics['unshaped'].residual:.3g} (exact plant), residual = peak tip "
        f"deflection after the reference is done (within {COMPLETION_TOLERANCE:g} of the distance)"
        + (
            f"; rest padding {bench.rest_s[0]:g} s before / {bench.rest_s[1]:g} s after the move, "
            "done counted from the move's start"
            if any(bench.rest_s)
            else ""
        ),
        "",
        f"| method | done [s] | residual [% unshaped] | at -{e:.0f} % / +{e:.0f} % freq "
        "| peak v | peak a | peak jerk | v peaks |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for key, label in METHOD_LABELS.items():
        m = bench.metrics[key]
        lines.append(
            f"| {label} | {m.completion_s:.3f} | {100 * m.residual_ratio:.3g} "
            f"| {100 * m.residual_ratio_low:.3g} / {100 * m.residual_ratio_high:.3g} "
            f"| {m.peak_velocity:.3g} | {m.peak_acceleration:.3g} | {m.peak_jerk:.3g} "
            f"| {m.velocity_peaks} |"
        )
    return "\n".join(lines)


def plot_benchmark(benches: list[Benchmark], path: str | Path) -> Path:
    """Velocity references (top) and payload tip velocities (bottom), one column per run.

    Like the paper's Fig. 13, with the unshaped and conventionally shaped moves added.
    """
    from tvist.figures import new_figure

    fig = new_figure(figsize=(6 * len(benches), 6), layout="tight")
    axes = fig.subplots(2, len(benches), sharex=True, squeeze=False)
    for col, bench in enumerate(benches):
        t = bench.t_s
        t_end = bench.rest_s[0] + bench.metrics["is"].completion_s + 1.0
        keep = t <= t_end
        for key, label in METHOD_LABELS.items():
            v = np.gradient(bench.references[key], bench.dt_s)
            axes[0, col].plot(t[keep], v[keep], label=label, lw=1.2)
            axes[1, col].plot(t[keep], bench.tip_velocity[key][keep], label=label, lw=1.0)
        for ax in axes[:, col]:
            ax.axvline(bench.rest_s[0] + bench.move_s, color="k", ls=":", lw=0.8)
            ax.grid(True, alpha=0.3)
        axes[0, col].set_title(
            f"{bench.reference}: T = {bench.move_s} s, {bench.freq_hz} Hz, {bench.shaper.upper()}"
        )
        axes[0, col].set_ylabel("reference velocity [rad/s]")
        axes[1, col].set_ylabel("payload tip velocity [rad/s]")
        axes[1, col].set_xlabel("time [s]")
    axes[0, 0].legend(fontsize=8)
    out = Path(path)
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=120)
    return out
