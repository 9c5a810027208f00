"""RTDE logs: the :class:`Record` of one identification run and reading/writing UR CSV files.

Two recorder formats share the RTDE column names (vector fields expanded to ``name_0 … name_n``):

- ``"ur_rtde"``: ``RTDEReceiveInterface.startFileRecording`` of the ur_rtde library,
  comma-separated, 6 decimals;
- ``"ur_client"``: Universal Robots' own RTDE client (``record.py``), space-separated.

Both are detected automatically from the header line. Columns other than the ones a
:class:`Record` holds are ignored.

Validation at load time (every message names the offending rows, counted from 0 over the data
rows, i.e. not counting the header):

- a missing required column is a ``ValueError`` naming the column;
- the text is read strictly by :func:`tvist.ident.csv_table.read_table`: a row with the wrong
  number of fields, a byte that is not ASCII text in a data row or a cell that is not a number
  is a :class:`LogFormatError` (a ``ValueError``) naming the file, the data row and the line,
  unless ``repair="drop-bad-rows"`` (then dropped with a :class:`LogWarning`); a repeated
  column name is refused unless ``repair="keep-first-duplicate"``; a UTF-8 byte-order mark is
  skipped;
- timestamps that do not advance, or that span more than 2⁵³ sampling periods (a corrupt
  timestamp such as 1e308), are a ``ValueError``; resampling refuses a grid longer than
  :data:`tvist.trajectory.resample.MAX_GRID_SAMPLES` and cells too large to interpolate;
- a row with NaN/inf is a ``ValueError`` unless ``drop_nan=True`` (then dropped with a
  :class:`LogWarning`);
- a repeated timestamp (the recorder wrote the same sample twice) is dropped with a
  :class:`LogWarning`;
- a timestamp that goes backwards is a ``ValueError``;
- skipped samples (a step longer than 1.5 sampling periods) are filled by linear
  interpolation onto a uniform grid, with a :class:`LogWarning` that says how many samples
  were filled (``resample=False`` only reports them); a log that would be more than half
  filled is refused;
- units (:func:`tvist.units.check_log`): declared units (``units="q=deg,acc=g"``) are
  converted to SI; joint angles beyond ±2π rad, velocities that are not the rate of change of
  the positions, ``actual_q`` that does not follow ``target_q`` or an accelerometer that does
  not read 9.81 m/s² at rest are a :class:`tvist.units.UnitError` (a ``ValueError``) naming
  the column, the likely unit and the ``--units`` that declares it.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, fields
from pathlib import Path
from typing import Any, Literal

import numpy as np

from tvist.ident.csv_table import LogFormatError, read_table
from tvist.trajectory.resample import MAX_GRID_SAMPLES
from tvist.units import UnitError, check_log

__all__ = [
    "PAYLOAD_COLUMNS",
    "LogFormatError",
    "LogWarning",
    "Record",
    "find_gaps",
    "is_uniform",
    "log_payload",
    "read_rtde_csv",
    "resample_uniform",
]

LogFormat = Literal["ur_rtde", "ur_client"]

#: Vector length of the joint fields (``JOINTS``): one entry per joint of the arm, 6 on a UR.
JOINTS = -1
#: Record field -> (RTDE field name, vector length). ``actual_TCP_pose`` is optional.
_FIELDS: dict[str, tuple[str, int]] = {
    "target_q": ("target_q", JOINTS),
    "target_qd": ("target_qd", JOINTS),
    "target_qdd": ("target_qdd", JOINTS),
    "actual_q": ("actual_q", JOINTS),
    "actual_TCP_pose": ("actual_TCP_pose", 6),
    "tool_accel": ("actual_tool_accelerometer", 3),
}
_OPTIONAL = {"actual_TCP_pose"}
#: A UR logs 6 joints; an arm with more writes the joint fields wider (``target_q_6`` …), up
#: to this many joints.
UR_JOINTS = 6
MAX_JOINTS = 12

#: A step longer than this many median sampling periods counts as skipped samples.
GAP_FACTOR = 1.5
#: Resampling refuses to fill more than this fraction of the resampled log.
MAX_FILLED_FRACTION = 0.5


class LogWarning(UserWarning):
    """A log was repaired or has a defect that the caller should know about."""


def _columns(rtde_name: str, n: int) -> list[str]:
    return [f"{rtde_name}_{i}" for i in range(n)]


def _rows_text(rows: np.ndarray, limit: int = 10) -> str:
    shown = ", ".join(str(int(r)) for r in rows[:limit])
    more = f" and {len(rows) - limit} more" if len(rows) > limit else ""
    return f"{shown}{more}"


@dataclass(frozen=True)
class Record:
    """One recorded run, time along rows.

    Attributes
    ----------
    t_s
        Timestamps, s, shape (n_samples,), strictly increasing.
    target_q, target_qd, target_qdd
        Reference joint position (rad), velocity (rad/s) and acceleration (rad/s²),
        shape (n_samples, n_joints) (6 on a UR).
    actual_q
        Measured joint positions, rad, shape (n_samples, n_joints).
    tool_accel
        Raw tool-flange accelerometer reading, m/s², in the flange frame, shape (n_samples, 3).
        At rest it reads the reaction to gravity (+9.8 m/s² pointing up).
    actual_TCP_pose
        Optional measured TCP pose ``[x, y, z, rx, ry, rz]`` (m, rotation vector in rad),
        shape (n_samples, 6).
    """

    t_s: np.ndarray
    target_q: np.ndarray
    target_qd: np.ndarray
    target_qdd: np.ndarray
    actual_q: np.ndarray
    tool_accel: np.ndarray
    actual_TCP_pose: np.ndarray | None = None

    def __post_init__(self) -> None:
        t = np.asarray(self.t_s, dtype=float)
        if t.ndim != 1 or t.size == 0:
            raise ValueError(f"t_s must be a non-empty 1-D array, got shape {t.shape}")
        object.__setattr__(self, "t_s", t)
        n = t.size
        n_joints = np.shape(self.target_q)[1] if np.ndim(self.target_q) == 2 else UR_JOINTS
        for name, (_, width) in _FIELDS.items():
            width = n_joints if width == JOINTS else width
            value = getattr(self, name)
            if value is None:
                if name in _OPTIONAL:
                    continue
                raise ValueError(f"{name} is required")
            arr = np.asarray(value, dtype=float)
            if arr.shape != (n, width):
                raise ValueError(f"{name} must have shape ({n}, {width}), got {arr.shape}")
            object.__setattr__(self, name, arr)

    @classmethod
    def from_rtde_fields(cls, source: Any) -> Record:
        """A record from any object with RTDE-named attributes (``timestamp``, ``target_q``,
        …, ``actual_tool_accelerometer``, optional ``actual_TCP_pose``), such as a run of the
        simulated twin (:class:`tvist.sim.SimRecord`)."""
        kwargs = {name: getattr(source, rtde, None) for name, (rtde, _) in _FIELDS.items()}
        return cls(t_s=source.timestamp, **kwargs)

    @property
    def n_samples(self) -> int:
        return int(self.t_s.size)

    @property
    def n_joints(self) -> int:
        """Number of joints logged."""
        return int(self.target_q.shape[1])

    @property
    def dt_s(self) -> float:
        """Median sampling period, s (NaN for a single sample)."""
        if self.t_s.size < 2:
            return float("nan")
        return float(np.median(np.diff(self.t_s)))

    def select(self, index: np.ndarray | slice) -> Record:
        """The record restricted to rows ``index`` (boolean mask, indices or slice)."""
        kwargs = {}
        for f in fields(self):
            value = getattr(self, f.name)
            kwargs[f.name] = None if value is None else value[index]
        return Record(**kwargs)

    def to_csv(self, path: str | Path, fmt: LogFormat = "ur_rtde") -> Path:
        """Write the record as a UR RTDE CSV file.

        Parameters
        ----------
        path
            Output file.
        fmt
            ``"ur_rtde"`` (comma-separated, 6 decimals, like ur_rtde's file recording) or
            ``"ur_client"`` (space-separated, full float precision, like UR's ``record.py``).
        """
        if fmt == "ur_rtde":
            sep, number = ",", "%.6f"
        elif fmt == "ur_client":
            sep, number = " ", "%.17g"
        else:
            raise ValueError(f"fmt must be 'ur_rtde' or 'ur_client', got {fmt!r}")
        header = ["timestamp"]
        blocks = [self.t_s[:, None]]
        for name, (rtde_name, _) in _FIELDS.items():
            value = getattr(self, name)
            if value is None:
                continue
            header += _columns(rtde_name, value.shape[1])
            blocks.append(value)
        path = Path(path)
        np.savetxt(
            path, np.hstack(blocks), fmt=number, delimiter=sep, header=sep.join(header), comments=""
        )
        return path


def find_gaps(t_s: np.ndarray, factor: float = GAP_FACTOR) -> np.ndarray:
    """Rows ``i`` where the step ``t_s[i] - t_s[i-1]`` exceeds ``factor`` median periods.

    Returns the indices (into ``t_s``) of the first sample after each gap.
    """
    t = np.asarray(t_s, dtype=float)
    if t.size < 3:
        return np.zeros(0, dtype=int)
    step = np.diff(t)
    period = np.median(step)
    return np.flatnonzero(step > factor * period) + 1


def _detect_separator(header_line: str) -> str:
    if "," in header_line:
        return ","
    if header_line.split() and header_line.split()[0] == "timestamp":
        return " "
    raise ValueError(
        "not a UR RTDE CSV file: the header must start with 'timestamp' and be comma- or "
        f"space-separated; got {header_line[:80]!r}"
    )


def resample_uniform(record: Record) -> tuple[Record, int]:
    """Linear interpolation of every channel onto a uniform grid at the median period.

    Returns the resampled record and the number of grid samples that had no recorded sample
    within half a period (filled by interpolation).

    Raises
    ------
    ValueError
        If more than :data:`MAX_FILLED_FRACTION` of the grid would be filled (a time jump,
        not skipped samples).
    """
    t = record.t_s
    dt = record.dt_s
    if not (math.isfinite(dt) and dt > 0):
        raise ValueError("cannot resample: the timestamps do not advance")
    span = (t[-1] - t[0]) / dt
    if not math.isfinite(span) or span + 1 > record.n_samples / (1.0 - MAX_FILLED_FRACTION):
        raise ValueError(
            f"the log spans {t[-1] - t[0]:.6g} s but holds only {record.n_samples} samples at "
            f"{dt * 1e3:.3f} ms: more than {100 * MAX_FILLED_FRACTION:.0f} % would be "
            "interpolated; split the log at its time jump"
        )
    n = int(np.floor(span + 1e-9)) + 1
    grid = t[0] + dt * np.arange(n)
    nearest = np.clip(np.searchsorted(t, grid), 1, t.size - 1)
    distance = np.minimum(np.abs(t[nearest] - grid), np.abs(t[nearest - 1] - grid))
    filled = int(np.count_nonzero(distance > 0.5 * dt))
    kwargs: dict[str, np.ndarray | None] = {"t_s": grid}
    for name in _FIELDS:
        value = getattr(record, name)
        if value is None:
            kwargs[name] = None
            continue
        kwargs[name] = np.column_stack([np.interp(grid, t, col) for col in value.T])
    return Record(**kwargs), filled


def is_uniform(t_s: np.ndarray, tolerance: float = 0.25) -> bool:
    """True if every step is within ``tolerance`` median periods of the median period."""
    step = np.diff(np.asarray(t_s, dtype=float))
    if step.size == 0:
        return True
    dt = float(np.median(step))
    return bool(np.all(np.abs(step - dt) <= tolerance * dt))


def read_rtde_csv(
    path: str | Path,
    *,
    repair: str | tuple[str, ...] | None = None,
    drop_nan: bool = False,
    resample: bool = True,
    units: str | dict[str, str] | None = None,
    check_units: bool = True,
) -> Record:
    """Read a UR RTDE log written by ur_rtde or by UR's ``record.py`` (format auto-detected).

    Parameters
    ----------
    path
        The CSV file.
    repair
        ``None`` (default: refuse a malformed file), ``"drop-bad-rows"`` (drop rows with the
        wrong number of fields, non-ASCII bytes or non-numeric cells, with a
        :class:`LogWarning` naming them), ``"keep-first-duplicate"`` (use the first of
        repeated columns, with a :class:`LogWarning`), or a tuple of both.
    drop_nan
        Drop rows containing NaN/inf (with a :class:`LogWarning`) instead of raising.
    resample
        If samples were skipped, interpolate all channels linearly onto a uniform grid at the
        median sampling period (default; with a :class:`LogWarning` that says how many
        samples were filled). ``False`` only reports the gaps.
    units
        Units of the log's columns where they are not SI, ``"q=deg,qd=deg/s,acc=g"`` or
        ``{"q": "deg"}`` (:func:`tvist.units.parse_units`); converted to SI.
    check_units
        Refuse a log whose values do not look like SI once converted (default); ``False``
        skips the check (synthetic data that is not a physical log).

    Returns
    -------
    Record
        Timestamps strictly increasing; duplicated samples removed.

    Raises
    ------
    LogFormatError
        (a ``ValueError``; the message names the file and, where one is at fault, the row)
        Unknown format, missing or repeated columns, malformed rows or undecodable bytes
        (unless repaired), NaN rows (unless ``drop_nan``), timestamps that go backwards, do
        not advance or are corrupt, fewer than 2 samples, or a resampling grid over the cap or
        cells too large to interpolate.
    UnitError
        (a ``ValueError``) A column that does not look like SI once the declared ``units``
        are converted: the message names it, its likely unit and the ``--units`` to declare.
    ValueError
        An unknown ``repair`` option or unit.
    """
    path = Path(path)
    required = ["timestamp"]
    extra_joints = []  # joint columns beyond a UR's six, if the arm has more joints
    for name, (rtde_name, width) in _FIELDS.items():
        if width == JOINTS:
            required += _columns(rtde_name, UR_JOINTS)
            extra_joints += [f"{rtde_name}_{i}" for i in range(UR_JOINTS, MAX_JOINTS)]
        elif name not in _OPTIONAL:
            required += _columns(rtde_name, width)
    table = read_table(
        path,
        required,
        _columns("actual_TCP_pose", 6) + extra_joints,
        separator=_detect_separator,
        repair=repair,
    )
    if table.dropped:
        warnings.warn(
            f"{path}: dropped {len(table.dropped)} malformed row(s): "
            + "; ".join(f"data row {b.row} (line {b.line}) {b.reason}" for b in table.dropped[:5])
            + (f"; and {len(table.dropped) - 5} more" if len(table.dropped) > 5 else ""),
            LogWarning,
            stacklevel=2,
        )
    if table.duplicates:
        warnings.warn(
            f"{path}: column(s) {', '.join(table.duplicates)} appear more than once; "
            "the first of each is used",
            LogWarning,
            stacklevel=2,
        )
    data, index = table.data, table.columns
    n_joints = _logged_joints(path, index)

    def take(columns: list[str]) -> np.ndarray:
        return data[:, [index[c] for c in columns]]

    used = ["timestamp"]
    has_pose = all(c in index for c in _columns("actual_TCP_pose", 6))
    for name, (rtde_name, width) in _FIELDS.items():
        if name in _OPTIONAL and not has_pose:
            continue
        used += _columns(rtde_name, n_joints if width == JOINTS else width)
    bad = np.flatnonzero(~np.all(np.isfinite(take(used)), axis=1))
    if bad.size:
        if not drop_nan:
            raise LogFormatError(
                f"{path}: non-finite values in data row(s) {_rows_text(table.rows[bad])} "
                "(drop them with --drop-nan, or drop_nan=True in Python)"
            )
        warnings.warn(
            f"{path}: dropped {bad.size} row(s) with non-finite values: "
            f"{_rows_text(table.rows[bad])}",
            LogWarning,
            stacklevel=2,
        )
    keep = np.ones(data.shape[0], dtype=bool)
    keep[bad] = False
    rows = table.rows[keep]  # original data-row numbers of the kept rows
    data = data[keep]
    if data.shape[0] < 2:
        raise LogFormatError(f"{path}: need at least 2 valid samples, got {data.shape[0]}")

    t = data[:, index["timestamp"]]
    step = np.diff(t)
    backwards = np.flatnonzero(step < 0) + 1
    if backwards.size:
        r = backwards[0]
        raise LogFormatError(
            f"{path}: timestamp goes backwards at data row {rows[r]} "
            f"({t[r]:.6f} s after {t[r - 1]:.6f} s)"
        )
    duplicate = np.flatnonzero(step == 0) + 1
    if duplicate.size:
        warnings.warn(
            f"{path}: dropped {duplicate.size} sample(s) with a repeated timestamp at data "
            f"row(s) {_rows_text(rows[duplicate])}",
            LogWarning,
            stacklevel=2,
        )
        keep = np.ones(data.shape[0], dtype=bool)
        keep[duplicate] = False
        data, rows = data[keep], rows[keep]

    _check_time_and_grid(path, data[:, index["timestamp"]], take(used), used, rows, resample)
    record = Record(
        t_s=data[:, index["timestamp"]],
        target_q=_take(data, index, "target_q", n_joints),
        target_qd=_take(data, index, "target_qd", n_joints),
        target_qdd=_take(data, index, "target_qdd", n_joints),
        actual_q=_take(data, index, "actual_q", n_joints),
        tool_accel=_take(data, index, "actual_tool_accelerometer", 3),
        actual_TCP_pose=_take(data, index, "actual_TCP_pose", 6) if has_pose else None,
    )
    record = _in_si_units(path, record, rows, units, check_units)
    gaps = find_gaps(record.t_s)
    if gaps.size:
        dt = record.dt_s
        missing_n = int(np.sum(np.round(np.diff(record.t_s)[gaps - 1] / dt) - 1))
        where = f"before data row(s) {_rows_text(rows[gaps])} (period {dt * 1e3:.3f} ms)"
        if resample:
            try:
                record, filled = resample_uniform(record)
            except ValueError as exc:
                raise LogFormatError(f"{path}: {exc}") from None
            action = (
                f"resampled onto a uniform grid: {filled} of {record.n_samples} samples "
                f"({100 * filled / record.n_samples:.1f} %) filled by linear interpolation"
            )
        else:
            action = "left as is"
        warnings.warn(
            f"{path}: about {missing_n} skipped sample(s) {where}; {action}",
            LogWarning,
            stacklevel=2,
        )
    return record


#: Columns of the payload in a log (RTDE ``payload``, kg, and ``payload_cog``, m in the flange
#: frame), which ``tvist record`` and ``tvist run`` write when the controller provides them.
PAYLOAD_COLUMNS = ("payload", *_columns("payload_cog", 3))
#: Largest change of the payload within one log taken as one payload (kg; m): the CSV's
#: 6 decimals.
PAYLOAD_TOLERANCE = 1e-6


def log_payload(path: str | Path):
    """The payload a log was recorded with (:data:`PAYLOAD_COLUMNS`), a
    :class:`tvist.robots.Payload`, or ``None`` if the log has no payload columns.

    Raises
    ------
    LogFormatError
        If the payload changes within the log (which payload the fit should use is then
        unknown) or the file is not a readable RTDE log.
    """
    from tvist.robots import Payload

    # Only the payload is read here; the log itself is judged (or repaired, as asked) by
    # read_rtde_csv, so malformed rows are simply passed over.
    table = read_table(
        path,
        (),
        PAYLOAD_COLUMNS,
        separator=_detect_separator,
        repair=("drop-bad-rows", "keep-first-duplicate"),
    )
    if set(table.columns) != set(PAYLOAD_COLUMNS):
        return None
    values = table.data[:, [table.columns[c] for c in PAYLOAD_COLUMNS]]
    values = values[np.all(np.isfinite(values), axis=1)]
    if values.shape[0] == 0:
        return None
    if np.max(np.ptp(values, axis=0)) > PAYLOAD_TOLERANCE:
        raise LogFormatError(
            f"{path}: the payload changes during the log ({values[:, 0].min():g} to "
            f"{values[:, 0].max():g} kg); give the payload explicitly"
        )
    return Payload(float(values[0, 0]), tuple(float(v) for v in values[0, 1:]))


def _in_si_units(path: Path, record: Record, rows: np.ndarray, units: Any, check: bool) -> Record:
    """``record`` converted to SI from the declared ``units``, checked unless ``check`` is
    False (:func:`tvist.units.check_log`; ``rows`` are the samples' data rows)."""
    columns = {
        rtde: getattr(record, name)
        for name, (rtde, _) in _FIELDS.items()
        if getattr(record, name) is not None
    }
    try:
        si = check_log(record.t_s, columns, units, rows, check=check)
    except UnitError as exc:
        raise UnitError(f"{path}: {exc}") from None
    return Record(t_s=record.t_s, **{name: si.get(rtde) for name, (rtde, _) in _FIELDS.items()})


def _logged_joints(path: Path, index: dict[str, int]) -> int:
    """The number of joints the log's columns give: 6, or more where every joint field has
    the columns ``_6`` … of the same further joints.

    Raises
    ------
    LogFormatError
        The joint fields are of different widths (naming the column that is missing).
    """
    fields = [rtde for rtde, width in _FIELDS.values() if width == JOINTS]
    n = UR_JOINTS
    while n < MAX_JOINTS and f"target_q_{n}" in index:
        n += 1
    for rtde in fields:
        for i in range(UR_JOINTS, MAX_JOINTS):
            if (f"{rtde}_{i}" in index) != (i < n):
                missing = f"{rtde}_{i}" if i < n else f"target_q_{i}"
                raise LogFormatError(
                    f"{path}: column {missing} is missing: the joint fields must log the "
                    f"same joints ({n} from target_q)"
                )
    return n


def _take(data: np.ndarray, index: dict[str, int], rtde_name: str, width: int) -> np.ndarray:
    """Columns ``rtde_name_0 … rtde_name_{width-1}`` of ``data`` as an (n_samples, width) array."""
    return data[:, [index[c] for c in _columns(rtde_name, width)]]


#: Timestamps spanning more sampling periods than this are corrupt (beyond 2⁵³, sample counts
#: are not exact in float64).
MAX_SPAN_PERIODS = 2.0**53
#: Resampling refuses cells larger than this in magnitude: the difference of two of them, and
#: the interpolation formula, must stay finite.
MAX_INTERPOLATED_ABS = np.finfo(float).max / 4


def _check_time_and_grid(
    path: Path,
    t_s: np.ndarray,
    values: np.ndarray,
    names: list[str],
    rows: np.ndarray,
    resample: bool,
) -> None:
    """Refuse timestamps the reader cannot count with and a resampling it cannot do safely.

    ``t_s`` (n_samples,) finite and strictly increasing, ``values`` (n_samples, n_channels)
    finite with column names ``names``, ``rows`` the data-row number of each sample.
    """
    if t_s.size < 2:
        raise LogFormatError(
            f"{path}: the timestamps do not advance: every sample has timestamp {t_s[0]:.6g} s"
        )
    step = np.diff(t_s)
    dt = float(np.median(step))
    with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
        span_periods = (t_s[-1] - t_s[0]) / dt
    jump = int(np.argmax(step)) + 1  # the sample after the largest step
    at_jump = (
        f"the largest step is {step[jump - 1]:.6g} s, before data row {rows[jump]} "
        f"(timestamp {t_s[jump]:.6g} s)"
    )
    if not np.isfinite(span_periods) or span_periods > MAX_SPAN_PERIODS:
        raise LogFormatError(
            f"{path}: the timestamps span {t_s[-1] - t_s[0]:.6g} s at a period of "
            f"{dt * 1e3:.6g} ms, more than 2^53 periods: a corrupt timestamp; {at_jump}; fix it "
            "or split the log at its time jump"
        )
    if not resample or find_gaps(t_s).size == 0:
        return
    if span_periods + 1 > MAX_GRID_SAMPLES:
        raise LogFormatError(
            f"{path}: resampling would build {int(span_periods) + 1} samples at "
            f"{dt * 1e3:.6g} ms (limit {MAX_GRID_SAMPLES}); {at_jump}; split the log at its "
            "time jump"
        )
    too_large = np.argwhere(~(np.abs(values) <= MAX_INTERPOLATED_ABS))
    if too_large.size:
        r, c = too_large[0]
        raise LogFormatError(
            f"{path}: cannot resample: {names[c]} is {values[r, c]:.6g} at data row {rows[r]}, "
            f"too large to interpolate (limit ±{MAX_INTERPOLATED_ABS:.3g}); fix that cell"
        )
    with np.errstate(over="ignore"):
        slope = np.diff(values, axis=0) / step[:, None]
    steep = np.argwhere(~np.isfinite(slope))
    if steep.size:
        r, c = steep[0]
        raise LogFormatError(
            f"{path}: cannot resample: {names[c]} changes from {values[r, c]:.6g} to "
            f"{values[r + 1, c]:.6g} in {step[r]:.3g} s between data rows {rows[r]} and "
            f"{rows[r + 1]}, too fast to interpolate; fix those cells"
        )
