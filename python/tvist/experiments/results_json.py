"""``results.json`` of the experiments: their results as JSON, NaN and infinities as null."""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import numpy as np

from tvist.experiments.experiment import DemoResult


def json_safe(value: Any) -> Any:
    """NaN and infinities become null (JSON has no NaN); numpy scalars become floats."""
    if isinstance(value, dict):
        return {k: json_safe(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [json_safe(v) for v in value]
    if isinstance(value, (np.floating, float)):
        return float(value) if math.isfinite(float(value)) else None
    if isinstance(value, np.integer):
        return int(value)
    return value


def write_document(document: dict[str, Any], path: Path) -> Path:
    """Write an experiment's ``results.json``: ``document`` (its ``to_json()``) made JSON-safe
    (:func:`json_safe`), indented by 2, with a final newline."""
    path.write_text(json.dumps(json_safe(document), indent=2) + "\n", encoding="utf-8")
    return path


def write_json(result: DemoResult, path: Path) -> Path:
    """Write the UR5e experiment's ``results.json``."""
    return write_document(result.to_json(), path)
