"""The excitation segment of a log: where one joint is excited, without the moves around it.

A log recorded while an excitation program runs also holds what came before and after it:
the approach move to the pose (usually several joints at once, or the joint excited just
before returning to the pose) and rests. The excitation (paper Algorithm 2) is a series of
moves of *one* joint separated by short waits. So the log is cut into bouts of motion
separated by quiet stretches (:func:`~tvist.ident.preprocess.quiet_samples`); a bout is a
move of the excitation if it moves one joint only, by at most the width of Algorithm 2's
target range (``2 * MAX_DELTA_RAD``: a longer move of one joint is an approach); the
excitation is the longest run of consecutive such bouts of the same joint (the later one on
a tie: an excitation follows its approach). The
segment keeps at most :data:`MAX_REST_S` of the rest before its first move (the gravity
estimate's standstill) and after its last move (the last ringing).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from tvist.ident.excitation import MAX_DELTA_RAD
from tvist.ident.logs import Record
from tvist.ident.preprocess import QUIET_FRACTION, quiet_samples

__all__ = ["MAX_REST_S", "ExcitationSegment", "excitation_segment"]

#: The longest move of an excitation: between two targets of Algorithm 2's range, rad
#: (with 1 mrad for the 6 decimals of an exported program).
MAX_EXCITATION_SPAN_RAD = 2.0 * MAX_DELTA_RAD + 1e-3
#: Rest kept before the first and after the last move of the excitation, s: Algorithm 2's
#: longest wait (the ringing of a 20 Hz mode with ζ = 0.05 decays 100-fold in 0.7 s).
MAX_REST_S = 1.0


@dataclass(frozen=True)
class ExcitationSegment:
    """Rows ``[start, stop)`` of a log that hold the excitation of ``joint``.

    Attributes
    ----------
    joint
        The excited joint.
    start, stop
        First row and one past the last row of the segment.
    n_moves
        Bouts of motion of ``joint`` in the segment.
    n_rows
        Rows of the whole log.
    """

    joint: int
    start: int
    stop: int
    n_moves: int
    n_rows: int

    @property
    def trimmed(self) -> bool:
        """Whether the segment leaves rows of the log out."""
        return self.start > 0 or self.stop < self.n_rows

    def of(self, record: Record) -> Record:
        """The rows of ``record`` in the segment."""
        return record.select(slice(self.start, self.stop))


def _bouts(quiet: np.ndarray) -> list[tuple[int, int]]:
    """``[start, stop)`` of each run of non-quiet rows."""
    edges = np.flatnonzero(np.diff(np.r_[0, (~quiet).astype(np.int8), 0]))
    return [(int(a), int(b)) for a, b in zip(edges[::2], edges[1::2], strict=True)]


def excitation_segment(record: Record) -> ExcitationSegment:
    """Find the excitation in ``record`` (see the module docstring).

    Raises
    ------
    ValueError
        The target never moves, or no bout moves a single joint.
    """
    quiet = quiet_samples(record)
    bouts = _bouts(quiet)
    if not bouts:
        raise ValueError("the log's target never moves: no excitation in it")
    speed = np.abs(record.target_qd)
    # A joint takes part in a bout if its speed there exceeds the quiet threshold (a movej
    # moves every joint it changes; the others keep a speed of exactly 0).
    v_tol = QUIET_FRACTION * float(np.max(speed))
    labels = []
    for a, b in bouts:
        moving = np.flatnonzero(np.max(speed[a:b], axis=0) > v_tol)
        single = moving.size == 1
        if single:
            span = float(np.ptp(record.target_q[a:b, moving[0]]))
            single = span <= MAX_EXCITATION_SPAN_RAD
        labels.append(int(moving[0]) if single else None)
    runs: list[tuple[int, int, int]] = []  # (first bout, last bout, joint)
    for i, label in enumerate(labels):
        if label is None:
            continue
        if runs and runs[-1][2] == label and runs[-1][1] == i - 1:
            runs[-1] = (runs[-1][0], i, label)
        else:
            runs.append((i, i, label))
    if not runs:
        raise ValueError(
            "no move of a single joint in the log: every move turns several joints (an "
            "excitation moves one joint; give --joint to fit anyway)"
        )
    first, last, joint = max(runs, key=lambda r: (r[1] - r[0], r[0]))
    rest = max(1, int(round(MAX_REST_S / record.dt_s)))
    before = bouts[first - 1][1] if first > 0 else 0
    after = bouts[last + 1][0] if last + 1 < len(bouts) else record.n_samples
    start = max(before, bouts[first][0] - rest)
    stop = min(after, bouts[last][1] + rest)
    return ExcitationSegment(
        joint=joint, start=start, stop=stop, n_moves=last - first + 1, n_rows=record.n_samples
    )
