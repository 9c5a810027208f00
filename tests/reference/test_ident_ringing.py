"""Every mode that rings: the pose record's ``ringing`` list, its flags, the checks across logs
and poses.

The logs come from :mod:`ringing_reference`: modes integrated exactly from an off-grid
profile, each moving the flange in its own direction, accelerometer sampled with timing
jitter and noise, written as ur_rtde CSV and read back (none of the estimator's
discretisation).
"""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest

from ringing_reference import TrueRinging, generate_ringing_log
from tvist.ident.batch import identify_logs
from tvist.ident.local_fit import LocalFit
from tvist.ident.logs import read_rtde_csv
from tvist.ident.pose import PoseRecord, _linked, identify_pose
from tvist.ident.pose_checks import JUMP_REASON, flag_jumps
from tvist.ident.ringing import RingingMode
from tvist.ident.segment import excitation_segment
from tvist.robots import Payload, Robot, params

#: A stretched pose (flange 0.7 m from the base axis), base tangent along y.
Q_STRETCHED = np.array([0.0, -1.0, 1.3, -1.9, -1.57, 0.4])
ROBOT = Robot(params("ur5e"), Payload(0.0, (0.0, 0.0, 0.0)))


def _identify(tmp_path, modes_by_log: dict[int, list[TrueRinging]], seed: int = 1):
    records = {}
    for joint, modes in modes_by_log.items():
        path = generate_ringing_log(
            tmp_path / f"log{joint}.csv",
            seed=seed + joint,
            joint=joint,
            q0=Q_STRETCHED,
            modes=modes,
        )
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            record = read_rtde_csv(path)
        records[joint] = excitation_segment(record).of(record)
    return identify_pose(records.get(0), records.get(1), ROBOT, q=Q_STRETCHED)


def _confident(record: PoseRecord, log_joint: int):
    return [m for m in record.ringing if m.log_joint == log_joint and not m.low_confidence]


def _angle_deg(a, b) -> float:
    return math.degrees(math.acos(min(abs(float(np.dot(a, b))), 1.0)))


#: The base joint's tangent at the flange (unit): the base mode moves the flange along it, the
#: way the base turns.
_T0 = ROBOT.jacobian(Q_STRETCHED)[:3, 0]
T0 = tuple(_T0 / np.linalg.norm(_T0))

THREE_MODES = [
    TrueRinging(8.3, 0.06, T0, 0.7),  # the base mode, along the base tangent
    TrueRinging(13.7, 0.10, (0.6, 0.0, 0.8), 0.12),  # in the arm's plane
    TrueRinging(24.1, 0.08, (0.2, 0.3, 0.93), 0.06),
]


@pytest.mark.slow
def test_every_ringing_mode_is_reported_with_its_direction(tmp_path):
    record = _identify(tmp_path, {0: THREE_MODES})
    found = [m for m in record.ringing if m.log_joint == 0]
    assert len(found) == 3, [(m.fn_hz, m.zeta, m.reasons) for m in found]
    # The two strong modes are confident; the third (6 % of the ringing's amplitude) may be
    # flagged weak, but is reported.
    assert not found[0].low_confidence and not found[1].low_confidence
    for true, mode in zip(THREE_MODES, found, strict=True):
        direction = np.array(true.direction) / np.linalg.norm(true.direction)
        if mode.low_confidence:
            # Reported, and near the true mode (3 %, 20°), but doubted.
            assert mode.fn_hz == pytest.approx(true.freq_hz, rel=0.03)
            assert _angle_deg(mode.flange_direction, direction) < 20.0
            continue
        # Frequency 1 % and ζ 15 %: the local fit's accuracy on independent logs is 1 % / 5 %
        # for one mode at 20 dB; modes sharing the log, with a stiff remainder the model
        # approximates to first order, widen the damping's error.
        assert mode.fn_hz == pytest.approx(true.freq_hz, rel=0.01)
        assert mode.zeta == pytest.approx(true.zeta, rel=0.15)
        # Direction within 10°: the mode turns ±10° with the base during the log.
        assert _angle_deg(mode.flange_direction, direction) < 10.0
        assert max(mode.flange_direction, key=abs) > 0  # sign convention
        assert mode.amplitude_m_s2 > 0
    data = record.to_dict()
    assert [e["log_joint"] for e in data["ringing"]] == [0, 0, 0]
    assert PoseRecord.from_dict(data).ringing == record.ringing
    # The base mode of ``modes`` is the ringing entry along the base tangent.
    base = data["modes"][0]
    assert base["ringing_index"] == 0


