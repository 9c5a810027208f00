"""Tests of the MuJoCo twin (tvist.sim): model vs the rigid-body model, modes, sensors, logs."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from pinocchio_reference import flexible_joint_modes
from tvist import robots
from tvist.sim import (
    UR5E_FLEX,
    FlexParams,
    SimulationDiverged,
    Twin,
    csv_header,
)
from twin_calibration import TWIN_CALIBRATION

Q1 = np.array([0.0, -np.pi, 0.0, -np.pi / 2, 0.0, 0.0])
Q2 = np.array([np.pi / 2, -np.pi, 0.0, -np.pi / 2, 0.0, 0.0])
Q3 = np.array([np.pi / 2, -np.pi / 2, 5 * np.pi / 6, -np.pi / 2, 0.0, 0.0])
PAYLOAD_KG = 5.0
PAYLOAD_COM_M = (0.0, 0.0, 0.05)
#: The UR5e twin's control period (its robot data), s.
DT_S = robots.params("ur5e").control_period_s
TWO_PI = 2.0 * np.pi


@pytest.fixture(scope="module")
def twin() -> Twin:
    return Twin("ur5e", payload_kg=PAYLOAD_KG, payload_com_m=PAYLOAD_COM_M)


@pytest.fixture(scope="module")
def robot() -> robots.Robot:
    return robots.ur5e(PAYLOAD_KG, PAYLOAD_COM_M)


@pytest.fixture
def pinocchio() -> None:
    """The independent modal reference needs pinocchio (a test dependency)."""
    pytest.importorskip("pinocchio")


def hold(q: np.ndarray, duration_s: float) -> np.ndarray:
    """A constant joint reference of ``duration_s`` at 500 Hz."""
    return np.tile(q, (round(duration_s / DT_S), 1))


def smooth_move(q_from: np.ndarray, q_to: np.ndarray, move_s: float, total_s: float) -> np.ndarray:
    """Smoothstep joint move of ``move_s`` (zero velocity at both ends), held until ``total_s``."""
    blend = np.clip(np.arange(0.0, total_s, DT_S) / move_s, 0.0, 1.0)
    return q_from + np.outer(blend**2 * (3.0 - 2.0 * blend), q_to - q_from)


def ar2_mode(y: np.ndarray, dt_s: float) -> tuple[float, float]:
    """``(wn_rad_s, zeta)`` of a sampled damped sinusoid from a least-squares AR(2) fit.

    A sampled free decay ``y_k = A r^k cos(k theta + phi)`` obeys ``y_k = a1 y_{k-1} +
    a2 y_{k-2}`` exactly; the roots of ``z² - a1 z - a2`` are ``exp(s dt)``.
    """
    lagged = np.column_stack([y[1:-1], y[:-2]])
    (a1, a2), *_ = np.linalg.lstsq(lagged, y[2:], rcond=None)
    z = np.roots([1.0, -a1, -a2]).astype(complex)[0]
    s = np.log(z) / dt_s
    return float(abs(s)), float(-s.real / abs(s))


# ----------------------------------------------------------------------------- model


@pytest.mark.parametrize(
    ("payload_kg", "com_m", "inertia"),
    [
        (0.0, (0.0, 0.0, 0.0), None),
        (PAYLOAD_KG, PAYLOAD_COM_M, None),
        (3.0, (0.02, -0.01, 0.08), (0.01, 0.02, 0.015, 0.001, -0.002, 0.0005)),
    ],
)
def test_mjcf_model_matches_rigid_body_model(payload_kg, com_m, inertia) -> None:
    """MuJoCo's link-side M(q), gravity torque and flange pose equal the Rust rigid model.

    Both evaluate the same parameters in double precision (observed differences ~1e-14), so
    1e-9 kg m² (N m, m) only leaves room for rounding, not for a wrong frame or sign.
    """
    twin = Twin("ur5e", payload_kg=payload_kg, payload_com_m=com_m, payload_inertia_kg_m2=inertia)
    robot = robots.ur5e(payload_kg, com_m, inertia)
    model, data = twin.rigid_model()
    import mujoco

    flange = model.site("flange").id
    rng = np.random.default_rng(7)
    lower, upper = twin.params.joint_limits_rad.T
    for q in rng.uniform(np.maximum(lower, -np.pi), np.minimum(upper, np.pi), size=(20, 6)):
        np.testing.assert_allclose(twin.mass_matrix(q), robot.mass_matrix(q), rtol=0, atol=1e-9)
        data.qpos[:] = q
        data.qvel[:] = 0.0
        mujoco.mj_forward(model, data)
        np.testing.assert_allclose(data.qfrc_bias, robot.gravity_torque(q), rtol=0, atol=1e-9)
        pose = robot.flange_pose(q)
        np.testing.assert_allclose(data.site_xpos[flange], pose[:3, 3], rtol=0, atol=1e-12)
        np.testing.assert_allclose(
            data.site_xmat[flange].reshape(3, 3), pose[:3, :3], rtol=0, atol=1e-12
        )


def test_static_equilibrium_balances_gravity(twin: Twin, robot: robots.Robot) -> None:
    """At rest the gear spring torque (eq. 22) carries the rigid model's gravity torque."""
    for q in (Q1, Q3):
        q_link = twin.equilibrium(q)
        spring = twin.flex.spring_torque_nm(q - q_link)
        # Newton stops at a residual < 1e-11 N m; 1e-8 N m covers the model difference (1e-14).
        np.testing.assert_allclose(spring, robot.gravity_torque(q_link), rtol=0, atol=1e-8)
    # The shoulder sags under the arm's weight in the stretched-out pose Q1 (gear torque
    # ~107 N m at ~5.7 mrad): a deflection of milliradians, as in real strain-wave gears.
    sag = Q1 - twin.equilibrium(Q1)
    assert 1e-3 < abs(sag[1]) < 2e-2


