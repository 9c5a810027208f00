"""Recorded twin run with RTDE field names, and a small ur_rtde-style CSV writer."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

#: Vector length of the joint fields in :data:`RTDE_FIELDS`: one entry per joint (6 on a UR).
JOINTS = -1

#: RTDE fields of a :class:`SimRecord` in CSV column order, with their vector length
#: (0 = scalar, :data:`JOINTS` = one per joint). Vector fields are written as
#: ``name_0 .. name_{n-1}``.
RTDE_FIELDS: tuple[tuple[str, int], ...] = (
    ("timestamp", 0),
    ("target_q", JOINTS),
    ("target_qd", JOINTS),
    ("target_qdd", JOINTS),
    ("actual_q", JOINTS),
    ("actual_qd", JOINTS),
    ("actual_TCP_pose", 6),
    ("actual_tool_accelerometer", 3),
)


def csv_header(n_dof: int = 6) -> list[str]:
    """Column names of :meth:`SimRecord.to_csv` of an arm of ``n_dof`` joints, in order."""
    columns: list[str] = []
    for name, width in RTDE_FIELDS:
        width = n_dof if width == JOINTS else width
        columns.extend([name] if width == 0 else [f"{name}_{i}" for i in range(width)])
    return columns


@dataclass(frozen=True)
class SimRecord:
    """One simulated run sampled at the control rate; time along rows, RTDE field names.

    Attributes
    ----------
    timestamp
        Time since the start of the run (s), ``(n_samples,)``.
    target_q, target_qd, target_qdd
        Joint reference and its finite-difference derivatives (rad, rad/s, rad/s²),
        ``(n_samples, n_dof)``.
    actual_q, actual_qd
        Link-side joint angles and velocities (rad, rad/s), ``(n_samples, n_dof)``.
    actual_TCP_pose
        Flange pose in the base frame, UR convention ``[x, y, z, rx, ry, rz]`` (m, axis-angle
        rad), ``(n_samples, 6)``.
    actual_tool_accelerometer
        Specific force at the flange (acceleration minus gravity) in flange axes (m/s²),
        ``(n_samples, 3)``; at rest it reads ``R^T [0, 0, +g]``.
    deflection_rad
        Gear deflection ``q_motor - q_link`` (rad), ``(n_samples, n_dof)``; not an RTDE field
        and not written to CSV.
    """

    timestamp: np.ndarray
    target_q: np.ndarray
    target_qd: np.ndarray
    target_qdd: np.ndarray
    actual_q: np.ndarray
    actual_qd: np.ndarray
    actual_TCP_pose: np.ndarray  # noqa: N815 (RTDE field name)
    actual_tool_accelerometer: np.ndarray
    deflection_rad: np.ndarray

    @property
    def n_samples(self) -> int:
        """Number of samples."""
        return int(self.timestamp.shape[0])

    def as_table(self) -> np.ndarray:
        """All RTDE fields side by side in :func:`csv_header` order, ``(n_samples, n_cols)``."""
        parts = []
        n_dof = int(np.shape(self.target_q)[1])
        for name, width in RTDE_FIELDS:
            width = n_dof if width == JOINTS else width
            value = np.asarray(getattr(self, name), dtype=float)
            parts.append(value.reshape(-1, 1) if width == 0 else value.reshape(-1, width))
        return np.hstack(parts)

    def to_csv(self, path: str | Path) -> Path:
        """Write the record like ur_rtde's ``startFileRecording``: comma-separated, 6 decimals.

        Parameters
        ----------
        path
            Output file; parent folders must exist.

        Returns
        -------
        Path
            The written file.
        """
        table = self.as_table()
        if not np.all(np.isfinite(table)):
            raise ValueError("record contains NaN or infinite values; refusing to write it")
        out = Path(path)
        np.savetxt(
            out,
            table,
            fmt="%.6f",
            delimiter=",",
            header=",".join(csv_header(int(np.shape(self.target_q)[1]))),
            comments="",
        )
        return out
