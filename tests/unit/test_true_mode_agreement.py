"""The campaign summary's counts against the twin's true modes, on hand-made records."""

from __future__ import annotations

import math

from tvist.ident.true_mode_agreement import (
    JointAgreement,
    RingingAgreement,
    agreement,
    ringing_agreement,
    within_tolerance,
)


def _record(base_hz: float, base_true_hz: float, *, flagged: bool = False) -> dict:
    """A pose record: the base identified at ``base_hz`` (flagged or not), the shoulder
    exactly at its true 10 Hz; true modes as the twin stores them."""
    return {
        "modes": [
            {"joint": 0, "wn_rad_s": base_hz, "low_confidence": flagged},
            {"joint": 1, "wn_rad_s": 10.0},
        ],
        "true_modes": [
            {"joint": 0, "wn_rad_s": base_true_hz},
            {"joint": 1, "wn_rad_s": 10.0},
        ],
    }


def test_counts_split_by_tolerance_and_confidence():
    records = [
        _record(8.0, 8.0),  # right, confident
        _record(8.0, 8.0 / 1.029),  # 2.9 % off: within 3 %
        _record(8.0, 8.0 / 1.031),  # 3.1 % off, confident: wrong and confident
        _record(9.0, 8.0, flagged=True),  # 12.5 % off but flagged
        {"modes": [{"joint": 0, "wn_rad_s": 8.0}], "ringing": []},  # a real robot's: no truth
    ]
    records[-1]["modes"].append({"joint": 1, "wn_rad_s": 10.0})
    counts = agreement(records)
    assert counts["base"] == JointAgreement(within=2, compared=4, confident=3, confident_outside=1)
    assert counts["shoulder"] == JointAgreement(
        within=4, compared=4, confident=4, confident_outside=0
    )
    assert within_tolerance(records) == {"base": (2, 4), "shoulder": (4, 4)}


def test_a_joint_without_identification_is_left_out():
    record = _record(8.0, 8.0)
    record["modes"] = [m for m in record["modes"] if m["joint"] != 0]
    record["modes"].append({"joint": 0, "reason": "no ringing above noise"})  # no wn_rad_s
    assert set(agreement([record])) == {"shoulder"}


def _ringing(hz: float, *, flagged: bool = False) -> dict:
    return {"wn_rad_s": 2 * math.pi * hz, "low_confidence": flagged}


def test_ringing_modes_above_the_band_of_true_modes_are_not_counted_wrong():
    # True modes listed up to 60 Hz: 8 and 20 Hz. A confident 63 Hz mode (the stiff elbow's,
    # which the record does not list) cannot be judged, nor can 58.5 Hz (a true mode at
    # 60.2 Hz would be within 3 % of it and is not listed); 58.2 Hz can (58.2 * 1.03 <= 60)
    # and is wrong, as is 20.7 Hz (3.5 % off).
    record = {
        "true_modes": [{"freq_hz": 8.0}, {"freq_hz": 20.0}],
        "ringing": [
            _ringing(8.1),
            _ringing(20.7),
            _ringing(58.2),
            _ringing(58.5),
            _ringing(63.0),
            _ringing(30.0, flagged=True),
        ],
    }
    robot = {"ringing": [_ringing(40.0)]}  # a real robot's record: no truth, left out
    assert ringing_agreement([record, robot], band_hz=60.0) == RingingAgreement(
        modes=6, confident=5, compared=3, outside=2, above_band=2
    )