# ----------------------------------------------------------------------------- modes


@pytest.mark.parametrize("pose", ["Q1", "Q3"])
def test_twin_calibration_is_pinned(twin: Twin, pose: str) -> None:
    """The 5 kg modes at Q1 and Q3 within 1 % of TWIN_CALIBRATION (tests/twin_calibration.py,
    where the reason for each value is given)."""
    q = {"Q1": Q1, "Q3": Q3}[pose]
    for (wn, zeta), (f_pinned, zeta_pinned) in zip(
        twin.modes(q), TWIN_CALIBRATION[pose], strict=True
    ):
        # ±1 %: a 10 % stiffness change moves the modes by 3-5 %, any retuning shows.
        assert wn / TWO_PI == pytest.approx(f_pinned, rel=0.01)
        assert zeta == pytest.approx(zeta_pinned, rel=0.01)
    # Q2 differs from Q1 only by the base angle, which changes neither inertia nor gravity.
    if pose == "Q1":
        np.testing.assert_allclose(twin.modes(Q2), twin.modes(Q1), rtol=1e-9)


@pytest.mark.parametrize(
    ("payload_kg", "pose"),
    [
        (PAYLOAD_KG, Q1),
        (PAYLOAD_KG, Q3),
        (0.0, Q3),
        (2.0, np.array([0.3, -1.2, 1.4, -0.5, 1.1, 0.7])),
    ],
)
def test_twin_modes_equal_an_independent_pinocchio_analysis(pinocchio, payload_kg, pose) -> None:
    """Every mode of the twin's linearisation against one built from pinocchio's mass matrix,
    gravity torque and gravity derivative with the gear laws written out (no MuJoCo, no
    twin code): equilibrium, stiffness, damping, eigenvalues, and the base/shoulder choice."""
    twin = Twin("ur5e", payload_kg=payload_kg, payload_com_m=PAYLOAD_COM_M)
    payload = robots.Payload(payload_kg, PAYLOAD_COM_M) if payload_kg else robots.Payload()
    ref = flexible_joint_modes(twin.params, payload, UR5E_FLEX, pose, twin.gravity_m_s2)
    np.testing.assert_allclose(twin.equilibrium(pose), ref.q_link, rtol=0, atol=1e-10)
    analysis = twin.modal_analysis(pose)
    # The twin's gravity stiffness is a central difference (step 1e-6 rad): rounding of
    # ~1e-16 · 100 N m / 1e-6 rad = 1e-8 N m/rad against stiffnesses ≥ 2000 N m/rad, and the
    # two equilibria agree to ~1e-13 rad: 1e-7 relative is far above both and far below any
    # modelling change (observed 4e-13).
    np.testing.assert_allclose(analysis.wn_rad_s, ref.wn_rad_s, rtol=1e-7)
    np.testing.assert_allclose(analysis.zeta, ref.zeta, rtol=1e-7)
    np.testing.assert_allclose(twin.modes(pose), ref.base_and_shoulder(), rtol=1e-7)


