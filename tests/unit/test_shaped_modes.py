"""How many of its lowest eigenmodes an identified modal map shapes
(:func:`tvist.ident.shaped_modes.shaping_field`) and what the map's report says it costs
(:func:`tvist.ident.shaped_modes.with_coverage`), on physical-mode reports built from each
mode's frequency rank and flange participation at every pose of a campaign."""

from __future__ import annotations

import numpy as np
import pytest

from tvist.ident.shaped_modes import (
    MIN_IDENTIFIED_POSES,
    MIN_IDENTIFIED_SHARE,
    MIN_RANK_SHARE,
    identified_often_enough,
    identified_where_it_rings,
    shaping_field,
    with_coverage,
)


def _report(ranks: dict[str, str], shaped: set[str], participation=None) -> list[dict]:
    """A report of :func:`~tvist.ident.shaped_modes.physical_modes`' form (the fields the rule
    reads) from each mode's 1-based frequency rank per pose (one character per pose; at each
    pose the modes' ranks are a permutation) and, optionally, its flange participation per
    pose."""
    table = np.array([[int(c) for c in r] for r in ranks.values()])  # (mode, pose)
    m, n = table.shape
    assert all(sorted(table[:, p]) == list(range(1, m + 1)) for p in range(n))
    report = []
    for i, name in enumerate(ranks):
        part = np.ones(n) if participation is None else np.asarray(participation[name])
        report.append(
            {
                "name": name,
                "frequency_rank": int(table[i].max()),
                "rank_share": [float(np.mean(table[i] == r)) for r in range(1, m + 1)],
                "participation_by_rank": [
                    float(part[table[i] == r].max(initial=0.0)) for r in range(1, m + 1)
                ],
                "shaped": name in shaped,
            }
        )
    return report


#: The physical modes' frequency ranks at the 16 poses of the FR3 test campaign
#: (tests/integration/test_urdf_twin.py), as its fit's model gives them, and the base mode's flange
#: participation there. Joint index 2's mode was identified at 2 of the 16 poses: not shaped.
FR3_RANKS = {
    "joint 0": "3241211241422412",
    "joint 1": "1113122112131321",
    "joint 2": "4424444434244144",
    "joint 3": "2332333323313233",
}
FR3_BASE_PARTICIPATION = [
    0.04, 0.67, 0.17, 0.96, 0.78, 0.95, 0.89, 0.95, 0.00, 0.71, 0.13, 0.70, 0.85, 0.01, 0.98, 0.99
]  # fmt: skip


def test_a_rank_mostly_held_by_an_unshaped_mode_is_not_shaped_for_a_few_poses():
    """The FR3 campaign: the shaped base mode is the fourth lowest at 4 of 16 poses, the
    fourth lowest is the unshaped joint-2 mode at the 12 others. Covering the base mode at
    every pose would take K = 4 (its largest rank); the rule takes K = 3 and the report says
    at which share of the poses each mode is among the 3 lowest, and the base mode's largest
    participation where it is not (0.17, at the third pose)."""
    report = _report(
        FR3_RANKS,
        {"joint 0", "joint 1", "joint 3"},
        {**{k: np.zeros(16) for k in FR3_RANKS}, "joint 0": FR3_BASE_PARTICIPATION},
    )
    assert max(m["frequency_rank"] for m in report if m["shaped"]) == 4
    assert shaping_field(report) == {"shaped_modes": 3}
    covered = {m["name"]: m for m in with_coverage(report, 3)}
    assert covered["joint 0"]["among_shaped_at_poses"] == 12 / 16
    assert covered["joint 0"]["participation_outside"] == 0.17
    assert covered["joint 1"]["among_shaped_at_poses"] == 1.0
    assert covered["joint 1"]["participation_outside"] is None
    assert covered["joint 3"]["among_shaped_at_poses"] == 1.0
    assert covered["joint 2"]["among_shaped_at_poses"] == 4 / 16


def test_every_shaped_mode_stays_among_the_k_lowest_at_half_the_poses():
    """A shaped mode B spread over ranks 2-4 (4, 3 and 3 of 10 poses), ranks mostly held by
    unshaped modes C and D: no rank above the lowest is a shaped mode at half the poses, but
    dropping B would leave it unshaped everywhere; K = 3 keeps it at 7 of the 10 poses."""
    ranks = {
        "A": "1111111111",
        "B": "2222333444",
        "C": "3333222333",
        "D": "4444444222",
    }
    report = _report(ranks, {"A", "B"})
    assert shaping_field(report) == {"shaped_modes": 3}
    b = next(m for m in with_coverage(report, 3) if m["name"] == "B")
    assert b["among_shaped_at_poses"] == pytest.approx(0.7)


def test_a_rank_mostly_held_by_shaped_modes_is_shaped():
    """Shaped B and C each among the 3 lowest at 6 of 10 poses ((a) alone: K = 3), and the
    fourth lowest is one of them at 8 of the 10 poses: K = 4 shapes both everywhere."""
    ranks = {
        "A": "1111111111",
        "B": "4444222222",
        "C": "3333444433",
        "D": "2222333344",
    }
    assert shaping_field(_report(ranks, {"A", "B", "C"})) == {"shaped_modes": 4}
    # Without C shaped, the fourth lowest holds a shaped mode at 4 poses: not shaped.
    assert shaping_field(_report(ranks, {"A", "B"})) == {"shaped_modes": 2}


