"""Dynamic-map fit (paper section 5.3) on synthetic data.

The data are made by an independent numpy transcription of the map equations
(``tests/map_reference.py``), never by the core the fit evaluates, and a control made with a
different law must not fit.
"""

from __future__ import annotations

import functools
import math

import numpy as np
import pytest

import tvist
from map_reference import PAPER_MODES, mode_reference, modes_reference
from tvist.ident.map_fit import K_0_FIXED, ModeSpec, fit_map
from tvist.maps.paper10 import RANGE_FIELDS
from tvist.robots import ur5e

ROBOTS = {p: ur5e(p, (0.0, 0.0, 0.05)) for p in (0.0, 1.0, 3.0, 5.0)}
FREQ = ("k_0", "k_j", "k_p")
DAMP = ("c_0", "c_2", "c_tau")


def random_q(rng: np.random.Generator) -> np.ndarray:
    return np.r_[
        rng.uniform(-np.pi, np.pi),
        rng.uniform(-np.pi, 0.0),  # upper arm above the horizontal
        rng.uniform(-2.8, 2.8),
        rng.uniform(-np.pi, np.pi, 3),
    ]


def synthetic_poses(
    seed: int,
    noise: float,
    mode_maps=PAPER_MODES,
    per_payload: int = 52,
    law: str = "paper",
) -> list[dict]:
    """208 poses (4 payloads x 52, like the paper) with modes of the maps ``mode_maps``
    evaluated by the independent reference (``law``) and relative Gaussian noise ``noise`` on
    every ω_n and ζ."""
    rng = np.random.default_rng(seed)
    poses = []
    for robot in ROBOTS.values():
        for _ in range(per_payload):
            q = random_q(rng)
            inertia = robot.joint_inertia(q)
            tau = robot.gravity_torque(q)
            modes = modes_reference(mode_maps, [inertia], [tau], law=law)[0]
            poses.append(
                {
                    "inertia_kg_m2": inertia.tolist(),
                    "gravity_torque_nm": tau.tolist(),
                    "modes": [
                        {
                            "joint": i,
                            "wn_rad_s": wn * (1 + noise * rng.normal()),
                            "zeta": zeta * (1 + noise * rng.normal()),
                        }
                        for i, (wn, zeta) in enumerate(modes)
                    ],
                }
            )
    return poses


@functools.cache
def noisy_fit(seed: int, k_0: float | None = None) -> tvist.DynamicMap:
    """The map fitted to the 2 %-noise data set of ``seed`` (shared by several tests), with
    ``k_0`` estimated (``None``) or fixed."""
    return fit_map(synthetic_poses(seed, noise=0.02), k_0=k_0)


def rel_err(fitted: dict, true: dict, key: str) -> float:
    return abs(fitted[key] / true[key] - 1.0)


def test_noise_free_data_recovers_every_coefficient_and_the_structure():
    fitted = fit_map(synthetic_poses(0, noise=0.0))
    stats = fitted.metadata["fit_statistics"]["modes"]
    for mode, true, st in zip(fitted.mode_maps, PAPER_MODES, stats, strict=True):
        for key in FREQ + DAMP:
            assert rel_err(mode, true, key) < 1e-6, key  # exact data: solver precision
        for key in ("k_g", "c_1", "frequency_joint", "damping_joint"):
            assert mode[key] == true[key], key
        assert mode["damping_gain_exponent"] == true["damping_gain_exponent"]
        assert mode["frequency_gain_exponent"] == true["frequency_gain_exponent"]
        assert set(st["frequency"]["dropped"]) == {"k_g"}
        assert set(st["damping"]["dropped"]) == {"c_1"}
    # The base frequency is explained by J_1 (eq. 47), far better than by J_0 (eq. 46).
    rms = stats[0]["frequency_joint_rms_relative_error"]
    assert rms["J_1"] < 1e-9 < 0.1 < rms["J_0"]


