"""The dynamic map: the paper's Table 3, an independent re-evaluation of eqs. 42-51, map files."""

from __future__ import annotations

import json

import numpy as np
import pytest

import tvist
from map_reference import PAPER_MODES, modes_reference
from map_smoothing_reference import (
    RANGE_BLEND_WIDTH,
    smooth_abs_torque,
    soft_clamp,
)
from tvist.maps.paper10 import MODE_FIELDS, RANGE_FIELDS, general_mode

# Table 1 / Table 2 of the paper (UR5e), typed in independently of the core.
BASE = {"k_0": 10000.0, "k_j": 1060.0, "k_p": 2.54, "c_0": 1.53, "c_2": 0.39, "c_tau": 3.81}
SHOULDER = {"k_0": 10000.0, "k_j": 763.0, "k_p": 1.73, "c_0": 0.27, "c_2": 0.038, "c_tau": 47.2}


def _damped_hz(wn_rad_s: float, zeta: float) -> float:
    return wn_rad_s * np.sqrt(1.0 - zeta**2) / (2.0 * np.pi)


def _paper_modes_reference(j0: float, j1: float) -> list[tuple[float, float]]:
    """Eqs. 47-48 (base, as printed) and 50-51 (shoulder) from the independent transcription."""
    modes = modes_reference(PAPER_MODES, [[j0, j1]])[0]
    return [(float(wn), float(zeta)) for wn, zeta in modes]


@pytest.mark.parametrize(
    ("j", "expected"),
    [
        # SPEC section 3, Table 3 reproduction: (f_d0 Hz, zeta_0, f_d1 Hz, zeta_1).
        ((9.73, 9.25), (8.018, 0.2645, 6.909, 0.3730)),
        ((1.12, 1.58), (22.026, 0.0772, 19.220, 0.1357)),
    ],
)
def test_paper_map_reproduces_table_3(j, expected):
    (wn0, z0), (wn1, z1) = tvist.DynamicMap.paper_ur5e().modes_from_inertia(j)
    got = (_damped_hz(wn0, z0), z0, _damped_hz(wn1, z1), z1)
    # 1e-3 relative: the reference values carry 4-5 significant digits.
    np.testing.assert_allclose(got, expected, rtol=1e-3)


def test_paper_map_equals_an_independent_evaluation_of_the_equations():
    rng = np.random.default_rng(1)
    paper = tvist.DynamicMap.paper_ur5e()
    for j0, j1 in rng.uniform(0.05, 15.0, size=(500, 2)):
        got = paper.modes_from_inertia([j0, j1])
        # Same formulas, different operation order: equal to ~1e-15 relative.
        np.testing.assert_allclose(got, _paper_modes_reference(j0, j1), rtol=1e-12)


def test_paper_map_coefficients_are_tables_1_and_2():
    base, shoulder = tvist.DynamicMap.paper_ur5e().mode_maps
    for mode, table in ((base, BASE), (shoulder, SHOULDER)):
        for key, value in table.items():
            assert mode[key] == value
        assert mode["k_g"] == 0.0 and mode["c_1"] == 0.0
    assert (base["frequency_joint"], base["damping_joint"]) == (1, 0)
    assert (base["damping_gain_exponent"], base["frequency_gain_exponent"]) == (1.0, -0.5)
    assert (shoulder["frequency_joint"], shoulder["damping_joint"]) == (1, 1)


def test_many_equals_one_by_one():
    paper = tvist.DynamicMap.paper_ur5e()
    j = np.random.default_rng(4).uniform(-0.5, 12.0, size=(300, 2))
    many = paper.modes_from_inertia_many(j)
    assert many.shape == (300, 2, 2)
    for row, modes in zip(j, many, strict=True):
        np.testing.assert_array_equal(modes, np.array(paper.modes_from_inertia(row)))
    gravity_map = tvist.DynamicMap([general_mode(1, **dict(SHOULDER, k_g=30.0))])
    with pytest.raises(ValueError, match="gravity torques"):
        gravity_map.modes_from_inertia_many(j)
    with pytest.raises(ValueError, match="shape of inertia_kg_m2"):
        gravity_map.modes_from_inertia_many(j, np.zeros((300, 3)))
    with pytest.raises(ValueError, match="reads 2 joint inertias"):
        paper.modes_from_inertia_many(np.ones((4, 1)))


