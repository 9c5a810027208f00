"""The physical modes of a fitted modal map, their participation at the flange, which to shape.

A *physical mode* is the eigenmode dominated by one flexible coordinate (at each pose the
modes and coordinates are paired one to one by strain-energy share), named by it: a joint, or
one axis of a bending link's hinge pair ("link 1 bending": the upper arm bending about the
axis parallel to its joint (axis 0) or across it (axis 1)). For each the
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

:func:`shaping_field` turns the report into the map file's field naming the shaped modes: the
``K`` lowest (frequency-ranked), ``K`` covering every shaped physical mode.
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
    """Per flexible coordinate of ``fit`` (:class:`tvist.ident.all_modes_fit.AllModesFit`),
    its physical mode: ``name`` (``"joint 1"``, ``"link 2 bending (axis 0)"``), ``joint``
    (or ``link`` and ``axis`` for a bending link), ``freq_hz`` (min, median, max over the poses),
    ``frequency_rank`` (max, 1-based), ``flange_participation`` (median, max),
    ``identified_at_poses`` (share of poses), ``shaped``."""
    modes = fit.model_modes()
    obs = fit.observed
    index = physical_index(modes.joint_shares)  # (n, m): eigenmode of each joint's mode
    n = obs.n_poses
    used = fit.assignment >= 0
    out = []
    for k, name in enumerate(fit.coordinate_names()):
        rank = index[:, k]
        freq = modes.wn_rad_s[np.arange(n), rank] / (2 * np.pi)
        part = modes.flange_participation[np.arange(n), rank]
        hit = used & (fit.assignment == rank[obs.pose].clip(min=0))
        identified = np.unique(obs.pose[hit]).size / n
        participates = float(np.mean(part >= MIN_PARTICIPATION))
        words = name.split()
        if words[0] == "joint":
            label: dict[str, Any] = {"joint": int(words[1])}
        else:  # "link l bending (axis a)"
            label = {"link": int(words[1]), "axis": int(words[-1].rstrip(")"))}
        out.append(
            {
                "name": name,
                **label,
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
    """The map file's field naming the shaped modes of ``report`` (:func:`physical_modes`):
    ``{"shaped_modes": K}``, the frequency-ranked form, with ``K`` the largest
    ``frequency_rank`` of the shaped physical modes: the ``K`` lowest eigenmodes then include
    every shaped physical mode at every pose of the campaign.

    The one place that chooses the field. Frequency-ranked because the streaming shaper then
    follows each of the ``K`` lowest eigenmodes along a motion (two that cross or veer keep
    their filters) and shapes per move only the lowest ones that move makes ring
    (:func:`tvist.modal_map.set_modes_for_move`, at most ``K``); a joint-named mode would
    follow the one eigenmode that strains its joint most, which can be another far-apart one
    at the next pose. Raises ``ValueError`` if no mode was identified often enough.
    """
    ranks = [m["frequency_rank"] for m in report if m["shaped"]]
    if not ranks:
        raise ValueError(
            f"no mode was identified at {MIN_IDENTIFIED_SHARE:.0%} of the poses or more: "
            "nothing to shape (excite more poses, or check the records' ringing modes)"
        )
    return {"shaped_modes": int(max(ranks))}
