"""The paper's section-6 experiment on the simulated flexible UR5e: shape, simulate, measure.

For every motion and every method (row) the reference is built, run on the MuJoCo twin, and
the gravity-free tool acceleration after the stop is reduced to the paper's numbers:

- **stop time**: when the sent reference stops moving (``t_b`` unshaped, ``t_b*`` shaped);
- **delay**: ``t_b* − t_b``;
- **residual vibration**: the acceleration amplitude at the stop, from the log decay of the
  peaks after it, extrapolated back to the stop;
- **reduction**: ``1 − RV / RV_unshaped`` of the same motion, %;
- **peak jerk** of the reference (third difference), rad/s³;
- **spectrum** of the acceleration after the stop (eq. 56);
- **time to settled** from the start of the move (:mod:`tvist.experiments.settle`), beside the
  move's own duration, and the same for the best "slow down instead" profile
  (:mod:`tvist.experiments.slow_down`).
"""

from __future__ import annotations

import math
import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from tvist import robots
from tvist.analysis import (
    EnergySpectrum,
    ResidualVibration,
    path_deviation,
    peak_acceleration,
    peak_jerk,
    peak_velocity,
)
from tvist.experiments.measure import (
    damped_frequency_hz,
    measure_residual,
    modes_json,
    residual_spectrum,
    stop_time_s,
    tool_acceleration,
    zv_delay_s,
)
from tvist.experiments.method_row import Method, MotionContext
from tvist.experiments.methods import default_methods
from tvist.experiments.motions import (
    A_MAX_RAD_S2,
    DT_S,
    JERK_TIME_S,
    MOTIONS,
    PAYLOAD_COM_M,
    PAYLOAD_KG,
    V_MAX_RAD_S,
    Motion,
)
from tvist.experiments.settle import (
    SettleTimes,
    flange_error_m,
    measure_settle,
    rest_flange_position,
    settle_config,
)
from tvist.experiments.slow_down import ACCEL_SCALES, JERK_TIMES_S, Candidate, SlowDown, slow_down
from tvist.sim import Twin
from tvist.trajectory import Trajectory

#: Rest after the planned move (s): room for the longest shaper delay (~0.13 s) plus the
#: spectrum window, and for the unshaped vibration to decay to ~1e-4 of its start (ζω ≈ 5/s
#: at Q1).
TAIL_S = 2.0
#: Window of the residual spectrum after each stop (s): 1.5 s gives 0.67 Hz bins.
SPECTRUM_WINDOW_S = 1.5
#: Shorter settings of the quick run (the first motion only).
QUICK_TAIL_S = 1.4
QUICK_SPECTRUM_WINDOW_S = 1.0
#: Modes along a motion are evaluated every this many samples (10 ms) for the figures ...
TRACK_STRIDE = 5
#: ... up to this long after the planned move (s); the pose does not change after it.
TRACK_AFTER_S = 0.3


@dataclass(frozen=True)
class ModeTracks:
    """Inertias and modes along the planned reference of one motion (Figs. 32-34).

    Attributes
    ----------
    t_s
        Sample times, s, ``(m,)``.
    inertia_kg_m2
        ``J_0, J_1`` of the rigid-body model with payload, ``(m, 2)``.
    modes
        Per source (``"true modes"``, a map label): ``(m, n_modes, 2)`` holding
        ``(f_d_hz, zeta)`` per mode, base first.
    """

    t_s: np.ndarray
    inertia_kg_m2: np.ndarray
    modes: dict[str, np.ndarray]