def base_damping_from_rigid_model(robot: robots.Robot, q_link: np.ndarray) -> float:
    """The base damping of UR5E_FLEX written out from its documented law (N m s/rad).

    ``c0 (1 + c_load |L|_s) (1 + c_load2 |L|_s)`` with the load ``L`` the tilting moment on the
    base bearing, i.e. the shoulder's gravity torque of the rigid model (at rest the shoulder
    spring carries it).
    """
    load = robot.gravity_torque(q_link)[1]
    s = UR5E_FLEX.load_smoothing_nm
    smooth_abs = math.sqrt(load * load + s * s) - s
    assert UR5E_FLEX.c_load2_per_nm is not None
    return (
        UR5E_FLEX.c0_nms_per_rad[0]
        * (1.0 + UR5E_FLEX.c_load_per_nm[0] * smooth_abs)
        * (1.0 + UR5E_FLEX.c_load2_per_nm[0] * smooth_abs)
    )


def test_base_mode_at_q1_matches_single_joint_formula(twin: Twin, robot: robots.Robot) -> None:
    """In Q1 the base axis carries no gravity load and is decoupled from the other joints
    (M[0, j] ~ 0 at the reference pose), so the base mode is the one-joint oscillator
    ``wn = sqrt(k1 / J0)``, ``zeta = c / (2 sqrt(k1 J0))`` with the base damping ``c`` at the
    tilting moment the stretched arm puts on the base bearing."""
    # Up to the links' small products of inertia (~1e-5 kg m²).
    np.testing.assert_allclose(robot.mass_matrix(Q1)[0, 1:], 0.0, atol=1e-4)
    q_link = twin.equilibrium(Q1)
    mass = robot.mass_matrix(q_link)
    # The gravity sag (~6 mrad at the shoulder) tilts the arm slightly out of that symmetry:
    # |M[0, j]| ~ 1e-2 kg m² against J0 ~ 9 kg m². The base then mixes weakly with the
    # shoulder mode 0.2 Hz away; observed effect 3e-6 on wn and 1.3e-5 on zeta, so 1e-3.
    assert np.max(np.abs(mass[0, 1:])) < 0.02
    j0 = mass[0, 0]
    k1 = UR5E_FLEX.k1_nm_per_rad[0]
    c = base_damping_from_rigid_model(robot, q_link)
    # The load terms dominate: the stretched arm's ~100 N m multiply the unloaded damping
    # about fortyfold, so a modal analysis (or loop) without them would be far off.
    assert c > 10.0 * UR5E_FLEX.c0_nms_per_rad[0]
    (wn, zeta), _ = twin.modes(Q1)
    assert wn == pytest.approx(math.sqrt(k1 / j0), rel=1e-3)
    assert zeta == pytest.approx(c / (2.0 * math.sqrt(k1 * j0)), rel=1e-3)


