"""Robot data, loader and rigid-body model, cross-checked against pinocchio.

The pinocchio model is built here, independently of tvist's kinematics: one revolute-z joint
per DH row, placed by the previous row's fixed transform ``Tz(d) Tx(a) Rx(alpha)``, with each
link's inertia moved into its joint frame by pinocchio's own ``SE3.act``.
"""

from __future__ import annotations

import dataclasses
import json
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest

import tvist
from pinocchio_reference import pinocchio_model
from tvist.robots import Payload, Robot, RobotParams, _cylinders, names, params
from tvist.trajectory import PAPER_POSES

pin = pytest.importorskip("pinocchio")

N_POSES = 1000
PAYLOADS = [
    Payload(),
    Payload(5.0, (0.0, 0.0, 0.05)),
    Payload(2.3, (0.03, -0.02, 0.08), (0.010, 0.012, 0.008, 0.001, -0.0005, 0.0007)),
]
Q1, Q2, Q3 = PAPER_POSES["Q1"], PAPER_POSES["Q2"], PAPER_POSES["Q3"]


def _random_poses(n_dof: int, seed: int) -> np.ndarray:
    return np.random.default_rng(seed).uniform(-np.pi, np.pi, size=(N_POSES, n_dof))


# ---- the data file and its loader ----


def test_data_file_has_every_robot_with_the_schema_fields():
    doc = json.loads(tvist._core.ROBOT_DATA_JSON)
    assert doc["schema_version"] == 1
    assert set(doc["robots"]) == {"ur3e", "ur5e", "ur10e", "ur16e", "ur20", "ur3", "ur5", "ur10"}
    for entry in doc["robots"].values():
        for key in ("description", "source", "inertia_source", "max_payload_kg"):
            assert key in entry
        assert len(entry["com_m"]) == len(entry["inertia_kg_m2"]) == len(entry["mass_kg"]) == 6


def test_ur5e_numbers_are_those_of_the_spec():
    # SPEC section 6, typed in here independently of the data file.
    p = params("ur5e")
    np.testing.assert_array_equal(p.d_m, [0.1625, 0, 0, 0.1333, 0.0997, 0.0996])
    np.testing.assert_array_equal(p.a_m, [0, -0.425, -0.3922, 0, 0, 0])
    np.testing.assert_array_equal(p.mass_kg, [3.761, 8.058, 2.846, 1.37, 1.3, 0.365])
    np.testing.assert_allclose(p.alpha_rad, [np.pi / 2, 0, 0, np.pi / 2, -np.pi / 2, 0])
    np.testing.assert_array_equal(p.com_m[1], [0.2125, 0, 0.11336])
    np.testing.assert_array_equal(p.com_m[5], [0, 0, -0.001159])


def test_loader_returns_frozen_read_only_params():
    p = params("ur10e")
    assert names() == ("ur3e", "ur5e", "ur10e", "ur16e", "ur20", "ur3", "ur5", "ur10")
    assert p.n_dof == 6 and p.inertia_tensors_kg_m2.shape == (6, 3, 3)
    with pytest.raises(ValueError):
        p.mass_kg[0] = 1.0
    with pytest.raises(dataclasses.FrozenInstanceError):
        p.name = "x"  # type: ignore[misc]
    with pytest.raises(ValueError, match="unknown robot 'ur99'"):
        params("ur99")


def test_every_published_inertia_is_physical():
    # Principal moments >= 0 and satisfying the triangle inequality (rounded data: 1e-12 slack).
    for name in names():
        for tensor in params(name).inertia_tensors_kg_m2:
            e = np.linalg.eigvalsh(tensor)
            assert e[0] >= -1e-12 and e[0] + e[1] >= e[2] - 1e-12, name


@pytest.mark.parametrize(
    ("change", "message"),
    [
        ({"mass_kg": [1.0] * 5}, "mass_kg: expected shape"),
        ({"mass_kg": [-1.0, 1, 1, 1, 1, 1]}, "mass_kg must be >= 0"),
        ({"com_m": np.full((6, 3), np.nan)}, "com_m: contains NaN"),
        ({"joint_limits_rad": [[1.0, -1.0]] * 6}, "lower < upper"),
        ({"max_velocity_rad_s": [0.0] * 6}, "max_velocity_rad_s must be > 0"),
        ({"inertia_kg_m2": "abc"}, "inertia_kg_m2: not a numeric array"),
    ],
)
def test_robot_params_reject_bad_fields(change, message):
    with pytest.raises(ValueError, match=message):
        dataclasses.replace(params("ur5e"), **change)


