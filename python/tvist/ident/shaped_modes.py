"""The physical modes of a fitted modal map, their participation at the flange, which to shape.

A *physical mode* is the eigenmode dominated by one flexible joint (at each pose the modes
and joints are paired one to one by strain-energy share), named by that joint. For each the
report gives its frequency range over the campaign's poses, its flange participation
(:attr:`tvist.ident.model_modes.ModelModes.flange_participation`: its share of the flange's
residual vibration after a stop), how many identified modes were matched to it, and
whether it should be shaped:

    a physical mode is shaped if it was identified (an identified mode matched to it) at
    :data:`MIN_IDENTIFIED_SHARE` of the poses or more.

A mode the campaign's excitations never made ring above noise is not shaped, whatever the
model predicts for it: its frequency is then the model's extrapolation (on the default twin
the stiff elbow's mode, 38-140 Hz, identified at 14 % of the demo campaign's poses, is
predicted 7 % RMS off). Its flange participation is reported so that a campaign which
excites it can be planned. Nor does a stiffness the fit determines without identifying
its mode suffice: on a 26-pose simulated campaign of ``family:ur5e:14`` whose records name
base and shoulder modes only, the elbow's stiffness came out with a 4 % standard error and
its mode 12.6 % RMS off the arm's true elbow mode.

:func:`shaping_field` turns the report into the map file's field naming the shaped modes:
by joint, or the K lowest as a set where a shaped mode climbs above an unshaped one.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from scipy import optimize

__all__ = ["physical_index", "physical_modes", "shaping_field"]

#: Share of the poses at which a mode must be identified to be shaped.
MIN_IDENTIFIED_SHARE = 0.2
#: Flange participation counted as significant in the report: 5 % of the residual vibration.
MIN_PARTICIPATION = 0.05


def physical_index(shares: np.ndarray) -> np.ndarray:
    """``(n, m)``: at each pose, the eigenmode (frequency rank) of each flexible joint's
    physical mode (one to one, largest total strain-energy share)."""
    out = np.empty(shares.shape[:2], dtype=int)
    for p in range(shares.shape[0]):
        modes, joints = optimize.linear_sum_assignment(-shares[p])
        out[p, joints] = modes
    return out


def physical_modes(fit: Any) -> list[dict[str, Any]]:
    """Per flexible joint of ``fit`` (:class:`tvist.ident.all_modes_fit.AllModesFit`), its
    physical mode: ``joint``, ``freq_hz`` (min, median, max over the poses),
    ``frequency_rank`` (max, 1-based), ``flange_participation`` (median, max),
    ``identified_at_poses`` (share of poses), ``shaped``."""
    modes = fit.model_modes()
    obs = fit.observed
    index = physical_index(modes.joint_shares)  # (n, m): eigenmode of each joint's mode
    n = obs.n_poses
    used = fit.assignment >= 0
    out = []
    for k, joint in enumerate(modes.flex_joints):
        rank = index[:, k]
        freq = modes.wn_rad_s[np.arange(n), rank] / (2 * np.pi)
        part = modes.flange_participation[np.arange(n), rank]
        hit = used & (fit.assignment == rank[obs.pose].clip(min=0))
        identified = np.unique(obs.pose[hit]).size / n
        participates = float(np.mean(part >= MIN_PARTICIPATION))
        out.append(
            {
                "joint": int(joint),
                "freq_hz": [float(freq.min()), float(np.median(freq)), float(freq.max())],
                "frequency_rank": int(rank.max()) + 1,
                "flange_participation": [float(np.median(part)), float(part.max())],
                "participates_at_poses": participates,
                "identified_at_poses": float(identified),
                "shaped": bool(identified >= MIN_IDENTIFIED_SHARE),
            }
        )
    return out


def shaping_field(report: list[dict[str, Any]]) -> dict[str, Any]:
    """The map file's field naming the shaped modes of ``report`` (:func:`physical_modes`).

    The one place that chooses the field. ``{"mode_joints": [joints of the shaped modes,
    ascending]}`` while the shaped physical modes are the lowest ones at every pose (each
    one's largest ``frequency_rank`` is at most their number ``K``): then naming them by
    joint shapes the K lowest modes, and keeps each filter on its mode where two cross. Where
    a shaped mode climbs above an unshaped one at some pose (on a 7-joint arm, the base mode
    at a pose where the arm stands over the base: 80 Hz and more, above the elbow's), the
    joint-named set would shape that high mode and leave a lower one ringing; the map then
    shapes the K lowest modes as a set, ``{"shaped_modes": K}``.
    """
    shaped = [m for m in report if m["shaped"]]
    joints = sorted(m["joint"] for m in shaped)
    if shaped and max(m["frequency_rank"] for m in shaped) > len(shaped):
        return {"shaped_modes": len(shaped)}
    return {"mode_joints": joints}