def test_general_map_with_gravity_term():
    coeffs = dict(SHOULDER, k_g=30.0, c_1=0.1)
    dynmap = tvist.DynamicMap([general_mode(1, **coeffs)])
    assert dynmap.uses_gravity
    with pytest.raises(ValueError, match="gravity torques"):
        dynmap.modes_from_inertia([2.0, 3.0])
    ((wn, zeta),) = dynmap.modes_from_inertia([2.0, 3.0], [0.0, -40.0])
    j, tau = 3.0, -40.0
    k = coeffs["k_0"] + coeffs["k_j"] * j + coeffs["k_g"] * smooth_abs_torque(tau)
    gain = 1 + coeffs["k_p"] / j
    wn_ref = np.sqrt(gain) * np.sqrt(k / j)
    num = (coeffs["c_0"] + coeffs["c_1"] * np.sqrt(j) + coeffs["c_2"] * j) * (
        1 + coeffs["c_tau"] * j
    )
    zeta_ref = np.sqrt(gain) * num / (2 * np.sqrt(k * j))
    np.testing.assert_allclose([wn, zeta], [wn_ref, zeta_ref], rtol=1e-12)
    # The smoothing moves the stiffness by less than k_g τ_s = 30 N m/rad (0.2 % of k_0 here):
    # with the plain |τ| of eq. 42, ω_n would be higher by less than half of that, 0.1 %.
    k_plain = coeffs["k_0"] + coeffs["k_j"] * j + coeffs["k_g"] * abs(tau)
    assert 0.0 < np.sqrt(k_plain / k) - 1.0 < 0.5 * coeffs["k_g"] / coeffs["k_0"]


def test_the_gravity_term_is_smooth_where_the_torque_changes_sign():
    dynmap = tvist.DynamicMap([general_mode(1, **dict(SHOULDER, k_g=30.0))])
    j1 = 3.0
    taus = np.linspace(-3.0, 3.0, 601)  # 0.01 N m steps through τ = 0
    wn = np.array([dynmap.modes_from_inertia([1.0, j1], [0.0, t])[0][0] for t in taus])
    k = (
        SHOULDER["k_0"]
        + SHOULDER["k_j"] * j1
        + 30.0 * np.array([smooth_abs_torque(t) for t in taus])
    )
    wn_ref = np.sqrt(1 + SHOULDER["k_p"] / j1) * np.sqrt(k / j1)
    # Same formula, different operation order: 1e-12 relative.
    np.testing.assert_allclose(wn, wn_ref, rtol=1e-12)
    # No kink at τ = 0. The smoothed term's curvature there is 1/τ_s, so per 0.01 N m step
    # the slope of ω_n changes by ~1.05 % of its value far from 0 (s ≈ 0.09 rad/s per N m);
    # with |τ| it would jump from −s to +s at once, a change of 200 %.
    slope = np.diff(wn) / np.diff(taus)
    assert np.max(np.abs(np.diff(slope))) < 0.02 * np.max(np.abs(slope))
    assert wn[300] == dynmap.modes_from_inertia([1.0, j1], [0.0, 0.0])[0][0]
    assert wn[300] == pytest.approx(np.sqrt((1 + SHOULDER["k_p"] / j1) * k[300] / j1), rel=1e-15)


def test_base_frequency_from_j0_is_a_general_mode_on_joint_0():
    dynmap = tvist.DynamicMap([general_mode(0, **BASE)])
    a = dynmap.modes_from_inertia([2.0, 1.0])
    b = dynmap.modes_from_inertia([2.0, 7.0])
    assert a == b


