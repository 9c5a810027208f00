"""Fixed (time-invariant) shaper baselines: what a user would run instead of FD-TVIST.

- ``fixed-start``: the two-mode ZV shaper of the twin's modes at the start pose, held for the
  whole move (tune once, where the robot stands).
- ``fixed-robust``: the shortest time-invariant shaper built from tvist's shaper library (one
  registry shaper, or the convolution of two, each designed for one mode ``(ω_n, ζ)``) whose
  percent residual vibration (PRV, eqs. 52-55) stays at or below :data:`ROBUST_PRV_LIMIT` for
  every mode the twin has along the planned move: both modes, every
  :data:`ROBUST_STRIDE`-th sample from the start pose to the end pose.

Both run through the real-time core (:class:`tvist.TvShaper` with constant modes; a
convolution is two filters in series), like every other row.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass

import numpy as np

import tvist
from tvist.experiments.method_row import Method, MotionContext, Reference

__all__ = [
    "ROBUST_PRV_LIMIT",
    "RobustDesign",
    "Stage",
    "fixed_robust_row",
    "fixed_start_row",
    "modes_along",
    "search_robust_shaper",
]

#: Largest residual vibration the robust shaper may leave on any mode along the move.
ROBUST_PRV_LIMIT = 0.05
#: Modes along the move are evaluated every this many samples (20 ms at 500 Hz): the modes
#: change by less than 2 % between neighbours on the paper's motions.
ROBUST_STRIDE = 10
#: How the registry shapers are written in reports.
SHAPER_NAMES = {
    "zv": "ZV",
    "zvd": "ZVD",
    "zvdd": "ZVDD",
    "mzv": "MZV",
    "ei": "EI",
    "2hump_ei": "2-hump EI",
    "3hump_ei": "3-hump EI",
}
#: Design frequencies: a geometric grid over this multiple of the range of natural
#: frequencies along the move (a robust design may sit outside it) ...
GRID_SPAN = (0.6, 1.5)
#: ... with this many points for single shapers and for each factor of a convolution.
GRID_SINGLE = 60
GRID_PAIR = 24


@dataclass(frozen=True)
class Stage:
    """One registry shaper designed for one mode (a factor of a time-invariant shaper)."""

    shaper: str
    wn_rad_s: float
    zeta: float

    def impulses(self) -> tvist.Impulses:
        return tvist.shaper(self.shaper, self.wn_rad_s, self.zeta)

    def text(self) -> str:
        name = SHAPER_NAMES.get(self.shaper, self.shaper)
        return f"{name} at f_n {self.wn_rad_s / (2 * math.pi):.2f} Hz, ζ {self.zeta:.3f}"


@dataclass(frozen=True)
class RobustDesign:
    """The result of :func:`search_robust_shaper`.

    Attributes
    ----------
    stages
        The factors, in series (their impulse sequences convolve).
    duration_s
        Length of the impulse sequence: the delay the shaper adds, s.
    max_prv
        Largest PRV over the modes along the move (fraction).
    feasible
        Whether ``max_prv`` is within the limit (if no candidate is, the design with the
        smallest ``max_prv`` is returned and this is False).
    n_candidates
        How many designs were evaluated.
    range_hz, range_zeta
        Natural frequencies (Hz) and damping ratios the design must cover: ``(min, max)``.
    """

    stages: tuple[Stage, ...]
    duration_s: float
    max_prv: float
    feasible: bool
    n_candidates: int
    range_hz: tuple[float, float]
    range_zeta: tuple[float, float]

    def text(self) -> str:
        """Design and range in one phrase for the report."""
        design = " convolved with ".join(s.text() for s in self.stages)
        return (
            f"{design}: {1e3 * self.duration_s:.1f} ms long, PRV at most "
            f"{100 * self.max_prv:.1f} % over f_n {self.range_hz[0]:.1f}-{self.range_hz[1]:.1f} "
            f"Hz, ζ {self.range_zeta[0]:.3f}-{self.range_zeta[1]:.3f} (natural frequencies)"
        )

    def to_json(self) -> dict:
        return {
            "stages": [
                {"shaper": s.shaper, "wn_rad_s": s.wn_rad_s, "zeta": s.zeta} for s in self.stages
            ],
            "duration_s": self.duration_s,
            "max_prv": self.max_prv,
            "prv_limit": ROBUST_PRV_LIMIT,
            "feasible": self.feasible,
            "n_candidates": self.n_candidates,
            "range_natural_hz": list(self.range_hz),
            "range_zeta": list(self.range_zeta),
        }


def modes_along(ctx: MotionContext, stride: int = ROBUST_STRIDE) -> np.ndarray:
    """The twin's modes ``(m, 2 modes, 2)`` of ``(wn_rad_s, zeta)`` along the planned move,
    every ``stride`` samples from its start to its end (both included)."""
    traj = ctx.trajectory
    first = int(round(traj.t_motion_start_s / traj.dt_s))
    last = int(round(traj.t_motion_end_s / traj.dt_s))
    index = np.unique(np.append(np.arange(first, last, stride), last))
    return np.array([ctx.twin.modes(traj.q[k]) for k in index])


def _design(stages: tuple[Stage, ...]) -> tvist.Impulses | None:
    try:
        parts = [s.impulses() for s in stages]
    except ValueError:  # outside a shaper's design range (e.g. EI damping)
        return None
    return parts[0] if len(parts) == 1 else tvist.convolve(*parts)


def search_robust_shaper(modes: np.ndarray, prv_limit: float = ROBUST_PRV_LIMIT) -> RobustDesign:
    """Shortest time-invariant shaper from the library with PRV <= ``prv_limit`` on every mode.

    Parameters
    ----------
    modes
        ``(..., 2)`` array of ``(wn_rad_s, zeta)``: the modes to cover.
    prv_limit
        Largest allowed residual vibration (fraction).

    The candidates are every registry shaper of :data:`tvist.SHAPERS` designed on a
    geometric grid of natural frequencies (:data:`GRID_SPAN` × the range, :data:`GRID_SINGLE`
    points) and at the smallest, median and largest damping of ``modes``; and every
    convolution of two of them on a coarser grid (:data:`GRID_PAIR` points), at the median
    damping. Among those within the limit the shortest wins (ties: the lower PRV).
    """
    wn = np.asarray(modes, dtype=float)[..., 0].ravel()
    zeta = np.asarray(modes, dtype=float)[..., 1].ravel()
    lo, hi = float(wn.min()), float(wn.max())
    z_choices = sorted({float(zeta.min()), float(np.median(zeta)), float(zeta.max())})
    single_grid = np.geomspace(GRID_SPAN[0] * lo, GRID_SPAN[1] * hi, GRID_SINGLE)
    pair_grid = np.geomspace(GRID_SPAN[0] * lo, GRID_SPAN[1] * hi, GRID_PAIR)
    z_mid = float(np.median(zeta))

    candidates: list[tuple[Stage, ...]] = [
        (Stage(name, float(w), z),)
        for name in tvist.SHAPERS
        for w in single_grid
        for z in z_choices
    ]
    for (na, wa), (nb, wb) in itertools.combinations_with_replacement(
        [(n, float(w)) for n in tvist.SHAPERS for w in pair_grid], 2
    ):
        candidates.append((Stage(na, wa, z_mid), Stage(nb, wb, z_mid)))

    best: tuple[float, float, tuple[Stage, ...]] | None = None  # (duration, prv, stages)
    fallback: tuple[float, float, tuple[Stage, ...]] | None = None  # (prv, duration, stages)
    for stages in candidates:
        impulses = _design(stages)
        if impulses is None:
            continue
        duration = float(impulses.duration_s)
        if best is not None and duration > best[0]:
            continue  # cannot win: longer than a feasible design
        worst = float(np.max(tvist.prv(impulses, wn, zeta)))
        if worst <= prv_limit:
            if best is None or (duration, worst) < best[:2]:
                best = (duration, worst, stages)
        elif fallback is None or (worst, duration) < fallback[:2]:
            fallback = (worst, duration, stages)
    if best is not None:
        duration, worst, stages = best
    else:
        assert fallback is not None
        worst, duration, stages = fallback
    return RobustDesign(
        stages=stages,
        duration_s=duration,
        max_prv=worst,
        feasible=best is not None,
        n_candidates=len(candidates),
        range_hz=(lo / (2 * math.pi), hi / (2 * math.pi)),
        range_zeta=(float(zeta.min()), float(zeta.max())),
    )


def _run_stages(ctx: MotionContext, stages: tuple[Stage, ...]) -> np.ndarray:
    """The planned reference through one constant-mode FD-TVIST filter per stage, in series."""
    q = np.ascontiguousarray(ctx.trajectory.q)
    for stage in stages:
        shaper = tvist.TvShaper(
            tvist.ConstantModes([(stage.wn_rad_s, stage.zeta)]),
            ctx.trajectory.dt_s,
            ctx.trajectory.n_dof,
            shaper=stage.shaper,
        )
        shaper.reset(np.ascontiguousarray(q[0]))
        q = np.ascontiguousarray(shaper.shape(q))
    return np.array(q)


def _fixed_start(ctx: MotionContext) -> Reference:
    modes = ctx.twin.modes(ctx.motion.q_start)
    stages = tuple(Stage("zv", w, z) for w, z in modes)
    return Reference(
        _run_stages(ctx, stages),
        {
            "shaper": "zv x 2 modes, time-invariant",
            "provider": f"twin eigen-analysis at the start pose {ctx.motion.start}",
            "design": " convolved with ".join(s.text() for s in stages),
            "modes": [list(m) for m in modes],
            "impulse_duration_s": float(_design(stages).duration_s),
        },
    )


def _fixed_robust(ctx: MotionContext) -> Reference:
    design = search_robust_shaper(modes_along(ctx))
    return Reference(
        _run_stages(ctx, design.stages),
        {
            "shaper": "time-invariant robust design",
            "provider": "twin eigen-analysis along the planned move (design only)",
            "design": design.text(),
            "robust_design": design.to_json(),
            "impulse_duration_s": design.duration_s,
        },
    )


def fixed_start_row() -> Method:
    """``fixed-start``: two-mode ZV at the start pose's true modes for the whole move."""
    return Method("fixed-start", "Fixed ZV, start-pose modes", _fixed_start)


def fixed_robust_row() -> Method:
    """``fixed-robust``: the shortest library shaper within 5 % PRV along the move."""
    return Method("fixed-robust", "Fixed robust shaper over the move", _fixed_robust)