def test_base_damping_ratio_falls_when_the_arm_folds(twin: Twin) -> None:
    """The real UR5e's trend (SPEC Table 3): base ζ 0.26 stretched (Q1), 0.08 folded (Q3).

    The base bearing's tilting moment, and with it the base damping, shrinks as the arm
    folds towards the base axis faster than ``sqrt(J0)`` does."""
    (_, zeta_q1), _ = twin.modes(Q1)
    (_, zeta_q3), _ = twin.modes(Q3)
    assert zeta_q1 > 1.5 * zeta_q3
    # A constant base damping would give the opposite: ζ ∝ 1/sqrt(J0), J0 ~9.7 vs ~1.1 kg m².
    constant = dataclasses.replace(
        UR5E_FLEX, c_load_per_nm=(0.0, *UR5E_FLEX.c_load_per_nm[1:]), c_load2_per_nm=None
    )
    plain = Twin("ur5e", payload_kg=PAYLOAD_KG, payload_com_m=PAYLOAD_COM_M, flex=constant)
    assert plain.modes(Q1)[0][1] < plain.modes(Q3)[0][1]


@pytest.mark.slow
def test_base_damping_ratio_stays_moderate_over_the_campaign() -> None:
    """Over the mapping campaign's poses (both payload extremes) the base mode stays a clearly
    underdamped mode (0.03 <= ζ <= 0.35), also where the arm is folded near the base axis."""
    from tvist.ident.campaign import campaign_poses

    poses = campaign_poses(payloads_kg=(0.0, 5.0))
    for payload in (0.0, 5.0):
        twin = Twin("ur5e", payload_kg=payload, payload_com_m=PAYLOAD_COM_M)
        zetas = [twin.modes(p.q)[0][1] for p in poses if p.payload_kg == payload]
        assert len(zetas) == 52
        assert 0.03 <= min(zetas) and max(zetas) <= 0.35, (payload, min(zetas), max(zetas))


@pytest.mark.parametrize("load_joint", [(1, 1, 2, 3, 4, 5), None])
def test_free_decay_after_base_impulse_matches_modes(pinocchio, load_joint) -> None:
    """A tap on the base link in Q1 rings at the base mode of the eigen-analysis.

    This checks that the time-stepping loop's damping (evaluated in place for speed) is the
    law of FlexParams.damping_nms_per_rad used by the modal analysis: with the base damper
    loaded by the shoulder (default) the base ζ is ~0.25, loaded by its own, torque-free gear
    ~0.006; either way the simulation must ring at the ζ of an independent modal analysis."""
    flex = dataclasses.replace(UR5E_FLEX, damper_load_joint=load_joint)
    twin = Twin("ur5e", payload_kg=PAYLOAD_KG, payload_com_m=PAYLOAD_COM_M, flex=flex)
    payload = robots.Payload(PAYLOAD_KG, PAYLOAD_COM_M)
    # The independent (pinocchio) modal analysis, not the twin's own linearisation.
    ref = flexible_joint_modes(twin.params, payload, flex, Q1, twin.gravity_m_s2)
    (wn, zeta), _ = ref.base_and_shoulder()
    # 1e-5 rad/s keeps the gear torque swing ~0.01 N m, so the load-dependent damping and the
    # cubic spring stay linear to ~1e-5.
    record = twin.run(hold(Q1, 0.6), initial_qd_rad_s=[1e-5, 0, 0, 0, 0, 0])
    y = record.actual_q[:, 0] - ref.q_link[0]
    wn_sim, zeta_sim = ar2_mode(y, DT_S)
    # Second-order integration at 0.5 ms: frequency error ~(wn dt)²/24 ~ 3e-5 (observed 3e-5;
    # zeta error observed <= 1.3e-6).
    assert wn_sim == pytest.approx(wn, rel=5e-4)
    assert zeta_sim == pytest.approx(zeta, abs=1e-3)