def test_modes_at_a_pose_use_the_robots_inertia():
    robot = tvist.robots.ur5e(payload_kg=5.0, payload_com_m=(0.0, 0.0, 0.05))
    q = np.array([0.2, -2.0, 1.1, -1.2, 0.4, 0.0])
    paper = tvist.DynamicMap.paper_ur5e()
    j = robot.joint_inertia(q)
    np.testing.assert_allclose(
        paper.modes(robot, q), _paper_modes_reference(j[0], j[1]), rtol=1e-12
    )


def test_invalid_inertia_gives_nan_modes():
    ((wn0, z0), (wn1, z1)) = tvist.DynamicMap.paper_ur5e().modes_from_inertia([0.0, -1.0])
    assert all(np.isnan([wn0, z0, wn1, z1]))
    with pytest.raises(ValueError, match="reads 2 joint inertias"):
        tvist.DynamicMap.paper_ur5e().modes_from_inertia([1.0])


# ---- map files ----


def test_save_and_load_round_trip(tmp_path):
    payload = tvist.robots.Payload(5.0, (0.0, 0.0, 0.05))
    original = tvist.DynamicMap(
        tvist.DynamicMap.paper_ur5e().mode_maps,
        metadata={
            "robot": "ur5e",
            "payload": payload,
            "source": "test",
            "fit_statistics": {"rmse_hz": 0.1, "n_poses": 208},
        },
    )
    path = tmp_path / "map.json"
    original.save(path)
    loaded = tvist.DynamicMap.load(path)
    assert loaded.mode_maps == original.mode_maps
    assert loaded.metadata == original.metadata
    assert loaded.metadata["payload"] == {
        "mass_kg": 5.0,
        "com_m": [0, 0, 0.05],
        "inertia_kg_m2": None,
    }
    doc = json.loads(path.read_text())
    assert doc["schema_version"] == 1 and doc["kind"] == "paper10"
    j = [3.0, 4.0]
    assert loaded.modes_from_inertia(j) == original.modes_from_inertia(j)


def _write(tmp_path, doc) -> str:
    path = tmp_path / "bad.json"
    path.write_text(doc if isinstance(doc, str) else json.dumps(doc))
    return str(path)


def _good_doc() -> dict:
    return tvist.DynamicMap.paper_ur5e().to_dict()


def _with(change):
    doc = _good_doc()
    change(doc)
    return doc


@pytest.mark.parametrize(
    ("doc", "message"),
    [
        ("{not json", "not valid JSON"),
        ([1, 2], "top level must be a JSON object"),
        (_with(lambda d: d.pop("schema_version")), "schema_version"),
        (_with(lambda d: d.update(schema_version=2)), "schema_version: must be the integer 1"),
        (_with(lambda d: d.update(schema_version=1.0)), "schema_version: must be the integer 1"),
        (_with(lambda d: d.update(schema_version=True)), "schema_version: must be the integer 1"),
        (_with(lambda d: d.update(kind="other")), 'kind: unknown map kind "other"'),
        (
            _with(lambda d: d["modes"][0].update(damping_gain_exponent=-1e6)),
            r"modes\[0\]\.damping_gain_exponent: -1000000 is outside \[-2, 2\]",
        ),
        (
            _with(lambda d: d["modes"][1].update(frequency_gain_exponent=2.5)),
            r"modes\[1\]\.frequency_gain_exponent: 2.5 is outside",
        ),
        (_with(lambda d: d.pop("modes")), "modes: missing"),
        (_with(lambda d: d.update(modes=[])), "modes: must be a non-empty list"),
        (_with(lambda d: d["modes"][1].pop("k_p")), r"modes\[1\]\.k_p: missing"),
        (_with(lambda d: d["modes"][0].update(k_j="big")), r"modes\[0\]\.k_j: must be a number"),
        (_with(lambda d: d["modes"][0].update(c_tau=None)), r"modes\[0\]\.c_tau"),
        (_with(lambda d: d["modes"][0].update(k_jj=1.0)), r"modes\[0\]: unknown field\(s\) k_jj"),
        (
            _with(lambda d: d["modes"][1].update(damping_joint=-1)),
            r"modes\[1\]\.damping_joint: must be a joint index",
        ),
        (
            _with(lambda d: d["modes"][1].update(frequency_joint=1.5)),
            r"modes\[1\]\.frequency_joint",
        ),
        (_with(lambda d: d["modes"].__setitem__(0, 3)), r"modes\[0\]: must be an object"),
        (_with(lambda d: d.update(metadata=[1])), "metadata: must be an object"),
        (_with(lambda d: d["metadata"].update(robot=5)), "metadata.robot"),
        (
            _with(lambda d: d["metadata"].update(payload={"mass_kg": -1})),
            r"metadata\.payload\.mass_kg: must be >= 0",
        ),
        (_with(lambda d: d["metadata"].update(fit_statistics=3)), "metadata.fit_statistics"),
    ],
)
def test_load_rejects_malformed_files_naming_the_field(tmp_path, doc, message):
    with pytest.raises(ValueError, match=message):
        tvist.DynamicMap.load(_write(tmp_path, doc))


