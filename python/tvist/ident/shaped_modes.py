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
    :data:`MIN_IDENTIFIED_POSES` poses or more, and at :data:`MIN_IDENTIFIED_SHARE` or more
    of the poses where it can ring at the flange: those where its flange participation is
    :data:`MIN_PARTICIPATION` or more, or where it was identified.

A mode the campaign's excitations never made ring above noise is not shaped, whatever the
model predicts for it: its frequency is then the model's extrapolation (on the default twin
the stiff elbow's mode, 38-140 Hz, identified at 1 of the demo campaign's 36 poses, is
predicted 7 % RMS off). Its flange participation is reported so that a campaign which
excites it can be planned. Nor does a stiffness the fit determines without identifying
its mode suffice: on a 26-pose simulated campaign of ``family:ur5e:14`` whose records name
base and shoulder modes only, the elbow's stiffness came out with a 4 % standard error and
its mode 12.6 % RMS off the arm's true elbow mode.

The share is of the poses where the mode can ring, not of all poses, because a mode that
rings at the flange only in part of the workspace can only be identified there: on
``family:ur5e:3`` and ``:9`` the elbow's mode takes part at 16 of 30 poses (the folded ones)
and was identified at 5. Counted against all 30 poses (17 %) it was not shaped, and the
demo's Q1 -> Q3, which stops folded where the map gives that mode 3.7 % and 8.4 % of the
ringing, kept 98.80 % and 95.87 %; shaped (31 % of the 16), 99.49 % and 99.67 %, the third
lowest mode 3.4 % and 2.4 % RMS off (11 % and 5 % max) the arms' true modes at held-out
poses. On the FR3 twin's demo campaign the same rule shapes the modes of joints 2 and 3
too (the upper arm's roll and the elbow; 19 % and 13 % of all poses, 40 % and 22 % of those
where they ring): Q1 -> Q3 97.81 -> 99.17 % on the same records. The :data:`MIN_IDENTIFIED_POSES`
floor keeps a mode identified once or twice unshaped, however few poses it rings at.

**How many modes a map shapes.** A map shapes its ``K`` lowest eigenmodes (frequency-ranked,
``"shaped_modes": K``): the streaming shaper follows each of the ``K`` lowest along a motion
and per move shapes only the lowest ones that move makes ring
(:func:`tvist.maps.mode_choice.set_modes_for_move`). A physical mode does not keep its frequency
rank over the poses (on a 16-pose FR3 campaign the base mode is the lowest at 5 poses and the
fourth at 4, where it is a stiff 49-75 Hz mode with at most 17 % flange participation), so
the ``K`` lowest are not exactly the shaped modes at every pose. :func:`shaping_field`
chooses ``K`` by this rule:

    ``K`` is the smallest number such that (a) every shaped physical mode is among the ``K``
    lowest at :data:`MIN_RANK_SHARE` (half) of the campaign's poses or more, and (b) no
    higher eigenmode (rank above ``K``) is a shaped physical mode at half of the poses or
    more.

Each of the ``K`` filters tracks one frequency rank, and its frequency is the map's fitted one
where a shaped (identified) mode holds that rank and an extrapolation where an unshaped mode
does. Covering every shaped mode at every pose (``K`` its largest rank) can add a rank held
by an unshaped mode at most poses: on that FR3 campaign ``K`` would be 4, and the fourth
lowest is at 12 of the 16 poses the mode of joint index 2, identified at 12.5 % of the poses
and 11.6 % RMS off the twin's true mode (the rule: ``K = 3``). (b) keeps a rank that mostly
holds a shaped mode; (a) keeps every shaped mode shaped at most poses, even one whose rank
is spread over ranks mostly held by unshaped modes.

