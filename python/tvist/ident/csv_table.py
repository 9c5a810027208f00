"""Strict reading of a delimited numeric table (the text layer of the RTDE log formats).

:func:`read_table` turns a header line plus data rows into named float columns, refusing
anything it would otherwise have to guess about:

- a UTF-8 byte-order mark is skipped; a UTF-16 file (with its byte-order mark) is decoded;
- the header must be UTF-8; data rows must be ASCII text (numbers only), so a stray byte is
  never read as part of a number; there is no fallback decoding;
- every data row must have as many fields as the header (a trailing separator is ignored on
  both); blank lines are skipped (there are no comment lines: a ``#`` is a bad row);
- every wanted column must be present exactly once in the header;
- every wanted cell must be a decimal number (``nan``/``inf`` are numbers here: the caller
  decides about non-finite values); a cell with ``_`` is refused, though Python's ``float``
  would accept ``1_0`` as 10.

Failures are :class:`LogFormatError` (a ``ValueError``) naming the file, the data row (counted
from 0 after the header, blank lines not counted) and the line of the file.
Explicit repairs (``repair=``) turn some failures into dropped rows or a chosen column; the
caller reports them, from :attr:`Table.dropped` and :attr:`Table.duplicates`.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import NamedTuple

import numpy as np

__all__ = ["REPAIRS", "BadRow", "LogFormatError", "Table", "read_table"]

#: Explicit repairs :func:`read_table` accepts, and what each does.
REPAIRS: dict[str, str] = {
    "drop-bad-rows": "drop rows with the wrong number of fields, bytes that are not ASCII text "
    "or cells that are not numbers",
    "keep-first-duplicate": "use the first of several columns with the same name",
}

_BOM_UTF8 = b"\xef\xbb\xbf"
_BOM_UTF16 = (b"\xff\xfe", b"\xfe\xff")


class LogFormatError(ValueError):
    """A log file that cannot be read as written; the message names the file and the row."""


class BadRow(NamedTuple):
    """A data row dropped by ``repair="drop-bad-rows"``."""

    row: int  # data row, counted from 0 after the header
    line: int  # line of the file, counted from 1
    reason: str


@dataclass(frozen=True)
class Table:
    """The wanted columns of a table.

    Attributes
    ----------
    columns
        Column name -> column of :attr:`data`, for every wanted column present in the header.
    data
        Float cells, shape (n_rows, len(columns)).
    rows
        Data-row number (counted from 0 after the header) of each row of :attr:`data`,
        shape (n_rows,), increasing.
    dropped
        Rows dropped by ``repair="drop-bad-rows"``.
    duplicates
        Wanted column names that appear more than once in the header (with
        ``repair="keep-first-duplicate"``; the first is used).
    """

    columns: dict[str, int]
    data: np.ndarray
    rows: np.ndarray
    dropped: tuple[BadRow, ...] = ()
    duplicates: tuple[str, ...] = ()


def _repairs(repair: str | Iterable[str] | None) -> frozenset[str]:
    chosen = frozenset([repair] if isinstance(repair, str) else (repair or ()))
    unknown = sorted(chosen - REPAIRS.keys())
    if unknown:
        known = ", ".join(repr(k) for k in REPAIRS)
        raise ValueError(f"unknown repair {', '.join(map(repr, unknown))}; choose from {known}")
    return chosen


def _lines(path: Path, raw: bytes) -> list[bytes | str]:
    """The file's lines: bytes (decoded later, line by line) or str for a UTF-16 file."""
    if raw.startswith(_BOM_UTF16):
        try:
            text = raw.decode("utf-16")
        except UnicodeDecodeError as exc:
            raise LogFormatError(
                f"{path}: starts with a UTF-16 byte-order mark but is not valid UTF-16 "
                f"(byte {exc.start}); save it as UTF-8 or ASCII text"
            ) from None
        return [line.rstrip("\r") for line in text.split("\n")]
    if raw.startswith(_BOM_UTF8):
        raw = raw[len(_BOM_UTF8) :]
    return [line.rstrip(b"\r") for line in raw.split(b"\n")]


def _decode_data_line(line: bytes | str) -> tuple[str | None, str]:
    """``(text, "")`` for an ASCII line, else ``(None, reason)``."""
    if isinstance(line, bytes):
        try:
            text = line.decode("ascii")
        except UnicodeDecodeError as exc:
            return None, (
                f"byte 0x{line[exc.start]:02x} at character {exc.start + 1} is not ASCII text "
                "(data rows hold only numbers)"
            )
        return text, ""
    if not line.isascii():
        at = next(i for i, ch in enumerate(line) if not ch.isascii())
        return None, f"character {line[at]!r} at position {at + 1} is not ASCII text"
    return line, ""


def _split(text: str, sep: str) -> list[str]:
    """Fields of one line (surrounding blanks kept: ``float`` ignores them); trailing empty
    fields (a trailing separator) are removed."""
    fields = text.split(",") if sep == "," else text.split()
    while fields and not fields[-1].strip():
        fields.pop()
    return fields