def test_non_finite_coefficients_are_rejected(tmp_path):
    # Map files are strict JSON: a NaN token is not JSON at all.
    text = json.dumps(_good_doc()).replace('"c_0": 1.53', '"c_0": NaN')
    assert "NaN" in text
    with pytest.raises(ValueError, match=r"bad\.json: \(document\): not valid JSON"):
        tvist.DynamicMap.load(_write(tmp_path, text))
    # Built in Python, a NaN coefficient is refused naming the field.
    mode = dict(tvist.DynamicMap.paper_ur5e().mode_maps[0], c_0=float("nan"))
    with pytest.raises(ValueError, match=r"modes\[0\]\.c_0: must be finite"):
        tvist.DynamicMap([mode])


def test_mode_fields_are_the_cores():
    fields = set(tvist.DynamicMap.paper_ur5e().mode_maps[0])
    assert set(MODE_FIELDS) | set(RANGE_FIELDS) == fields
    assert not set(MODE_FIELDS) & set(RANGE_FIELDS)


# ---- inertia ranges: the map never extrapolates beyond the inertias it was identified on ----
# Each inertia is saturated into its range by a C² soft clamp: the identity on
# [min(1 + ε), max(1 − ε)], exactly the bound beyond min(1 − ε) and max(1 + ε), quartic
# blends in between (tvist-core dynmap module docs).

#: The paper's base mode limited to J_0 in [1, 9] (damping) and J_1 in [2, 8] (frequency).
BASE_RANGES = {
    "damping_inertia_range_kg_m2": [1.0, 9.0],
    "frequency_inertia_range_kg_m2": [2.0, 8.0],
}


def _ranged_paper() -> tvist.DynamicMap:
    base, shoulder = tvist.DynamicMap.paper_ur5e().mode_maps
    return tvist.DynamicMap([{**base, **BASE_RANGES}, shoulder])


def test_the_paper_map_has_no_range():
    paper = tvist.DynamicMap.paper_ur5e()
    assert paper.inertia_ranges == [{}, {}]
    assert all(m[key] is None for m in paper.mode_maps for key in RANGE_FIELDS)


