"""Which joints a mapping campaign excites at every pose (Algorithm 2, one joint at a time).

The base and the shoulder are always excited: their logs give each pose record's ``modes``
entries, the ones the paper's map reads (:data:`tvist.ident.pose.IDENTIFIED_JOINTS`). The
robot's elbow is excited too by default (:func:`default_excited_joints`): its log rings the
elbow-dominated mode (the lowest at folded poses, the third that rings after a long move)
that a base or shoulder excitation barely moves, as ``ringing`` entries for the modal fit.
Wrist 1 of a UR may be added.

Joints are indices from the base (0). Which one is the elbow is the robot's data
(:attr:`tvist.robots.RobotParams.elbow_joint`): 2 on a UR (3 wrist 1); 3 on an arm placed as
its URDF places it (FR3, iiwa14), whose joint 2 turns the upper arm about its own axis.
"""

from __future__ import annotations

from collections.abc import Sequence

__all__ = ["EXCITABLE_JOINTS", "default_excited_joints", "excited_joints"]

#: Joints a campaign can excite: base, shoulder, and on a UR elbow and wrist 1 (on an FR3 or
#: iiwa14 the upper-arm rotation and the elbow). Further joints turn the flange about axes
#: through or near it (too little tangential acceleration to identify from).
EXCITABLE_JOINTS: tuple[int, ...] = (0, 1, 2, 3)


def default_excited_joints(robot_name: str) -> tuple[int, ...]:
    """The joints a campaign on ``robot_name`` excites by default: base, shoulder and the
    robot's elbow (:attr:`~tvist.robots.RobotParams.elbow_joint`; a UR's ``(0, 1, 2)``, an
    FR3's or iiwa14's ``(0, 1, 3)``); base and shoulder alone for an arm without an elbow.

    Raises
    ------
    ValueError
        An unknown robot.
    """
    from tvist.robots import params

    elbow = params(robot_name).elbow_joint
    return (0, 1) if elbow is None else excited_joints((0, 1, elbow))


def excited_joints(joints: Sequence[int] | None, robot_name: str | None = None) -> tuple[int, ...]:
    """``joints`` checked as a campaign's excited joints: sorted, without repeats; ``None``:
    :func:`default_excited_joints` of ``robot_name``.

    Raises
    ------
    ValueError
        A joint outside :data:`EXCITABLE_JOINTS`, or the base (0) or the shoulder (1) left
        out (every pose record needs their modes); ``joints`` and ``robot_name`` both
        ``None``.
    """
    if joints is None:
        if robot_name is None:
            raise ValueError("excited joints: give the joints or the robot's name")
        return default_excited_joints(robot_name)
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