@pytest.mark.parametrize(("pose", "which"), [(Q1, 1), (Q3, 0), (Q3, 1)])
def test_free_decay_of_mode_shape_matches_modes(
    pinocchio, twin: Twin, pose: np.ndarray, which: int
) -> None:
    """Started in one eigenvector of the independent (pinocchio) modal analysis, the nonlinear
    simulation rings at that mode's wn and zeta."""
    payload = robots.Payload(PAYLOAD_KG, PAYLOAD_COM_M)
    analysis = flexible_joint_modes(twin.params, payload, UR5E_FLEX, pose, twin.gravity_m_s2)
    base = analysis.dominant(0)
    index = base if which == 0 else analysis.dominant(1, exclude=(base,))
    wn, zeta = analysis.wn_rad_s[index], analysis.zeta[index]
    lam = wn * (-zeta + 1j * math.sqrt(1.0 - zeta**2))
    shape = analysis.shapes[:, index]
    amplitude_rad = 1e-5  # linear regime, as above
    record = twin.run(
        hold(pose, 0.6),
        initial_dq_rad=amplitude_rad * shape.real,
        initial_qd_rad_s=amplitude_rad * (lam * shape).real,
    )
    joint = int(np.argmax(analysis.energy[:, index]))
    y = record.actual_q[:, joint] - analysis.q_link[joint]
    n_fit = min(len(y), round(4.0 / (zeta * wn) / DT_S))  # four decay time constants
    wn_sim, zeta_sim = ar2_mode(y[:n_fit], DT_S)
    # Observed: |rel. error of wn| <= 3.6e-4, |error of zeta| <= 7.3e-4 (Q3 base, whose
    # neighbouring shoulder mode is 1.3 Hz away and leaks in through the nonlinearities).
    assert wn_sim == pytest.approx(wn, rel=2e-3)
    assert zeta_sim == pytest.approx(zeta, abs=3e-3)


# ----------------------------------------------------------------------------- sensors


@pytest.mark.parametrize("pose", [Q1, Q3, np.array([0.3, -1.2, 1.4, -0.5, 1.1, 0.7])])
def test_accelerometer_at_rest_reads_gravity(
    twin: Twin, robot: robots.Robot, pose: np.ndarray
) -> None:
    """At rest the accelerometer reads ``R^T [0, 0, +g]`` in the flange frame (acceptance)."""
    record = twin.run(hold(pose, 0.2))
    for q_link, accel in zip(record.actual_q, record.actual_tool_accelerometer, strict=True):
        rotation = robot.flange_pose(q_link)[:3, :3]
        expected = rotation.T @ np.array([0.0, 0.0, twin.gravity_m_s2])
        np.testing.assert_allclose(accel, expected, rtol=0, atol=1e-6)
    # It stays at rest: the start is an exact equilibrium of the discrete dynamics.
    np.testing.assert_allclose(record.actual_q, record.actual_q[:1].repeat(100, 0), atol=1e-12)


def test_tcp_pose_is_flange_pose_of_link_angles(twin: Twin, robot: robots.Robot) -> None:
    """actual_TCP_pose = UR axis-angle pose of the flange at the link-side angles."""
    from scipy.spatial.transform import Rotation

    record = twin.run(smooth_move(Q1, Q3, 1.5, 1.6))
    poses = robot.flange_pose_many(record.actual_q)
    np.testing.assert_allclose(record.actual_TCP_pose[:, :3], poses[:, :3, 3], atol=1e-12)
    rotations = Rotation.from_rotvec(record.actual_TCP_pose[:, 3:]).as_matrix()
    np.testing.assert_allclose(rotations, poses[:, :3, :3], atol=1e-12)
    assert np.all(np.linalg.norm(record.actual_TCP_pose[:, 3:], axis=1) <= np.pi + 1e-12)