def test_ranges_saturate_each_inertia_into_its_range():
    ranged = _ranged_paper()
    assert ranged.inertia_ranges == [{0: (1.0, 9.0), 1: (2.0, 8.0)}, {}]
    rng = np.random.default_rng(7)
    # Random poses, plus points in each blend zone (J_0 near 1 and 9, J_1 near 2 and 8).
    points = np.r_[
        rng.uniform(0.05, 15.0, size=(400, 2)),
        np.c_[rng.uniform(0.9, 1.1, 50), rng.uniform(1.85, 2.15, 50)],
        np.c_[rng.uniform(8.5, 9.5, 50), rng.uniform(7.5, 8.5, 50)],
    ]
    for j0, j1 in points:
        got = ranged.modes_from_inertia([j0, j1])
        # Base mode: the independent equations at the saturated inertias; shoulder (no
        # range): at the raw J_1. Same formulas, different operation order: 1e-12 relative.
        base_ref = _paper_modes_reference(soft_clamp(j0, 1.0, 9.0), soft_clamp(j1, 2.0, 8.0))
        shoulder_ref = _paper_modes_reference(j0, j1)[1]
        np.testing.assert_allclose(got, [base_ref[0], shoulder_ref], rtol=1e-12)
    paper = tvist.DynamicMap.paper_ur5e()
    # Exact (bit-identical): beyond the blend zones the value at the bound, inside the core
    # zones [1.05, 8.55] x [2.1, 7.6] the unbounded map.
    for j, at in [
        ([0.3, 0.5], [1.0, 2.0]),
        ([0.95, 1.9], [1.0, 2.0]),
        ([40.0, 30.0], [9.0, 8.0]),
        ([9.5, 8.4], [9.0, 8.0]),
        ([4.0, 5.0], [4.0, 5.0]),
        ([1.06, 7.6], [1.06, 7.6]),
    ]:
        assert ranged.modes_from_inertia(j)[0] == paper.modes_from_inertia(at)[0]
    many = ranged.modes_from_inertia_many(np.array([[0.3, 0.5], [40.0, 30.0]]))
    np.testing.assert_array_equal(
        many[:, 0], [paper.modes_from_inertia(a)[0] for a in ([1.0, 2.0], [9.0, 8.0])]
    )


def test_the_soft_clamp_never_leaves_the_range_and_has_no_kink():
    # A base mode whose frequency depends on J_1 only, so ω_n(J_1) shows the saturation.
    ranged = _ranged_paper()
    j1 = np.linspace(1.5, 9.0, 7501)  # 1e-3 kg m² steps through both blend zones of [2, 8]
    wn = ranged.modes_from_inertia_many(np.c_[np.full_like(j1, 4.0), j1])[:, 0, 0]
    paper = tvist.DynamicMap.paper_ur5e()
    wn_lo, wn_hi = (paper.modes_from_inertia([4.0, b])[0][0] for b in (2.0, 8.0))
    # Never beyond the values at the bounds (ω_n decreases with J_1), and monotone.
    assert np.all((wn <= wn_lo) & (wn >= wn_hi))
    assert np.all(np.diff(wn) <= 0.0)
    # The slope changes gradually: between neighbouring 1e-3 kg m² steps the difference
    # quotient changes by at most 0.55 % of its peak (measured; set by the blend curvature
    # 1/(2 ε J_bound)), bounded here by 2 %; a hard clamp drops the slope to 0 in one step.
    slope = np.diff(wn) / np.diff(j1)
    assert np.max(np.abs(np.diff(slope))) < 0.02 * np.max(np.abs(slope))
    hard = np.array([paper.modes_from_inertia([4.0, b])[0][0] for b in np.clip(j1, 2.0, 8.0)])
    hard_slope = np.diff(hard) / np.diff(j1)
    assert np.max(np.abs(np.diff(hard_slope))) > 0.5 * np.max(np.abs(hard_slope))


def test_a_range_too_narrow_for_the_blend_zones_is_rejected(tmp_path):
    # (1 + ε)/(1 − ε) = 1.105: [1, 1.1] leaves no room for both blend zones, [1, 1.11] does.
    base = tvist.DynamicMap.paper_ur5e().mode_maps[0]
    with pytest.raises(ValueError, match=r"damping_inertia_range_kg_m2.*too narrow"):
        tvist.DynamicMap([{**base, "damping_inertia_range_kg_m2": [1.0, 1.1]}])
    tvist.DynamicMap([{**base, "damping_inertia_range_kg_m2": [1.0, 1.11]}])
    doc = _with_range(0, "frequency_inertia_range_kg_m2", [2.0, 2.1])
    with pytest.raises(ValueError, match=r"frequency_inertia_range_kg_m2.*too narrow"):
        tvist.DynamicMap.load(_write(tmp_path, doc))


def test_a_range_does_not_turn_broken_inertias_into_modes():
    ranged = _ranged_paper()
    for j in ([0.0, 3.0], [-2.0, 3.0], [float("nan"), 3.0], [float("inf"), 3.0]):
        wn, zeta = ranged.modes_from_inertia(j)[0]
        assert np.isnan(wn) and np.isnan(zeta), j


