"""The modes of a log at rest: the free decays after its stops, and the flag on a whole-log
fit that a gear stiffening under the moves' torque pulls away from them.

Two references: damped sinusoids written down exactly (the estimator's own model, to check
its standard errors), and excitation logs from :mod:`ringing_reference` in which a mode's
spring stiffens with deflection (``ë + 2ζω ė + ω² (e + κ e³) = -q̈``, integrated by DOP853
from every off-grid switch, written as ur_rtde CSV): the arm the estimator does not model.
"""

from __future__ import annotations

import math
import re
import warnings

import numpy as np
import pytest

from ringing_reference import TrueRinging, generate_ringing_log
from tvist.ident.free_decay import decay_windows, fit_free_decays
from tvist.ident.logs import read_rtde_csv
from tvist.ident.pose import identify_pose
from tvist.ident.ringing import AT_REST_REASON
from tvist.ident.segment import excitation_segment
from tvist.robots import Payload, Robot, params

Q_STRETCHED = np.array([0.0, -1.0, 1.3, -1.9, -1.57, 0.4])
ROBOT = Robot(params("ur5e"), Payload(0.0, (0.0, 0.0, 0.0)))
_T0 = ROBOT.jacobian(Q_STRETCHED)[:3, 0]
T0 = tuple(_T0 / np.linalg.norm(_T0))
DT = 0.002


def test_decay_windows_run_from_each_stop_to_the_next_move():
    u = np.zeros(400)
    u[50:80] = 3.0  # a move, stopped at 80
    u[200:230] = -3.0  # another, stopped at 230
    u[390:] = 1.0  # a last one still moving at the end: no window after it
    assert decay_windows(u, DT) == [(82, 200), (232, 390)]
    assert decay_windows(u, DT, lag=3) == [(85, 203), (235, 393)]
    # A window longer than max_window_s is cut; one shorter than min_samples dropped.
    assert decay_windows(u, DT, max_window_s=0.1) == [(82, 132), (232, 282)]
    assert decay_windows(u, DT, min_samples=200) == []


def _decays(rng, modes, n_windows=5, length=300, noise=0.05):
    """Exact free decays of ``modes`` ((ω, ζ) each) with random amplitudes and phases per
    window, an offset per window and white noise; the windows back to back."""
    tau = np.arange(length) * DT
    parts, windows = [], []
    for w in range(n_windows):
        y = np.full(length, rng.normal(0.0, 0.2))
        for wn, zeta in modes:
            wd = wn * math.sqrt(1 - zeta**2)
            amp, phase = rng.uniform(1.0, 4.0), rng.uniform(0, 2 * math.pi)
            y += amp * np.exp(-zeta * wn * tau) * np.cos(wd * tau + phase)
        parts.append(y + rng.normal(0.0, noise, length))
        windows.append((w * length, (w + 1) * length))
    return np.concatenate(parts), windows


def test_free_decay_standard_errors_cover_the_truth():
    """Two modes 1.4 x apart, started 4 % off: over 30 noise draws the frequency errors in
    standard errors have an RMS near 1 (0.6-1.6 allows the chi-square spread of 60 values
    and the Gauss-Newton approximation)."""
    truth = [(2 * math.pi * 9.0, 0.15), (2 * math.pi * 12.6, 0.08)]
    z = []
    for seed in range(30):
        y, windows = _decays(np.random.default_rng(seed), truth)
        fit = fit_free_decays(y, DT, windows, [(w * 1.04, zeta) for w, zeta in truth])
        assert fit is not None
        for (w_true, _), w, se in zip(truth, fit.wn_rad_s, fit.wn_se_rad_s, strict=True):
            z.append((w - w_true) / se)
    rms = float(np.sqrt(np.mean(np.square(z))))
    assert 0.6 < rms < 1.6, rms


def test_too_few_samples_give_no_fit():
    y, windows = _decays(np.random.default_rng(0), [(60.0, 0.1)], n_windows=1, length=8)
    assert fit_free_decays(y, DT, windows, [(60.0, 0.1)]) is None
    assert fit_free_decays(y, DT, [], [(60.0, 0.1)]) is None


def _base_log_record(tmp_path, stiffening: float, seed: int):
    modes = [
        TrueRinging(8.3, 0.12, T0, 0.7, stiffening=stiffening),
        TrueRinging(13.7, 0.10, (0.6, 0.0, 0.8), 0.12),
    ]
    path = generate_ringing_log(
        tmp_path / f"base_{stiffening:g}_{seed}.csv",
        seed=seed,
        joint=0,
        q0=Q_STRETCHED,
        modes=modes,
    )
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        record = read_rtde_csv(path)
    record = excitation_segment(record).of(record)
    return identify_pose(record, None, ROBOT, q=Q_STRETCHED)


def _at_rest_hz(reasons) -> float | None:
    for reason in reasons:
        if reason.startswith(AT_REST_REASON) or AT_REST_REASON in reason:
            return float(re.search(r"ring at ([0-9.]+) Hz", reason).group(1))
    return None


