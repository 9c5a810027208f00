"""Matching a file's or message's joint names to the robot's joint order.

Universal Robots arms use the ROS names ``shoulder_pan_joint … wrist_3_joint`` (often with a
prefix such as ``ur5e_``); generic files number their joints (``q0``, ``joint_1``,
``target_q_2``). :func:`joint_order` returns, for each robot joint, the column that holds it.
"""

from __future__ import annotations

import re
from collections.abc import Sequence

__all__ = ["UR_JOINT_NAMES", "joint_order"]

#: ROS joint names of a Universal Robots arm, base to wrist (the robot model's joint order).
UR_JOINT_NAMES: tuple[str, ...] = (
    "shoulder_pan_joint",
    "shoulder_lift_joint",
    "elbow_joint",
    "wrist_1_joint",
    "wrist_2_joint",
    "wrist_3_joint",
)

_NUMBERED = re.compile(r"^(.*?)(\d+)$")


def joint_order(names: Sequence[str], n_dof: int) -> tuple[list[int], str]:
    """Column of each robot joint ``0 … n_dof − 1`` among ``names``, and how it was matched.

    - UR names (any common prefix): by name;
    - names that share a prefix and end in distinct numbers (``q0 … q5``, ``joint_1 … 6``): by
      number (1-based numbering is recognised by its range);
    - otherwise, when there are exactly ``n_dof`` names: in the given order.

    Raises
    ------
    ValueError
        Duplicated names, a UR joint missing, or a number of columns that differs from
        ``n_dof`` without names to match.
    """
    names = [str(n).strip() for n in names]
    if len(set(names)) != len(names):
        dup = next(n for n in names if names.count(n) > 1)
        raise ValueError(f"joint name {dup!r} appears more than once")
    if n_dof == len(UR_JOINT_NAMES) and any(n.endswith(UR_JOINT_NAMES) for n in names):
        order = []
        for ur in UR_JOINT_NAMES:
            hits = [i for i, n in enumerate(names) if n == ur or n.endswith("_" + ur)]
            if len(hits) != 1:
                raise ValueError(
                    f"joint {ur!r} {'is missing' if not hits else 'matches several names'} in "
                    f"{names}"
                )
            order.append(hits[0])
        return order, "by UR joint name"
    numbered = [_NUMBERED.match(n) for n in names]
    if len(names) == n_dof and all(numbered):
        prefixes = {m.group(1) for m in numbered if m}
        numbers = [int(m.group(2)) for m in numbered if m]
        ranges = (list(range(n_dof)), list(range(1, n_dof + 1)))
        if len(prefixes) == 1 and sorted(numbers) in ranges:
            base = min(numbers)
            order = [numbers.index(base + j) for j in range(n_dof)]
            return order, "by joint number"
    if len(names) != n_dof:
        raise ValueError(f"{len(names)} joint columns {names} for a robot with {n_dof} joints")
    return list(range(n_dof)), "in file order"
