"""Local second-order fit (eq. 17): accuracy on independently generated data, the exact
sampled mode, and one test per low-confidence reason.

The data come from :func:`ident_reference.mode_signals`: an off-grid continuous profile and the
mode integrated exactly (not the estimator's held-input model); the full logs-to-modes
acceptance is in ``test_ident_independent.py``.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import signal

from ident_reference import mode_signals
from tvist.ident.local_fit import (
    NO_RINGING,
    FitOptions,
    LocalFit,
    fit_local,
    interval_mean_acceleration,
    saturated_samples,
)
from tvist.ident.zoh import zoh_responses


def _lsim_reference(
    wn: float, zeta: float, u: np.ndarray, dt: float, delay_s: float, fine: int
) -> list[np.ndarray]:
    """Responses of ``1 / (s² + 2ζω s + ω²)`` and ``s / (...)`` to the held input ``u``
    delayed by ``delay_s`` (``u[k]`` on ``[t_k, t_k+1)``, ``u[0]`` before the first sample),
    by scipy's lsim on a ``fine`` times finer grid, at the samples of ``u``. lsim is exact
    for a held input on its own grid."""
    den = [1, 2 * zeta * wn, wn**2]
    t_fine = dt / fine * np.arange(u.size * fine)
    index = np.floor((t_fine - delay_s) / dt + 1e-9).astype(int)
    u_fine = np.where(index < 0, u[0], u[np.clip(index, 0, u.size - 1)])
    return [
        signal.lsim(signal.lti(num, den), u_fine, t_fine, interp=False)[1][::fine]
        for num in ([1], [1, 0])
    ]


@pytest.mark.parametrize("delay_s", [0.0, 0.0013, -0.0031, 0.0040])
def test_zoh_responses_match_a_fine_grid_simulation(delay_s):
    """Exact sampled responses for any delay, against scipy's lsim on a 100x finer grid with
    the held input shifted by the delay (lsim is exact for a held input on its own grid)."""
    dt, fine = 0.002, 100
    rng = np.random.default_rng(2)
    u = np.repeat(rng.normal(0.0, 1.0, 40), 5)  # held values, changing every 5 samples
    wn, zeta = 2 * math.pi * 17.0, 0.07
    ours = zoh_responses(wn, zeta, u, dt, delay_s)
    for col, ref in enumerate(_lsim_reference(wn, zeta, u, dt, delay_s, fine)):
        np.testing.assert_allclose(ours[:, col], ref, atol=1e-9 * np.max(np.abs(ref)))


@pytest.mark.parametrize("zeta", [1.0, 1.0 - 3e-9, 1.0 + 3e-9, 1.0 - 3e-5, 1.0 + 3e-3])
def test_zoh_responses_at_and_near_critical_damping(zeta):
    """Where the two eigenvalues merge (|ζ² - 1| < 1e-8: the augmented matrix exponential) and
    just outside it (nearly equal eigenvalues in Sylvester's formula), against the same
    fine-grid lsim reference."""
    dt, fine, delay_s = 0.002, 100, 0.0013
    rng = np.random.default_rng(5)
    u = np.repeat(rng.normal(0.0, 1.0, 40), 5)
    wn = 2 * math.pi * 9.0
    ours = zoh_responses(wn, zeta, u, dt, delay_s)
    for col, ref in enumerate(_lsim_reference(wn, zeta, u, dt, delay_s, fine)):
        np.testing.assert_allclose(ours[:, col], ref, atol=1e-9 * np.max(np.abs(ref)))


@pytest.mark.parametrize("lag_s", [-0.0015, 0.0037])
def test_gain_and_a_timing_offset_of_either_sign(lag_s):
    """Noise-free data whose sensor lags (or leads) the logged target by a fraction of a
    sample: mode, DC gain and the sign of the offset are recovered."""
    wn, zeta, radius = 2 * math.pi * 20.0, 0.05, 0.6
    u, y, dt = mode_signals(9, wn, zeta, snr_db=None, radius_m=radius, sensor_lag_s=lag_s)
    fit = fit_local(u, y, dt)
    # Left: held interval means within intervals that contain a switch (~1e-4, measured).
    assert fit.wn_rad_s == pytest.approx(wn, rel=1e-3)
    assert fit.zeta == pytest.approx(zeta, rel=5e-3)
    assert fit.k_b / fit.k_d == pytest.approx(radius, rel=5e-3)  # DC gain is the radius
    # The offset trades against the numerator's zero (k_a), so it is found to within about a
    # sample, with the right sign.
    assert fit.delay_s == pytest.approx(lag_s, abs=1.2 * dt)
    assert math.copysign(1.0, fit.delay_s) == math.copysign(1.0, lag_s)
    assert fit.fit_percent > 99.0 and not fit.low_confidence


def test_two_modes_fit_the_dominant_one():
    w1, w2 = 2 * math.pi * 12.0, 2 * math.pi * 30.0
    u, y1, dt = mode_signals(4, w1, 0.05, snr_db=None, radius_m=0.5)
    _, y2, _ = mode_signals(4, w2, 0.1, snr_db=None, radius_m=0.1)
    fit = fit_local(u, y1 + y2, dt)
    # the weaker 30 Hz mode biases the single-mode fit slightly; 1 % as in the acceptance
    assert fit.wn_rad_s == pytest.approx(w1, rel=0.01)


def test_too_short_log_is_an_error():
    u, y, dt = mode_signals(0, 2 * math.pi * 10.0, 0.1)
    with pytest.raises(ValueError, match="too short"):
        fit_local(u[:300], y[:300], dt)


def test_no_excitation_is_an_error():
    rng = np.random.default_rng(0)
    with pytest.raises(ValueError, match="no excitation"):
        fit_local(np.zeros(4000), rng.normal(size=4000), 0.002)


@pytest.mark.parametrize("dt_s", [0.0, -0.002, math.nan, math.inf])
def test_the_sampling_period_must_be_positive_and_finite(dt_s):
    u, y, _ = mode_signals(0, 2 * math.pi * 10.0, 0.1, snr_db=None, duration_s=2.0)
    with pytest.raises(ValueError, match="dt_s must be finite and > 0"):
        fit_local(u, y, dt_s)


def test_fit_percent_is_the_nrmse_about_the_mean_of_the_response():
    """A constant offset in ψ (the standstill gravity estimate is never exact) changes neither
    the fit nor its NRMSE, which compares the residual with the response's spread about its
    mean. Reference: the textbook NRMSE with the added white noise as the residual."""
    u, clean, dt = mode_signals(4, 2 * math.pi * 15.0, 0.05, snr_db=None)
    rng = np.random.default_rng(4)
    noise = rng.normal(0.0, 0.2 * np.std(clean), clean.size)
    for offset in (0.0, 5.0 * np.std(clean)):
        y = clean + noise + offset
        fit = fit_local(u, y, dt)
        expected = 100.0 * (1.0 - np.linalg.norm(noise) / np.linalg.norm(y - y.mean()))
        # The fit absorbs a share ~6/n of the noise energy (6 parameters, 4000 samples) and the
        # noise's own mean and correlation with ψ: well under 0.5 percentage points of ~80 %.
        assert fit.fit_percent == pytest.approx(expected, abs=0.5), offset
        assert fit.offset == pytest.approx(offset, abs=0.05 * np.std(clean))


def lightly_damped_fit(field_values: dict) -> LocalFit:
    base = dict(
        wn_rad_s=2 * math.pi * 10.0,
        zeta=0.05,
        k_a=0.0,
        k_b=1.0,
        k_c=2 * 0.05 * 2 * math.pi * 10.0,
        k_d=(2 * math.pi * 10.0) ** 2,
        offset=0.0,
        delay_s=0.0,
        fit_percent=90.0,
        wn_se_rad_s=0.1,
        zeta_se=0.001,
        n_samples=4000,
        n_used=4000,
        low_confidence=False,
    )
    return LocalFit(**{**base, **field_values})


def test_damped_natural_frequency():
    # ζ = 0.6: √(1 - ζ²) = 0.8 exactly; from ζ = 1 on there is no oscillation (NaN).
    assert lightly_damped_fit({"zeta": 0.6}).fd_hz == pytest.approx(8.0, rel=1e-12)
    assert lightly_damped_fit({"zeta": 0.0}).fd_hz == pytest.approx(10.0, rel=1e-12)
    for zeta in (1.0, 1.2, 1.9):
        assert math.isnan(lightly_damped_fit({"zeta": zeta}).fd_hz), zeta


# One case per low-confidence reason; each asserts its own reason (others may come along).


def reasons_of(fit: LocalFit, prefix: str) -> list[str]:
    return [r for r in fit.reasons if r.startswith(prefix)]


def test_a_rigid_arm_is_reported_as_no_ringing():
    u, _, dt = mode_signals(1, 2 * math.pi * 15.0, 0.05, snr_db=None)
    rng = np.random.default_rng(3)
    y = 0.5 * u + rng.normal(0.0, 0.05 * np.std(0.5 * u), u.size)  # ψ = r q̈, no resonance
    fit = fit_local(u, y, dt)
    assert fit.low_confidence and fit.no_ringing
    assert reasons_of(fit, NO_RINGING)


def test_ringing_snr_follows_the_noise_level_and_ignores_the_units():
    """The ringing SNR is an energy ratio: 20 dB more white noise on the same response lowers
    it by 20 dB, and a change of units (ψ x 1000) leaves it unchanged. Tolerance 1.5 dB: the
    residual is the noise less the small share the fit absorbs, and the excess of the rigid
    residual over it is the mode's ringing (the same in both cases) to within its
    correlation with the noise."""
    u, clean, dt = mode_signals(1, 2 * math.pi * 15.0, 0.05, snr_db=None)
    rng = np.random.default_rng(11)
    noise = rng.normal(0.0, 0.01 * np.std(clean), clean.size)
    quiet, noisy = (fit_local(u, clean + k * noise, dt) for k in (1.0, 10.0))
    assert quiet.ringing_snr_db - noisy.ringing_snr_db == pytest.approx(20.0, abs=1.5)
    scaled = fit_local(u, 1000.0 * (clean + 10.0 * noise), dt)
    assert scaled.ringing_snr_db == pytest.approx(noisy.ringing_snr_db, abs=0.01)


def test_interval_mean_acceleration_integrates_to_the_logged_velocities():
    # qd(t) = t² (q̈ = 2t): the mean over [t_k, t_k+1] is 2 t_k + dt; the last sample repeats
    # the one before (there is no next velocity).
    dt = 0.002
    t = dt * np.arange(7)
    mean = interval_mean_acceleration(t**2, dt)
    np.testing.assert_allclose(mean[:-1], 2.0 * t[:-1] + dt, rtol=1e-9)
    assert mean[-1] == mean[-2]
    np.testing.assert_allclose(np.cumsum(mean[:-1]) * dt, t[1:] ** 2, rtol=1e-9)


def test_a_clear_mode_is_not_reported_as_no_ringing():
    u, y, dt = mode_signals(1, 2 * math.pi * 15.0, 0.05, snr_db=20.0)
    fit = fit_local(u, y, dt)
    assert not fit.no_ringing and not fit.low_confidence, fit.reasons
    assert fit.ringing_snr_db > 10.0  # measured 17 dB


def test_noise_bigger_than_the_signal_is_a_poor_fit():
    u, y, dt = mode_signals(2, 2 * math.pi * 15.0, 0.05, snr_db=-3.0)
    fit = fit_local(u, y, dt)
    assert reasons_of(fit, "poor fit"), fit.reasons  # measured 18 % < 50 %


def test_an_ill_determined_frequency_is_flagged():
    # 1.5 s of a heavily damped 6 Hz mode at 3 dB: standard error ~3 % of ω_n (limit 1 %).
    u, y, dt = mode_signals(4, 2 * math.pi * 6.0, 0.4, snr_db=3.0, duration_s=1.5)
    fit = fit_local(u, y, dt)
    assert reasons_of(fit, "uncertain frequency"), fit.reasons
    assert 0.01 < fit.wn_se_rad_s / fit.wn_rad_s < 0.2


def test_an_ill_determined_damping_is_flagged():
    # 3 s of a 30 Hz mode, ζ 0.35, at 0 dB: standard error of ζ ~0.05 (limit 10 % of ζ).
    u, y, dt = mode_signals(5, 2 * math.pi * 30.0, 0.35, snr_db=0.0, duration_s=3.0)
    fit = fit_local(u, y, dt)
    assert reasons_of(fit, "uncertain damping"), fit.reasons
    assert 0.1 * fit.zeta < fit.zeta_se < 0.5


def test_the_damping_error_has_an_absolute_floor():
    """A lightly damped mode is flagged for its damping only when the standard error of ζ
    exceeds both 10 % of ζ and 0.005 (FitOptions.max_zeta_rel_se): 2 s of a 15 Hz mode with
    ζ = 0.02 at 0 dB and at -6 dB SNR, standard errors 0.0029 and 0.0056 (measured), both
    above 10 % of ζ."""
    u, y_0db, dt = mode_signals(1, 2 * math.pi * 15.0, 0.02, snr_db=0.0, duration_s=2.0)
    _, y_6db, _ = mode_signals(1, 2 * math.pi * 15.0, 0.02, snr_db=-6.0, duration_s=2.0)
    below, above = fit_local(u, y_0db, dt), fit_local(u, y_6db, dt)
    for fit in (below, above):
        assert fit.zeta_se > 0.1 * fit.zeta  # the relative limit alone would flag both
    # the cases sit on either side of the floor, and not near a relative threshold's scale
    assert 0.002 < below.zeta_se < 0.004 and 0.0052 < above.zeta_se < 0.007
    assert not reasons_of(below, "uncertain damping"), below.reasons
    assert reasons_of(above, "uncertain damping"), above.reasons


def test_a_mode_above_the_band_is_flagged_at_its_edge():
    u, y, dt = mode_signals(6, 2 * math.pi * 60.0, 0.05, snr_db=30.0)
    fit = fit_local(u, y, dt, options=FitOptions(f_max_hz=40.0))
    assert reasons_of(fit, "frequency 40.00 Hz at the edge of the searched band 1.00-40.00 Hz"), (
        fit.reasons
    )


def test_an_overdamped_response_is_flagged():
    u, y, dt = mode_signals(8, 2 * math.pi * 15.0, 1.5, snr_db=20.0)
    fit = fit_local(u, y, dt)
    assert reasons_of(fit, "overdamped"), fit.reasons


def test_an_undamped_mode_is_flagged_at_the_damping_bound():
    u, y, dt = mode_signals(7, 2 * math.pi * 15.0, 0.0, snr_db=None)
    fit = fit_local(u, y, dt)
    assert fit.wn_rad_s == pytest.approx(2 * math.pi * 15.0, rel=1e-3)
    assert fit.reasons == ("damping at the lower search bound",)


def test_a_single_move_is_weak_excitation():
    u, y, dt = mode_signals(9, 2 * math.pi * 15.0, 0.1, snr_db=30.0, max_moves=1, tail_s=1.0)
    fit = fit_local(u, y, dt)
    assert fit.wn_rad_s == pytest.approx(2 * math.pi * 15.0, rel=0.01)
    assert fit.reasons == (
        f"weak excitation: only {fit.reasons[0].split()[-3]} acceleration changes",
    )


def test_local_fit_round_trips_through_its_dict():
    import json

    from tvist.ident.two_mode import fit_two_modes

    w1, w2 = 2 * math.pi * 12.0, 2 * math.pi * 22.0
    u, y1, dt = mode_signals(8, w1, 0.15, snr_db=None, radius_m=0.2)
    _, y2, _ = mode_signals(8, w2, 0.35, snr_db=20.0, radius_m=0.5)
    single = fit_local(u, y1 + y2, dt, joint=0)
    fit = LocalFit(**{**single.__dict__, "two_mode": fit_two_modes(u, y1 + y2, dt, single)})
    text = json.dumps(fit.to_dict())
    assert LocalFit.from_dict(json.loads(text)) == fit
    with pytest.raises(ValueError, match="lacks wn_rad_s"):
        LocalFit.from_dict({k: v for k, v in fit.to_dict().items() if k != "wn_rad_s"})


def test_saturated_samples_are_detected():
    rng = np.random.default_rng(0)
    clean = np.column_stack(
        [rng.normal(0, 3, 2000), rng.normal(0, 3, 2000), 9.81 + rng.normal(0, 1, 2000)]
    )
    assert not saturated_samples(clean).any()
    clipped = clean.copy()
    clipped[:, 0] = np.clip(clipped[:, 0], -5.0, 5.0)
    mask = saturated_samples(clipped)
    np.testing.assert_array_equal(mask, np.abs(clean[:, 0]) >= 5.0)
    # a known range marks readings at or beyond it
    np.testing.assert_array_equal(
        saturated_samples(clean, limit_m_s2=8.0), np.any(np.abs(clean) >= 8.0, axis=1)
    )


def test_two_mode_fit_separates_a_damped_mode_hidden_behind_a_light_one():
    """The twin's V = π/4 situation: a light 12 Hz mode and a heavily damped 22 Hz mode."""
    from tvist.ident.two_mode import fit_two_modes

    w1, z1, w2, z2 = 2 * math.pi * 12.0, 0.15, 2 * math.pi * 22.0, 0.35
    u, y1, dt = mode_signals(8, w1, z1, snr_db=None, radius_m=0.2)
    _, y2, _ = mode_signals(8, w2, z2, snr_db=None, radius_m=0.5)
    y = y1 + y2
    rng = np.random.default_rng(8)
    y += rng.normal(0.0, np.sqrt(np.mean(y**2)) / 10.0, y.size)  # 20 dB SNR
    single = fit_local(u, y, dt)
    # the single mode is a blend, off both true modes by more than 3 %
    assert min(abs(single.wn_rad_s / w - 1) for w in (w1, w2)) > 0.03
    split = fit_two_modes(u, y, dt, single)
    assert split.significant
    low, high = split.modes
    # Two modes share the information: 2 % in frequency, 15 % in damping.
    assert low.wn_rad_s == pytest.approx(w1, rel=0.02)
    assert high.wn_rad_s == pytest.approx(w2, rel=0.02)
    assert low.zeta == pytest.approx(z1, rel=0.15)
    assert high.zeta == pytest.approx(z2, rel=0.15)
    assert low.energy_share + high.energy_share == pytest.approx(1.0)
    assert split.away_from(w1) is high


def test_two_mode_fit_is_not_significant_for_one_mode():
    from tvist.ident.two_mode import fit_two_modes

    wn = 2 * math.pi * 17.0
    u, y, dt = mode_signals(3, wn, 0.08)
    single = fit_local(u, y, dt)
    split = fit_two_modes(u, y, dt, single)
    assert not split.significant
    dominant = max(split.modes, key=lambda m: m.energy_share)
    assert dominant.wn_rad_s == pytest.approx(wn, rel=0.01)
