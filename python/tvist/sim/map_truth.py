"""A modal map's shaped modes against a twin variant's true modes at given poses.

The true mode of a shaped mode named by joint ``j`` is the variant's eigenmode paired with
``j`` when the map's mode joints and the true modes below ``max_freq_hz`` are paired one to
one by strain-energy share (Hungarian assignment): the dominant eigenmode, never a blend.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
from scipy import optimize

from tvist.robots import Payload, Robot, params
from tvist.sim.family import Variant, modes_of

__all__ = ["map_frequency_errors", "true_mode_of_joints"]


def true_mode_of_joints(truth: Sequence[Any], joints: Sequence[int]) -> list[int | None]:
    """Index into ``truth`` (:class:`~tvist.sim.family.TrueMode` list) of the mode of each of
    ``joints`` (one to one by strain-energy share), ``None`` where there are fewer modes."""
    if not truth:
        return [None] * len(joints)
    shares = np.array([[m.joint_shares[j] for m in truth] for j in joints])
    rows, cols = optimize.linear_sum_assignment(-shares)
    out: list[int | None] = [None] * len(joints)
    for r, c in zip(rows, cols, strict=True):
        out[r] = int(c)
    return out


def map_frequency_errors(
    modal_map: Any,
    variant: Variant,
    poses: Sequence[tuple[str, np.ndarray, float, Sequence[float]]],
    *,
    max_freq_hz: float = 60.0,
) -> dict[int, np.ndarray]:
    """``{joint: relative frequency errors (n_poses,)}`` of each shaped mode of
    ``modal_map`` (:class:`tvist.ModalMap`, evaluated by the core) against ``variant``'s true
    mode of that joint at ``poses`` ``[(key, q, payload_kg, payload_com_m), ...]``; NaN
    where the variant has no such mode below ``max_freq_hz``."""
    joints = list(modal_map.mode_joints)
    out = {j: np.full(len(poses), np.nan) for j in joints}
    twins: dict[tuple, Any] = {}
    robots: dict[tuple, Robot] = {}
    for p, (_, q, payload_kg, com) in enumerate(poses):
        key = (float(payload_kg), tuple(float(v) for v in com))
        if key not in twins:
            twins[key] = variant.twin(payload_kg, com)
            robots[key] = Robot(params(variant.robot), Payload(*key))
        truth = modes_of(twins[key], q, max_freq_hz=max_freq_hz)
        predicted = modal_map.modes(robots[key], q)
        for j, index, (wn, _) in zip(
            joints, true_mode_of_joints(truth, joints), predicted, strict=True
        ):
            if index is not None:
                out[j][p] = wn / (2 * np.pi * truth[index].freq_hz) - 1.0
    return out