**What the rule costs, and what the map says about it.** At a pose where a shaped mode is
above the ``K`` lowest it is not shaped: a move ending there leaves its ringing (its share
of the flange's vibration there, its flange participation) unshaped, and the per-move choice
cannot add it (it shapes at most the ``K`` lowest). Where an unshaped mode is among the ``K``
lowest, a move that makes it ring has it shaped at the model's extrapolated frequency. The
map's report (:func:`with_coverage`, ``fit_statistics.physical_modes`` of the map) states
both per physical mode: ``among_shaped_at_poses``, the share of the campaign's poses at which
it is among the ``K`` lowest, and ``participation_outside``, its largest flange participation
at the poses where it is not. A map's frequency accuracy is checked by frequency rank over
its ``K`` lowest (:func:`tvist.sim.map_truth.ranked_mode_errors`, the generalization
harness): it says nothing of a shaped mode where that mode is above them, and
``among_shaped_at_poses`` says how often that is.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from scipy import optimize

__all__ = [
    "MIN_RANK_SHARE",
    "identified_often_enough",
    "identified_where_it_rings",
    "physical_index",
    "physical_modes",
    "shaping_field",
    "with_coverage",
]

#: Share of the poses where a mode can ring at the flange at which it must be identified to
#: be shaped (module docstring).
MIN_IDENTIFIED_SHARE = 0.2
#: Fewest poses at which a mode must be identified to be shaped: its stiffness law (a constant
#: and up to two load terms) is not determined by fewer.
MIN_IDENTIFIED_POSES = 3
#: Flange participation counted as significant in the report: 5 % of the residual vibration.
MIN_PARTICIPATION = 0.05
#: Share of the poses at which a shaped mode must be among the ``K`` lowest, and at which a
#: higher eigenmode must be a shaped mode to be shaped too: half (the module docstring).
MIN_RANK_SHARE = 0.5


def physical_index(shares: np.ndarray) -> np.ndarray:
    """``(n, m)``: at each pose, the eigenmode (frequency rank) of each flexible joint's
    physical mode (one to one, largest total strain-energy share)."""
    out = np.empty(shares.shape[:2], dtype=int)
    for p in range(shares.shape[0]):
        modes, joints = optimize.linear_sum_assignment(-shares[p])
        out[p, joints] = modes
    return out


def identified_where_it_rings(identified: np.ndarray, participates: np.ndarray) -> float:
    """The share of the poses where a physical mode can ring at the flange at which it was
    identified, from two flags per pose: ``identified`` (an identified mode was matched to
    it there) and ``participates`` (its flange participation is :data:`MIN_PARTICIPATION` or
    more there); 0 where it can ring nowhere."""
    identified = np.asarray(identified, dtype=bool)
    can_ring = np.count_nonzero(identified | np.asarray(participates, dtype=bool))
    return float(np.count_nonzero(identified) / can_ring) if can_ring else 0.0


def identified_often_enough(identified: np.ndarray, participates: np.ndarray) -> bool:
    """Whether a physical mode is shaped (the module docstring's rule), from the flags of
    :func:`identified_where_it_rings`."""
    # A small tolerance so that a share of exactly MIN_IDENTIFIED_SHARE (6 of 30) counts.
    share = identified_where_it_rings(identified, participates)
    count = int(np.count_nonzero(identified))
    return count >= MIN_IDENTIFIED_POSES and share >= MIN_IDENTIFIED_SHARE - 1e-9


def physical_modes(fit: Any) -> list[dict[str, Any]]:
    """Per flexible coordinate of ``fit`` (:class:`tvist.ident.all_modes_fit.AllModesFit`),
    its physical mode: ``name`` (``"joint 1"``, ``"link 2 bending (axis 0)"``), ``joint``
    (or ``link`` and ``axis`` for a bending link), ``freq_hz`` (min, median, max over the poses),
    ``frequency_rank`` (max, 1-based), ``rank_share`` (per frequency rank 1, 2, …: the share of
    the poses at which the mode has that rank), ``participation_by_rank`` (per rank: its
    largest flange participation at those poses, 0 at none), ``flange_participation``
    (median, max), ``participates_at_poses`` (share of poses with a participation of
    :data:`MIN_PARTICIPATION` or more), ``identified_at_poses`` (share of poses),
    ``identified_where_it_rings`` (share of the poses where it participates or was
    identified), ``shaped`` (:func:`identified_often_enough`)."""
    modes = fit.model_modes()
    obs = fit.observed
    index = physical_index(modes.joint_shares)  # (n, m): eigenmode of each joint's mode
    n, m = index.shape
    used = fit.assignment >= 0
    out = []
    for k, name in enumerate(fit.coordinate_names()):
        rank = index[:, k]
        freq = modes.wn_rad_s[np.arange(n), rank] / (2 * np.pi)
        part = modes.flange_participation[np.arange(n), rank]
        hit = used & (fit.assignment == rank[obs.pose].clip(min=0))
        identified = np.zeros(n, dtype=bool)
        identified[obs.pose[hit]] = True
        participates = part >= MIN_PARTICIPATION
        by_rank = np.zeros(m)
        np.maximum.at(by_rank, rank, part)
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
                "rank_share": [float(v) for v in np.bincount(rank, minlength=m) / n],
                "participation_by_rank": [float(v) for v in by_rank],
                "flange_participation": [float(np.median(part)), float(part.max())],
                "participates_at_poses": float(np.mean(participates)),
                "identified_at_poses": float(np.mean(identified)),
                "identified_where_it_rings": identified_where_it_rings(identified, participates),
                "shaped": identified_often_enough(identified, participates),
            }
        )
    return out


