"""Results file of a mapping campaign: one JSON line per pose, appended as poses finish.

- Every record carries the ``fingerprint`` of the settings that produced it (robot, payload
  centre of mass, seed, excitation length, sensor noise, fit settings, plan version); a file
  written with other settings is refused (:class:`SettingsMismatch`), so a rerun with changed
  settings never reuses old records. Choose another file or overwrite it.
- One writer at a time: :class:`ResultsStore` holds an advisory lock (``fcntl.flock``) on the
  file while a campaign appends to it.
- A line that is not a pose record (torn by an interrupted write, ``null``, no ``key``) is
  moved to ``<file>.quarantine`` with a warning, and its pose runs again.
"""

from __future__ import annotations

import hashlib
import json
import os
import warnings
from collections.abc import Iterator
from pathlib import Path
from typing import Any

__all__ = [
    "FileLocked",
    "ResultsStore",
    "SettingsMismatch",
    "append_record",
    "fingerprint",
    "load_results",
    "repair_tail",
]

#: Version of the pose plan and record layout; part of every fingerprint.
PLAN_VERSION = 2


class SettingsMismatch(ValueError):
    """The results file was written with other settings."""


class FileLocked(ValueError):
    """Another process is writing the results file."""


def fingerprint(settings: dict[str, Any]) -> str:
    """Short stable hash of the settings that change a campaign's results."""
    text = json.dumps({"plan_version": PLAN_VERSION, **settings}, sort_keys=True, default=str)
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def _is_record(value: Any) -> bool:
    return isinstance(value, dict) and isinstance(value.get("key"), str)


def _parsed_lines(lines: list[str]) -> Iterator[tuple[int, str, Any]]:
    """``(index, line, value)`` of every non-blank line, ``value`` its JSON or ``None`` when
    the line is not JSON (a torn or foreign line); ``index`` counts blank lines too."""
    for i, line in enumerate(lines):
        if not line.strip():
            continue
        try:
            value = json.loads(line)
        except json.JSONDecodeError:
            value = None
        yield i, line, value


def load_results(path: str | Path) -> list[dict]:
    """Pose records of a results file (JSON lines); a torn last line is ignored.

    Raises
    ------
    ValueError
        A line other than the last is not a pose record (use :class:`ResultsStore` to
        quarantine such lines).
    """
    path = Path(path)
    if not path.exists():
        return []
    out = []
    lines = path.read_text(encoding="utf-8").splitlines()
    for i, _, value in _parsed_lines(lines):
        if _is_record(value):
            out.append(value)
        elif i == len(lines) - 1:  # interrupted while writing: that pose reruns
            continue
        else:
            raise ValueError(f"{path}: line {i + 1} is not a pose record") from None
    return out


def append_record(path: Path, record: dict) -> None:
    with path.open("a", encoding="utf-8") as fh:
        fh.write(json.dumps(record) + "\n")
        fh.flush()
        os.fsync(fh.fileno())


def repair_tail(path: Path) -> None:
    """Drop a torn last line so appended records start on a fresh line."""
    if not path.exists():
        return
    text = path.read_text(encoding="utf-8")
    if text and not text.endswith("\n"):
        path.write_text(text[: text.rfind("\n") + 1], encoding="utf-8")


class ResultsStore:
    """A campaign's results file, locked for writing, for one settings fingerprint.

    Use as a context manager: entering locks the file (``FileLocked`` if another process
    holds it), quarantines lines that are not pose records and checks every record's
    fingerprint (``SettingsMismatch``; ``overwrite=True`` empties the file instead).
    """

    def __init__(self, path: str | Path, settings_fingerprint: str, *, overwrite: bool = False):
        self.path = Path(path)
        self.fingerprint = settings_fingerprint
        self.overwrite = overwrite
        self._lock = None
        self.records: list[dict] = []

    def __enter__(self) -> ResultsStore:
        import fcntl

        self.path.parent.mkdir(parents=True, exist_ok=True)
        self._lock = self.path.with_name(self.path.name + ".lock").open("a")
        try:
            fcntl.flock(self._lock.fileno(), fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            self._lock.close()
            self._lock = None
            raise FileLocked(
                f"{self.path} is being written by another campaign; wait for it or choose "
                "another results file"
            ) from None
        try:
            if self.overwrite:
                self.path.write_text("", encoding="utf-8")
            self.records = self._read_and_quarantine()
            other = [r["key"] for r in self.records if r.get("fingerprint") != self.fingerprint]
            if other:
                raise SettingsMismatch(
                    f"{self.path} holds {len(other)} pose record(s) made with other settings "
                    f"(e.g. {other[0]}); choose another results file or overwrite it"
                )
        except BaseException:
            self.__exit__(None, None, None)
            raise
        return self

    def __exit__(self, *exc: object) -> None:
        if self._lock is not None:
            import fcntl

            fcntl.flock(self._lock.fileno(), fcntl.LOCK_UN)
            self._lock.close()
            self._lock = None

    @property
    def done(self) -> set[str]:
        return {r["key"] for r in self.records}

    def append(self, record: dict) -> None:
        record = {**record, "fingerprint": self.fingerprint}
        append_record(self.path, record)
        self.records.append(record)

    def replace_all(self, records: list[dict]) -> None:
        """Write ``records`` (this store's poses, e.g. with flags from checks across poses)
        in place of the file's, atomically; records keep their fingerprints."""
        if records == self.records:
            return
        tmp = self.path.with_name(self.path.name + ".tmp")
        tmp.write_text("".join(json.dumps(r) + "\n" for r in records), encoding="utf-8")
        os.replace(tmp, self.path)
        self.records = list(records)

    def _read_and_quarantine(self) -> list[dict]:
        if not self.path.exists():
            return []
        text = self.path.read_text(encoding="utf-8")
        good, bad = [], []
        for _, line, value in _parsed_lines(text.splitlines()):
            (good if _is_record(value) else bad).append((line, value))
        if bad:
            quarantine = self.path.with_name(self.path.name + ".quarantine")
            with quarantine.open("a", encoding="utf-8") as fh:
                for line, _ in bad:
                    fh.write(line + "\n")
            tmp = self.path.with_name(self.path.name + ".tmp")
            tmp.write_text("".join(line + "\n" for line, _ in good), encoding="utf-8")
            os.replace(tmp, self.path)
            warnings.warn(
                f"{self.path}: {len(bad)} line(s) that are not pose records moved to "
                f"{quarantine}; their poses run again",
                stacklevel=3,
            )
        return [value for _, value in good]
