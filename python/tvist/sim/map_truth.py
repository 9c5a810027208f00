"""A modal map's modes against a twin variant's true modes at given poses.

Two views, both from the map's model (:func:`tvist.ident.model_modes.model_modes`: every
eigenmode, no blending):

- **by joint** (:func:`physical_mode_errors`): the map's physical mode of joint ``j`` (its
  eigenmode paired with ``j`` by strain-energy share, one to one) against the variant's
  mode paired with ``j`` likewise among all its modes;
- **by frequency rank** (:func:`ranked_mode_errors`): the map's ``k``-th lowest mode against
  the variant's mode matched to it by frequency and flange direction
  (:func:`tvist.ident.all_modes_fit.match_modes`' cost, one to one) among those below
  ``max_freq_hz``: what a frequency-ranked shaper (``"shaped_modes": K``) shapes.

NaN where the true mode is above ``max_freq_hz`` (or none matches).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
from scipy import optimize

from tvist.robots import Payload, Robot, params
from tvist.sim.family import Variant, modes_of

__all__ = ["held_out_poses", "physical_mode_errors", "ranked_mode_errors"]

Pose = tuple[str, np.ndarray, float, Sequence[float]]


def held_out_poses(robot_name: str = "ur5e", n: int = 20, seed: int = 5) -> list[Pose]:
    """``n`` poses unlike a campaign plan's: Algorithm 1's construction
    (:func:`tvist.ident.campaign.campaign_poses`) at radii, angles, payloads (0, 2.5, 5 kg)
    and wrist draws the plans do not use, ``n`` of them drawn (seeded)."""
    from tvist.ident.campaign import campaign_poses

    poses = campaign_poses(
        robot_name,
        payloads_kg=(0.0, 2.5, 5.0),
        angles_rad=(math.pi / 8, 3 * math.pi / 8, 5 * math.pi / 8),
        radii_m=(0.3, 0.5, 0.65, 0.78, 0.88),
        seed=77,
    )
    poses = [p for p in poses if p.q is not None]
    pick = np.random.default_rng(seed).choice(len(poses), n, replace=False)
    return [
        (poses[i].key, poses[i].q, poses[i].payload_kg, poses[i].payload_com_m)
        for i in sorted(pick)
    ]


def _each_pose(entries: Sequence[Mapping[str, Any]], variant: Variant, poses: Sequence[Pose]):
    """Per pose: the variant's true modes and the map model's modes (one pose)."""
    from tvist.ident.model_modes import model_modes

    cache: dict[tuple, tuple] = {}
    for _, q, payload_kg, com in poses:
        key = (float(payload_kg), tuple(float(v) for v in com))
        if key not in cache:
            cache[key] = (variant.twin(*key), Robot(params(variant.robot), Payload(*key)))
        twin, robot = cache[key]
        model = model_modes(
            entries,
            robot.mass_matrix(q)[None],
            robot.gravity_torque(q)[None],
            robot.jacobian(q)[None],
        )
        yield modes_of(twin, q), model


def physical_mode_errors(
    entries: Sequence[Mapping[str, Any]],
    variant: Variant,
    poses: Sequence[Pose],
    joints: Sequence[int],
    *,
    max_freq_hz: float = 60.0,
) -> dict[int, np.ndarray]:
    """``{joint: relative frequency errors (n_poses,)}`` by joint (module docstring) of the
    map with flexible joints ``entries``, for ``joints`` (flexible ones)."""
    from tvist.ident.shaped_modes import physical_index

    flex = [int(e["joint"]) for e in entries]
    out = {j: np.full(len(poses), np.nan) for j in joints}
    for p, (truth, model) in enumerate(_each_pose(entries, variant, poses)):
        rank = physical_index(model.joint_shares)[0]
        shares = np.array([[m.joint_shares[j] for m in truth] for j in flex])
        rows, cols = optimize.linear_sum_assignment(-shares)
        true_of = {flex[r]: truth[c] for r, c in zip(rows, cols, strict=True)}
        for j in joints:
            if j in true_of and true_of[j].freq_hz <= max_freq_hz:
                wn = model.wn_rad_s[0, rank[flex.index(j)]]
                out[j][p] = wn / (2 * math.pi * true_of[j].freq_hz) - 1.0
    return out


def ranked_mode_errors(
    entries: Sequence[Mapping[str, Any]],
    variant: Variant,
    poses: Sequence[Pose],
    n_modes: int,
    *,
    max_freq_hz: float = 60.0,
    damping: bool = False,
) -> np.ndarray:
    """``(n_modes, n_poses)`` relative frequency errors by frequency rank (module docstring)
    of the ``n_modes`` lowest modes of the map with flexible joints ``entries``; with
    ``damping``, the errors of their damping ratios instead (``ζ_map − ζ_true``, absolute)
    of the same pairs."""
    from tvist.ident.all_modes_fit import D_TOL, F_TOL, GATE

    out = np.full((n_modes, len(poses)), np.nan)
    for p, (truth, model) in enumerate(_each_pose(entries, variant, poses)):
        truth = [m for m in truth if m.freq_hz <= max_freq_hz]
        if not truth:
            continue
        f_true = 2 * math.pi * np.array([m.freq_hz for m in truth])
        d_true = np.array([m.flange_direction for m in truth])
        wn = model.wn_rad_s[0, :n_modes]
        cos = np.abs(model.flange_direction[0, :n_modes] @ d_true.T)
        cost = (np.log(wn[:, None] / f_true[None, :]) / F_TOL) ** 2
        cost += np.clip(1 - cos**2, 0, 1) / D_TOL**2
        rows, cols = optimize.linear_sum_assignment(np.nan_to_num(cost, nan=1e6))
        for r, c in zip(rows, cols, strict=True):
            if cost[r, c] <= GATE:
                out[r, p] = model.zeta[0, r] - truth[c].zeta if damping else wn[r] / f_true[c] - 1.0
    return out
