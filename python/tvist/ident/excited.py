"""Which joints a mapping campaign excites at every pose (Algorithm 2, one joint at a time).

The base and the shoulder are always excited: their logs give each pose record's ``modes``
entries, the ones the paper's map reads (:data:`tvist.ident.pose.IDENTIFIED_JOINTS`). The
elbow is excited too by default: its log rings the elbow-dominated mode (the lowest at folded
poses, the third that rings after a long move) that a base or shoulder excitation barely
moves, as ``ringing`` entries for the modal fit. Wrist 1 may be added.

Joints are indices from the base (0). The names are a UR's (2 elbow, 3 wrist 1); on an arm
placed as its URDF places it (FR3, iiwa14) index 2 turns the upper arm about its own axis
and its elbow is index 3.
"""

from __future__ import annotations

from collections.abc import Sequence

__all__ = ["EXCITABLE_JOINTS", "EXCITED_JOINTS", "excited_joints"]

#: Joints a campaign excites at every pose by default, in this order: base, shoulder, elbow.
EXCITED_JOINTS: tuple[int, ...] = (0, 1, 2)
#: Joints a campaign can excite: base, shoulder, elbow and wrist 1. Wrists 2 and 3 turn the
#: flange about axes through or near it (too little tangential acceleration to identify from).
EXCITABLE_JOINTS: tuple[int, ...] = (0, 1, 2, 3)


def excited_joints(joints: Sequence[int]) -> tuple[int, ...]:
    """``joints`` checked as a campaign's excited joints: sorted, without repeats.

    Raises
    ------
    ValueError
        A joint outside :data:`EXCITABLE_JOINTS`, or the base (0) or the shoulder (1) left
        out (every pose record needs their modes).
    """
    out = tuple(sorted({int(j) for j in joints}))
    allowed = ", ".join(str(j) for j in EXCITABLE_JOINTS)
    bad = [j for j in out if j not in EXCITABLE_JOINTS]
    if bad:
        why = f"joint {bad[0]} cannot be excited"
    elif not {0, 1} <= set(out):
        why = "the base (0) and the shoulder (1) are always excited"
    else:
        return out
    raise ValueError(f"{why}: give joints among {allowed}, with 0 and 1")
