"""ZTDIS and modified ZTDIS: the paper's numbers, the compensator against scipy and against its
defining property (eqs. 16-18), the end-to-end time-scaling claim (eq. 10), the benchmark's
acceptance figures, and bad input."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from scipy import signal

import tvist
from tvist import _core
from tvist.experiments.ztdis_benchmark import count_velocity_peaks, run_benchmark
from tvist.ztdis import compress, zero_delay

ROOT = Path(__file__).resolve().parents[2]

# The paper's experiment: 2.55 Hz payload mode, zeta = 0.04, ZVD, T = 0.734 s. 500 Hz control.
WN = 2.0 * np.pi * 2.55
ZETA = 0.04
DT = 0.002
T_MOVE = 0.734
N_MOVE = 368  # T / dt + 1
DIST = 0.3


def quintic(t: np.ndarray, move_s: float = T_MOVE, distance: float = DIST) -> np.ndarray:
    """Analytic minimum-jerk move, evaluable at any time (independent of tvist.trajectory)."""
    s = np.clip(t / move_s, 0.0, 1.0)
    return distance * s**3 * (10.0 - 15.0 * s + 6.0 * s**2)


def move() -> np.ndarray:
    return quintic(DT * np.arange(N_MOVE))[:, None]


def plant_eq1(wn: float = WN, zeta: float = ZETA):
    """The paper's plant, eq. 1 with K = 1: G(s) = wn^2 / (s^2 + 2 zeta wn s + wn^2)."""
    return ([wn * wn], [1.0, 2.0 * zeta * wn, wn * wn])


@pytest.fixture(scope="module")
def benches():
    return {ref: run_benchmark(ref, dt_s=DT) for ref in ("min_jerk", "trapezoid")}


# --- the paper's numbers -------------------------------------------------------------------


def test_time_scales_match_the_paper():
    r_z = zero_delay(move(), DT, [(WN, ZETA)], method="ztdis")
    r_m = zero_delay(move(), DT, [(WN, ZETA)], method="modified")
    # Paper / SPEC: delta_n = 0.39247 s, alpha = 0.4653, alpha' = 0.6516 (4 digits given).
    assert r_z.delay_s == pytest.approx(0.3925, abs=1e-4)
    assert r_z.alpha == pytest.approx(0.4653, abs=1e-4)
    assert r_m.alpha == pytest.approx(0.6516, abs=1e-4)
    assert r_z.move_s == pytest.approx(T_MOVE, abs=1e-12)
    # Closed forms (eqs. 5 and 11), computed here independently of the core.
    assert r_z.alpha == pytest.approx((T_MOVE - r_z.delay_s) / T_MOVE, rel=1e-12)
    assert r_m.alpha == pytest.approx(T_MOVE / (T_MOVE + r_m.delay_s), rel=1e-12)
    assert r_z.method == "ztdis" and r_m.method == "modified"


def test_shapers_applied_are_the_plain_and_the_alpha_scaled_one():
    base = tvist.shaper("zvd", WN, ZETA)
    r_z = zero_delay(move(), DT, [(WN, ZETA)], method="ztdis")
    r_m = zero_delay(move(), DT, [(WN, ZETA)], method="modified")
    np.testing.assert_allclose(r_z.impulses.times_s, base.times_s, atol=1e-12)
    # eq. 13: same amplitudes, times alpha' * delta_i.
    np.testing.assert_allclose(r_m.impulses.amplitudes, base.amplitudes, atol=1e-12)
    np.testing.assert_allclose(r_m.impulses.times_s, r_m.alpha * base.times_s, atol=1e-12)
    # Both end at T: alpha*T + delta_n = T and alpha'*T + alpha'*delta_n = T.
    assert r_z.alpha * T_MOVE + r_z.impulses.duration_s == pytest.approx(T_MOVE, abs=1e-12)
    assert r_m.alpha * T_MOVE + r_m.impulses.duration_s == pytest.approx(T_MOVE, abs=1e-12)