def test_half_of_the_poses_is_enough():
    """:data:`MIN_RANK_SHARE` is reached at exactly half the poses (shares summed from
    1/n terms): the shaped mode B among the 2 lowest at 3 of 6 poses gives K = 2, at 2 of 6
    K = 3 (no higher rank is B's at half the poses in either)."""
    assert MIN_RANK_SHARE == 0.5
    half = {"A": "111111", "B": "222344", "C": "333422", "D": "444233"}
    assert shaping_field(_report(half, {"A", "B"})) == {"shaped_modes": 2}
    third = {"A": "111111", "B": "223344", "C": "332233", "D": "444422"}
    assert shaping_field(_report(third, {"A", "B"})) == {"shaped_modes": 3}
    # A rank held by a shaped mode at exactly half the poses is shaped too.
    tie = {"A": "111111", "B": "222333", "C": "333222"}
    assert shaping_field(_report(tie, {"A", "B"})) == {"shaped_modes": 3}


def _poses(n: int, *spans: tuple[int, int]) -> np.ndarray:
    """``n`` per-pose flags, set on each ``(start, stop)`` span."""
    flags = np.zeros(n, dtype=bool)
    for start, stop in spans:
        flags[start:stop] = True
    return flags


def test_a_mode_is_judged_by_the_poses_where_it_can_ring():
    """A mode that rings at the flange only at folded poses can only be identified there:
    ``family:ur5e:3``'s elbow mode, identified at 5 of 30 poses, takes part (participation
    5 % or more) at 16 of them. 5 of the 16 is shaped; the same 5 identifications of a mode
    that takes part at all 30 are not (17 %, below 20 %), nor are 2 identifications of a
    mode that rings at 4 poses (half of them, but below 3 poses)."""
    assert (MIN_IDENTIFIED_SHARE, MIN_IDENTIFIED_POSES) == (0.2, 3)
    identified = _poses(30, (0, 5))
    folded = _poses(30, (0, 16))
    assert identified_where_it_rings(identified, folded) == 5 / 16
    assert identified_often_enough(identified, folded)
    assert not identified_often_enough(identified, np.ones(30, dtype=bool))
    assert not identified_often_enough(_poses(30, (0, 2)), _poses(30, (0, 4)))
    assert identified_often_enough(_poses(30, (0, 3)), _poses(30, (0, 4)))


def test_identifications_where_the_model_sees_no_participation_still_count_as_poses():
    """The poses where a mode can ring are those where the model gives it 5 % of the
    flange's vibration *or* where it was identified: 3 identifications outside the 20 poses
    the model names are 3 of 23 (13 %), not 3 of 20; exactly 20 % (6 of 30) is enough."""
    outside = _poses(30, (0, 3))
    named = _poses(30, (10, 30))
    assert identified_where_it_rings(outside, named) == 3 / 23
    assert not identified_often_enough(outside, named)
    assert identified_often_enough(_poses(30, (0, 6)), np.ones(30, dtype=bool))
    assert identified_where_it_rings(np.zeros(30, dtype=bool), np.zeros(30, dtype=bool)) == 0.0


def test_a_map_with_no_shaped_mode_is_refused():
    with pytest.raises(ValueError, match="nothing to shape"):
        shaping_field(_report({"A": "12", "B": "21"}, set()))


def test_fit_map_prints_where_a_mode_is_not_where_its_shaping_wants_it():
    """``tvist fit-map --kind modal``'s line per physical mode: a shaped mode left out at some
    poses says at which share of the poses it is shaped and the participation left; an
    unshaped mode taken in says where; a mode where its shaping wants it adds nothing."""
    from tvist.cli.modal_fit import _coverage

    report = with_coverage(
        _report(
            FR3_RANKS,
            {"joint 0", "joint 1", "joint 3"},
            {**{k: np.zeros(16) for k in FR3_RANKS}, "joint 0": FR3_BASE_PARTICIPATION},
        ),
        3,
    )
    lines = {m["name"]: _coverage(m) for m in report}
    assert "at 75 % of the poses" in lines["joint 0"] and "up to 17 %" in lines["joint 0"]
    assert "at 25 % of the poses" in lines["joint 2"] and "extrapolated" in lines["joint 2"]
    assert lines["joint 1"] == lines["joint 3"] == ""


def test_shares_that_sum_to_one_only_up_to_rounding_count_as_every_pose():
    """A mode at ranks 1, 2 and 3 at 17, 10 and 3 of 30 poses: its shares (each a count / 30)
    sum to 0.9999999999999999 in floating point. With ``K = 3`` it is among the shaped lowest
    at every pose, with no participation left outside, and ``tvist fit-map`` says nothing of
    it; a mode never among them is at exactly none. (A campaign's records once made the
    first a shaped mode "among the shaped lowest at 100 % of the poses" with no participation
    outside, and ``tvist fit-map`` stopped on a ``TypeError``.)"""
    from tvist.cli.modal_fit import _coverage

    shares = [17 / 30, 10 / 30, 3 / 30, 0.0]
    assert sum(shares) != 1.0  # the rounding this test is about
    common = {"frequency_rank": 3, "participation_by_rank": [1.0, 1.0, 1.0, 0.0]}
    base = {"name": "A", "rank_share": shares, "shaped": True, **common}
    above = {
        "name": "B",
        "rank_share": [0.0, 0.0, 0.0, 1.0],
        "participation_by_rank": [0.0, 0.0, 0.0, 0.3],
        "frequency_rank": 4,
        "shaped": False,
    }
    a, b = with_coverage([base, above], 3)
    assert a["among_shaped_at_poses"] == 1.0 and a["participation_outside"] is None
    assert b["among_shaped_at_poses"] == 0.0 and b["participation_outside"] == 0.3
    assert _coverage(a) == "" and _coverage(b) == ""
