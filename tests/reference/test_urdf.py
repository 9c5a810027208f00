"""Arms from URDF: the model read by ``tvist.robots.from_urdf`` (yourdfpy's parser, the core's
URDF joint placement) against pinocchio loading the same file with its own URDF parser and
rigid-body algorithms; the UR arms written as URDF against their DH chains; refusals of what
the model cannot represent; the robot file in Python and C++."""

from __future__ import annotations

import json
import subprocess
from pathlib import Path

import numpy as np
import pytest

import tvist
from tvist.cli import main
from tvist.robots import Payload, Robot, dh_urdf, from_urdf, params, shipped_urdf
from tvist.robots.urdf import SHIPPED_URDFS

#: 1,000 random poses per arm: pinocchio's CRBA and gravity in a Python loop take well under
#: a second for all of them, so no smaller CI count is needed.
N_POSES = 1000
PAYLOAD = Payload(2.0, (0.01, -0.02, 0.06), (0.003, 0.0035, 0.002, 0.0001, 0.0, -0.0002))


def _pin_model(path: Path, tip_link: str, payload: Payload):
    """pinocchio's model of URDF ``path`` (its own parser) with ``payload`` on ``tip_link``."""
    import pinocchio as pin

    model = pin.buildModelFromUrdf(str(path))
    model.gravity.linear[:] = (0.0, 0.0, -9.81)  # the model's gravity (GRAVITY_M_S2 in the core)
    frame = model.frames[model.getFrameId(tip_link)]
    tensor = tvist.robots.inertia_tensor(np.asarray(payload.inertia_kg_m2))
    body = pin.Inertia(payload.mass_kg, np.asarray(payload.com_m), tensor)
    model.appendBodyToJoint(frame.parentJoint, frame.placement.act(body), pin.SE3.Identity())
    return model


def _pin_quantities(model, poses: np.ndarray):
    import pinocchio as pin

    data = model.createData()
    mass, gravity = [], []
    for angles in poses:
        q = _pin_configuration(model, angles)
        m = pin.crba(model, data, q)
        mass.append(np.triu(m) + np.triu(m, 1).T)  # crba fills the upper triangle
        gravity.append(pin.computeGeneralizedGravity(model, data, q).copy())
    return np.array(mass), np.array(gravity)


def _pin_configuration(model, angles: np.ndarray) -> np.ndarray:
    """pinocchio's configuration of joint angles (a continuous joint is ``(cos q, sin q)``)."""
    q = []
    for joint, angle in zip(model.joints[1:], angles, strict=True):
        q += [np.cos(angle), np.sin(angle)] if joint.nq == 2 else [angle]
    return np.array(q)


def _urdf_arms(tmp: Path) -> dict[str, tuple[Path, str, str]]:
    """Every shipped arm and the UR5e and UR10e written as URDF from their DH parameters."""
    arms = {name: shipped_urdf(name) for name in SHIPPED_URDFS}
    for name in ("ur5e", "ur10e"):
        path = tmp / f"{name}.urdf"
        path.write_text(dh_urdf(params(name)))
        arms[name] = (path, "base_link", "flange")
    return arms


def _poses(robot: Robot, seed: int) -> np.ndarray:
    limits = np.clip(robot.params.joint_limits_rad, -np.pi, np.pi)
    return np.random.default_rng(seed).uniform(limits[:, 0], limits[:, 1], (N_POSES, robot.n_dof))


@pytest.mark.parametrize("arm", ["fr3", "iiwa14", "gen3", "ur5e", "ur10e"])
@pytest.mark.filterwarnings("ignore:.*is continuous")
def test_urdf_arm_equals_pinocchio_on_the_same_file(tmp_path, arm):
    path, base, tip = _urdf_arms(tmp_path)[arm]
    robot = from_urdf(path, base, tip, PAYLOAD.mass_kg, PAYLOAD.com_m, PAYLOAD.inertia_kg_m2)
    poses = _poses(robot, seed=len(arm))
    mass_ref, gravity_ref = _pin_quantities(_pin_model(path, tip, PAYLOAD), poses)
    mass = robot.mass_matrix_many(poses)
    # Tolerance 1e-10 of the largest entry: both sides are exact algorithms in double
    # precision (rounding ~1e-15 relative); a wrong frame, axis, sign or inertia rotation
    # moves entries by O(1e-3) or more.
    for what, got, ref in (
        ("mass matrix", mass, mass_ref),
        ("joint-axis inertias", robot.joint_inertia_many(poses), np.diagonal(mass_ref, 0, 1, 2)),
        ("gravity torques", robot.gravity_torque_many(poses), gravity_ref),
    ):
        scale = np.max(np.abs(ref))
        assert np.max(np.abs(got - ref)) <= 1e-10 * scale, f"{arm}: {what}"


