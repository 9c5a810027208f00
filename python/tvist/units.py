"""Units and limits: what an RTDE log or a joint trajectory must satisfy before it is used.

One place for the rules that tell a wrong unit, a mislabelled column or an impossible motion
from a right one, shared by the log reader (:func:`tvist.ident.read_rtde_csv`) and the commands
that write or run trajectories (``tvist shape``, ``tvist run``).

Units. tvist works in SI: joint positions rad, velocities rad/s, accelerations rad/s², the
tool accelerometer m/s². Other units are declared, never guessed (:func:`parse_units`,
``--units q=deg,acc=g``) and converted by :func:`to_si`. What looks like another unit is
refused, naming the column and the likely unit:

- joint angles: a UR joint turns at most ±2π rad, so a value beyond ±2π (up to ±360) looks
  like degrees (:func:`angle_unit`);
- joint velocities against the rate of change of the positions: their least-squares ratio is
  the velocity unit's factor (1 for rad/s, π/180 for deg/s); a ratio that matches no unit, or
  velocities that do not correlate with the positions' change, is a mislabelled or swapped
  column (:func:`rate_unit`);
- ``actual_q`` follows ``target_q`` (to :data:`TRACKING_TOL_RAD`, median over the log);
- the accelerometer at rest reads the reaction to gravity, 9.81 m/s²: ≈1 looks like g,
  ≈9810 like mg (:func:`accel_unit`).

Limits. A trajectory stays inside the robot model's joint limits and joint speed limits
(:class:`tvist.robots.RobotParams`, the one source of robot data); the model has no
acceleration or jerk limit, so those are reported (:func:`joint_peaks`), not checked.

Every refusal is a ``ValueError`` (:class:`UnitError` for a unit) whose one-line message
names the column, the row and the fix.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from typing import Any

import numpy as np

__all__ = [
    "DEG",
    "STANDARD_GRAVITY",
    "UNITS",
    "UnitError",
    "accel_unit",
    "angle_unit",
    "check_log",
    "check_trajectory",
    "joint_peaks",
    "parse_units",
    "rate_unit",
    "to_si",
    "units_text",
]

DEG = math.pi / 180.0
#: Standard gravity, m/s² (the g of an accelerometer reading in g).
STANDARD_GRAVITY = 9.80665

#: Quantity -> {unit: factor to SI}; the first unit of each is the SI one.
UNITS: dict[str, dict[str, float]] = {
    "q": {"rad": 1.0, "deg": DEG},
    "qd": {"rad/s": 1.0, "deg/s": DEG},
    "qdd": {"rad/s2": 1.0, "deg/s2": DEG},
    "acc": {"m/s2": 1.0, "g": STANDARD_GRAVITY, "mg": STANDARD_GRAVITY / 1000.0},
}
#: What each quantity is, for help texts.
QUANTITIES = {
    "q": "joint positions",
    "qd": "joint velocities",
    "qdd": "joint accelerations",
    "acc": "tool accelerometer",
}
#: RTDE log column -> quantity.
LOG_QUANTITY = {
    "target_q": "q",
    "actual_q": "q",
    "target_qd": "qd",
    "target_qdd": "qdd",
    "actual_tool_accelerometer": "acc",
}

#: Largest joint angle of a UR, rad (every joint turns at most ±2π; +1e-5 for 6 decimals).
MAX_ANGLE_RAD = 2.0 * math.pi + 1e-5
#: A joint moves if its position changes faster than this somewhere, rad/s (6-decimal
#: rounding at 500 Hz makes at most 5e-4 rad/s of apparent speed).
MOVING_RAD_S = 0.05
#: Velocities match the positions' rate of change if they correlate at least this well.
MIN_RATE_CORRELATION = 0.9
#: A ratio within this factor of a unit's factor is that unit (deg/s and rad/s differ 57x).
RATE_FACTOR_TOL = 1.5
#: ``actual_q`` follows ``target_q`` to this, rad (median over the log; a real arm's
#: following error is a few mrad, a swapped or mislabelled column is off by much more).
TRACKING_TOL_RAD = 0.1
#: The accelerometer reads the reaction to gravity at rest, m/s² (local g is 9.78-9.83).
GRAVITY_AT_REST = 9.81
#: A magnitude at rest within this factor of 9.81 m/s² is in that unit (sensor bias and
#: ringing move it a few %; g and mg are 10x and 1000x away).
ACCEL_FACTOR_TOL = 1.25
#: The arm is at rest when no target joint moves faster than this, rad/s.
REST_RAD_S = 0.01
#: Fewest samples at rest to judge the accelerometer by (else the whole log's median).
MIN_REST_SAMPLES = 10


class UnitError(ValueError):
    """A value that is not in the unit expected (SI, or the one declared)."""


# --------------------------------------------------------------------------- declaring units


def parse_units(
    spec: str | Mapping[str, str] | None, allowed: tuple[str, ...] = tuple(UNITS)
) -> dict[str, str]:
    """Declared units, ``"q=deg,acc=g"`` or a mapping, as ``{quantity: unit}`` for every
    quantity in ``allowed`` (SI where not declared).

    Raises
    ------
    ValueError
        An unknown quantity or unit, naming ``--units`` and what is known.
    """
    out = {quantity: next(iter(UNITS[quantity])) for quantity in allowed}
    if not spec:
        return out
    if isinstance(spec, str):
        items = []
        for item in spec.split(","):
            if not item.strip():
                continue
            name, sep, unit = item.partition("=")
            if not sep:
                raise ValueError(f"--units: {item!r} is not QUANTITY=UNIT (e.g. q=deg,acc=g)")
            items.append((name.strip(), unit.strip()))
    else:
        items = list(spec.items())
    for name, unit in items:
        if name not in allowed:
            raise ValueError(f"--units: unknown quantity {name!r}; known: {', '.join(allowed)}")
        if unit not in UNITS[name]:
            known = ", ".join(UNITS[name])
            raise ValueError(f"--units: {name}={unit} is not a known unit of {name} ({known})")
        out[name] = unit
    return out


def units_text(units: Mapping[str, str]) -> str:
    """The non-SI entries of ``units`` as ``--units`` takes them (``""`` if all SI)."""
    return ",".join(f"{q}={u}" for q, u in units.items() if u != next(iter(UNITS[q])))


def units_help(quantities: tuple[str, ...] = tuple(UNITS)) -> str:
    """Help text of a ``--units`` option accepting ``quantities``."""
    choices = "; ".join(f"{q} ({QUANTITIES[q]}): {' | '.join(UNITS[q])}" for q in quantities)
    example = "q=deg,acc=g" if "acc" in quantities else "q=deg"
    return (
        f"units of the input where not SI, e.g. {example} (default: the first of each): {choices}"
    )


def to_si(values: Any, quantity: str, unit: str) -> np.ndarray:
    """``values`` in ``unit`` of ``quantity``, converted to SI."""
    return np.asarray(values, dtype=float) * UNITS[quantity][unit]


# --------------------------------------------------------------------------- detection


def angle_unit(q: np.ndarray) -> str | None:
    """The unit joint angles ``q`` can be in: ``"rad"`` if within ±2π, ``"deg"`` if within
    ±360 (a UR joint turns at most ±2π rad), else ``None``."""
    peak = float(np.max(np.abs(q))) if np.size(q) else 0.0
    if peak <= MAX_ANGLE_RAD:
        return "rad"
    if peak <= MAX_ANGLE_RAD / DEG:
        return "deg"
    return None


def rate_ratio(x: np.ndarray, xdot: np.ndarray, t_s: np.ndarray) -> tuple[float, float]:
    """``(ratio, correlation)`` of the rate of change of ``x`` to ``xdot`` (1-D, sampled at
    ``t_s``): least squares ``dx/dt ≈ ratio · xdot`` and their correlation coefficient."""
    rate = np.gradient(x, t_s)
    cross, rate_sq, xdot_sq = float(rate @ xdot), float(rate @ rate), float(xdot @ xdot)
    if xdot_sq == 0.0:
        return math.inf, 0.0
    return cross / xdot_sq, cross / math.sqrt(rate_sq * xdot_sq) if rate_sq else 0.0


def rate_unit(ratio: float, correlation: float, quantity: str) -> str | None:
    """The unit of a rate (``quantity`` ``"qd"`` or ``"qdd"``) whose SI-converted integral
    changes ``ratio`` times as fast as its values (see :func:`rate_ratio`), or ``None``."""
    if not correlation >= MIN_RATE_CORRELATION:
        return None
    for unit, factor in UNITS[quantity].items():
        if abs(math.log(ratio / factor)) < math.log(RATE_FACTOR_TOL):
            return unit
    return None


def accel_unit(magnitude_at_rest: float) -> str | None:
    """The accelerometer unit in which ``magnitude_at_rest`` is 9.81 m/s², or ``None``."""
    if not magnitude_at_rest > 0.0:
        return None
    for unit, factor in UNITS["acc"].items():
        if abs(math.log(magnitude_at_rest * factor / GRAVITY_AT_REST)) < math.log(ACCEL_FACTOR_TOL):
            return unit
    return None


# --------------------------------------------------------------------------- RTDE logs


def check_log(
    t_s: np.ndarray,
    columns: Mapping[str, np.ndarray],
    units: str | Mapping[str, str] | None = None,
    rows: np.ndarray | None = None,
    *,
    check: bool = True,
) -> dict[str, np.ndarray]:
    """Convert an RTDE log's columns to SI and refuse what does not look like SI.

    Parameters
    ----------
    t_s
        Timestamps, s, ``(n,)``, strictly increasing.
    columns
        RTDE name -> values ``(n, width)``: ``target_q``, ``target_qd``, ``target_qdd``,
        ``actual_q``, ``actual_tool_accelerometer`` (checked) and any others (returned as
        they are, and searched for the data of a misplaced column).
    units
        Declared units (see :func:`parse_units`); SI where not declared.
    rows
        Data-row number of each sample, for the messages (default ``0 … n-1``).
    check
        ``False``: only convert the declared units (for synthetic data that is not a
        physical log).

    Returns
    -------
    dict
        The columns in SI units.

    Raises
    ------
    UnitError
        One line naming the first column that looks wrong and the fix: the ``--units`` that
        declares every unit that looks wrong, or the column to fix.
    """
    declared = parse_units(units)
    raw = {name: np.asarray(values, dtype=float) for name, values in columns.items()}
    if check:
        likely = dict(declared)
        findings: list[tuple[str, bool]] = []  # (text, True if --units can fix it)
        rows = np.arange(len(t_s)) if rows is None else rows
        # Cells near the float limit overflow in the differences: such a column fails its
        # check (inf and NaN never pass a comparison), without a numpy warning.
        with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
            _check_positions(raw["target_q"], rows, declared, likely, findings)
            _check_rates(t_s, raw, declared, likely, findings)
            _check_tracking(raw, likely, findings)
            _check_accelerometer(t_s, rows, raw, declared, likely, findings)
        if findings:
            text, by_units = findings[0]
            if by_units:
                wanted = units_text(likely)
                text += (
                    f"; declare the log's units: --units {wanted} (Python: units={wanted!r})"
                    if wanted
                    else "; the log is in SI units: leave out --units"
                )
            raise UnitError(text)
    return {
        name: to_si(values, LOG_QUANTITY[name], declared[LOG_QUANTITY[name]])
        if name in LOG_QUANTITY
        else values
        for name, values in raw.items()
    }


_Findings = list[tuple[str, bool]]


def _check_positions(
    target_q: np.ndarray,
    rows: np.ndarray,
    declared: Mapping[str, str],
    likely: dict[str, str],
    findings: _Findings,
) -> None:
    """Joint angles within ±2π rad once in the declared unit; else degrees, or no angles."""
    factor = UNITS["q"][declared["q"]]
    found = angle_unit(target_q * factor)
    if found == "rad":
        return
    row, joint = np.argwhere(np.abs(target_q * factor) > MAX_ANGLE_RAD)[0]
    at = f"target_q_{joint} is {target_q[row, joint]:.6g} at data row {rows[row]}, beyond ±2π rad"
    if declared["q"] != "rad":
        at += f" in the declared {declared['q']}"
    if found == "deg" and declared["q"] == "rad":
        likely["q"] = "deg"
        findings.append((f"{at}: the joint angles look like degrees", True))
    else:
        findings.append((f"{at}: these are not joint angles; fix that column", False))


def _check_rates(
    t_s: np.ndarray,
    raw: Mapping[str, np.ndarray],
    declared: Mapping[str, str],
    likely: dict[str, str],
    findings: _Findings,
) -> None:
    """``target_qd`` against the rate of change of ``target_q`` (per moving joint), then the
    unit of ``target_qdd`` against the rate of change of ``target_qd`` (its unit only: a
    controller's target acceleration may be coarse)."""
    target_q, target_qd, target_qdd = raw["target_q"], raw["target_qd"], raw["target_qdd"]
    q_si = to_si(target_q, "q", likely["q"])
    for joint in range(q_si.shape[1]):
        x = q_si[:, joint]
        if float(np.max(np.abs(np.gradient(x, t_s)))) < MOVING_RAD_S:
            continue
        ratio, corr = rate_ratio(x, target_qd[:, joint], t_s)
        unit = rate_unit(ratio, corr, "qd")
        if unit is None and likely["q"] == "rad" and declared["q"] == "rad":
            if rate_unit(ratio * DEG, corr, "qd") == declared["qd"]:
                # Degrees that stay within ±2π: they change 57 times as fast as they should.
                likely["q"] = "deg"
                findings.append(
                    (
                        f"target_q_{joint} changes {1 / DEG:.1f} times as fast as "
                        f"target_qd_{joint} says: the joint angles look like degrees",
                        True,
                    )
                )
                return
        if unit is None:
            findings.append(
                (
                    f"target_qd_{joint} is not the rate of change of target_q_{joint} (ratio "
                    f"{ratio:.3g}, correlation {corr:.2f}): a mislabelled or swapped column; "
                    "fix the log",
                    False,
                )
            )
            return
        if unit != declared["qd"]:
            likely["qd"] = unit
            findings.append((f"target_qd_{joint} looks like {unit}, not {declared['qd']}", True))
            break
    qd_si = to_si(target_qd, "qd", likely["qd"])
    for joint in range(qd_si.shape[1]):
        if float(np.max(np.abs(np.gradient(qd_si[:, joint], t_s)))) < MOVING_RAD_S:
            continue
        unit = rate_unit(*rate_ratio(qd_si[:, joint], target_qdd[:, joint], t_s), "qdd")
        if unit is not None and unit != declared["qdd"]:
            likely["qdd"] = unit
            findings.append((f"target_qdd_{joint} looks like {unit}, not {declared['qdd']}", True))
        return


def _check_tracking(
    raw: Mapping[str, np.ndarray], likely: dict[str, str], findings: _Findings
) -> None:
    """``actual_q`` follows ``target_q``; a column that does not is named, with the column
    that holds its data if there is one."""
    q_target = to_si(raw["target_q"], "q", likely["q"])
    q_actual = to_si(raw["actual_q"], "q", likely["q"])
    for joint in range(q_target.shape[1]):
        off = float(np.median(np.abs(q_actual[:, joint] - q_target[:, joint])))
        if off <= TRACKING_TOL_RAD:
            continue
        text = (
            f"actual_q_{joint} does not follow target_q_{joint} (median difference {off:.3g} rad)"
        )
        partner = _column_following(raw, q_target[:, joint], exclude=f"actual_q_{joint}")
        if partner:
            text += f" but {partner} does: the two columns look swapped; fix the log"
        else:
            text += ": a mislabelled or misplaced column; fix the log"
        findings.append((text, False))
        return


def _check_accelerometer(
    t_s: np.ndarray,
    rows: np.ndarray,
    raw: Mapping[str, np.ndarray],
    declared: Mapping[str, str],
    likely: dict[str, str],
    findings: _Findings,
) -> None:
    """The accelerometer reads 9.81 m/s² at rest: the magnitude of its mean over the longest
    stretch where the target is at rest (one pose; the mean removes the noise, which would
    bias a magnitude upward), else the median magnitude over the whole log."""
    q_target = to_si(raw["target_q"], "q", likely["q"])
    acc = raw["actual_tool_accelerometer"]
    rest = np.all(np.abs(np.gradient(q_target, t_s, axis=0)) < REST_RAD_S, axis=1)
    start, stop = _longest_run(rest)
    if stop - start >= MIN_REST_SAMPLES:
        magnitude = float(np.linalg.norm(np.mean(acc[start:stop], axis=0)))
        where = (
            f"actual_tool_accelerometer reads {magnitude:.4g} at rest (mean over data rows "
            f"{rows[start]}-{rows[stop - 1]})"
        )
    else:
        magnitude = float(np.median(np.linalg.norm(acc, axis=1)))
        where = (
            f"actual_tool_accelerometer reads {magnitude:.4g} (median magnitude; the arm is "
            "never at rest)"
        )
    unit = accel_unit(magnitude)
    if unit is None:
        findings.append(
            (
                f"{where}, not 9.81 m/s² (nor 1 g or 9810 mg): a mislabelled or swapped "
                "column, or a broken sensor; fix the log",
                False,
            )
        )
    elif unit != declared["acc"]:
        likely["acc"] = unit
        findings.append((f"{where}: it looks like {unit}, not {declared['acc']}", True))


def _longest_run(mask: np.ndarray) -> tuple[int, int]:
    """``(start, stop)`` of the longest run of True in ``mask`` (``(0, 0)`` if none)."""
    edges = np.flatnonzero(np.diff(np.concatenate([[0], mask.astype(np.int8), [0]])))
    if edges.size == 0:
        return 0, 0
    starts, stops = edges[0::2], edges[1::2]
    longest = int(np.argmax(stops - starts))
    return int(starts[longest]), int(stops[longest])


def _column_following(
    raw: Mapping[str, np.ndarray], reference: np.ndarray, exclude: str
) -> str | None:
    """The log column (``name_i``) whose values follow ``reference`` (rad) best, to
    :data:`TRACKING_TOL_RAD` (median), other than ``exclude`` and ``target_q``; or ``None``."""
    best, best_off = None, TRACKING_TOL_RAD
    for name, values in raw.items():
        if name == "target_q":
            continue
        for i in range(values.shape[1]):
            column = f"{name}_{i}"
            if column == exclude:
                continue
            off = float(np.median(np.abs(values[:, i] - reference)))
            if off <= best_off:
                best, best_off = column, off
    return best


# --------------------------------------------------------------------------- trajectories


def joint_peaks(q: np.ndarray, dt_s: float) -> dict[str, np.ndarray]:
    """Peak joint speed (rad/s), acceleration (rad/s²) and jerk (rad/s³) of ``q``
    ``(n_samples, n_dof)`` sampled every ``dt_s``, by finite differences; each ``(n_dof,)``
    (zeros where there are too few samples)."""
    out = {}
    diff = np.asarray(q, dtype=float)
    for name in ("speed", "acceleration", "jerk"):
        diff = np.diff(diff, axis=0) / dt_s
        out[name] = np.max(np.abs(diff), axis=0) if diff.shape[0] else np.zeros(diff.shape[1])
    return out


def check_trajectory(
    q: np.ndarray,
    dt_s: float | None,
    params=None,
    *,
    columns: list[str] | None = None,
    row_label: Callable[[int], str] = lambda i: f"row {i}",
    what: str = "the trajectory",
) -> None:
    """Refuse a joint trajectory in the wrong unit or beyond the robot's limits.

    Parameters
    ----------
    q
        Joint positions, rad, ``(n_samples, n_dof)``, one row every ``dt_s`` s.
    dt_s
        Sample period, s; ``None`` for waypoints (no speed check: check their resampling).
    params
        :class:`tvist.robots.RobotParams` whose joint and speed limits apply (its ``n_dof``
        must match); ``None`` checks the unit only.
    columns
        Column names for the messages (default ``q0 … q{n-1}``).
    row_label
        The name of sample ``i`` in the messages (e.g. its row in the file).
    what
        What ``q`` is, for the messages.

    Raises
    ------
    UnitError
        A value beyond ±2π rad (looks like degrees).
    ValueError
        A sample outside the joint limits, or a step faster than the joint speed limit.
    """
    q = np.asarray(q, dtype=float)
    columns = columns or [f"q{j}" for j in range(q.shape[1])]
    beyond = np.argwhere(np.abs(q) > MAX_ANGLE_RAD)
    if beyond.size:
        row, joint = beyond[0]
        at = (
            f"{what}, {row_label(row)}, column {columns[joint]}: {q[row, joint]:.6g} is beyond "
            "±2π rad"
        )
        if angle_unit(q) == "deg":
            raise UnitError(
                f"{at}: the joint angles look like degrees; convert them to radians or "
                "declare them with --units q=deg"
            )
        raise UnitError(f"{at} and ±360: not joint angles; fix that column")
    if params is None:
        return
    lower, upper = params.joint_limits_rad.T
    outside = np.argwhere((q < lower) | (q > upper))
    if outside.size:
        row, joint = outside[0]
        raise ValueError(
            f"{what}, {row_label(row)}, column {columns[joint]}: {q[row, joint]:.6g} rad is "
            f"outside joint {joint}'s limits [{lower[joint]:.4g}, {upper[joint]:.4g}] rad on the "
            f"{params.name}; keep every pose inside the limits"
        )
    if dt_s is None:
        return
    speed = np.abs(np.diff(q, axis=0)) / dt_s
    fast = np.argwhere(speed > params.max_velocity_rad_s)
    if fast.size:
        row, joint = fast[0]
        raise ValueError(
            f"{what}, {row_label(row)} to {row_label(row + 1)}, column {columns[joint]}: "
            f"joint {joint} would move at {speed[row, joint]:.4g} rad/s, above its limit "
            f"{params.max_velocity_rad_s[joint]:.4g} rad/s on the {params.name} "
            f"(rows {dt_s:g} s apart); slow the move down"
        )