def test_accelerometer_noise_is_seeded_white_noise() -> None:
    clean = Twin().run(hold(Q3, 1.0)).actual_tool_accelerometer
    noisy_a = Twin(accel_noise_std=0.05, seed=3).run(hold(Q3, 1.0)).actual_tool_accelerometer
    noisy_b = Twin(accel_noise_std=0.05, seed=3).run(hold(Q3, 1.0)).actual_tool_accelerometer
    np.testing.assert_array_equal(noisy_a, noisy_b)
    # A run seed makes the noise depend on that seed only, whatever ran before, and leaves
    # the twin's own generator (used by runs without one) untouched.
    twin = Twin(accel_noise_std=0.05, seed=3)
    first = twin.run(hold(Q3, 1.0), noise_seed=[3, 11]).actual_tool_accelerometer
    assert not np.array_equal(first, noisy_a)
    np.testing.assert_array_equal(twin.run(hold(Q3, 1.0)).actual_tool_accelerometer, noisy_a)
    again = twin.run(hold(Q3, 1.0), noise_seed=[3, 11]).actual_tool_accelerometer
    np.testing.assert_array_equal(first, again)
    with pytest.raises(ValueError, match="noise_seed"):
        twin.run(hold(Q3, 0.1), noise_seed=-1)
    noise = noisy_a - clean
    # 1500 samples: the sample std has a relative standard error of 1/sqrt(2*1500) ~ 1.8 %,
    # so 10 % is more than 5 standard errors; the mean's standard error is 0.05/sqrt(1500).
    assert np.std(noise) == pytest.approx(0.05, rel=0.1)
    assert abs(np.mean(noise)) < 5 * 0.05 / math.sqrt(noise.size)


def test_motion_deflects_the_gears_and_rings_after_the_stop(twin: Twin) -> None:
    """A fast move leaves residual vibration at the end pose's modes (no shaping)."""
    # 1.5 s of hold: the slowest-decaying mode at Q3 (base, ζ ≈ 0.05 at 20 Hz) falls by e in
    # 1 / (ζ wn) ≈ 0.15 s, so by ~1e-4 at the end.
    record = twin.run(smooth_move(Q1, Q3, 1.5, 3.0))
    residual = record.actual_tool_accelerometer[int(1.5 / DT_S) :]
    residual = residual - residual[-50:].mean(axis=0)
    assert np.max(np.abs(residual[:25])) > 0.05  # m/s², rings right after the stop
    assert np.max(np.abs(residual[-100:])) < 1e-3 * np.max(np.abs(residual[:25]))  # and decays
    # target_qd / target_qdd are finite differences of the reference.
    np.testing.assert_allclose(record.target_qd, np.gradient(record.target_q, DT_S, axis=0))
    np.testing.assert_allclose(record.target_qdd, np.gradient(record.target_qd, DT_S, axis=0))


# ----------------------------------------------------------------------------- failures


def test_divergence_is_detected_and_names_the_time() -> None:
    """A wrist-3 spring far too stiff for the 0.5 ms step (wn dt ~ 13) blows up and raises."""
    k1 = list(UR5E_FLEX.k1_nm_per_rad)
    k1[5] = 2.0e5
    twin = Twin(flex=dataclasses.replace(UR5E_FLEX, k1_nm_per_rad=tuple(k1)))
    q_ref = np.linspace(Q1, Q1 + [0, 0, 0, 0, 0, 0.5], 500)
    with pytest.raises(SimulationDiverged, match=r"diverged at t = \d+\.\d{4} s") as info:
        twin.run(q_ref)
    assert 0.0 < info.value.time_s <= 1.0


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"robot_name": "ur6"}, "unknown robot"),
        ({"payload_kg": -1.0}, "payload_kg"),
        ({"payload_kg": float("nan")}, "payload_kg"),
        ({"payload_kg": 7.6}, "payload_kg"),
        ({"payload_com_m": (0.0, float("inf"), 0.0)}, "com_m"),
        ({"physics_dt_s": 0.001}, "physics_dt_s"),
        ({"accel_noise_std": -0.1}, "accel_noise_std"),
        ({"robot_name": "ur3e", "payload_kg": 1.0}, "has no twin of robot"),
    ],
)
def test_bad_twin_arguments_raise_value_error(kwargs: dict, message: str) -> None:
    with pytest.raises(ValueError, match=message):
        Twin(**kwargs)


