"""Random bang-coast-bang excitation of one joint (paper Algorithm 2).

Starting from a standstill (used to estimate gravity, eq. 12), the joint repeatedly moves to
``q_j0 + δq`` with ``δq`` uniform in ``±π/18`` rad, a random speed (0.5-2 rad/s) and
acceleration (0.3-7 rad/s²), then waits a random 0.1-1.0 s; this continues until about 8 s
have passed. Each move is a trapezoidal velocity profile (bang-coast-bang in acceleration), the
profile URScript's ``movej`` runs.

The sampled reference is exact in discrete time: the acceleration is constant over each sample
interval (zero-order hold, sample ``k`` holds the value on ``[t_k, t_k + dt_s)``) and every
phase lasts a whole number of samples. To get there, each phase duration is rounded *up* to
whole samples and the speed and acceleration are lowered so the move still covers exactly
``δq``; the adjusted values never exceed the drawn ones and are the ones exported to URScript.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

__all__ = [
    "BangCoastBangMove",
    "Excitation",
    "random_excitation",
    "to_urscript",
    "write_trajectory_csv",
]

#: Algorithm 2's targets lie within this of the start position, rad (±10°).
MAX_DELTA_RAD = math.pi / 18.0


@dataclass(frozen=True)
class BangCoastBangMove:
    """One trapezoidal move of the excited joint, then a wait.

    Attributes
    ----------
    t_start_s
        Start time relative to the start of the excitation, s.
    q_from_rad, q_to_rad
        Joint position at start and end, rad.
    speed_rad_s, accel_rad_s2
        Peak speed and acceleration of the sampled profile (after rounding the phases to
        whole samples; at most the drawn ``speed_drawn_rad_s``, ``accel_drawn_rad_s2``).
    accel_time_s, coast_time_s
        Duration of the acceleration phase (the deceleration phase is as long) and of the
        constant-speed phase, s; whole multiples of the sampling period.
    wait_s
        Standstill after the move, s.
    speed_drawn_rad_s, accel_drawn_rad_s2
        The random limits drawn for this move.
    """

    t_start_s: float
    q_from_rad: float
    q_to_rad: float
    speed_rad_s: float
    accel_rad_s2: float
    accel_time_s: float
    coast_time_s: float
    wait_s: float
    speed_drawn_rad_s: float
    accel_drawn_rad_s2: float

    @property
    def move_time_s(self) -> float:
        return 2.0 * self.accel_time_s + self.coast_time_s


@dataclass(frozen=True)
class Excitation:
    """A sampled excitation of one joint around ``q0``.

    Attributes
    ----------
    joint
        Index of the excited joint (0 = base, 1 = shoulder, 2 = elbow, ...).
    q0
        Pose the excitation starts from and returns around, rad, shape (6,).
    dt_s
        Sampling period, s.
    standstill_s
        Initial standstill, s.
    moves
        The bang-coast-bang moves in order.
    t_s
        Sample times from 0, s, shape (n_samples,).
    q, qd, qdd
        Reference joint position, velocity and acceleration, shape (n_samples, 6); only
        column ``joint`` varies.
    seed
        Seed of the generator the moves were drawn from, if one was given.
    """

    joint: int
    q0: np.ndarray
    dt_s: float
    standstill_s: float
    moves: tuple[BangCoastBangMove, ...]
    t_s: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    qdd: np.ndarray
    seed: int | None = None

    @property
    def duration_s(self) -> float:
        return float(self.t_s[-1] - self.t_s[0])

    @property
    def standstill_samples(self) -> int:
        return int(round(self.standstill_s / self.dt_s))


def _check_range(name: str, lo_hi: tuple[float, float]) -> tuple[float, float]:
    lo, hi = (float(v) for v in lo_hi)
    if not (math.isfinite(lo) and math.isfinite(hi) and 0.0 < lo <= hi):
        raise ValueError(f"{name} must be a finite range 0 < low <= high, got {lo_hi}")
    return lo, hi


def _samples_up(duration_s: float, dt_s: float) -> int:
    """Whole number of samples >= duration (tolerating floating-point noise)."""
    return int(math.ceil(duration_s / dt_s - 1e-9))


def random_excitation(
    q0: np.ndarray,
    joint: int,
    *,
    seed: int | np.random.Generator | None = None,
    duration_s: float = 8.0,
    dt_s: float,
    standstill_s: float = 0.5,
    max_delta_rad: float = MAX_DELTA_RAD,
    speed_range_rad_s: tuple[float, float] = (0.5, 2.0),
    accel_range_rad_s2: tuple[float, float] = (0.3, 7.0),
    wait_range_s: tuple[float, float] = (0.1, 1.0),
) -> Excitation:
    """Draw a random bang-coast-bang excitation of ``joint`` around ``q0`` (Algorithm 2).

    Parameters
    ----------
    q0
        Start pose, rad, shape ``(n_dof,)``.
    joint
        Joint to excite, ``0 … n_dof − 1`` (the paper uses 0 = base and 1 = shoulder).
    seed
        Seed or ``numpy.random.Generator``; the same seed gives the same excitation.
    duration_s
        Moves are started while the elapsed time (after the standstill) is below this, like
        the ``while t < 8 s`` loop of Algorithm 2; the last move and its wait complete.
    dt_s
        Sampling period of the reference, s: the robot's control period
        (:attr:`~tvist.robots.RobotParams.control_period_s`).
    standstill_s
        Initial standstill for the gravity estimate, s (> 0).
    max_delta_rad
        Targets are ``q0[joint] + δq`` with ``δq`` uniform in ``±max_delta_rad``.
    speed_range_rad_s, accel_range_rad_s2, wait_range_s
        Uniform ranges of the speed and acceleration limits and of the wait after each move.

    Returns
    -------
    Excitation
    """
    q0 = np.asarray(q0, dtype=float)
    if q0.ndim != 1 or q0.size < 2 or not np.all(np.isfinite(q0)):
        raise ValueError(f"q0 must be finite joint angles (one per joint), got {q0!r}")
    n_dof = q0.size
    if not 0 <= int(joint) < n_dof or int(joint) != joint:
        raise ValueError(f"joint must be an integer 0-{n_dof - 1}, got {joint!r}")
    joint = int(joint)
    for name, value in (
        ("dt_s", dt_s),
        ("duration_s", duration_s),
        ("standstill_s", standstill_s),
        ("max_delta_rad", max_delta_rad),
    ):
        if not (math.isfinite(value) and value > 0):
            raise ValueError(f"{name} must be finite and > 0, got {value!r}")
    v_lo, v_hi = _check_range("speed_range_rad_s", speed_range_rad_s)
    a_lo, a_hi = _check_range("accel_range_rad_s2", accel_range_rad_s2)
    w_lo, w_hi = _check_range("wait_range_s", wait_range_s)

    seed_value = seed if isinstance(seed, int) else None
    rng = seed if isinstance(seed, np.random.Generator) else np.random.default_rng(seed)

    n_standstill = max(1, _samples_up(standstill_s, dt_s))
    # Per-sample acceleration of the excited joint (ZOH), built phase by phase.
    qdd_segments: list[np.ndarray] = [np.zeros(n_standstill)]
    moves: list[BangCoastBangMove] = []
    k = n_standstill  # samples so far
    q_now = float(q0[joint])
    while (k - n_standstill) * dt_s < duration_s:
        target = float(q0[joint] + rng.uniform(-max_delta_rad, max_delta_rad))
        v_drawn = float(rng.uniform(v_lo, v_hi))
        a_drawn = float(rng.uniform(a_lo, a_hi))
        wait = float(rng.uniform(w_lo, w_hi))
        n_wait = max(1, int(round(wait / dt_s)))
        distance = abs(target - q_now)
        direction = math.copysign(1.0, target - q_now)
        if distance < 1e-9:  # nothing to move; only wait
            qdd_segments.append(np.zeros(n_wait))
            k += n_wait
            continue
        if distance >= v_drawn**2 / a_drawn:  # trapezoid: the speed limit is reached
            t_acc, t_coast = v_drawn / a_drawn, distance / v_drawn - v_drawn / a_drawn
        else:  # triangle
            t_acc, t_coast = math.sqrt(distance / a_drawn), 0.0
        n_acc = max(1, _samples_up(t_acc, dt_s))
        n_coast = max(0, _samples_up(t_coast, dt_s))
        speed = distance / ((n_acc + n_coast) * dt_s)
        accel = speed / (n_acc * dt_s)
        moves.append(
            BangCoastBangMove(
                t_start_s=k * dt_s,
                q_from_rad=q_now,
                q_to_rad=target,
                speed_rad_s=speed,
                accel_rad_s2=accel,
                accel_time_s=n_acc * dt_s,
                coast_time_s=n_coast * dt_s,
                wait_s=n_wait * dt_s,
                speed_drawn_rad_s=v_drawn,
                accel_drawn_rad_s2=a_drawn,
            )
        )
        qdd_segments += [
            np.full(n_acc, direction * accel),
            np.zeros(n_coast),
            np.full(n_acc, -direction * accel),
            np.zeros(n_wait),
        ]
        k += 2 * n_acc + n_coast + n_wait
        q_now = target

    qdd_j = np.concatenate(qdd_segments)
    n = qdd_j.size + 1  # one more sample so the final state is included
    qdd_j = np.append(qdd_j, 0.0)
    # Exact integration of a piecewise-constant acceleration.
    qd_j = np.concatenate([[0.0], np.cumsum(qdd_j[:-1] * dt_s)])
    dq = qd_j[:-1] * dt_s + 0.5 * qdd_j[:-1] * dt_s**2
    q_j = q0[joint] + np.concatenate([[0.0], np.cumsum(dq)])

    q = np.tile(q0, (n, 1))
    qd = np.zeros((n, n_dof))
    qdd = np.zeros((n, n_dof))
    q[:, joint], qd[:, joint], qdd[:, joint] = q_j, qd_j, qdd_j
    return Excitation(
        joint=joint,
        q0=q0.copy(),
        dt_s=float(dt_s),
        standstill_s=n_standstill * dt_s,
        moves=tuple(moves),
        t_s=dt_s * np.arange(n),
        q=q,
        qd=qd,
        qdd=qdd,
        seed=seed_value,
    )


def _fmt_q(q: np.ndarray) -> str:
    return "[" + ", ".join(f"{v:.6f}" for v in q) + "]"


def to_urscript(
    excitation: Excitation,
    *,
    name: str = "tvist_excitation",
    approach_accel_rad_s2: float = 0.5,
    approach_speed_rad_s: float = 0.3,
) -> str:
    """A URScript program that runs ``excitation`` on a real robot.

    The program moves (slowly) to ``q0``, stands still for the standstill time, then runs each
    move as ``movej(q, a=…, v=…)`` followed by ``sleep(wait)``. Record RTDE (for example with
    ``tvist campaign --robot-ip`` or ur_rtde's ``startFileRecording``) from before the
    standstill until the end, then identify with ``tvist identify LOG.csv``.

    Parameters
    ----------
    excitation
        From :func:`random_excitation`.
    name
        Name of the URScript function.
    approach_accel_rad_s2, approach_speed_rad_s
        Limits of the initial move to ``q0``.

    Returns
    -------
    str
        The program text.
    """
    if not name.isidentifier():
        raise ValueError(f"name must be a valid identifier, got {name!r}")
    seed = "" if excitation.seed is None else f", seed {excitation.seed}"
    lines = [
        f"def {name}():",
        f"  # tvist random bang-coast-bang excitation of joint {excitation.joint}{seed};",
        f"  # {len(excitation.moves)} moves, {excitation.duration_s:.3f} s after the approach",
        f"  movej({_fmt_q(excitation.q0)}, a={approach_accel_rad_s2:.6f}, "
        f"v={approach_speed_rad_s:.6f})",
        f"  sleep({excitation.standstill_s:.6f})",
    ]
    q = excitation.q0.copy()
    for move in excitation.moves:
        q[excitation.joint] = move.q_to_rad
        lines.append(f"  movej({_fmt_q(q)}, a={move.accel_rad_s2:.6f}, v={move.speed_rad_s:.6f})")
        lines.append(f"  sleep({move.wait_s:.6f})")
    lines += ["end", f"{name}()", ""]
    return "\n".join(lines)


def write_trajectory_csv(excitation: Excitation, path: str | Path) -> Path:
    """Write the excitation's sampled reference as a trajectory CSV: a header ``time_s,
    q0..q{n-1}`` and one row per sample (s, rad; 9 decimals), the format ``tvist shape`` and
    ``tvist run`` read (``tvist run --unshaped`` streams it with servoJ)."""
    path = Path(path)
    n_dof = excitation.q.shape[1]
    header = ",".join(["time_s", *(f"q{j}" for j in range(n_dof))])
    table = np.column_stack([excitation.t_s, excitation.q])
    np.savetxt(path, table, fmt="%.9f", delimiter=",", header=header, comments="")
    return path