def test_from_dict_names_a_missing_field():
    doc = json.loads(tvist._core.ROBOT_DATA_JSON)
    entry = dict(doc["robots"]["ur3e"])
    del entry["mass_kg"]
    with pytest.raises(ValueError, match="mass_kg"):
        RobotParams.from_dict("ur3e", entry)


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"mass_kg": -1.0}, "mass_kg must be finite and >= 0"),
        ({"mass_kg": float("nan")}, "mass_kg must be finite"),
        ({"mass_kg": 1.0, "com_m": (0.0, 0.0)}, "com_m: expected shape"),
        ({"mass_kg": 1.0, "inertia_kg_m2": (1.0, 1.0, 1.0)}, "inertia_kg_m2: expected shape"),
    ],
)
def test_payload_rejects_bad_values(kwargs, message):
    with pytest.raises(ValueError, match=message):
        Payload(**kwargs)


@pytest.mark.parametrize(
    ("inertia", "message"),
    [
        ((1.0, 1.0, 1.0, 2.0, 0.0, 0.0), "not positive semi-definite"),
        ((0.1, 0.1, 0.5, 0.0, 0.0, 0.0), "triangle inequality"),
    ],
)
def test_robot_rejects_non_physical_payload_inertia(inertia, message):
    with pytest.raises(ValueError, match=message):
        tvist.robots.ur5e(payload_kg=1.0, payload_inertia_kg_m2=inertia)


def test_robot_rejects_non_physical_link_inertia():
    p = params("ur5e")
    bad = np.array(p.inertia_kg_m2)
    bad[2] = [0.01, 0.01, 0.05, 0, 0, 0]
    with pytest.raises(ValueError, match="link 2.*triangle inequality"):
        Robot.from_params(dataclasses.replace(p, inertia_kg_m2=bad))


def test_robot_methods_reject_wrong_shapes():
    robot = tvist.robots.ur5e()
    with pytest.raises(ValueError, match=r"q must have shape \(6,\)"):
        robot.joint_inertia(np.zeros(5))
    with pytest.raises(ValueError, match=r"shape \(n_samples, 6\)"):
        robot.joint_inertia_many(np.zeros((3, 5)))
    with pytest.raises(ValueError, match="q must have shape"):
        robot.mass_matrix(np.zeros((2, 6)))
    with pytest.raises(ValueError, match="q contains NaN"):
        robot.gravity_torque([0.0, np.nan, 0.0, 0.0, 0.0, 0.0])
    bad = np.zeros((4, 6))
    bad[2, 3] = np.inf
    with pytest.raises(ValueError, match="Q row 2"):
        robot.jacobian_many(bad)


# ---- cylinder-approximated link inertias (UR3e, UR5e and the CB-series) ----


def _data_text() -> str:
    """The robot data as the core embeds it (an independent parse for these checks)."""
    return tvist._core.ROBOT_DATA_JSON


ROOT = Path(__file__).resolve().parents[2]
DATA_FILE = ROOT / "crates" / "tvist-core" / "data" / "ur_e_series.json"


def test_the_robot_data_lives_in_the_core_crate_and_packages_with_it():
    # One file, inside the crate: the core embeds it, Python reads it from the core.
    assert DATA_FILE.read_text(encoding="utf-8") == tvist._core.ROBOT_DATA_JSON
    assert not list((ROOT / "python").rglob("ur_e_series.json"))
    cargo = shutil.which("cargo")
    assert cargo is not None, "cargo is needed (make test installs nothing without it)"
    listing = subprocess.run(
        [cargo, "package", "-p", "tvist-core", "--features", "json", "--list", "--allow-dirty"],
        cwd=ROOT,
        capture_output=True,
        text=True,
        check=True,
    ).stdout.split()
    assert "data/ur_e_series.json" in listing
    # Every field of the Python record comes from the core's parse.
    entry = json.loads(_data_text())["robots"]["ur10e"]
    p = params("ur10e")
    np.testing.assert_array_equal(p.d_m, entry["dh"]["d"])
    np.testing.assert_array_equal(p.joint_limits_rad, entry["joint_limits_rad"])
    assert (p.description, p.max_payload_kg) == (entry["description"], entry["max_payload_kg"])


