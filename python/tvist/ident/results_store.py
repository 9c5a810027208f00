"""Results file of a mapping campaign: one JSON line per pose, appended as poses finish."""

from __future__ import annotations

import json
import os
from pathlib import Path

__all__ = ["append_record", "load_results", "repair_tail"]


def load_results(path: str | Path) -> list[dict]:
    """Pose records of a campaign results file (JSON lines); a torn last line is ignored."""
    path = Path(path)
    if not path.exists():
        return []
    out = []
    lines = path.read_text(encoding="utf-8").splitlines()
    for i, line in enumerate(lines):
        if not line.strip():
            continue
        try:
            out.append(json.loads(line))
        except json.JSONDecodeError:
            if i == len(lines) - 1:  # interrupted while writing: that pose reruns
                continue
            raise ValueError(f"{path}: line {i + 1} is not valid JSON") from None
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