@pytest.mark.parametrize(
    ("field", "value", "message"),
    [
        ("k1_nm_per_rad", (22000.0, -1.0, 1.0, 1.0, 1.0, 1.0), "must be > 0"),
        ("k3_nm_per_rad3", (0.0,) * 5, "expected 6 values"),
        ("c0_nms_per_rad", (float("nan"),) * 6, "NaN"),
        ("c_load_per_nm", (-0.1,) * 6, "must be >= 0"),
        ("c_load2_per_nm", (0.1, -0.1, 0.0, 0.0, 0.0, 0.0), "c_load2_per_nm: must be >= 0"),
        ("c_load2_per_nm", (0.1,) * 5, "c_load2_per_nm: expected 6 values"),
        ("damper_load_joint", (1, 1, 2, 3, 4), "damper_load_joint"),
        ("damper_load_joint", (1, 1, 2, 3, 4, 6), "damper_load_joint"),
        ("damper_load_joint", (1, 1, 2, 3, 4, 0.5), "damper_load_joint"),
        ("damper_load_joint", 1, "damper_load_joint"),
    ],
)
def test_bad_flex_params_raise_value_error(field: str, value: tuple, message: str) -> None:
    flex = dataclasses.replace(UR5E_FLEX, **{field: value})
    with pytest.raises(ValueError, match=message):
        Twin(flex=flex)


@pytest.mark.parametrize(
    ("q_ref", "dt_s", "message"),
    [
        (np.full((10, 6), np.nan), DT_S, "row 0"),
        (np.vstack([hold(Q1, 0.02), [[0, 0, np.nan, 0, 0, 0]]]), DT_S, "row 10"),
        (Q1, DT_S, "shape"),
        (hold(Q1, 0.02)[:, :5], DT_S, "shape"),
        (Q1[None, :], DT_S, "shape"),
        (np.vstack([hold(Q1, 0.02), [[0, -1.0, 3.5, 0, 0, 0]]]), DT_S, "joint 2 .* limits"),
        ([["a"] * 6] * 3, DT_S, "numeric"),
        (np.linspace(Q1, Q3, 200), DT_S, "joint 0 moves at .* speed limit"),
        (hold(Q1, 0.02), 0.0013, "multiple"),
        (hold(Q1, 0.02), float("nan"), "dt_s"),
    ],
)
def test_bad_trajectory_raises_before_simulating(twin: Twin, q_ref, dt_s, message) -> None:
    with pytest.raises(ValueError, match=message):
        twin.run(q_ref, dt_s=dt_s)


def test_damping_law_reads_the_load_of_the_named_joint() -> None:
    """c_j = c0_j (1 + c_load_j |L_j|_s) (1 + c_load2_j |L_j|_s), L_j = tau[load_joint[j]],
    |x|_s = sqrt(x² + s²) - s."""
    flex = FlexParams(
        (1.0, 1.0, 1.0), (0.0,) * 3, (2.0, 3.0, 4.0), (0.5, 0.1, 0.0), 5.0, 0.1, (1, 1, 0)
    )
    tau = np.array([[40.0, -12.0, 7.0], [0.0, 0.0, 0.0]])
    smooth_12 = math.sqrt(12.0**2 + 25.0) - 5.0  # 8 N m
    expected = [[2.0 * (1 + 0.5 * smooth_12), 3.0 * (1 + 0.1 * smooth_12), 4.0], [2.0, 3.0, 4.0]]
    np.testing.assert_allclose(flex.damping_nms_per_rad(tau), expected, rtol=1e-14)
    # Without a mapping every damper is loaded by its own gear.
    own = dataclasses.replace(flex, damper_load_joint=None).damping_nms_per_rad(tau[0])
    smooth_40 = math.sqrt(40.0**2 + 25.0) - 5.0
    np.testing.assert_allclose(own, [2.0 * (1 + 0.5 * smooth_40), 3.0 * (1 + 0.1 * smooth_12), 4.0])
    # The second load factor multiplies: c0 (1 + c_load |L|_s) (1 + c_load2 |L|_s).
    quadratic = dataclasses.replace(flex, c_load2_per_nm=(0.25, 0.0, 2.0))
    expected_q = [2.0 * (1 + 0.5 * smooth_12) * (1 + 0.25 * smooth_12), 3.0 * (1 + 0.1 * smooth_12)]
    np.testing.assert_allclose(quadratic.damping_nms_per_rad(tau[0])[:2], expected_q, rtol=1e-14)
    own_quadratic = quadratic.damping_nms_per_rad(tau[0])[2]
    np.testing.assert_allclose(own_quadratic, 4.0 * (1 + 2.0 * smooth_40), rtol=1e-14)