@pytest.mark.parametrize("name", ["ur5e", "ur10e"])
def test_ur_arms_from_urdf_equal_their_dh_models(tmp_path, name):
    path = tmp_path / f"{name}.urdf"
    path.write_text(dh_urdf(params(name)))
    from_file = from_urdf(path, "base_link", "flange", PAYLOAD.mass_kg, PAYLOAD.com_m)
    dh = Robot(params(name), Payload(PAYLOAD.mass_kg, PAYLOAD.com_m))
    poses = _poses(dh, seed=3)
    # Tolerance 1e-12 of each quantity's scale: the same numbers through XML text (17
    # significant digits, exact), the inertial frames rotated and back (a few ulp).
    for method in ("mass_matrix_many", "gravity_torque_many", "flange_pose_many"):
        got, ref = getattr(from_file, method)(poses), getattr(dh, method)(poses)
        assert np.max(np.abs(got - ref)) <= 1e-12 * np.max(np.abs(ref)), f"{name}: {method}"


# ---- refusals --------------------------------------------------------------------------

TWO_LINKS = """<robot name="arm">
  <link name="base"/>
  <link name="l1">
    <inertial><origin xyz="0.1 0 0" rpy="0 0 0"/><mass value="2"/>
      <inertia ixx="0.01" ixy="0" ixz="0" iyy="0.02" iyz="0" izz="0.02"/></inertial>
  </link>
  <link name="l2">
    <inertial><origin xyz="0.1 0 0" rpy="0 0 0"/><mass value="1"/>
      <inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial>
  </link>
  <link name="other"/>
  <joint name="j1" type="revolute"><parent link="base"/><child link="l1"/>
    <origin xyz="0 0 0.2" rpy="0 0 0"/><axis xyz="0 0 1"/>
    <limit lower="-3" upper="3" velocity="2" effort="1"/></joint>
  <joint name="j2" type="revolute"><parent link="l1"/><child link="l2"/>
    <origin xyz="0.3 0 0" rpy="1.5707963267948966 0 0"/><axis xyz="0 0 1"/>
    <limit lower="-3" upper="3" velocity="2" effort="1"/></joint>
  <joint name="j3" type="fixed"><parent link="base"/><child link="other"/>
    <origin xyz="1 0 0" rpy="0 0 0"/></joint>
</robot>
"""

BAD = {
    "missing inertial": (
        TWO_LINKS.replace(
            TWO_LINKS[
                TWO_LINKS.index('<link name="l2">') : TWO_LINKS.index('<link name="other"/>')
            ],
            '<link name="l2"/>\n  ',
        ),
        "l2",
        "link 'l2' has no <inertial>",
    ),
    "zero mass": (
        TWO_LINKS.replace('mass value="1"', 'mass value="0"'),
        "l2",
        "link 'l2' has mass 0",
    ),
    "tip not below the base": (TWO_LINKS, "l1", "tip link 'l1' is not below base link 'l2'"),
    "prismatic joint": (
        TWO_LINKS.replace('name="j2" type="revolute"', 'name="j2" type="prismatic"'),
        "l2",
        "joint 'j2' is prismatic",
    ),
    "mimic joint": (
        TWO_LINKS.replace(
            '<axis xyz="0 0 1"/>\n    <limit lower="-3" upper="3" velocity="2" '
            'effort="1"/></joint>\n  <joint name="j3"',
            '<axis xyz="0 0 1"/>\n    <limit lower="-3" upper="3" velocity="2" '
            'effort="1"/><mimic joint="j1"/></joint>\n  <joint name="j3"',
        ),
        "l2",
        "joint 'j2' mimics joint 'j1'",
    ),
}


def test_a_good_two_link_urdf_is_accepted(tmp_path):
    """The base of the refusal cases is itself valid (each refusal comes from its one change)."""
    path = tmp_path / "arm.urdf"
    path.write_text(TWO_LINKS)
    assert from_urdf(path, "base", "l2").n_dof == 2


