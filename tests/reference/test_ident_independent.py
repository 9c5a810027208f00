"""Identification against data that share none of the estimator's assumptions.

The logs come from :mod:`ident_reference`: a continuous-time profile switching off the log's
grid, the mode integrated exactly, the accelerometer from plain-numpy kinematics with gravity
in the tool frame, a sensor bias, a sensor timing offset of either sign and 20 dB noise, all
written to a ur_rtde CSV file and read back with :func:`read_rtde_csv`.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import integrate, linalg

from ident_reference import Profile, _expm, integrate_mode, mode_signals, random_case
from tvist.ident.local_fit import FitOptions, fit_local
from tvist.ident.local_identification import identify_local
from tvist.ident.logs import read_rtde_csv
from tvist.robots import ur5e

N_CASES = 40


def test_the_generator_integrates_the_mode_exactly():
    """The generator's own exactness, against scipy's expm and an adaptive ODE solver."""
    m = np.array([[0.0, 1.0, 0.0], [-900.0, -3.0, 2.5], [0.0, 0.0, 0.0]]) * 0.013
    np.testing.assert_allclose(_expm(m), linalg.expm(m), rtol=1e-12, atol=1e-14)
    profile = Profile(np.array([0.1013, 0.2377, 0.31, 0.4441]), np.array([3.0, 0.0, -3.0]), 0.0)
    wn, zeta = 2 * math.pi * 13.0, 0.07
    t_out = 0.002 * np.arange(300) + 0.0007

    def rhs(t, x):
        _, _, a = profile.sample(np.array([t]))
        return [x[1], -(wn**2) * x[0] - 2 * zeta * wn * x[1] - a[0]]

    ref = integrate.solve_ivp(
        rhs, (0.0, t_out[-1]), [0.0, 0.0], t_eval=t_out, rtol=1e-11, atol=1e-13, max_step=1e-3
    )
    e, e_dot = integrate_mode(profile, wn, zeta, t_out)
    np.testing.assert_allclose(e, ref.y[0], atol=1e-9 * np.max(np.abs(ref.y[0])))
    np.testing.assert_allclose(e_dot, ref.y[1], atol=1e-8 * np.max(np.abs(ref.y[1])))


@pytest.fixture(scope="module")
def independent_fits(tmp_path_factory):
    folder = tmp_path_factory.mktemp("independent_logs")
    robot = ur5e()  # kinematics only: the generator's arm carries no payload
    out = []
    for seed in range(N_CASES):
        case = random_case(folder, seed)
        record = read_rtde_csv(case.path)
        out.append((case, identify_local(record, case.joint, robot, base_mode=False)))
    return out


@pytest.mark.slow
def test_acceptance_on_40_independent_logs(independent_fits):
    """ω_n within 1 % and ζ within 5 % in at least 95 % of the cases (5-40 Hz, ζ 0.02-0.4,
    20 dB). Measured: 40/40, worst ω_n 0.53 %, worst ζ 2.8 %."""
    good = [
        abs(fit.wn_rad_s / case.wn_rad_s - 1) < 0.01 and abs(fit.zeta / case.zeta - 1) < 0.05
        for case, fit in independent_fits
    ]
    assert sum(good) >= math.ceil(0.95 * N_CASES), f"{sum(good)}/{N_CASES} within tolerance"
    confident = sum(not fit.low_confidence for _, fit in independent_fits)
    assert confident >= math.ceil(0.95 * N_CASES), f"only {confident}/{N_CASES} confident"


@pytest.mark.slow
def test_standard_errors_cover_the_true_errors(independent_fits):
    """Honest uncertainty: the true error exceeds 3 standard errors in few cases (a Gaussian
    would allow 0.3 %; the model mismatch of these logs - deflected sensor orientation,
    centripetal terms, sensor lag - is not noise, so allow 10 %). Measured: 0 of 40 for both."""
    for name, err in (
        ("ω_n", lambda c, f: abs(f.wn_rad_s - c.wn_rad_s) / f.wn_se_rad_s),
        ("ζ", lambda c, f: abs(f.zeta - c.zeta) / f.zeta_se),
    ):
        outside = [c.path.name for c, f in independent_fits if err(c, f) > 3.0]
        assert len(outside) <= 0.1 * N_CASES, (name, outside)


def test_point_samples_without_a_timing_offset_are_biased():
    """Control: fed with point samples of the acceleration held over the next interval and no
    timing offset (a whole-sample model of a profile that switches between samples), the same
    fit is 17 % high in ζ on a stiff, well-damped mode; with interval means and the
    sub-sample offset it is within 0.5 %. Noise-free, so the differences are the input model
    alone (measured: 16.6 % and 0.3 % in ζ, 0.95 % and 0.05 % in ω_n)."""
    wn, zeta = 2 * math.pi * 38.0, 0.3
    u_mean, y, dt = mode_signals(3, wn, zeta, snr_db=None)
    u_point, y_again, _ = mode_signals(3, wn, zeta, snr_db=None, point_samples=True)
    np.testing.assert_array_equal(y, y_again)
    exact = fit_local(u_mean, y, dt)
    assert exact.zeta == pytest.approx(zeta, rel=0.005)
    assert exact.wn_rad_s == pytest.approx(wn, rel=0.001)
    whole_sample = fit_local(u_point, y, dt, options=FitOptions(max_delay_s=0.0))
    assert whole_sample.zeta / zeta - 1 > 0.05