def test_flex_params_inverse_spring_law() -> None:
    """deflection_rad inverts eq. 22 on both sides of zero."""
    flex = FlexParams((2.0e4,), (2.4e9,), (1.0,), (0.0,))
    tau = np.array([-300.0, -5.0, 0.0, 1e-3, 42.0, 300.0])
    delta = flex.deflection_rad(tau[:, None])
    np.testing.assert_allclose(flex.spring_torque_nm(delta)[:, 0], tau, rtol=1e-12, atol=1e-12)


# ----------------------------------------------------------------------------- CSV


def test_csv_has_rtde_columns_and_six_decimals(twin: Twin, tmp_path) -> None:
    record = twin.run(np.linspace(Q1, Q1 + 0.01, 50), progress=True)
    path = record.to_csv(tmp_path / "run.csv")
    lines = path.read_text().splitlines()
    header = lines[0].split(",")
    expected = (
        ["timestamp"]
        + [f"target_q_{i}" for i in range(6)]
        + [f"target_qd_{i}" for i in range(6)]
        + [f"target_qdd_{i}" for i in range(6)]
        + [f"actual_q_{i}" for i in range(6)]
        + [f"actual_qd_{i}" for i in range(6)]
        + [f"actual_TCP_pose_{i}" for i in range(6)]
        + [f"actual_tool_accelerometer_{i}" for i in range(3)]
    )
    assert header == expected == csv_header()
    assert len(lines) == 51
    assert all(len(cell.split(".")[1]) == 6 for cell in lines[1].split(","))
    table = np.loadtxt(path, delimiter=",", skiprows=1)
    np.testing.assert_allclose(table[:, 0], record.timestamp, atol=5e-7)
    np.testing.assert_allclose(table[:, 19:25], record.actual_q, atol=5e-7)
    np.testing.assert_allclose(table[:, -3:], record.actual_tool_accelerometer, atol=5e-7)


def test_csv_reads_back_with_the_log_reader(twin: Twin, tmp_path) -> None:
    from tvist.ident import read_rtde_csv

    record = twin.run(hold(Q3, 0.1))
    loaded = read_rtde_csv(record.to_csv(tmp_path / "run.csv"))
    np.testing.assert_allclose(loaded.actual_q, record.actual_q, atol=5e-7)
    np.testing.assert_allclose(loaded.tool_accel, record.actual_tool_accelerometer, atol=5e-7)


def test_non_finite_record_is_never_written(twin: Twin, tmp_path) -> None:
    record = twin.run(hold(Q1, 0.02))
    broken = dataclasses.replace(
        record, actual_tool_accelerometer=np.full_like(record.actual_tool_accelerometer, np.nan)
    )
    with pytest.raises(ValueError, match="NaN"):
        broken.to_csv(tmp_path / "broken.csv")
    assert not (tmp_path / "broken.csv").exists()