def test_cylinder_robots_are_ur3e_ur5e_and_the_cb_series_and_their_source_says_so():
    robots = json.loads(_data_text())["robots"]
    cylinders = {"ur3e", "ur5e", "ur3", "ur5", "ur10"}
    assert {n for n, e in robots.items() if "inertia_cylinders" in e} == cylinders
    for name in sorted(cylinders):
        entry, source = robots[name], robots[name]["inertia_source"]
        assert "publishes no inertia tensors" in source
        assert "I_axis = m r^2/2, I_perpendicular = m (3 r^2 + l^2)/12" in source
        assert "centre of mass" in source and "DH frame i" in source
        # Every radius/length pair of the block is written out in the text, in link order.
        block = entry["inertia_cylinders"]
        at = 0
        for r, length in zip(block["radius_m"], block["length_m"], strict=True):
            at = source.index(f" {r:g}/{length:g}", at) + 1  # ValueError if missing/out of order


def test_stored_cylinder_tensors_are_the_ones_the_generator_writes():
    # Regenerating the derived rows must leave the data file unchanged, byte for byte.
    text = _data_text()
    assert _cylinders.regenerate(text) == text, "run: python -m tvist.robots._cylinders --write"
    assert _cylinders.main([]) == 0


def test_cylinder_formula_matches_pinocchio_for_every_axis():
    # pinocchio's own solid cylinder (axis z, about the centre), rotated onto x and y.
    mass, radius, length = 2.7, 0.06, 0.31
    reference = pin.Inertia.FromCylinder(mass, radius, length).inertia
    onto = {"x": pin.utils.rotate("y", np.pi / 2), "y": pin.utils.rotate("x", np.pi / 2)}
    for axis in ("x", "y", "z"):
        rot = onto.get(axis, np.eye(3))
        six = _cylinders.cylinder_inertia(mass, radius, length, axis)
        # Exact formulas on both sides: agreement to double round-off.
        np.testing.assert_allclose(
            tvist.robots.inertia_tensor(np.array(six)), rot @ reference @ rot.T, atol=1e-15
        )


def test_ur5e_rows_follow_the_block_and_the_link_masses():
    # Values typed in from the ROS 1 block, not read from code. 5e-10 relative: the file keeps
    # ten significant digits (at most half a unit of the tenth digit off).
    p = params("ur5e")
    # Upper arm: 8.058 kg, r = 0.06 m, l = 0.425 m, along DH x.
    across = 8.058 * (3 * 0.06**2 + 0.425**2) / 12
    expected = [8.058 * 0.06**2 / 2, across, across, 0, 0, 0]
    np.testing.assert_allclose(p.inertia_kg_m2[1], expected, rtol=5e-10)
    # Wrist 3: 0.365 kg, r = 0.0375 m, l = 0.0458 m, along DH z.
    across = 0.365 * (3 * 0.0375**2 + 0.0458**2) / 12
    expected = [across, across, 0.365 * 0.0375**2 / 2, 0, 0, 0]
    np.testing.assert_allclose(p.inertia_kg_m2[5], expected, rtol=5e-10)


def test_ur5e_inertias_at_q1_and_q3_are_those_of_the_spec():
    # SPEC section 6 (typed in independently): with 5 kg 5 cm beyond the flange and the
    # cylinder approximation, J_0, J_1 = 8.94, 8.36 at Q1 and 1.12, 1.18 at Q3. 1 %: the spec
    # prints three figures (rounding <= 0.45 %); other plausible tensors miss by more (the
    # ROS 2 'tensor' blocks: +2.7 % and +20 %; ur_e_description's 0.075 m radii: +1.07 % at Q3).
    robot = tvist.robots.ur5e(payload_kg=5.0, payload_com_m=(0.0, 0.0, 0.05))
    np.testing.assert_allclose(robot.joint_inertia(Q1)[:2], [8.94, 8.36], rtol=0.01)
    np.testing.assert_allclose(robot.joint_inertia(Q3)[:2], [1.12, 1.18], rtol=0.01)


@pytest.mark.parametrize(
    ("args", "message"),
    [
        ((1.0, 0.05, 0.2, "w"), "axis must be one of"),
        ((1.0, 0.0, 0.2, "x"), "radius, length > 0"),
        ((-1.0, 0.05, 0.2, "x"), "mass >= 0"),
        ((1.0, 0.05, float("nan"), "z"), "radius, length > 0"),
    ],
)
def test_cylinder_inertia_rejects_bad_values(args, message):
    with pytest.raises(ValueError, match=message):
        _cylinders.cylinder_inertia(*args)