@dataclass(frozen=True)
class MethodRun:
    """One method on one motion.

    Attributes
    ----------
    method
        The row.
    q
        Reference sent to the twin, rad, ``(n_samples, 6)``.
    psi
        Gravity-free tool acceleration in flange axes, m/s², ``(n_samples, 3)``.
    t_stop_s
        When the reference stops moving, s.
    delay_s
        ``t_stop_s`` minus the unshaped stop, s.
    residual
        Residual vibration analysis at ``t_stop_s``.
    reduction_percent
        ``100 (1 − RV / RV_unshaped)``.
    peak_jerk_rad_s3
        Largest third difference of the reference over all joints, rad/s³.
    spectrum
        Energy spectrum (eq. 56) of the acceleration after the stop.
    dt_s
        Sample period of ``q`` and ``psi``, s (the arm's control period).
    path_deviation_m
        Largest distance of the reference's flange path from the planned one, m
        (:func:`tvist.analysis.path_deviation`).
    details
        How the reference was made (from :class:`~tvist.experiments.method_row.Reference`).
    settle
        Time to settled from the start of the move (:mod:`tvist.experiments.settle`).
    """

    method: Method
    q: np.ndarray
    psi: np.ndarray
    t_stop_s: float
    delay_s: float
    residual: ResidualVibration
    reduction_percent: float
    peak_jerk_rad_s3: float
    spectrum: EnergySpectrum
    dt_s: float
    details: dict[str, Any] = field(default_factory=dict)
    path_deviation_m: float = math.nan
    settle: SettleTimes | None = None

    def to_json(self) -> dict[str, Any]:
        """The row as stored in ``results.json``."""
        rv = self.residual
        return {
            "label": self.method.label,
            "delay_s": self.delay_s,
            "residual_vibration_m_s2": rv.amplitude,
            "reduction_percent": self.reduction_percent,
            "peak_jerk_rad_s3": self.peak_jerk_rad_s3,
            "peak_velocity_rad_s": peak_velocity(self.q, self.dt_s),
            "peak_acceleration_rad_s2": peak_acceleration(self.q, self.dt_s),
            "t_stop_s": self.t_stop_s,
            "path_deviation_m": self.path_deviation_m,
            "oracle": self.method.oracle,
            "settle": None if self.settle is None else self.settle.to_json(),
            "residual_fit": {
                "method": rv.method,
                "reliable": rv.reliable,
                "log_decay_amplitude_m_s2": rv.log_decay_amplitude,
                "freq_hz": rv.freq_hz,
                "zeta": rv.zeta,
                "n_peaks": rv.n_peaks,
                "note": rv.note,
            },
            "details": self.details,
        }


@dataclass(frozen=True)
class MotionRun:
    """All methods on one motion.

    Attributes
    ----------
    motion
        The motion.
    t_s
        Sample times, s.
    t_stop_unshaped_s
        When the planned move stops (``t_b``), s.
    true_end_modes
        The twin's modes at the end pose, ``[(wn_rad_s, zeta) base, shoulder]``.
    map_end_modes
        Per map row label: the map's modes at the end pose.
    runs
        One per method that applies to the motion, unshaped first.
    tracks
        Inertias and modes along the planned move.
    slow_down
        The "slow down instead" profiles of the move (``None`` if not run).
    """

    motion: Motion
    t_s: np.ndarray
    t_stop_unshaped_s: float
    true_end_modes: list[tuple[float, float]]
    map_end_modes: dict[str, list[tuple[float, float]]]
    runs: list[MethodRun]
    tracks: ModeTracks
    slow_down: SlowDown | None = None

    @property
    def analytic_zv_delay_s(self) -> float:
        """Two-mode ZV delay ``1/(2 f_d0) + 1/(2 f_d1)`` of the true modes at the end pose."""
        return zv_delay_s(self.true_end_modes)

    def run(self, key: str) -> MethodRun:
        """The run of method ``key``."""
        for r in self.runs:
            if r.method.key == key:
                return r
        raise KeyError(key)

    def to_json(self) -> dict[str, Any]:
        """The motion as stored in ``results.json``."""
        return {
            "start_pose": self.motion.start,
            "end_pose": self.motion.end,
            "t_stop_unshaped_s": self.t_stop_unshaped_s,
            "end_pose_modes": {
                "true": modes_json(self.true_end_modes),
                **{label: modes_json(m) for label, m in self.map_end_modes.items()},
            },
            "analytic_zv_delay_s": self.analytic_zv_delay_s,
            "analytic_zv_delay_map_s": {
                label: zv_delay_s(m) for label, m in self.map_end_modes.items()
            },
            "methods": {r.method.key: r.to_json() for r in self.runs},
            "slow_down": None if self.slow_down is None else self.slow_down.to_json(),
        }


@dataclass(frozen=True)
class DemoResult:
    """The whole experiment.

    Attributes
    ----------
    motions
        One :class:`MotionRun` per motion.
    config
        Settings of the run (JSON-ready).
    wall_time_s
        Wall-clock time of the simulations and measurements, s.
    identification
        Summary of the campaign behind an identified-map row, if one was run.
    """

    motions: list[MotionRun]
    config: dict[str, Any]
    wall_time_s: float
    identification: dict[str, Any] | None = None

    def to_json(self) -> dict[str, Any]:
        """The ``results.json`` document."""
        doc = {
            "config": self.config,
            "wall_time_s": self.wall_time_s,
            "motions": {m.motion.name: m.to_json() for m in self.motions},
        }
        if self.identification is not None:
            doc["identified_map"] = self.identification
        return doc