@pytest.mark.parametrize("seed", range(3))
def test_two_percent_noise(seed):
    fitted = noisy_fit(seed)
    base, shoulder = fitted.mode_maps
    true_base, true_shoulder = PAPER_MODES
    stats = fitted.metadata["fit_statistics"]["modes"]
    assert base["frequency_joint"] == 1
    assert base["k_g"] == shoulder["k_g"] == base["c_1"] == shoulder["c_1"] == 0.0
    # Frequency coefficients of both modes, k_0 estimated with them: each within 3 of its
    # standard errors of the truth, and each determined (standard errors: k_0 6-17 %, k_J
    # 6-8 %, k_p 8-19 % over seeds 0-2, for 208 poses with 2 % noise; at most 25 % here).
    for mode, true, st in zip((base, shoulder), PAPER_MODES, stats, strict=True):
        coefficients = st["frequency"]["coefficients"]
        for key in FREQ:
            se = coefficients[key]["se"]
            assert abs(mode[key] - true[key]) < 3 * se, key
            assert se < 0.25 * mode[key], key
    # Shoulder damping: with J_1 >= ~1 kg m² and c_τ = 47, the "1" in (1 + c_τ J_1) is a 2 %
    # effect, below the noise, so c_0 and c_τ are barely separable; the fit must say so
    # (relative standard errors of 25 % and more; measured 47-88 % over seeds 0-2).
    shoulder_se = stats[1]["damping"]["coefficients"]
    for key in ("c_0", "c_tau"):
        assert shoulder_se[key]["se"] > 0.25 * abs(shoulder[key]), key
    # What the data determine, the modes, stay within 1 % RMS of the truth (ω_n and ζ).
    rng = np.random.default_rng(99)
    ratios = []
    for robot in ROBOTS.values():
        for _ in range(20):
            inertia = robot.joint_inertia(random_q(rng))
            got = fitted.modes_from_inertia(inertia)
            want = modes_reference(PAPER_MODES, [inertia])[0]
            ratios += [g[k] / w[k] - 1.0 for g, w in zip(got, want, strict=True) for k in (0, 1)]
    assert math.sqrt(np.mean(np.square(ratios))) < 0.01


@pytest.mark.parametrize("seed", range(3))
def test_two_percent_noise_with_the_true_k0_fixed(seed):
    """The paper's reduced map (k_0 fixed, here at the value that made the data): the other
    coefficients then come back tighter."""
    fitted = noisy_fit(seed, K_0_FIXED)
    base, shoulder = fitted.mode_maps
    true_base, true_shoulder = PAPER_MODES
    stats = fitted.metadata["fit_statistics"]["modes"]
    assert base["k_0"] == shoulder["k_0"] == K_0_FIXED
    # Frequency coefficients of both modes: within 10 % (fitted standard errors 1-2 %).
    for key in ("k_j", "k_p"):
        assert rel_err(base, true_base, key) < 0.10, key
        assert rel_err(shoulder, true_shoulder, key) < 0.10, key
    # Base damping: the scatter of c_2 over seeds is about 5 % (the fitted standard errors,
    # 2-5 %, leave out the uncertainty of k_J, k_p carried over from the frequency step), so
    # 10 % is a 2σ band: require 15 % here and 10 % in most seeds (test below).
    for key in DAMP:
        assert rel_err(base, true_base, key) < 0.15, key
    # Shoulder damping: c_0 and c_τ trade off (see test_two_percent_noise); the truth lies
    # within 3 standard errors...
    shoulder_se = stats[1]["damping"]["coefficients"]
    for key in ("c_0", "c_tau"):
        assert shoulder_se[key]["se"] > 0.25 * abs(shoulder[key]), key
        assert abs(shoulder[key] - true_shoulder[key]) < 3 * shoulder_se[key]["se"], key
    # ...while the polynomial it does determine, c_0 + (c_2 + c_0 c_τ) J + c_2 c_τ J², has its
    # J and J² coefficients within 10 %.
    for fitted_c, true_c in [
        (
            shoulder["c_2"] + shoulder["c_0"] * shoulder["c_tau"],
            true_shoulder["c_2"] + true_shoulder["c_0"] * true_shoulder["c_tau"],
        ),
        (shoulder["c_2"] * shoulder["c_tau"], true_shoulder["c_2"] * true_shoulder["c_tau"]),
    ]:
        assert abs(fitted_c / true_c - 1.0) < 0.10