def test_general_mode_with_a_range():
    mode = general_mode(1, inertia_range_kg_m2=(0.5, 4.0), **SHOULDER)
    assert mode[RANGE_FIELDS[0]] == mode[RANGE_FIELDS[1]] == [0.5, 4.0]
    dynmap = tvist.DynamicMap([mode])
    # Beyond the upper blend zone (J >= 4.2 kg m²) the mode is the one at the bound, exactly.
    assert dynmap.modes_from_inertia([9.0, 10.0]) == dynmap.modes_from_inertia([9.0, 4.2])
    unbounded = tvist.DynamicMap([general_mode(1, **SHOULDER)])
    assert dynmap.modes_from_inertia([9.0, 10.0]) == unbounded.modes_from_inertia([9.0, 4.0])


def test_ranges_round_trip_and_old_files_still_load(tmp_path):
    ranged = _ranged_paper()
    ranged.save(tmp_path / "ranged.json")
    doc = json.loads((tmp_path / "ranged.json").read_text())
    assert doc["schema_version"] == 1
    assert doc["modes"][0]["damping_inertia_range_kg_m2"] == [1.0, 9.0]
    back = tvist.DynamicMap.load(tmp_path / "ranged.json")
    assert back.mode_maps == ranged.mode_maps
    assert back.modes_from_inertia([0.2, 50.0]) == ranged.modes_from_inertia([0.2, 50.0])
    # A file without the range fields (written before they existed) loads, unbounded.
    old = tvist.DynamicMap.paper_ur5e().to_dict()
    for mode in old["modes"]:
        for key in RANGE_FIELDS:
            del mode[key]
    (tmp_path / "old.json").write_text(json.dumps(old))
    loaded = tvist.DynamicMap.load(tmp_path / "old.json")
    assert loaded.inertia_ranges == [{}, {}]
    assert loaded.mode_maps == tvist.DynamicMap.paper_ur5e().mode_maps


def _with_range(mode: int, key: str, value):
    def change(doc):
        doc["modes"][mode][key] = value

    return _with(change)


@pytest.mark.parametrize(
    ("doc", "message"),
    [
        (
            _with_range(0, "damping_inertia_range_kg_m2", [0.0, 2.0]),
            r"modes\[0\]\.damping_inertia_range_kg_m2: .*min must be > 0",
        ),
        (
            _with_range(0, "damping_inertia_range_kg_m2", [-1.0, 2.0]),
            r"modes\[0\]\.damping_inertia_range_kg_m2: .*min must be > 0",
        ),
        (
            _with_range(0, "frequency_inertia_range_kg_m2", [3.0, 3.0]),
            r"modes\[0\]\.frequency_inertia_range_kg_m2: .*min must be < max",
        ),
        (
            _with_range(0, "frequency_inertia_range_kg_m2", [3.0, 1.0]),
            "min must be < max",
        ),
        (
            _with_range(0, "frequency_inertia_range_kg_m2", [1.0]),
            r"frequency_inertia_range_kg_m2: must be \[min, max\]",
        ),
        (
            _with_range(0, "frequency_inertia_range_kg_m2", "1-2"),
            r"frequency_inertia_range_kg_m2: must be \[min, max\]",
        ),
        (
            _with_range(0, "frequency_inertia_range_kg_m2", [1.0, "big"]),
            r"frequency_inertia_range_kg_m2\[1\]: must be a number",
        ),
        (
            _with_range(1, "frequency_inertia_range_kg_m2", [1.0, 2.0]),
            r"modes\[1\]: frequency and damping both read joint 1",
        ),
    ],
)
def test_load_rejects_bad_ranges(tmp_path, doc, message):
    with pytest.raises(ValueError, match=message):
        tvist.DynamicMap.load(_write(tmp_path, doc))