def _mode_track(modes: Sequence[tuple[float, float]]) -> list[tuple[float, float]]:
    return [(damped_frequency_hz(w, z), z) for w, z in modes]


def mode_tracks(
    traj: Trajectory, twin: Twin, robot: robots.Robot, methods: Sequence[Method]
) -> ModeTracks:
    """Inertias, true modes and every map's modes along the planned reference, from its start
    to :data:`TRACK_AFTER_S` after the move, every :data:`TRACK_STRIDE` samples."""
    t_s = np.asarray(traj.t_s)
    last = int(np.searchsorted(t_s, traj.t_motion_end_s + TRACK_AFTER_S))
    index = np.unique(np.append(np.arange(0, last, TRACK_STRIDE), last))
    q = np.ascontiguousarray(traj.q[index])
    inertia = robot.joint_inertia_many(q)[:, :2]
    modes = {"true modes": np.array([_mode_track(twin.modes(qk)) for qk in q])}
    for method in methods:
        if method.dynmap is not None:
            modes[method.label] = np.array(
                [_mode_track(method.dynmap.modes(robot, qk)) for qk in q]
            )
    return ModeTracks(t_s=t_s[index], inertia_kg_m2=inertia, modes=modes)


def run_motion(
    motion: Motion,
    methods: Sequence[Method],
    twin: Twin,
    robot: robots.Robot,
    *,
    tail_s: float = TAIL_S,
    spectrum_window_s: float = SPECTRUM_WINDOW_S,
    log: Any = None,
    with_slow_down: bool = True,
) -> MotionRun:
    """Run every method of ``methods`` that applies to ``motion`` on the twin.

    Parameters
    ----------
    motion
        The test motion.
    methods
        The rows; the first must be ``"unshaped"`` (the baseline of the reduction).
    twin, robot
        Simulated arm and the rigid-body model with the same payload.
    tail_s
        Rest after the planned move, s.
    spectrum_window_s
        Length of the spectrum window after each stop, s.
    log
        Optional ``log(text)`` for progress lines.
    with_slow_down
        Also run the "slow down instead" grid (:mod:`tvist.experiments.slow_down`).
    """
    if not methods or methods[0].key != "unshaped":
        raise ValueError("the first method must be the 'unshaped' baseline")
    traj = motion.reference(tail_s, robot.params.sample_period_s())
    t = np.asarray(traj.t_s)
    t_b = stop_time_s(t, traj.q, motion.q_end)
    tracks = mode_tracks(traj, twin, robot, methods)
    true_modes = tracks.modes["true modes"]
    # One-mode ZV delay 1/(2 f_d) along the move: sizes the callable provider's delay lines.
    max_mode_delay = float(np.max(0.5 / true_modes[:, :, 0]))
    ctx = MotionContext(motion, traj, twin, robot, max_mode_delay)
    rest_m = rest_flange_position(twin, motion.q_end)
    move_s = traj.t_motion_end_s - traj.t_motion_start_s

    runs: list[MethodRun] = []
    baseline_rv = math.nan
    for method in methods:
        if not method.applies_to(motion):
            continue
        start = time.perf_counter()
        ref = method.build(ctx)
        record = twin.run(ref.q, dt_s=traj.dt_s)
        psi = tool_acceleration(record)
        t_stop = stop_time_s(t, ref.q, motion.q_end)
        residual = measure_residual(t, psi, t_stop)
        if method.key == "unshaped":
            baseline_rv = residual.amplitude
        runs.append(
            MethodRun(
                method=method,
                q=ref.q,
                psi=psi,
                t_stop_s=t_stop,
                delay_s=t_stop - t_b,
                residual=residual,
                reduction_percent=100.0 * (1.0 - residual.amplitude / baseline_rv),
                peak_jerk_rad_s3=peak_jerk(ref.q, traj.dt_s),
                spectrum=residual_spectrum(psi, t, t_stop, spectrum_window_s, traj.dt_s),
                dt_s=traj.dt_s,
                details=ref.details,
                path_deviation_m=path_deviation(robot, traj.q, ref.q).max_m,
                settle=measure_settle(
                    t, psi, flange_error_m(record, rest_m), traj.t_motion_start_s, move_s
                ),
            )
        )
        if log is not None:
            log(
                f"{motion.name:8} {method.label:36} RV {residual.amplitude:8.4f} m/s²  "
                f"({time.perf_counter() - start:.1f} s)"
            )
    slow = None
    if with_slow_down:
        start = time.perf_counter()
        planned = Candidate(motion.jerk_time_s, 1.0, runs[0].settle)
        slow = slow_down(
            motion.q_start,
            motion.q_end,
            twin,
            rest_m,
            planned,
            v_max=motion.v_max_rad_s,
            a_max=motion.a_max_rad_s2,
            pre_s=traj.t_motion_start_s,
            tail_s=tail_s,
            dt_s=traj.dt_s,
        )
        if log is not None:
            log(
                f"{motion.name:8} {'slow down instead':36} {len(slow.candidates) - 1} profiles "
                f"({time.perf_counter() - start:.1f} s)"
            )
    # A map row's modes at the end pose: those its shaper shaped there (a frequency-ranked
    # map shapes the modes the move needs), else the map's.
    shaped_end = {r.method.label: r.details.get("end_modes") for r in runs}
    map_end = {
        m.label: shaped_end.get(m.label) or m.dynmap.modes(robot, motion.q_end)
        for m in methods
        if m.dynmap is not None and m.applies_to(motion)
    }
    return MotionRun(
        motion=motion,
        t_s=t,
        t_stop_unshaped_s=t_b,
        true_end_modes=twin.modes(motion.q_end),
        map_end_modes=map_end,
        runs=runs,
        tracks=tracks,
        slow_down=slow,
    )