def read_table(
    path: str | Path,
    required: Sequence[str],
    optional: Sequence[str] = (),
    *,
    separator: Callable[[str], str],
    repair: str | Iterable[str] | None = None,
) -> Table:
    """Read the ``required`` and present ``optional`` columns of a delimited text table.

    Parameters
    ----------
    path
        The file.
    required, optional
        Wanted column names; a missing required one is an error, a missing optional one is
        left out of :attr:`Table.columns`.
    separator
        Given the header line, returns ``","`` (comma-separated) or ``" "`` (any run of
        whitespace); raises ``ValueError`` if the header is not of the expected format.
    repair
        ``None`` (refuse every defect) or one or more of :data:`REPAIRS`.

    Raises
    ------
    LogFormatError
        An unreadable header, a missing or (without ``"keep-first-duplicate"``) repeated
        wanted column, or (without ``"drop-bad-rows"``) a bad data row; the message names the
        file, the column or the data row and the line.
    """
    path = Path(path)
    repairs = _repairs(repair)
    lines = _lines(path, path.read_bytes())

    # Header: the first line that is not blank.
    header_at = next((i for i, line in enumerate(lines) if line.strip()), None)
    if header_at is None:
        raise LogFormatError(f"{path}: the file is empty (no header line)")
    header = lines[header_at]
    if isinstance(header, bytes):
        try:
            header = header.decode("utf-8")
        except UnicodeDecodeError as exc:
            raise LogFormatError(
                f"{path}: line {header_at + 1} (the header): byte 0x{header[exc.start]:02x} "
                f"at byte {exc.start + 1} is not UTF-8 text"
            ) from None
    header = header.strip()
    try:
        sep = separator(header)
    except ValueError as exc:
        raise LogFormatError(f"{path}: line {header_at + 1}: {exc}") from None
    names = [name.strip() for name in _split(header, sep)]

    where: dict[str, list[int]] = {}
    for i, name in enumerate(names):
        where.setdefault(name, []).append(i)
    missing = [c for c in required if c not in where]
    if missing:
        raise LogFormatError(f"{path}: missing column(s) {', '.join(missing)}")
    wanted = list(dict.fromkeys([*required, *(c for c in optional if c in where)]))
    duplicates = tuple(c for c in wanted if len(where[c]) > 1)
    if duplicates and "keep-first-duplicate" not in repairs:
        c = duplicates[0]
        fields = ", ".join(str(i + 1) for i in where[c])
        raise LogFormatError(
            f"{path}: line {header_at + 1} (the header): column {c!r} appears "
            f"{len(where[c])} times (fields {fields}); remove all but one, or pass "
            "repair='keep-first-duplicate' (CLI: --repair keep-first-duplicate) to use the first"
        )
    use = [where[c][0] for c in wanted]

    values: list[list[float]] = []
    rows: list[int] = []
    dropped: list[BadRow] = []
    row = -1
    for line_at in range(header_at + 1, len(lines)):
        raw_line = lines[line_at]
        if not raw_line.strip():
            continue
        row += 1
        text, reason = _decode_data_line(raw_line)
        parsed: list[float] | None = None
        if text is not None:
            fields = _split(text, sep)
            if len(fields) != len(names):
                reason = f"has {len(fields)} fields, the header has {len(names)}"
            else:
                parsed, reason = _parse_cells(text, fields, use, wanted)
        if parsed is None:
            if "drop-bad-rows" not in repairs:
                raise LogFormatError(
                    f"{path}: data row {row} (line {line_at + 1}) {reason}; fix or delete "
                    "that line, or pass repair='drop-bad-rows' (CLI: --repair drop-bad-rows) "
                    "to drop such rows with a warning"
                )
            dropped.append(BadRow(row, line_at + 1, reason))
            continue
        values.append(parsed)
        rows.append(row)

    data = np.array(values, dtype=float).reshape(len(values), len(wanted))
    return Table(
        columns={c: k for k, c in enumerate(wanted)},
        data=data,
        rows=np.array(rows, dtype=int),
        dropped=tuple(dropped),
        duplicates=duplicates,
    )


def _parse_cells(
    text: str, fields: list[str], use: list[int], wanted: list[str]
) -> tuple[list[float] | None, str]:
    """The wanted cells of one row (``text`` split into ``fields``) as floats, or
    ``(None, reason)`` naming the first bad cell."""
    if "_" not in text:  # fast path: every wanted cell parses
        try:
            return [float(fields[i]) for i in use], ""
        except ValueError:
            pass
    out = []
    for i, name in zip(use, wanted, strict=True):
        cell = fields[i]
        try:
            if "_" in cell:  # float() would read "1_0" as 10
                raise ValueError
            out.append(float(cell))
        except ValueError:
            return None, f"column {name!r} holds {cell.strip()[:40]!r}, not a number"
    return out, ""  # the "_" was in a column that is not wanted
