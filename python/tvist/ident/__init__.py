"""Identification of the arm's vibration modes: RTDE logs, excitation, preprocessing (eqs.
12-13), local transfer-function fit (eq. 17), dynamic-map fit and mapping campaigns."""

from __future__ import annotations

from tvist.ident.logs import LogWarning, Record, find_gaps, read_rtde_csv

__all__ = [
    "LogWarning",
    "Record",
    "find_gaps",
    "read_rtde_csv",
]