def test_cylinder_block_needs_one_entry_per_link():
    entry = json.loads(_data_text())["robots"]["ur5e"]
    entry["inertia_cylinders"]["axis"] = ["x"] * 5
    with pytest.raises(ValueError, match="one entry per link"):
        _cylinders.link_inertias(entry)


# ---- the model against pinocchio ----


@pytest.mark.parametrize("name", ["ur3e", "ur5e", "ur10e", "ur16e", "ur20", "ur3", "ur5", "ur10"])
@pytest.mark.parametrize("payload_index", range(len(PAYLOADS)))
def test_model_matches_pinocchio(name, payload_index):
    payload = PAYLOADS[payload_index]
    p = params(name)
    robot = Robot(p, payload)
    model, flange = pinocchio_model(p, payload)
    data = model.createData()
    qs = _random_poses(p.n_dof, seed=10 * names().index(name) + payload_index)
    mass = robot.mass_matrix_many(qs)
    diag = robot.joint_inertia_many(qs)
    pose = robot.flange_pose_many(qs)
    jac = robot.jacobian_many(qs)
    grav = robot.gravity_torque_many(qs)
    for k, q in enumerate(qs):
        m_ref = pin.crba(model, data, q)
        m_ref = np.triu(m_ref) + np.triu(m_ref, 1).T  # crba fills the upper triangle
        g_ref = pin.computeGeneralizedGravity(model, data, q)
        j_ref = pin.computeFrameJacobian(model, data, q, flange, pin.LOCAL_WORLD_ALIGNED)
        pin.framesForwardKinematics(model, data, q)
        t_ref = data.oMf[flange].homogeneous
        # 1e-9 absolute on values of order 0.01-100 (kg m², N m, m): both libraries are exact
        # to double round-off (~1e-13 here); any modelling difference would be far larger.
        np.testing.assert_allclose(mass[k], m_ref, rtol=0, atol=1e-9)
        np.testing.assert_allclose(diag[k], np.diag(m_ref), rtol=0, atol=1e-9)
        np.testing.assert_allclose(grav[k], g_ref, rtol=0, atol=1e-9)
        np.testing.assert_allclose(jac[k], j_ref, rtol=0, atol=1e-9)
        np.testing.assert_allclose(pose[k], t_ref, rtol=0, atol=1e-9)


def test_single_pose_methods_equal_the_batch_ones():
    robot = tvist.robots.ur16e(payload_kg=4.0, payload_com_m=(0.0, 0.1, 0.05))
    qs = _random_poses(6, seed=3)[:20]
    for q, m, j, t, g in zip(
        qs,
        robot.mass_matrix_many(qs),
        robot.jacobian_many(qs),
        robot.flange_pose_many(qs),
        robot.gravity_torque_many(qs),
        strict=True,
    ):
        np.testing.assert_array_equal(robot.mass_matrix(q), m)
        np.testing.assert_array_equal(robot.jacobian(q), j)
        np.testing.assert_array_equal(robot.flange_pose(q), t)
        np.testing.assert_array_equal(robot.gravity_torque(q), g)
        np.testing.assert_array_equal(robot.joint_inertia(q), np.diag(m))


def test_core_batch_entry_points_read_any_memory_layout():
    robot = tvist.robots.ur5e(payload_kg=1.0)
    qs = _random_poses(6, seed=5)[:10]
    expected = robot.joint_inertia_many(qs)
    np.testing.assert_array_equal(robot.core.joint_inertia_many(np.asfortranarray(qs)), expected)
    j = np.asfortranarray(expected[:, :2])
    paper = tvist.DynamicMap.paper_ur5e()
    np.testing.assert_array_equal(
        paper.core.modes_from_inertia_many(j), paper.modes_from_inertia_many(expected[:, :2])
    )


def test_ur5e_q1_q3_inertias_and_stretched_pose():
    robot = tvist.robots.ur5e(payload_kg=5.0, payload_com_m=(0.0, 0.0, 0.05))
    assert robot.n_dof == 6 and robot.params.name == "ur5e" and robot.payload.mass_kg == 5.0
    # Q1 and Q2 differ only in the base angle, on which no J_i depends.
    np.testing.assert_array_equal(Q1[1:], Q2[1:])
    np.testing.assert_allclose(robot.joint_inertia(Q1), robot.joint_inertia(Q2), rtol=1e-14)
    # q = 0: arm stretched out horizontally along -x of the base at shoulder height (d1),
    # reach a2 + a3 = 0.8172 m; the flange is offset by d4 (y) and lowered by d5.
    t = robot.flange_pose(np.zeros(6))
    np.testing.assert_allclose(t[:3, 3], [-0.8172, -0.1333 - 0.0996, 0.1625 - 0.0997], atol=1e-12)