# --- the compensator against scipy ----------------------------------------------------------


def compensator_section(alpha: float, method: str, dt_s: float = DT):
    ((b, a),) = _core.Compensator([(WN, ZETA)], alpha, dt_s, 1, method).sections
    return np.array(b), np.array(a)


def f_continuous(alpha: float):
    """F(s) of eq. 17."""
    return [1.0, 2.0 * ZETA * WN, WN * WN], [alpha**2, 2.0 * alpha * ZETA * WN, WN * WN]


def test_tustin_section_is_scipy_bilinear_with_prewarping():
    alpha = 0.6516
    b, a = compensator_section(alpha, "tustin")
    # Pre-warping at wn is the bilinear map with the sample time 2 tan(wn dt/2)/wn.
    dt_warped = 2.0 * np.tan(WN * DT / 2.0) / WN
    num, den, _ = signal.cont2discrete(f_continuous(alpha), dt_warped, method="bilinear")
    np.testing.assert_allclose(b, np.ravel(num) / den[0], rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(a, den / den[0], rtol=1e-10, atol=1e-12)


def test_matched_section_sits_on_the_sampled_plant_poles():
    alpha = 0.6516
    b, a = compensator_section(alpha, "matched")
    # Zeros = poles of scipy's ZOH discretization of the plant G; poles = those of G(alpha s).
    _, den_g, _ = signal.cont2discrete(plant_eq1(), DT, method="zoh")
    _, den_fast, _ = signal.cont2discrete(plant_eq1(WN / alpha), DT, method="zoh")
    np.testing.assert_allclose(
        np.sort_complex(np.roots(b)), np.sort_complex(np.roots(den_g)), atol=1e-10
    )
    np.testing.assert_allclose(
        np.sort_complex(np.roots(a)), np.sort_complex(np.roots(den_fast)), atol=1e-10
    )
    assert np.sum(b) / np.sum(a) == pytest.approx(1.0, abs=1e-12)  # F(0) = 1


@pytest.mark.parametrize(("method", "bound"), [("matched", 2e-4), ("tustin", 1e-2)])
def test_section_frequency_response_matches_continuous_compensator(method, bound):
    # Up to a fifth of the Nyquist frequency (≈ 20 wn): measured max relative error 7.2e-5
    # (matched) and 2.8e-3 (Tustin, largest near the pole wn/alpha); bounds ~3x that.
    alpha = 0.6516
    b, a = compensator_section(alpha, method)
    w = np.linspace(0.05, 0.2 * np.pi / DT, 400)
    _, h_d = signal.freqz(b, a, worN=w * DT)
    _, h_c = signal.freqs(*f_continuous(alpha), worN=w)
    err = np.max(np.abs(h_d - h_c) / np.abs(h_c))
    assert err < bound, f"{method}: {err:.3g}"


def scaling_error(apply_f) -> float:
    """Largest |y_comp(t) - y_orig(t/alpha')| relative to the largest deflection |y - u|.

    Sample k of the compressed move, at t = k dt, equals the original at k dt/alpha', so the
    original is simulated on the grid with step dt/alpha' from the same numbers.
    """
    r = zero_delay(move(), DT, [(WN, ZETA)], method="modified")
    alpha = r.alpha
    n = int(3.0 / DT)
    t = DT * np.arange(n)
    u = quintic(t / alpha)
    _, y_orig, _ = signal.lsim(plant_eq1(), u, t / alpha)
    _, y_comp, _ = signal.lsim(plant_eq1(), apply_f(u, alpha), t)
    return float(np.max(np.abs(y_comp - y_orig)) / np.max(np.abs(y_orig - u)))


def test_compensated_compressed_plant_is_the_time_scaled_plant():
    """eqs. 16-18: F(s) G(s) = G(alpha' s), checked on the plant simulated by scipy."""

    def core_f(method):
        def run(u, alpha):
            c = _core.Compensator([(WN, ZETA)], alpha, DT, 1, method)
            return c.filter(u[:, None])[:, 0]

        return run

    def scipy_zoh(u, alpha):
        num, den, _ = signal.cont2discrete(f_continuous(alpha), DT, method="zoh")
        zi = signal.lfiltic(np.ravel(num), den, y=[0.0, 0.0])
        return signal.lfilter(np.ravel(num), den, u, zi=zi)[0]

    errors = {
        "matched": scaling_error(core_f("matched")),
        "tustin": scaling_error(core_f("tustin")),
        "scipy zoh": scaling_error(scipy_zoh),
        "none": scaling_error(lambda u, alpha: u),
    }
    # Measured: matched 1.5e-5, Tustin 4.5e-4, scipy's ZOH equivalent of F ~1e-1 (its zeros
    # are not on the sampled plant poles and it lags half a sample), no compensator 3.
    assert errors["matched"] < 1e-4, errors
    assert errors["tustin"] < 2e-3, errors
    assert errors["matched"] < errors["tustin"] < errors["scipy zoh"], errors
    assert errors["none"] > 0.5, errors  # the check can fail


def test_modified_response_is_the_conventional_response_compressed():
    """eq. 10: plant response to modified ZTDIS at t = response to conventional IS at t/alpha'."""
    r = zero_delay(move(), DT, [(WN, ZETA)], method="modified")
    n = N_MOVE + int(2.0 / DT)
    t = DT * np.arange(n)
    q = np.concatenate([r.Q[:, 0], np.full(n - N_MOVE, r.Q[-1, 0])])
    _, y_mod, _ = signal.lsim(plant_eq1(), q, t)
    # Conventional shaping of the analytic move, evaluated on the stretched grid t / alpha'.
    imp = tvist.shaper("zvd", WN, ZETA)
    s = t / r.alpha
    u_is = sum(a * quintic(s - d) for a, d in zip(imp.amplitudes, imp.times_s, strict=True))
    _, y_is, _ = signal.lsim(plant_eq1(), u_is, s)
    # Measured 2.2e-5 of the peak deflection (compensator discretization, spline compression
    # and fractional-delay interpolation together); bound 5x.
    err = np.max(np.abs(y_mod - y_is)) / np.max(np.abs(y_is - u_is))
    assert err < 1e-4, err


# --- compression ----------------------------------------------------------------------------


def test_compress_follows_the_analytic_move():
    alpha = 0.6
    q = move()
    out = compress(q, DT, alpha)
    t = DT * np.arange(N_MOVE)
    expected = quintic(t / alpha)
    # Clamped cubic spline of a quintic sampled at 500 Hz: error O(h^4 q'''') <= 1e-8 of the
    # distance; measured 1.2e-11 (4e-11 of the distance).
    assert np.max(np.abs(out[:, 0] - expected)) < 1e-8 * DIST
    assert np.all(out[t >= alpha * T_MOVE] == q[-1])
    np.testing.assert_array_equal(compress(q, DT, 1.0), q)


def test_zero_delay_output_ends_at_the_input_end():
    q = move()
    for method in ("ztdis", "modified"):
        r = zero_delay(q, DT, [(WN, ZETA)], method=method)
        assert r.Q.shape == q.shape and r.compressed.shape == q.shape
        assert r.Q[0, 0] == pytest.approx(q[0, 0], abs=1e-12)
        # Measured tail (what cutting at T leaves out): 1.1e-8 (ZTDIS) and 5.7e-9 (modified).
        assert r.tail_error < 1e-6 * DIST, (method, r.tail_error)
        assert abs(r.Q[-1, 0] - q[-1, 0]) <= r.tail_error


def test_channels_are_shaped_independently_and_1d_input_is_kept_1d():
    q = np.hstack([move(), -2.0 * move() + 1.0])
    r = zero_delay(q, DT, [(WN, ZETA)])
    r0 = zero_delay(q[:, 0], DT, [(WN, ZETA)])
    r1 = zero_delay(q[:, 1], DT, [(WN, ZETA)])
    assert r0.Q.shape == (N_MOVE,)
    np.testing.assert_allclose(r.Q[:, 0], r0.Q, atol=1e-12)
    np.testing.assert_allclose(r.Q[:, 1], r1.Q, atol=1e-12)


def test_two_modes_use_the_convolved_shaper_and_suppress_both():
    modes = [(WN, ZETA), (2.0 * np.pi * 7.0, 0.02)]
    t_move = 1.0
    n = int(round(t_move / DT)) + 1
    q = quintic(DT * np.arange(n), t_move)[:, None]
    delay = sum(tvist.shaper("zvd", w, z).duration_s for w, z in modes)
    n_sim = n + int(4.0 / DT)
    for method in ("ztdis", "modified"):
        r = zero_delay(q, DT, modes, method=method)
        assert r.delay_s == pytest.approx(delay, abs=1e-12)
        scale = r.alpha if method == "modified" else 1.0
        assert r.impulses.duration_s == pytest.approx(scale * delay, abs=1e-12)
        for w, z in modes:
            t = DT * np.arange(n_sim)
            ext = lambda x: np.concatenate([x, np.full(n_sim - n, x[-1])])  # noqa: E731
            _, y_ref, _ = signal.lsim(plant_eq1(w, z), ext(q[:, 0]), t)
            _, y_out, _ = signal.lsim(plant_eq1(w, z), ext(r.Q[:, 0]), t)
            res_ref = np.max(np.abs(y_ref[n:] - DIST))
            res_out = np.max(np.abs(y_out[n:] - DIST))
            # Each mode is suppressed to below 1 % of the unshaped move's residual.
            assert res_out < 0.01 * res_ref, (method, w, res_out / res_ref)


# --- benchmark acceptance -------------------------------------------------------------------


def test_benchmark_zero_delay_and_residual(benches):
    for ref, b in benches.items():
        m = b.metrics
        t0 = m["unshaped"].completion_s
        # Completion is read with a 1e-6-of-distance tolerance, identically for all methods,
        # so a smooth end can read one sample early; compare against the unshaped move's.
        assert t0 == pytest.approx(T_MOVE, abs=2 * DT), ref
        for method in ("ztdis", "modified"):
            assert m[method].completion_s == pytest.approx(t0, abs=2 * DT), (ref, method)
        assert m["is"].completion_s - t0 == pytest.approx(b.delay_s, abs=3 * DT), ref
        for method in ("is", "ztdis", "modified"):
            # Acceptance floor: <= 1 % of the unshaped residual on the exact plant. Measured
            # <= 6.3e-6 (what is left is discretization), so 1e-4 still leaves margin and
            # catches regressions far below the floor.
            assert m[method].residual_ratio < 1e-4, (ref, method, m[method].residual_ratio)


def test_benchmark_smoothness_claims(benches):
    mj = benches["min_jerk"].metrics
    # Paper Figs. 6 and 13: ZTDIS splits a smooth move into several velocity peaks; the
    # modified method keeps one.
    assert mj["unshaped"].velocity_peaks == 1
    assert mj["modified"].velocity_peaks == 1
    assert mj["ztdis"].velocity_peaks >= 2
    assert mj["modified"].peak_velocity < mj["ztdis"].peak_velocity
    assert mj["modified"].peak_jerk < mj["ztdis"].peak_jerk
    tz = benches["trapezoid"].metrics
    # Where it is not smoother: the compensator's high-frequency gain 1/alpha'^2 sharpens the
    # trapezoid's acceleration steps (more velocity peaks, higher jerk than ZTDIS).
    assert tz["modified"].peak_jerk > tz["ztdis"].peak_jerk
    assert tz["modified"].velocity_peaks > tz["ztdis"].velocity_peaks


def test_velocity_peak_count():
    t = np.linspace(0.0, 1.0, 1001)
    one = np.sin(np.pi * t)
    two = np.exp(-(((t - 0.3) / 0.1) ** 2)) + 0.8 * np.exp(-(((t - 0.7) / 0.1) ** 2))
    shoulder = one + 0.005 * np.sin(40 * np.pi * t)  # ripple below the 1 % threshold
    flat = np.minimum(one, 0.7) + 1e-14 * np.sin(1000 * t)  # plateau with rounding ripple
    assert count_velocity_peaks(one) == 1
    assert count_velocity_peaks(two) == 2
    assert count_velocity_peaks(flat) == 1
    assert count_velocity_peaks(shoulder) == 1
    assert count_velocity_peaks(-two) == 2
    assert count_velocity_peaks(np.zeros(5)) == 0


@pytest.mark.slow
def test_benchmark_cli_writes_the_plot(tmp_path):
    out = tmp_path / "zero_delay.png"
    proc = subprocess.run(
        [
            sys.executable,
            "-m",
            "tvist.cli",
            "zero-delay",
            "--reference",
            "min_jerk",
            "--plot",
            str(out),
        ],
        capture_output=True,
        text=True,
        check=True,
        cwd=ROOT,
    )
    assert "modified ZTDIS" in proc.stdout
    assert out.stat().st_size > 10_000


@pytest.mark.slow
def test_example_runs(tmp_path):
    out = tmp_path / "example.png"
    proc = subprocess.run(
        [sys.executable, str(ROOT / "examples" / "02_zero_delay.py"), str(out)],
        capture_output=True,
        text=True,
        check=True,
        cwd=tmp_path,
    )
    assert "alpha = 0.6516" in proc.stdout and "alpha = 0.4653" in proc.stdout
    assert out.exists()


# --- bad input ------------------------------------------------------------------------------


def test_limits_are_checked_and_named():
    q = move()
    r = zero_delay(q, DT, [(WN, ZETA)], v_max=10.0, a_max=100.0)
    v_peak = np.max(np.abs(np.gradient(r.compressed[:, 0], DT)))
    # The compressed move's peak speed is ~1/alpha' times the original's.
    with pytest.raises(ValueError, match="v_max"):
        zero_delay(q, DT, [(WN, ZETA)], v_max=0.99 * v_peak)
    with pytest.raises(ValueError, match="a_max"):
        zero_delay(q, DT, [(WN, ZETA)], method="ztdis", a_max=1.0)
    with pytest.raises(ValueError, match="v_max"):
        zero_delay(q, DT, [(WN, ZETA)], v_max=-1.0)
    with pytest.raises(ValueError, match="v_max"):
        zero_delay(np.hstack([q, q]), DT, [(WN, ZETA)], v_max=[1.0, 2.0, 3.0])


def test_move_shorter_than_the_shaper_is_refused_by_ztdis():
    n = int(round(0.3 / DT)) + 1  # T = 0.3 s < delta_n = 0.39 s
    q = quintic(DT * np.arange(n), 0.3)
    with pytest.raises(ValueError, match="too short"):
        zero_delay(q, DT, [(WN, ZETA)], method="ztdis")
    # The modified method has alpha' > 0 for any length.
    r = zero_delay(q, DT, [(WN, ZETA)], method="modified")
    assert 0.0 < r.alpha < 0.5


def test_compensator_above_nyquist_is_refused():
    # A 1550 rad/s mode at 500 Hz (Nyquist 1570.8 rad/s): ZVD delay 2 pi / 1550 = 4.05 ms, a
    # 0.24 s move gives alpha' = 0.983 and a compensator pole at wn/alpha' = 1576 rad/s, above
    # Nyquist. (120 samples: a sampled quintic is "at rest" at its ends only when finely
    # sampled, and rest padding would not count as part of the move.)
    dt, wn, n = 0.002, 1550.0, 120
    s = np.arange(n + 1) / n
    q = s**3 * (10.0 - 15.0 * s + 6.0 * s**2)
    with pytest.raises(ValueError, match="Nyquist"):
        zero_delay(q, dt, [(wn, 0.0)], method="modified")
    alpha = zero_delay(q, dt, [(wn, 0.0)], method="ztdis").alpha
    assert alpha == pytest.approx((n * dt - 2.0 * np.pi / wn) / (n * dt), rel=1e-12)


@pytest.mark.parametrize(
    ("q", "match"),
    [
        (np.full(N_MOVE, np.nan), "NaN"),
        (DT * np.arange(N_MOVE), "not at rest at its start"),
        (quintic(DT * np.arange(N_MOVE), T_MOVE * 1.2), "not at rest at its end"),
        (np.zeros((2, 3, 4)), "shape"),
        (np.zeros(3), "at least 4"),
    ],
)
def test_bad_moves_are_refused(q, match):
    with pytest.raises(ValueError, match=match):
        zero_delay(q, DT, [(WN, ZETA)])


def test_bad_settings_are_refused():
    q = move()
    with pytest.raises(ValueError, match="method"):
        zero_delay(q, DT, [(WN, ZETA)], method="fast")  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="shaper"):
        zero_delay(q, DT, [(WN, ZETA)], shaper="nope")
    with pytest.raises(ValueError, match="mode"):
        zero_delay(q, DT, [(WN, 1.5)])
    with pytest.raises(ValueError, match="mode"):
        zero_delay(q, DT, [])
    with pytest.raises(ValueError, match="dt_s"):
        zero_delay(q, 0.0, [(WN, ZETA)])
    with pytest.raises(ValueError, match="discretization"):
        zero_delay(q, DT, [(WN, ZETA)], discretization="zoh")


