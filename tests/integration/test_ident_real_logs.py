"""Logs like a real CB-series UR records them: 125 Hz, UR's ``record.py`` format, skipped
samples, target velocities hovering at 1e-2 rad/s between moves."""

from __future__ import annotations

import math

import numpy as np
import pytest

from ident_reference import generate_log
from tvist.cli import main
from tvist.ident.local_identification import identify_local
from tvist.ident.logs import LogWarning, read_rtde_csv
from tvist.robots import Robot, params

Q0 = np.array([0.4, -1.6, 1.3, -1.3, 1.57, 0.2])
DT_125HZ = 0.008


def cb_log(path, wn, zeta, snr_db, seed):
    return generate_log(
        path,
        seed=seed,
        joint=1,
        wn_rad_s=wn,
        zeta=zeta,
        q0=Q0,
        dt_s=DT_125HZ,
        snr_db=snr_db,
        robot_name="ur5",
        hover_rad_s=1e-2,
        skip_fraction=0.03,
        sep=" ",
    )


@pytest.mark.parametrize("robot_name", ["ur3", "ur5", "ur10"])
def test_cb_series_models_exist(robot_name):
    p = params(robot_name)
    assert p.n_dof == 6 and "CB-series" in p.description  # pinocchio check: test_robots.py


def test_a_125hz_cb_log_with_a_clear_mode_is_identified(tmp_path):
    wn, zeta = 2 * math.pi * 9.0, 0.08
    log = cb_log(tmp_path / "ur5_shoulder.txt", wn, zeta, 20.0, seed=3)
    with pytest.warns(LogWarning, match=r"samples \([0-9.]+ %\) filled"):
        record = read_rtde_csv(log.path)
    assert record.dt_s == pytest.approx(DT_125HZ)
    fit = identify_local(record, 1, Robot(params("ur5")))
    # 125 Hz: the band ends at 50 Hz (0.8 of Nyquist); a 9 Hz mode has 14 samples a period.
    assert fit.wn_rad_s == pytest.approx(wn, rel=0.01)
    assert fit.zeta == pytest.approx(zeta, rel=0.05)
    assert not fit.low_confidence, fit.reasons


def test_a_125hz_cb_log_without_strong_ringing_is_reported_not_crashed(tmp_path, capsys):
    # A stiff, heavily damped mode buried in noise: nothing rings above it.
    log = cb_log(tmp_path / "ur5_quiet.txt", 2 * math.pi * 40.0, 0.6, -10.0, seed=4)
    assert main(["identify", str(log.path), "--robot", "ur5", "--payload-kg", "0"]) == 0
    captured = capsys.readouterr()
    assert "filled by linear interpolation" in captured.err  # the repair is reported
    assert "Traceback" not in captured.err and "=True" not in captured.err
    assert "NO RINGING ABOVE NOISE" in captured.out or "LOW CONFIDENCE" in captured.out
    fit = identify_local(read_rtde_csv_quiet(log.path), 1, Robot(params("ur5")))
    assert fit.low_confidence


def read_rtde_csv_quiet(path):
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", LogWarning)
        return read_rtde_csv(path)