def test_base_damping_within_ten_percent_in_most_seeds():
    within = 0
    for seed in range(3):
        base = noisy_fit(seed, K_0_FIXED).mode_maps[0]
        within += all(rel_err(base, PAPER_MODES[0], key) < 0.10 for key in DAMP)
    assert within >= 2  # seed 0 misses by a hair (c_2 off by 10.4 %)


def test_base_frequency_from_j0_is_chosen_when_the_data_say_so():
    # Data from the general map with J_0 driving the base mode (eq. 46).
    base = dict(PAPER_MODES[0])
    base.update(
        frequency_joint=0, damping_joint=0, damping_gain_exponent=0.5, frequency_gain_exponent=0.0
    )
    fitted = fit_map(synthetic_poses(5, noise=0.01, mode_maps=[base, PAPER_MODES[1]]))
    assert fitted.mode_maps[0]["frequency_joint"] == 0
    assert fitted.mode_maps[0]["damping_gain_exponent"] == 0.5
    assert rel_err(fitted.mode_maps[0], base, "k_j") < 0.10


def test_gravity_term_is_kept_when_it_matters():
    shoulder = dict(PAPER_MODES[1])
    shoulder["k_g"] = 20.0  # 20 N m/rad per N m: a 5-15 % stiffness change over the workspace
    poses = synthetic_poses(6, noise=0.005, mode_maps=[PAPER_MODES[0], shoulder])
    fitted = fit_map(poses)
    # |τ_g| and J_1 are correlated over the workspace, so k_g trades off against k_J: 10 %.
    assert fitted.mode_maps[1]["k_g"] == pytest.approx(20.0, rel=0.10)
    assert fitted.mode_maps[0]["k_g"] == 0.0


def test_map_round_trips_through_json_with_statistics(tmp_path):
    fitted = noisy_fit(1)
    fitted = tvist.DynamicMap(fitted.mode_maps, {**fitted.metadata, "robot": "ur5e"})
    fitted.save(tmp_path / "map.json")
    back = tvist.DynamicMap.load(tmp_path / "map.json")
    assert back.mode_maps == fitted.mode_maps
    assert back.metadata["robot"] == "ur5e"
    assert back.metadata["fit_statistics"]["modes"][1]["n_poses"] == 208


def test_too_few_poses_is_an_error():
    poses = synthetic_poses(2, noise=0.02, per_payload=1)  # 4 poses
    with pytest.raises(ValueError, match="4 usable poses"):
        fit_map(poses)


def test_no_inertia_variation_is_singular():
    pose = synthetic_poses(3, noise=0.0, per_payload=1)[0]
    with pytest.raises(ValueError, match="singular|not identifiable"):
        fit_map([pose] * 20, mode_specs=(ModeSpec(1, (1,), 1),))


def test_low_confidence_identifications_are_skipped():
    poses = synthetic_poses(4, noise=0.0)
    for pose in poses[:50]:
        for mode in pose["modes"]:
            mode["wn_rad_s"] *= 3.0  # garbage...
            mode["low_confidence"] = True  # ...that the local fit flagged
    fitted = fit_map(poses)
    assert fitted.metadata["fit_statistics"]["modes"][0]["n_poses"] == 158
    assert rel_err(fitted.mode_maps[1], PAPER_MODES[1], "k_j") < 1e-6


def _used_range(poses: list[dict], joint: int, inertia_joint: int) -> list[float]:
    """[min, max] of J_inertia_joint over the poses whose mode of ``joint`` the fit uses."""
    j = [
        p["inertia_kg_m2"][inertia_joint]
        for p in poses
        for m in p["modes"]
        if m["joint"] == joint and not m.get("low_confidence", False)
    ]
    return [min(j), max(j)]