def test_compensator_binding_streams_like_the_block_form():
    u = move()
    c1 = _core.Compensator([(WN, ZETA)], 0.65, DT, 1)
    c2 = _core.Compensator([(WN, ZETA)], 0.65, DT, 1)
    block = c1.filter(u)
    steps = np.array([c2.step(row) for row in u])
    np.testing.assert_allclose(block, steps, atol=0.0)
    with pytest.raises(ValueError, match="n_dof"):
        c1.step(np.zeros(2))
    with pytest.raises(ValueError, match="shape"):
        c1.filter(np.zeros((5, 2)))
    c1.reset(np.array([1.0]))
    assert c1.step(np.array([1.0]))[0] == pytest.approx(1.0, abs=1e-10)
    assert c1.step(np.array([np.nan]))[0] == pytest.approx(1.0, abs=1e-10)
    assert c1.last_status & tvist.Status.INPUT_HELD


def test_compensator_block_filter_reads_any_memory_layout():
    # A Fortran-ordered (n, 3) block must be read row by row, like the C-ordered one; a
    # transposed read would mix samples of different joints.
    rng = np.random.default_rng(3)
    q = np.cumsum(rng.normal(size=(200, 3)), axis=0)
    c_order = _core.Compensator([(WN, ZETA)], 0.65, DT, 3).filter(np.ascontiguousarray(q))
    f_order = _core.Compensator([(WN, ZETA)], 0.65, DT, 3).filter(np.asfortranarray(q))
    np.testing.assert_array_equal(f_order, c_order)


def test_joints_that_do_not_move_are_at_rest_despite_round_off():
    # Joint 1 stands still at a value whose one-sided difference is round-off (~1e-13 rad/s):
    # it must not count as "moving at the start".
    t = np.linspace(0.0, 1.0, 501)
    s = 10 * t**3 - 15 * t**4 + 6 * t**5
    q = np.column_stack([0.3 * s, np.full_like(t, -1.570796326795)])
    result = zero_delay(q, 0.002, [(2 * np.pi * 2.55, 0.04)], method="modified")
    assert result.Q.shape == q.shape