def run_experiment(
    *,
    quick: bool = False,
    methods: Sequence[Method] | None = None,
    motions: Sequence[Motion] | None = None,
    log: Any = None,
    flex: Any = None,
    beams: Any = None,
    physics_dt_s: float | None = None,
) -> DemoResult:
    """Run the experiment without writing anything.

    Parameters
    ----------
    quick
        Only the first motion, with a shorter tail (for tests).
    methods
        The rows (default :func:`~tvist.experiments.methods.default_methods`), unshaped first.
    motions
        The motions (default all of :data:`~tvist.experiments.motions.MOTIONS`, or the first if
        ``quick``).
    log
        Optional ``log(text)`` for progress lines.
    flex
        The twin's :class:`~tvist.sim.FlexParams` (default: the UR5e's; e.g. a variant of
        :mod:`tvist.sim.variants`).
    beams
        The twin's bending links (:class:`~tvist.sim.beams.LinkBeams`, default none).
    physics_dt_s
        The twin's time step (default: the twin's own choice); a variant with joints stiffer
        than the default twin's needs a shorter one
        (:func:`tvist.sim.variants.variant_twin_kwargs`).
    """
    start = time.perf_counter()
    rows = list(default_methods() if methods is None else methods)
    keys = [m.key for m in rows]
    if len(set(keys)) != len(keys):
        raise ValueError(f"method keys must be unique, got {keys}")
    chosen = list(motions) if motions is not None else list(MOTIONS[:1] if quick else MOTIONS)
    tail_s = QUICK_TAIL_S if quick else TAIL_S
    window_s = QUICK_SPECTRUM_WINDOW_S if quick else SPECTRUM_WINDOW_S
    twin = Twin(
        "ur5e",
        payload_kg=PAYLOAD_KG,
        payload_com_m=PAYLOAD_COM_M,
        flex=flex,
        beams=beams,
        physics_dt_s=physics_dt_s,
    )
    robot = robots.ur5e(payload_kg=PAYLOAD_KG, payload_com_m=PAYLOAD_COM_M)
    runs = [
        run_motion(motion, rows, twin, robot, tail_s=tail_s, spectrum_window_s=window_s, log=log)
        for motion in chosen
    ]
    config = {
        "robot": "ur5e",
        "payload_kg": PAYLOAD_KG,
        "payload_com_m": list(PAYLOAD_COM_M),
        "dt_s": DT_S,
        "profile": {
            "v_max_rad_s": V_MAX_RAD_S,
            "a_max_rad_s2": A_MAX_RAD_S2,
            "jerk_time_s": JERK_TIME_S,
        },
        "tail_s": tail_s,
        "spectrum_window_s": window_s,
        "quick": quick,
        "accelerometer_noise_std_m_s2": 0.0,
        "methods": {m.key: m.label for m in rows},
        "oracle_methods": {m.key: m.oracle for m in rows if m.oracle is not None},
        "settle_criteria": settle_config(),
        "slow_down_grid": {"jerk_times_s": list(JERK_TIMES_S), "accel_scales": list(ACCEL_SCALES)},
    }
    return DemoResult(motions=runs, config=config, wall_time_s=time.perf_counter() - start)