def test_the_fitted_map_is_limited_to_the_inertias_of_its_data(tmp_path):
    poses = synthetic_poses(4, noise=0.0)
    for pose in poses[:50]:  # the lightest payload's first 50 poses are not used for the fit
        for mode in pose["modes"]:
            mode["low_confidence"] = True
    fitted = fit_map(poses)
    base, shoulder = fitted.mode_maps
    # Base: frequency from J_1 (eq. 47), damping from J_0 (eq. 48); shoulder: J_1 for both.
    assert base["frequency_inertia_range_kg_m2"] == _used_range(poses, 0, 1)
    assert base["damping_inertia_range_kg_m2"] == _used_range(poses, 0, 0)
    assert shoulder["frequency_inertia_range_kg_m2"] == _used_range(poses, 1, 1)
    assert shoulder["damping_inertia_range_kg_m2"] == _used_range(poses, 1, 1)
    assert _used_range(poses, 0, 0) != [
        min(p["inertia_kg_m2"][0] for p in poses),
        max(p["inertia_kg_m2"][0] for p in poses),
    ]  # the skipped poses would have widened the range: the test can tell the difference
    # Inside the ranges the fit is the paper's map (exact data); well outside (beyond the
    # soft clamp's blend zones of 5 % of a bound), the map holds the value at the bound instead
    # of extrapolating: the same coefficients without ranges, evaluated at the bounds.
    (lo0, hi0), (lo1, hi1) = (
        base["damping_inertia_range_kg_m2"],
        base["frequency_inertia_range_kg_m2"],
    )
    inside = [0.5 * (lo0 + hi0), 0.5 * (lo1 + hi1)]
    np.testing.assert_allclose(
        fitted.modes_from_inertia(inside), modes_reference(PAPER_MODES, [inside])[0], rtol=1e-6
    )
    outside = [0.5 * lo0, 2.0 * hi1]
    unbounded = tvist.DynamicMap(
        [{**mode, **dict.fromkeys(RANGE_FIELDS)} for mode in fitted.mode_maps]
    )
    assert fitted.modes_from_inertia(outside) == unbounded.modes_from_inertia([lo0, hi1])
    # Saved and loaded with its ranges.
    fitted.save(tmp_path / "map.json")
    back = tvist.DynamicMap.load(tmp_path / "map.json")
    assert back.inertia_ranges == fitted.inertia_ranges
    assert back.modes_from_inertia(outside) == fitted.modes_from_inertia(outside)


def test_an_unbounded_fit_on_request():
    fitted = fit_map(synthetic_poses(4, noise=0.0), limit_to_data=False)
    assert fitted.inertia_ranges == [{}, {}]