def test_non_finite_range_is_rejected(tmp_path):
    doc = _with_range(0, "damping_inertia_range_kg_m2", [1.0, 2.0])
    text = json.dumps(doc).replace("[1.0, 2.0]", "[1.0, Infinity]")
    with pytest.raises(ValueError, match="not valid JSON"):
        tvist.DynamicMap.load(_write(tmp_path, text))
    mode = dict(doc["modes"][0], damping_inertia_range_kg_m2=[1.0, float("inf")])
    with pytest.raises(ValueError, match=r"damping_inertia_range_kg_m2\[1\]: must be finite"):
        tvist.DynamicMap([mode])
    # The core checks too (for maps built without this module).
    mode = dict(tvist.DynamicMap.paper_ur5e().mode_maps[0], damping_inertia_range_kg_m2=[0.0, 1.0])
    with pytest.raises(ValueError, match="min must be > 0"):
        tvist._core.DynamicMap([mode])


# ---- MapDynamics validates the map as it is evaluated: saturated into its ranges ----

ROBOT_5KG = tvist.robots.ur5e(payload_kg=5.0, payload_com_m=(0.0, 0.0, 0.05))


def _overdamped_at_small_j0(inertia_range_kg_m2=None) -> tvist.DynamicMap:
    """A base mode (J = J_0) overdamped below J_0 ~ 0.35 kg m²: the (1 + k_p/J) factor grows
    at small J (ζ = 2.1 at 0.2, 0.75 at 0.6). The UR5e with 5 kg reaches J_0 ~ 0.18 kg m²
    with the arm pointing up."""
    coeffs = {"k_0": 1e4, "k_j": 763.0, "k_p": 1.73, "c_0": 60.0, "c_2": 0.038, "c_tau": 0.0}
    return tvist.DynamicMap([general_mode(0, inertia_range_kg_m2=inertia_range_kg_m2, **coeffs)])


def test_map_dynamics_accepts_a_map_overdamped_only_outside_its_range():
    unbounded = _overdamped_at_small_j0()
    assert unbounded.modes_from_inertia([0.2])[0][1] >= 1.0
    with pytest.raises(ValueError, match="no underdamped mode 0"):
        tvist.MapDynamics(ROBOT_5KG, unbounded)

    ranged = _overdamped_at_small_j0((0.6, 10.0))
    provider = tvist.MapDynamics(ROBOT_5KG, ranged)
    rng = np.random.default_rng(11)
    q = rng.uniform(-np.pi, np.pi, size=(3000, 6))
    j0 = ROBOT_5KG.joint_inertia_many(q)[:, 0]
    # The range's lower bound is held exactly at and below 0.6 (1 − ε) = 0.57 kg m².
    held = 0.6 * (1 - RANGE_BLEND_WIDTH)
    assert np.sum(j0 <= held) > 50  # the saturation is exercised (~8 % of random poses)
    for qk, jk in zip(q, j0, strict=True):
        ((wn, zeta),) = provider.modes(qk)
        assert np.isfinite(wn) and wn > 0 and 0.0 <= zeta < 1.0, (qk, jk, wn, zeta)
        # Below the range, the mode is the map's value at the bound, exactly.
        if jk <= held:
            assert (wn, zeta) == unbounded.modes_from_inertia([0.6])[0]


def test_map_dynamics_rejects_a_map_invalid_inside_its_own_range():
    with pytest.raises(
        ValueError, match=r"no underdamped mode 0 .*inertia ranges J_f \[0\.2, 10\] kg m²"
    ):
        tvist.MapDynamics(ROBOT_5KG, _overdamped_at_small_j0((0.2, 10.0)))


# ---- strict JSON, the map's robot, hostile files ----


def _strict_json(text: str):
    """``json.loads`` that refuses NaN/Infinity tokens (as other tools' parsers do)."""

    def refuse(token: str):
        raise ValueError(f"non-standard JSON token {token}")

    return json.loads(text, parse_constant=refuse)