@pytest.mark.parametrize("case", sorted(BAD))
def test_bad_urdfs_are_refused_naming_the_element(tmp_path, case, capsys):
    text, tip, message = BAD[case]
    # Each case changes the valid two-link file (or, for the chain, the base asked for).
    base = "l2" if case == "tip not below the base" else "base"
    assert (text != TWO_LINKS) != (base == "l2")
    path = tmp_path / "arm.urdf"
    path.write_text(text)
    with pytest.raises(ValueError, match=message.replace("(", r"\(")):
        from_urdf(path, base, tip)
    out = tmp_path / "arm.json"
    args = ["robot-file", str(path), "--base-link", base, "--tip-link", tip, "--out", str(out)]
    assert main(args) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and message in err[0], err
    assert not out.exists()


# ---- robot files -----------------------------------------------------------------------


def test_robot_file_round_trips_through_the_core(tmp_path, capsys):
    path, base, tip = shipped_urdf("fr3")
    out = tmp_path / "fr3.json"
    args = ["robot-file", str(path), "--base-link", base, "--tip-link", tip, "--out", str(out)]
    assert main([*args, "--max-payload-kg", "3"]) == 0
    assert "7 joints" in capsys.readouterr().out
    doc = json.loads(out.read_text())
    assert list(doc["robots"]) == ["fr3"] and len(doc["robots"]["fr3"]["joints"]) == 7
    loaded = tvist.robots.robot_file(out)
    assert loaded.max_payload_kg == 3.0
    from_file = Robot(loaded, PAYLOAD)
    direct = from_urdf(path, base, tip, PAYLOAD.mass_kg, PAYLOAD.com_m, PAYLOAD.inertia_kg_m2)
    poses = _poses(direct, seed=5)[:50]
    # The file holds every double to 17 significant digits: the same model bit for bit.
    np.testing.assert_array_equal(from_file.mass_matrix_many(poses), direct.mass_matrix_many(poses))


def test_cpp_shapes_from_a_robot_file_exactly_as_python(shape_with_map, tmp_path):
    """The 7-DOF FR3 from its robot file: tvist_shaper_new_map (C++ example over the C API)
    against Python on the same robot file and modal map (1e-12 rad: both run the same core
    code on the same parsed data; the C++ program writes 17 significant digits)."""
    path, base, tip = shipped_urdf("fr3")
    robot_path = tmp_path / "fr3.json"
    args = ["robot-file", str(path), "--base-link", base, "--tip-link", tip]
    assert main([*args, "--out", str(robot_path)]) == 0
    entries = [
        {
            "joint": 1,
            "stiffness_nm_per_rad": [9000.0, 0.0, 0.0],
            "damping_nms_per_rad": [20.0, 0.0, 0.0],
            "damping_load_joint": 1,
        },
        {
            "joint": 3,
            "stiffness_nm_per_rad": [7000.0, 0.0, 0.0],
            "damping_nms_per_rad": [10.0, 0.0, 0.0],
            "damping_load_joint": 3,
        },
    ]
    map_path = tmp_path / "fr3_modal.json"
    tvist.ModalMap(entries, (1, 3), {"robot": "fr3"}).save(map_path)
    dt_s, com = 0.002, (0.0, 0.0, 0.05)
    t = np.arange(0.0, 1.2, dt_s)
    s = np.clip(t / 0.8, 0.0, 1.0)
    blend = s**3 * (10 - 15 * s + 6 * s**2)
    start = np.array([0.0, -0.3, 0.0, -2.0, 0.0, 1.8, 0.8])
    q = start + np.outer(blend, [0.6, 0.5, 0.0, 0.4, 0.0, 0.0, 0.0])
    robot = Robot(tvist.robots.robot_file(robot_path), Payload(1.0, com))
    shaper = tvist.TvShaper(tvist.maps.dynamics_for(robot, tvist.load_map(map_path)), dt_s, 7, "zv")
    shaper.reset(q[0])
    expected = shaper.shape(q)
    samples, shaped = tmp_path / "in.txt", tmp_path / "out.txt"
    np.savetxt(samples, q, fmt="%.17g")
    cpp_args = [str(robot_path), "1.0", *map(str, com), str(map_path), str(dt_s), "zv"]
    subprocess.run([str(shape_with_map), *cpp_args, str(samples), str(shaped)], check=True)
    got = np.loadtxt(shaped)
    assert np.max(np.abs(expected - q)) > 1e-3  # the move is shaped
    np.testing.assert_allclose(got, expected, rtol=0, atol=1e-12)


# ---- the twin of a URDF arm ------------------------------------------------------------