def shaping_field(report: list[dict[str, Any]]) -> dict[str, Any]:
    """The map file's field naming the shaped modes of ``report`` (:func:`physical_modes`):
    ``{"shaped_modes": K}``, the frequency-ranked form, ``K`` by the module docstring's rule
    (:data:`MIN_RANK_SHARE`) from each mode's ``rank_share``.

    The one place that chooses the field. Frequency-ranked because the streaming shaper then
    follows each of the ``K`` lowest eigenmodes along a motion (two that cross or veer keep
    their filters) and shapes per move only the lowest ones that move makes ring
    (:func:`tvist.maps.mode_choice.set_modes_for_move`, at most ``K``); a joint-named mode would
    follow the one eigenmode that strains its joint most, which can be another far-apart one
    at the next pose. Raises ``ValueError`` if no mode was identified often enough.
    """
    shaped = np.array([m["rank_share"] for m in report if m["shaped"]], dtype=float)
    if shaped.size == 0:
        raise ValueError(
            f"no mode was identified at {MIN_IDENTIFIED_POSES} poses or more and at "
            f"{MIN_IDENTIFIED_SHARE:.0%} or more of the poses where it rings at the flange: "
            "nothing to shape (excite more poses, or check the records' ringing modes)"
        )
    # A small tolerance so that a share of exactly half, summed from 1/n terms, counts.
    tol = 1e-9
    among = np.cumsum(shaped, axis=1)  # (shaped mode, K - 1): share among the K lowest
    covering = int(np.argmax(np.all(among >= MIN_RANK_SHARE - tol, axis=0))) + 1
    held = shaped.sum(axis=0)  # per rank: share of the poses a shaped mode holds it
    mostly_shaped = np.flatnonzero(held >= MIN_RANK_SHARE - tol)
    k = max(covering, int(mostly_shaped[-1]) + 1 if mostly_shaped.size else 0)
    return {"shaped_modes": k}


def with_coverage(report: list[dict[str, Any]], k: int) -> list[dict[str, Any]]:
    """``report`` (:func:`physical_modes`) with what shaping the ``k`` lowest eigenmodes does
    to each physical mode over the campaign's poses: ``among_shaped_at_poses`` (the share of
    the poses at which it is among the ``k`` lowest: a shaped mode is left unshaped at the
    others, an unshaped mode is shaped at the model's extrapolated frequency at these when a
    move makes it ring) and ``participation_outside`` (its largest flange participation at the
    poses where it is above the ``k`` lowest, ``None`` if there are none)."""
    out = []
    for m in report:
        above = zip(m["participation_by_rank"][k:], m["rank_share"][k:], strict=True)
        left = [p for p, share in above if share > 0]
        inside = [share for share in m["rank_share"][:k] if share > 0]
        # Exactly 1 where the mode is never above the K lowest and exactly 0 where it is never
        # among them: a sum of the shares (each a count / n) can miss either by a rounding.
        among = 0.0 if not inside else 1.0 if not left else float(sum(inside))
        out.append(
            {
                **m,
                "among_shaped_at_poses": among,
                "participation_outside": max(left) if left else None,
            }
        )
    return out