def _observed(poses: list[dict], joint: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Inertias ``(n, 6)``, ω_n and ζ of the mode identified through ``joint``, in the order
    the fit reads them (pose by pose)."""
    rows = [(p["inertia_kg_m2"], m) for p in poses for m in p["modes"] if m["joint"] == joint]
    inertia = np.array([r[0] for r in rows])
    return (
        inertia,
        np.array([r[1]["wn_rad_s"] for r in rows]),
        np.array([r[1]["zeta"] for r in rows]),
    )


def test_fit_is_the_relative_least_squares_optimum_of_an_independent_model():
    """The reported RMS errors are the relative errors ``ω_map/ω_meas − 1`` (and the same for
    ζ) of the fitted coefficients, evaluated by the independent reference; and the frequency
    coefficients are the minimum of that relative least-squares problem, found again here by
    scipy on the reference equations. (Relative, not absolute, errors: the local fits are good
    to a relative accuracy, and absolute errors would weigh the stiff poses more.)"""
    from scipy import optimize

    poses = synthetic_poses(0, noise=0.02)
    fitted = noisy_fit(0)
    stats = fitted.metadata["fit_statistics"]["modes"]
    for index, mode in enumerate(fitted.mode_maps):
        inertia, wn_meas, zeta_meas = _observed(poses, index)
        # The fit statistics belong to the unbounded map (the ranges only clamp evaluations
        # outside the data); the reference ignores ranges.
        wn, zeta = mode_reference(mode, inertia)
        rms_wn = math.sqrt(np.mean((wn / wn_meas - 1.0) ** 2))
        rms_zeta = math.sqrt(np.mean((zeta / zeta_meas - 1.0) ** 2))
        # Same quantity, two evaluations in double precision.
        assert stats[index]["frequency"]["rms_relative_error"] == pytest.approx(rms_wn, rel=1e-9)
        assert stats[index]["damping"]["rms_relative_error"] == pytest.approx(rms_zeta, rel=1e-9)
        # k_g was dropped (no gravity term in the data): fit k_J, k_p on the same problem.

        def residual(x, mode=mode, inertia=inertia, wn_meas=wn_meas):
            trial = {**mode, "k_j": x[0], "k_p": x[1], "k_g": 0.0}
            return mode_reference(trial, inertia)[0] / wn_meas - 1.0

        best = optimize.least_squares(
            residual, [500.0, 1.0], x_scale="jac", xtol=1e-15, ftol=1e-15, gtol=1e-15
        )
        # A well-conditioned two-parameter problem (standard errors 1-2 %): both solvers stop
        # within ~1e-9 of the optimum; 1e-6 leaves room for the different paths.
        assert mode["k_j"] == pytest.approx(best.x[0], rel=1e-6)
        assert mode["k_p"] == pytest.approx(best.x[1], rel=1e-6)


def test_data_from_another_law_do_not_fit():
    """Control: data made with ω_n = (1 + k_p/J)·√(K/J) (the gain outside the square root)
    cannot be explained by the map's equations, so the fit must show it: without any noise the
    frequency errors stay at several percent (measured: base 4.4 %, shoulder 3.2 %; data of
    the right law fit to 1e-16), and the coefficients are far from those that made the data
    (k_J 45-72 % off): they end where the two (k_0, k_p) branches meet, k_0 = k_p k_J, because
    the curvature in 1/J these data ask for is beyond any real pair (k_0, k_p)."""
    fitted = fit_map(synthetic_poses(0, noise=0.0, law="gain_outside_root"))
    stats = fitted.metadata["fit_statistics"]["modes"]
    for mode, true, st in zip(fitted.mode_maps, PAPER_MODES, stats, strict=True):
        assert st["frequency"]["rms_relative_error"] > 0.02
        assert rel_err(mode, true, "k_j") > 0.3
        assert mode["k_0"] == pytest.approx(mode["k_p"] * mode["k_j"], rel=1e-3)
    # With the local fits' 2 % noise added the misfit still stands out of the noise:
    # RMS 4-5 % against 2.1 % for data of the map's own law (test above).
    noisy = fit_map(synthetic_poses(0, noise=0.02, law="gain_outside_root"))
    for st in noisy.metadata["fit_statistics"]["modes"]:
        assert st["frequency"]["rms_relative_error"] > 1.5 * 0.02


def test_the_damping_factorisation_switch_needs_a_non_zero_c0():
    """Without c_1, (c_0 + c_2 J)(1 + c_τ J) = (c_0 + c_0 c_τ J)(1 + (c_2/c_0) J): the swap to
    the paper's branch (c_2 <= c_0 c_τ) exists only for c_0 != 0 and c_2/c_0 >= 0."""
    from tvist.ident.map_fit import _other_branch_is_canonical

    assert _other_branch_is_canonical({"c_0": 0.5, "c_2": 2.0, "c_tau": 1.0})  # 2 > 0.5
    assert not _other_branch_is_canonical({"c_0": 0.5, "c_2": 0.2, "c_tau": 1.0})  # canonical
    assert not _other_branch_is_canonical({"c_0": -0.5, "c_2": 2.0, "c_tau": 1.0})  # c_2/c_0 < 0
    assert not _other_branch_is_canonical({"c_0": 0.0, "c_2": 2.0, "c_tau": 1.0})  # no swap


def test_poorly_determined_coefficients_are_those_with_large_standard_errors():
    """A coefficient is reported poorly determined when its standard error exceeds half its
    value. With 2 % noise the frequency coefficients and the base damping are known to 1-3 %
    (seed 0), while the shoulder's c_0, c_2, c_τ trade off (86-89 %, see
    test_two_percent_noise)."""
    stats = noisy_fit(0).metadata["fit_statistics"]["modes"]
    for mode in stats:
        for step in ("frequency", "damping"):
            coefficients = mode[step]["coefficients"]
            large = sorted(k for k, c in coefficients.items() if c["se"] >= 0.5 * abs(c["value"]))
            assert sorted(mode[step]["poorly_determined"]) == large
    assert stats[0]["frequency"]["poorly_determined"] == []
    assert stats[0]["damping"]["poorly_determined"] == []
    assert set(stats[1]["damping"]["poorly_determined"]) == {"c_0", "c_2", "c_tau"}


# ----------------------------------------------------------------------------- k_0, signs


def stiff_mode(base: dict, **changes: float) -> dict:
    """``base`` with some coefficients changed (a map that made other data)."""
    return {**base, **changes}


def test_k0_is_identified_not_a_scale():
    """ω_n² = k_J + (k_0 + k_p k_J)/J + k_p k_0/J²: three coefficients for three unknowns, so
    k_0 is estimated, not a scale to fix. Data from maps with k_0 = 25000 and 4000 N m/rad
    (1 % noise, 208 poses) give back k_0, k_J and k_p within 3 of their standard errors
    (measured 1-7 % of the values, the truth within 0.9 of them; required: below 20 %, within
    3). Fixing k_0 at the values a user would have guessed (10000, 20000, 40000) instead
    leaves a misfit that depends on the guess (base RMS 1.7 / 1.2 / 5.4 %, shoulder 5.4 / 41 /
    99 %, against 1.0 % estimated); the estimate has no guess to depend on."""
    truths = [
        stiff_mode(PAPER_MODES[0], k_0=25000.0, k_j=900.0, k_p=1.5),
        stiff_mode(PAPER_MODES[1], k_0=4000.0, k_j=1200.0, k_p=0.8),
    ]
    poses = synthetic_poses(11, noise=0.01, mode_maps=truths)
    fitted = fit_map(poses)
    stats = fitted.metadata["fit_statistics"]["modes"]
    assert fitted.metadata["fit_statistics"]["k_0_fixed"] is None
    for mode, true, st in zip(fitted.mode_maps, truths, stats, strict=True):
        coefficients = st["frequency"]["coefficients"]
        for key in FREQ:
            se = coefficients[key]["se"]
            assert se < 0.2 * true[key], key
            assert abs(mode[key] - true[key]) < 3 * se, (key, mode[key], true[key], se)
        assert st["frequency"]["rms_relative_error"] < 0.0115  # the 1 % noise
    guessed = [fit_map(poses, k_0=k) for k in (10000.0, 20000.0, 40000.0)]
    rms = [
        [st["frequency"]["rms_relative_error"] for st in g.metadata["fit_statistics"]["modes"]]
        for g in guessed
    ]
    # Base (true 25000): the misfit of a wrong fixed k_0 grows with the distance to the truth.
    assert rms[0][0] > rms[1][0] and rms[2][0] > rms[1][0]
    # Shoulder (true 4000): every guess is too stiff, and the misfit shows it.
    assert min(r[1] for r in rms) > 1.3 * stats[1]["frequency"]["rms_relative_error"]


def test_the_frequencies_cannot_tell_the_k0_branches_apart():
    """Why k_0 is determined only up to one swap: (k_0, k_p) and (k_p k_J, k_0/k_J) give the
    same three coefficients of ω_n² in 1/J, so the same ω_n at every inertia (the independent
    reference, to rounding). Data from the other branch of the paper's shoulder map come back
    on the branch with k_0 >= k_p k_J, the published one."""
    true = PAPER_MODES[1]
    other = stiff_mode(true, k_0=true["k_p"] * true["k_j"], k_p=true["k_0"] / true["k_j"])
    inertia = np.column_stack([np.linspace(0.3, 12.0, 50)] * 6)
    np.testing.assert_allclose(
        mode_reference(other, inertia)[0], mode_reference(true, inertia)[0], rtol=1e-12
    )
    fitted = fit_map(
        synthetic_poses(12, noise=0.0, mode_maps=[PAPER_MODES[0], other]),
        mode_specs=(ModeSpec(1, (1,), 1),),
    )
    (mode,) = fitted.mode_maps
    assert mode["k_0"] == pytest.approx(true["k_0"], rel=1e-6)
    assert mode["k_p"] == pytest.approx(true["k_p"], rel=1e-6)


def unphysical_poses() -> list[dict]:
    """Data that ask for negative coefficients (the shoulder's k_p = −0.2 and c_2 = −0.02
    with c_τ = 3; J_1 is 0.7-8.4 kg m² on these poses, where 1 + k_p/J_1 and c_0 + c_2 J_1
    stay positive, so the law is defined), as real arms' data can when the map's form does not
    fit them: 0.5 % noise."""
    shoulder = stiff_mode(PAPER_MODES[1], k_p=-0.2, c_2=-0.02, c_tau=3.0)
    return synthetic_poses(13, noise=0.005, mode_maps=[PAPER_MODES[0], shoulder])


def test_coefficients_keep_their_physical_signs_and_a_bound_is_reported_as_such():
    """Every coefficient stays >= 0 (module docstring of tvist.ident.map_fit: a negative k_p,
    k_J, k_0 or k_g makes ω_n² negative at some inertia or load, a negative c_2 or c_τ a
    negative damping). Where the data ask for a negative value, the coefficient is held at 0
    and reported "at bound" with no standard error, and it is not called poorly determined."""
    fitted = fit_map(unphysical_poses())
    for mode in fitted.mode_maps:
        for key in ("k_0", "k_j", "k_g", "k_p", "c_0", "c_1", "c_2", "c_tau"):
            assert mode[key] >= 0.0, key
    shoulder = fitted.metadata["fit_statistics"]["modes"][1]
    assert shoulder["frequency"]["at_bound"] == ["k_p"]
    assert shoulder["damping"]["at_bound"] == ["c_2"]
    assert fitted.mode_maps[1]["k_p"] == fitted.mode_maps[1]["c_2"] == 0.0
    for step, key in (("frequency", "k_p"), ("damping", "c_2")):
        assert shoulder[step]["coefficients"][key]["se"] is None  # NaN, stored as null
        assert key not in shoulder[step]["poorly_determined"]
    # The others are estimates with standard errors.
    assert math.isfinite(shoulder["frequency"]["coefficients"]["k_j"]["se"])


def test_fit_map_prints_a_coefficient_at_its_bound_as_such(tmp_path, capsys):
    """``tvist fit-map``: "k_p = 0 (at bound >= 0)", never "k_p = 2.4e-31 ± 0.11"."""
    import json

    from tvist.cli import main

    records = tmp_path / "records.jsonl"
    records.write_text(
        "".join(
            json.dumps({"key": f"pose{i}", **pose}) + "\n"
            for i, pose in enumerate(unphysical_poses())
        )
    )
    assert main(["fit-map", str(records), "--out", str(tmp_path / "map.json")]) == 0
    shoulder = capsys.readouterr().out.split("shoulder mode")[1]
    assert "k_p = 0 (at bound >= 0)" in shoulder
    assert "c_2 = 0 (at bound >= 0)" in shoulder
    assert "k_j = " in shoulder and "± " in shoulder.split("k_j = ")[1].split(",")[0]
