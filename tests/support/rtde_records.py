"""Random RTDE records and the reader's format layer, for the log reader's tests.

The records are uniform random numbers in [-3, 3) on an e-Series clock, not a physical log:
they exercise the CSV writer and reader, never the physics.
"""

from __future__ import annotations

import numpy as np

from tvist.ident.logs import Record
from tvist.ident.logs import read_rtde_csv as read_rtde_log
from tvist.robots import params

DT_S = params("ur5e").control_period_s  # e-Series RTDE period, s (the robot data)
G_UP = np.array([0.0, 0.0, 9.81])  # reading of an accelerometer at rest, m/s²


def read_rtde_csv(path, **kwargs) -> Record:
    """The reader's format layer: these records are random numbers, not a physical log, so
    the unit check (tested in test_log_units.py) is off."""
    return read_rtde_log(path, check_units=False, **kwargs)


def make_record(
    n: int = 20, seed: int = 0, *, gravity: bool = False, with_pose: bool = True
) -> Record:
    """``n`` samples from 1000 s (RTDE timestamps count from controller start), every column
    drawn from ``default_rng(seed)`` in the order target q, qd, qdd, actual q, tool
    acceleration (plus :data:`G_UP` with ``gravity``), TCP pose (drawn last, skipped without
    ``with_pose``)."""
    rng = np.random.default_rng(seed)
    t = 1000.0 + DT_S * np.arange(n)

    def block(width: int) -> np.ndarray:
        return rng.uniform(-3.0, 3.0, size=(n, width))

    return Record(  # keyword arguments are evaluated in order: the draws follow it
        t_s=t,
        target_q=block(6),
        target_qd=block(6),
        target_qdd=block(6),
        actual_q=block(6),
        tool_accel=block(3) + G_UP if gravity else block(3),
        actual_TCP_pose=block(6) if with_pose else None,
    )