def test_twin_of_a_urdf_arm_matches_the_model_and_rings(tmp_path):
    """The MuJoCo twin built from the FR3's URDF placement: MuJoCo's mass matrix and the flange
    pose equal the core's (both from the same parameters, different code: MuJoCo's CRBA and
    kinematics against tvist's), and a fast move of the shoulder rings the flange
    accelerometer after the move stops."""
    import dataclasses

    from tvist.sim import FlexParams, Twin

    path, base, tip = shipped_urdf("fr3")
    arm = dataclasses.replace(tvist.robots.urdf_params(path, base, tip), max_payload_kg=3.0)
    # Gear stiffness per joint for the 0.5 ms physics step: the wrists' tiny inertias (the
    # payload's own inertia gives joint 7 3e-3 kg m²) keep their modes below ~1 kHz.
    flex = FlexParams(
        k1_nm_per_rad=(9e3, 9e3, 7e3, 7e3, 2e3, 2e3, 1e3),
        k3_nm_per_rad3=(0.0,) * 7,
        c0_nms_per_rad=(8.0, 8.0, 6.0, 6.0, 1.0, 1.0, 0.5),
        c_load_per_nm=(0.0,) * 7,
    )
    payload = Payload(1.0, (0.0, 0.0, 0.05), (0.004, 0.004, 0.003, 0.0, 0.0, 0.0))
    twin = Twin(
        arm,
        payload_kg=payload.mass_kg,
        payload_com_m=payload.com_m,
        flex=flex,
        payload_inertia_kg_m2=payload.inertia_kg_m2,
    )
    robot = Robot(arm, payload)
    rng = np.random.default_rng(2)
    limits = arm.joint_limits_rad
    for q in rng.uniform(limits[:, 0], limits[:, 1], (20, 7)):
        m = robot.mass_matrix(q)
        # 1e-10 of the largest entry: two exact algorithms in double precision.
        assert np.max(np.abs(twin.mass_matrix(q) - m)) <= 1e-10 * np.max(np.abs(m))
    dt_s = 0.002
    t = np.arange(0.0, 1.0, dt_s)
    s = np.clip(t / 0.4, 0.0, 1.0)
    start = np.array([0.0, -0.3, 0.0, -2.0, 0.0, 1.8, 0.8])
    q_ref = start + np.outer(s**3 * (10 - 15 * s + 6 * s**2), [0.0, 0.4, 0.0, 0.0, 0.0, 0.0, 0.0])
    record = twin.run(q_ref, dt_s)
    accel = np.asarray(record.actual_tool_accelerometer)
    after_stop = accel[t > 0.45]
    ringing = np.ptp(after_stop - after_stop.mean(axis=0), axis=0).max()
    assert np.all(np.isfinite(accel)) and ringing > 1e-2, ringing


def test_rpy_convention_round_trips_and_matches_the_elementary_rotations():
    """URDF's ``Rz(yaw) Ry(pitch) Rx(roll)`` built here from the three elementary rotations:
    the matrix and quaternion forms agree with it, and the angles come back from the matrix
    (pitch inside ±π/2), at random angles and at the gimbal pose (pitch π/2, where only
    roll - yaw is defined: the rotation must come back, not the angles). To 1e-12."""
    from tvist.robots.rpy import rpy_angles, rpy_matrix, rpy_quat

    def elementary(axis: int, a: float) -> np.ndarray:
        c, s = np.cos(a), np.sin(a)
        i, j = [k for k in range(3) if k != axis]
        m = np.eye(3)
        m[i, i], m[i, j], m[j, i], m[j, j] = c, -s, s, c
        return m if axis != 1 else m.T  # Ry's sine signs are the other way round

    rng = np.random.default_rng(7)
    cases = [
        rng.uniform([-np.pi, -np.pi / 2, -np.pi], [np.pi, np.pi / 2, np.pi]) for _ in range(50)
    ]
    for rpy in [*cases, np.array([0.3, np.pi / 2, -0.4])]:
        expected = elementary(2, rpy[2]) @ elementary(1, rpy[1]) @ elementary(0, rpy[0])
        np.testing.assert_allclose(rpy_matrix(rpy), expected, atol=1e-12)
        w, x, y, z = rpy_quat(rpy)
        from_quat = np.array(
            [
                [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
            ]
        )
        np.testing.assert_allclose(from_quat, expected, atol=1e-12)
        np.testing.assert_allclose(rpy_matrix(rpy_angles(expected)), expected, atol=1e-12)
    for rpy in cases:
        np.testing.assert_allclose(rpy_angles(rpy_matrix(rpy)), rpy, atol=1e-12)