def _custom_params(name: str, d, a, alpha, mass, com, inertia) -> RobotParams:
    n = len(d)
    return RobotParams(
        name=name,
        description="test arm",
        source="test",
        d_m=d,
        a_m=a,
        alpha_rad=alpha,
        mass_kg=mass,
        com_m=com,
        inertia_kg_m2=inertia,
        inertia_source="test",
        joint_limits_rad=[[-np.pi, np.pi]] * n,
        max_velocity_rad_s=[1.0] * n,
        max_payload_kg=1.0,
    )


def test_planar_two_link_arm_matches_the_textbook_mass_matrix():
    # Two links of lengths l1, l2 with point masses at lc1, lc2 along them; vertical axes.
    l1, l2, lc1, lc2, m1, m2 = 0.7, 0.5, 0.3, 0.2, 4.0, 2.5
    p = _custom_params(
        "planar2",
        d=[0.0, 0.0],
        a=[l1, l2],
        alpha=[0.0, 0.0],
        mass=[m1, m2],
        # DH frame i sits at the far end of link i: the centre of mass is behind it on x.
        com=[[lc1 - l1, 0.0, 0.0], [lc2 - l2, 0.0, 0.0]],
        inertia=np.zeros((2, 6)),
    )
    robot = Robot.from_params(p)
    for q2 in np.linspace(-3.0, 3.0, 13):
        c2 = np.cos(q2)
        m11 = m1 * lc1**2 + m2 * (l1**2 + lc2**2 + 2 * l1 * lc2 * c2)
        m12 = m2 * (lc2**2 + l1 * lc2 * c2)
        expected = np.array([[m11, m12], [m12, m2 * lc2**2]])
        np.testing.assert_allclose(robot.mass_matrix([0.4, q2]), expected, rtol=0, atol=1e-12)
        np.testing.assert_allclose(robot.gravity_torque([0.4, q2]), 0.0, atol=1e-12)


def test_a_seven_joint_arm_matches_pinocchio():
    rng = np.random.default_rng(11)
    n = 7
    inertia = []
    for _ in range(n):
        # Physical tensors: R diag(principal) R^T with triangle-satisfying principal moments.
        a, b = rng.uniform(0.01, 0.05, size=2)
        principal = np.diag([a, b, rng.uniform(abs(a - b), a + b)])
        rot = np.linalg.qr(rng.normal(size=(3, 3)))[0]
        t = rot @ principal @ rot.T
        inertia.append([t[0, 0], t[1, 1], t[2, 2], t[0, 1], t[0, 2], t[1, 2]])
    p = _custom_params(
        "seven",
        d=rng.uniform(-0.2, 0.3, n),
        a=rng.uniform(-0.4, 0.4, n),
        alpha=rng.uniform(-np.pi, np.pi, n),
        mass=rng.uniform(0.5, 5.0, n),
        com=rng.uniform(-0.1, 0.1, (n, 3)),
        inertia=inertia,
    )
    payload = Payload(1.5, (0.0, 0.02, 0.1))
    robot = Robot.from_params(p, payload)
    model, flange = pinocchio_model(p, payload)
    data = model.createData()
    qs = rng.uniform(-np.pi, np.pi, (200, n))
    for q, m, g, j in zip(
        qs,
        robot.mass_matrix_many(qs),
        robot.gravity_torque_many(qs),
        robot.jacobian_many(qs),
        strict=True,
    ):
        m_ref = pin.crba(model, data, q)
        # Same 1e-9 absolute tolerance and reasoning as test_model_matches_pinocchio.
        np.testing.assert_allclose(m, np.triu(m_ref) + np.triu(m_ref, 1).T, rtol=0, atol=1e-9)
        np.testing.assert_allclose(g, pin.computeGeneralizedGravity(model, data, q), atol=1e-9)
        j_ref = pin.computeFrameJacobian(model, data, q, flange, pin.LOCAL_WORLD_ALIGNED)
        np.testing.assert_allclose(j, j_ref, rtol=0, atol=1e-9)