def _near_base(entries):
    return [m for m in entries if abs(m.fn_hz / 8.3 - 1) < 0.15]


@pytest.mark.slow
@pytest.mark.parametrize("seed", [3, 11, 12, 13])
def test_a_gear_stiffer_under_load_is_never_confident_off_its_mode_at_rest(tmp_path, seed):
    """A base mode whose spring is three times stiffer at rated deflection. The whole-log
    fits average the stiffer spring of the moves: some entry of the base mode comes out more
    than the 1.5 % floor above the small-signal 8.3 Hz (else this log would not test the
    check). No entry that far off stays confident. Where the multi-mode fit has no other
    doubt about the base mode (merged or unresolved neighbours), its frequency at rest is
    the small-signal one within 1 % (the 0.12 damping leaves 2-3 usable cycles per stop),
    and a flag quotes it."""
    record = _base_log_record(tmp_path, 3.0, seed)
    entries = [*_near_base(record.ringing), *_near_base([record.modes[0]])]
    assert max(m.fn_hz for m in entries) > 8.3 * 1.015, [m.fn_hz for m in entries]
    for mode in entries:
        if abs(mode.fn_hz / 8.3 - 1) > 0.015:
            assert mode.low_confidence, (mode.fn_hz, mode.reasons)
    undoubted = [
        m
        for m in _near_base(record.ringing)
        if all(r.startswith(AT_REST_REASON) for r in m.reasons)
    ]
    for mode in undoubted:
        at_rest_hz = mode.wn_at_rest_rad_s / (2 * math.pi)
        assert abs(at_rest_hz / 8.3 - 1) < 0.01, at_rest_hz
        if mode.low_confidence:
            assert _at_rest_hz(mode.reasons) == pytest.approx(at_rest_hz, abs=0.006)


@pytest.mark.slow
@pytest.mark.parametrize("seed", [3, 11, 12, 13])
def test_a_linear_gear_is_not_flagged(tmp_path, seed):
    """The same log with a linear spring: no entry carries the flag, and the confident base
    mode is the 8.3 Hz within 1 %."""
    record = _base_log_record(tmp_path, 1.0, seed)
    for mode in record.ringing:
        assert _at_rest_hz(mode.reasons) is None, mode.reasons
    entry = record.modes[0]
    assert not entry.low_confidence, entry.reasons
    assert abs(entry.fn_hz / 8.3 - 1) < 0.01, entry.fn_hz


def test_a_ringing_entry_round_trips_through_strict_json():
    """A frequency at rest that is missing (no decay window) or an infinite standard error (a
    fit at its bound) is written as null, never as NaN or Infinity, and read back as
    missing."""
    import json

    from tvist.ident.ringing import RingingMode

    mode = RingingMode(0, 52.0, 0.1, 0.2, 0.01, 3.0, (1.0, 0.0, 0.0), tangent_share=0.9)
    for at_rest, se in ((math.nan, math.nan), (51.0, math.inf)):
        entry = RingingMode(
            **{**mode.__dict__, "wn_at_rest_rad_s": at_rest, "wn_at_rest_se_rad_s": se}
        )
        back = RingingMode.from_dict(json.loads(json.dumps(entry.to_dict(), allow_nan=False)))
        for name, value in (("wn_at_rest_rad_s", at_rest), ("wn_at_rest_se_rad_s", se)):
            got = getattr(back, name)
            assert got == value if math.isfinite(value) else math.isnan(got), (name, got)


def test_only_a_whole_log_faster_than_at_rest_beyond_its_errors_is_not_the_arm_at_rest():
    """5 % faster than at rest, errors 0.2 %: flagged, the frequency at rest quoted; 5 %
    slower: not (a gear does not soften under load); 1 % faster: under the 1.5 % floor;
    4 % faster with 2 % standard errors: within 3 combined errors; no frequency at rest:
    nothing to say."""
    from tvist.ident.ringing import RingingMode, at_rest_reason

    def mode(at_rest, se):
        return RingingMode(
            0, 60.0, 0.1, 0.1, 0.01, 1.0, None, wn_at_rest_rad_s=at_rest, wn_at_rest_se_rad_s=se
        )

    reason = at_rest_reason(63.0, 0.12, mode(60.0, 0.12))
    assert reason is not None and reason.startswith(AT_REST_REASON)
    assert _at_rest_hz([reason]) == pytest.approx(60.0 / (2 * math.pi), abs=0.006)
    assert at_rest_reason(57.0, 0.12, mode(60.0, 0.12)) is None
    assert at_rest_reason(60.6, 0.06, mode(60.0, 0.06)) is None
    assert at_rest_reason(62.4, 1.25, mode(60.0, 1.2)) is None
    assert at_rest_reason(63.0, 0.12, mode(math.nan, math.nan)) is None
    assert at_rest_reason(63.0, 0.12, mode(60.0, math.inf)) is None