#: Two neighbours 16 % apart, heavily damped, moving the flange nearly the same way (the
#: situation of a base log at a folded pose), and a third mode; their directions tilt from the
#: tangent towards and away from the vertical, with gains that together carry the arm's lever
#: (0.72 m), so that little is left to the stiff remainder.
_UP = np.array([0.0, 0.0, 1.0])


def _tilted(degrees: float) -> tuple[float, float, float]:
    a = math.radians(degrees)
    return tuple(np.array(T0) * math.cos(a) + _UP * math.sin(a))


NEIGHBOURS = [
    TrueRinging(16.56, 0.170, T0, 0.436),
    TrueRinging(19.20, 0.129, _tilted(20.0), 0.25),
    TrueRinging(29.82, 0.290, _tilted(-60.0), 0.0987),
]


@pytest.mark.slow
@pytest.mark.parametrize("seed", [1, 2])
def test_merged_neighbours_are_never_confident_and_wrong(tmp_path, seed):
    record = _identify(tmp_path, {0: NEIGHBOURS}, seed=seed)
    true_hz = np.array([m.freq_hz for m in NEIGHBOURS])
    for mode in record.ringing:
        if mode.low_confidence:
            continue
        worst = float(np.min(np.abs(mode.fn_hz / true_hz - 1.0)))
        assert worst <= 0.03, (
            mode.fn_hz,
            mode.zeta,
            [(m.fn_hz, m.reasons) for m in record.ringing],
        )
    # The same holds for the paper map's base-mode entry.
    base = record.mode(0)
    if base is not None and not base.low_confidence:
        assert float(np.min(np.abs(base.fn_hz / true_hz - 1.0))) <= 0.03


@pytest.mark.slow
def test_a_mode_that_disagrees_between_the_logs_is_flagged(tmp_path):
    # The arm's mode at 11 Hz in the base log and 11.8 Hz (7 %) in the shoulder log.
    record = _identify(
        tmp_path,
        {
            0: [TrueRinging(11.0, 0.08, T0, 0.5)],
            1: [TrueRinging(11.8, 0.08, (0.6, 0.0, 0.8), 0.5)],
        },
    )
    base = [m for m in record.ringing if m.log_joint == 0]
    shoulder = [m for m in record.ringing if m.log_joint == 1]
    assert base and shoulder
    for mode in (
        min(base, key=lambda m: abs(m.fn_hz - 11.0)),
        min(shoulder, key=lambda m: abs(m.fn_hz - 11.8)),
    ):
        assert mode.low_confidence
        assert any("disagrees with the" in r for r in mode.reasons), mode.reasons


@pytest.mark.slow
def test_the_same_mode_in_both_logs_agrees(tmp_path):
    mode = TrueRinging(11.0, 0.08, (0.0, 0.6, 0.8), 0.4)
    record = _identify(tmp_path, {0: [mode], 1: [mode]})
    assert _confident(record, 0) and _confident(record, 1)


def _record(key, q1, modes_hz):
    return {
        "key": key,
        "q": [0.0, q1, 1.0, 0.0, 0.0, 0.0],
        "payload_kg": 5.0,
        "ringing": [
            {
                "log_joint": 0,
                "wn_rad_s": 2 * math.pi * f,
                "zeta": 0.1,
                "low_confidence": False,
                "reasons": [],
            }
            for f in modes_hz
        ],
    }


def test_a_mode_that_jumps_against_its_neighbouring_poses_is_flagged():
    # A mode that drifts 2 % per pose along a line of poses; one pose returns 20 % off.
    records = [_record(f"p{i}", -1.5 + 0.1 * i, [10.0 * 1.02**i]) for i in range(7)]
    records[3]["ringing"][0]["wn_rad_s"] *= 1.2
    flagged = flag_jumps(records)
    jumps = [r["key"] for r in flagged if r["ringing"][0]["low_confidence"]]
    assert jumps == ["p3"]
    assert flagged[3]["ringing"][0]["reasons"][0].startswith(JUMP_REASON)
    # Idempotent: checking again flags the same, once.
    again = flag_jumps(flagged)
    assert again == flagged


@pytest.mark.slow
def test_batch_identification_writes_ringing(tmp_path):
    paths = [
        generate_ringing_log(
            tmp_path / f"p_joint{j}.csv",
            seed=5 + j,
            joint=j,
            q0=Q_STRETCHED,
            modes=[TrueRinging(9.0, 0.07, T0, 0.5)],
        )
        for j in (0, 1)
    ]
    records = identify_logs(paths, payload_kg=0.0, workers=1)
    assert len(records) == 1
    ringing = records[0]["ringing"]
    assert {e["log_joint"] for e in ringing} == {0, 1}
    assert all(len(e["flange_direction"]) == 3 for e in ringing)