def test_map_files_are_strict_json_with_null_for_unavailable_statistics(tmp_path):
    # Statistics that could not be computed (NaN, inf, numpy scalars) are written as null.
    stats = {"rms": float("nan"), "worst": float("inf"), "n": np.int64(3), "r": np.float64(0.5)}
    dynmap = tvist.DynamicMap(
        tvist.DynamicMap.paper_ur5e().mode_maps,
        metadata={"robot": "ur5e", "fit_statistics": stats, "note": [np.float32(2.0)]},
    )
    path = tmp_path / "map.json"
    dynmap.save(path)
    doc = _strict_json(path.read_text())
    assert doc["kind"] == "paper10"
    assert doc["metadata"]["fit_statistics"] == {"rms": None, "worst": None, "n": 3, "r": 0.5}
    assert doc["metadata"]["note"] == [2.0]
    assert tvist.DynamicMap.load(path).metadata == dynmap.metadata
    # The paper's map and a map with ranges are strict too.
    for m in (tvist.DynamicMap.paper_ur5e(), _ranged_paper()):
        _strict_json(m.to_json())


def test_a_map_file_written_by_fit_map_is_strict_json(tmp_path):
    from tvist.cli import main

    results = tmp_path / "r.jsonl"
    paper = tvist.DynamicMap.paper_ur5e()
    rng = np.random.default_rng(3)
    with results.open("w") as fh:
        for i in range(30):
            inertia = [rng.uniform(0.3, 9.0), rng.uniform(0.9, 9.0), 0.5, 0.1, 0.1, 0.01]
            modes = paper.modes_from_inertia(inertia)
            record = {
                "key": f"p{i}",
                "inertia_kg_m2": inertia,
                "modes": [
                    {"joint": j, "wn_rad_s": w, "zeta": z, "low_confidence": False}
                    for j, (w, z) in enumerate(modes)
                ],
            }
            fh.write(json.dumps(record) + "\n")
    out = tmp_path / "map.json"
    assert main(["fit-map", str(results), "--out", str(out)]) == 0
    doc = _strict_json(out.read_text())
    assert doc["kind"] == "paper10" and doc["metadata"]["robot"] == "ur5e"


def test_a_map_of_another_robot_is_refused_naming_both():
    ur10e = tvist.robots.ur10e(5.0, (0, 0, 0.05))
    paper = tvist.DynamicMap.paper_ur5e()
    assert paper.robot == "ur5e" and ur10e.core.name == "ur10e"
    # It used to run silently (zeta 0.49 / 0.67 on the UR10e).
    with pytest.raises(ValueError, match="identified on ur5e, not on ur10e"):
        tvist.MapDynamics(ur10e, paper)
    provider = tvist.MapDynamics(ur10e, paper, allow_other_robot=True)
    assert provider.n_modes == 2
    # A map without a robot name, or of the same robot, is accepted.
    anonymous = tvist.DynamicMap(paper.mode_maps)
    assert anonymous.robot is None
    tvist.MapDynamics(ur10e, anonymous)
    tvist.MapDynamics(tvist.robots.ur5e(5.0, (0, 0, 0.05)), paper)


def test_hostile_map_files_give_value_errors(tmp_path):
    text = tvist.DynamicMap.paper_ur5e().to_json()
    # "k_0": 1 followed by 400 zeros used to raise OverflowError; 100k nested "[" a
    # RecursionError.
    huge = text.replace('"k_0": 10000.0', '"k_0": 1' + "0" * 400, 1)
    assert huge != text
    with pytest.raises(ValueError, match="number out of range"):
        tvist.DynamicMap.load(_write(tmp_path, huge))
    with pytest.raises(ValueError, match="recursion limit"):
        tvist.DynamicMap.load(_write(tmp_path, "[" * 100_000 + "]" * 100_000))
    with pytest.raises(ValueError, match="not UTF-8"):
        path = tmp_path / "latin1.json"
        path.write_bytes(text.replace("Thomsen", "Th\xf6msen").encode("latin-1"))
        tvist.DynamicMap.load(path)
    # Deep nesting built in Python is refused too.
    deep: list = []
    for _ in range(200):
        deep = [deep]
    with pytest.raises(ValueError, match="nested deeper"):
        tvist.DynamicMap(paper_modes(), metadata={"robot": "ur5e", "deep": deep})


def paper_modes() -> list:
    return tvist.DynamicMap.paper_ur5e().mode_maps