def _fit(joint: int, f_hz: float, rel_se: float) -> LocalFit:
    """A confident ``modes`` entry at ``f_hz`` with relative frequency standard error
    ``rel_se``."""
    wn = 2 * math.pi * f_hz
    return LocalFit(
        wn_rad_s=wn,
        zeta=0.1,
        k_a=1.0,
        k_b=wn**2,
        k_c=0.0,
        k_d=0.0,
        offset=0.0,
        delay_s=0.0,
        fit_percent=95.0,
        wn_se_rad_s=rel_se * wn,
        zeta_se=0.001,
        n_samples=4000,
        n_used=4000,
        low_confidence=False,
        joint=joint,
    )


def _ring(log_joint: int, f_hz: float, rel_se: float, direction, *reasons: str) -> RingingMode:
    wn = 2 * math.pi * f_hz
    return RingingMode(
        log_joint=log_joint,
        wn_rad_s=wn,
        zeta=0.1,
        wn_se_rad_s=rel_se * wn,
        zeta_se=0.002,
        amplitude_m_s2=5.0,
        flange_direction=direction,
        low_confidence=bool(reasons),
        reasons=tuple(reasons),
    )


#: Flange directions of the records below: the arm's vertical plane and the base tangent.
_UP = (0.0, 0.6, 0.8)
_SIDEWAYS = (1.0, 0.0, 0.0)
_MERGED = "merged neighbours: with one mode more it moves 1.5 % (to 8.00 Hz)"


def _shoulder_flags(partner: RingingMode, merged: str | None = _MERGED) -> tuple[str, ...]:
    """Reasons of a confident shoulder entry at 8.13 Hz (standard error 0.63 %) whose
    multi-mode fit finds it at 8.13 Hz (0.49 %), ``merged`` or not, with ``partner`` in the
    base log (the shoulder case of family:ur5e:4's 5 kg pose W4: true mode 7.85 Hz, the
    entry 3.5 % off)."""
    shoulder = _ring(1, 8.13, 0.0049, _UP, *(() if merged is None else (merged,)))
    modes = _linked({1: _fit(1, 8.13, 0.0063)}, [partner, shoulder])
    fit = modes[1]
    assert isinstance(fit, LocalFit)
    return fit.reasons if fit.low_confidence else ()


def test_a_merged_entry_another_log_resolves_elsewhere_is_flagged():
    # The base log resolves the same mode (same direction) 3.5 % lower: the shoulder log's
    # merged fit is the one pulled. A disagreement flag of its own does not disqualify it.
    base = _ring(0, 7.85, 0.0015, _UP, "disagrees with the shoulder log (3.5 %, ...)")
    reasons = _shoulder_flags(base)
    assert len(reasons) == 1 and reasons[0].startswith("merged in its log: the base log")
    # Not flagged: the log's fit does not call it merged; the other log's mode at that
    # frequency moves the flange another way (another mode, the base mode 7.6 % away in the
    # default twin's pose V0-R5); the other log agrees within the standard errors (0.4 %,
    # tolerance max(2 · 0.65 %, 1 %)); the other log's mode is merged too.
    assert _shoulder_flags(base, merged=None) == ()
    assert _shoulder_flags(_ring(0, 7.85, 0.0015, _SIDEWAYS)) == ()
    assert _shoulder_flags(_ring(0, 8.10, 0.0015, _UP)) == ()
    assert _shoulder_flags(_ring(0, 7.85, 0.0015, _UP, _MERGED)) == ()


def test_an_entry_whose_multi_mode_fit_leaves_the_frequency_uncertain_is_flagged():
    # family:ur5e:3's 5 kg pose V0-R12: the base entry at 7.41 Hz (standard error 0.20 %)
    # is 10 % from the true base mode (6.72 Hz); the multi-mode fit of the same log finds
    # it at 7.39 Hz with a standard error of 1.37 %, above the 1 % limit.
    uncertain = "uncertain frequency: standard error 1.37 % of ω_n"
    modes = _linked({0: _fit(0, 7.41, 0.0020)}, [_ring(0, 7.39, 0.0137, _UP, uncertain)])
    assert modes[0].low_confidence
    assert modes[0].reasons[-1].startswith("the multi-mode fit of the same log doubts it")
    resolved = _linked({0: _fit(0, 7.41, 0.0020)}, [_ring(0, 7.39, 0.005, _UP)])
    assert not resolved[0].low_confidence
