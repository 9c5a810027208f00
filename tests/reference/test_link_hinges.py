"""Bending links in the modal model: the hinged arm's mass matrix and its modes.

(a) The mass matrix of the arm with hinge pairs in the upper arm and forearm (the core's
``Robot::with_link_hinges``) against pinocchio's CRBA of the same split chain, assembled
here from the DH parameters (pinocchio's own frames and inertia transforms). (b) The modal
map's modes with hinges against the MuJoCo twin's true modes of a bending-link family
variant, whose beams are two hinges per link with the twin's own equilibrium and linearised
eigen-analysis: a finer, independent model.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import tvist
from pinocchio_reference import _fixed_dh, _pin
from tvist import _core
from tvist.maps.modal import ModalMap, modal_map_from_flex
from tvist.robots import Payload, params
from tvist.sim.family import sample_variant

PAYLOAD = Payload(5.0, (0.0, 0.0, 0.05))
HINGES = ((1, 0.5), (2, 0.5))


def _hinged_pinocchio():
    """pinocchio's model of the UR5e with a hinge pair at the middle of links 1 and 2, joints
    in the order of the core's hinged arm, with the last joint and the flange's placement in
    it."""
    pin = _pin()
    p = params("ur5e")
    model = pin.Model()
    parent, placement = 0, pin.SE3.Identity()
    hinged = dict(HINGES)
    for i in range(p.n_dof):
        joint = model.addJoint(parent, pin.JointModelRZ(), placement, f"joint_{i}")
        to_next = _fixed_dh(p.d_m[i], p.a_m[i], p.alpha_rad[i])
        link = to_next.act(pin.Inertia(p.mass_kg[i], p.com_m[i], p.inertia_tensors_kg_m2[i]))
        parent, placement = joint, to_next
        if i not in hinged:
            model.appendBodyToJoint(joint, link, pin.SE3.Identity())
            continue
        # The link in its joint frame, cut at the hinge (the split's own recombination is
        # checked below); two hinge joints about the returned axes at the hinge point.
        segments, axes = _core.split_link(
            to_next.translation, link.mass, link.lever, link.inertia, [hinged[i]]
        )
        (_, m0, c0, i0), (point, m1, c1, i1) = segments
        model.appendBodyToJoint(
            joint, pin.Inertia(m0, np.array(c0), np.array(i0)), pin.SE3.Identity()
        )
        point = np.array(point)
        first = model.addJoint(
            joint,
            pin.JointModelRevoluteUnaligned(np.array(axes[0])),
            pin.SE3(np.eye(3), point),
            f"hinge_{i}_a",
        )
        second = model.addJoint(
            first,
            pin.JointModelRevoluteUnaligned(np.array(axes[1])),
            pin.SE3.Identity(),
            f"hinge_{i}_b",
        )
        model.appendBodyToJoint(
            second, pin.Inertia(m1, np.array(c1) - point, np.array(i1)), pin.SE3.Identity()
        )
        parent = second
        placement = pin.SE3(to_next.rotation, to_next.translation - point)
    tensor = tvist.robots.inertia_tensor(np.zeros(6))
    payload = pin.Inertia(PAYLOAD.mass_kg, np.asarray(PAYLOAD.com_m), tensor)
    model.appendBodyToJoint(parent, placement.act(payload), pin.SE3.Identity())
    return model, parent, placement


#: The robot's joints among the hinged chain's coordinates (after joint 1 and joint 2 their
#: link's two hinges).
ROBOT_JOINTS = [0, 1, 4, 7, 8, 9]


def _hinged_pinocchio_mass(q: np.ndarray) -> np.ndarray:
    """CRBA of the UR5e with a hinge pair at the middle of links 1 and 2 (straight hinges),
    joints in the order of the core's hinged arm."""
    model, _, _ = _hinged_pinocchio()
    full = np.zeros(model.nq)
    full[ROBOT_JOINTS] = q
    mass = _pin().crba(model, model.createData(), full).copy()
    return np.triu(mass) + np.triu(mass, 1).T


def test_split_link_recombines_into_the_link() -> None:
    # Parallel-axis composite of the segments = the link (to rounding): what keeps the arm's
    # mass matrix unchanged at straight hinges.
    p = params("ur5e")
    inertia = p.inertia_tensors_kg_m2[1]
    segments, _ = _core.split_link([-0.425, 0.0, 0.0], p.mass_kg[1], p.com_m[1], inertia, [0.3])
    mass = sum(s[1] for s in segments)
    com = sum(s[1] * np.array(s[2]) for s in segments) / mass
    total = np.zeros((3, 3))
    for _, m, c, i in segments:
        d = np.array(c) - com
        total += np.array(i) + m * (d @ d * np.eye(3) - np.outer(d, d))
    assert mass == pytest.approx(p.mass_kg[1], rel=1e-12)
    np.testing.assert_allclose(com, p.com_m[1], atol=1e-12)
    np.testing.assert_allclose(total, inertia, atol=1e-12)


def test_hinged_mass_matrix_matches_pinocchio() -> None:
    robot = tvist.robots.ur5e(PAYLOAD.mass_kg, PAYLOAD.com_m)
    arm = robot.with_link_hinges(HINGES)
    assert arm.n_dof == 10
    rng = np.random.default_rng(3)
    for q in rng.uniform(-math.pi, math.pi, size=(20, 6)):
        mine = arm.mass_matrix_many(q[None])[0]
        reference = _hinged_pinocchio_mass(q)
        # Both are CRBA in double precision on entries of up to ~10 kg m²: rounding only.
        np.testing.assert_allclose(mine, reference, atol=1e-10, rtol=0)
        # Straight hinges leave the rigid arm's mass matrix as it was.
        rigid = robot.mass_matrix(q)
        np.testing.assert_allclose(
            mine[np.ix_(arm.joint_index, arm.joint_index)], rigid, atol=1e-12
        )


def test_hinged_velocity_torques_equal_pinocchio_recursive_newton_euler() -> None:
    # The Coriolis and centrifugal torques on every coordinate of the hinged arm (hinges
    # straight and at rest, the robot's joints moving) from central differences of the core's
    # hinged mass matrix, bent along each hinge, against pinocchio's RNEA(q, q', 0) −
    # RNEA(q, 0, 0) of the split chain. Tolerance 1e-7 N m: the differences' truncation
    # (step² ~ 1e-12 relative) and rounding (1e-16 / 1e-6 = 1e-10 relative) on torques of a
    # few N m.
    from tvist.maps.mode_choice import velocity_torque_many

    robot = tvist.robots.ur5e(PAYLOAD.mass_kg, PAYLOAD.com_m)
    arm = robot.with_link_hinges(HINGES)
    rng = np.random.default_rng(11)
    q = rng.uniform(-math.pi, math.pi, (20, 6))
    qd = rng.uniform(-2.0, 2.0, (20, 6))
    rows = list(range(arm.n_dof))
    got = velocity_torque_many(arm, q, qd, rows)
    pin = _pin()
    model, _, _ = _hinged_pinocchio()
    data = model.createData()
    zero = np.zeros(model.nv)
    want = []
    for a, v in zip(q, qd, strict=True):
        fq, fv = np.zeros(model.nv), np.zeros(model.nv)
        fq[ROBOT_JOINTS], fv[ROBOT_JOINTS] = a, v
        want.append(pin.rnea(model, data, fq, fv, zero) - pin.rnea(model, data, fq, zero, zero))
    want = np.array(want)
    hinge_rows = [i for i in rows if i not in ROBOT_JOINTS]
    assert np.abs(want[:, hinge_rows]).max() > 1.0  # the motion loads the hinges
    np.testing.assert_allclose(got, want, atol=1e-7)


def _known_maps(seed: int) -> tuple[ModalMap, ModalMap]:
    """The modal map of family variant ``seed`` at its known stiffness, with and without its
    bending links: gear laws from :func:`modal_map_from_flex` (base to wrist 2), each bending
    link one hinge pair at its middle with the beam's ``k = E I / L`` (the twin's own rule
    for one hinge per link) and its loss-factor damper."""
    variant = sample_variant("ur5e", seed)
    beams = variant.beams
    assert beams is not None, "a bending-link variant"
    joints = modal_map_from_flex(variant.flex, joints=(0, 1, 2, 3, 4)).flex_joints
    p = params("ur5e")
    hinges = []
    for link in beams.links:
        length = math.hypot(p.a_m[link], p.d_m[link])
        k = beams.bending_stiffness_nm2 / length
        c = beams.loss_factor * k / (2 * math.pi * beams.damping_reference_hz)
        hinges.append(
            {"link": link, "at_fraction": 0.5, "stiffness_nm_per_rad": k, "damping_nms_per_rad": c}
        )
    return (
        ModalMap(joints, shaped_modes=9, link_hinges=hinges),
        ModalMap(joints, shaped_modes=5),
    )


def test_hinged_modes_match_the_twin_with_bending_links() -> None:
    # Seed 0 of the family has bending upper arm and forearm (two hinges per link in the
    # twin, gravity stiffness included there, not in the model). Every true mode below 60 Hz
    # against the model's mode of the same frequency rank: within 3 % with the hinges (the
    # lumped single hinge and the neglected gravity stiffness: measured up to 2.4 %), while
    # the same joints with rigid links are more than 5 % off at some pose.
    variant = sample_variant("ur5e", 0)
    hinged, rigid = _known_maps(0)
    robot = tvist.robots.ur5e(PAYLOAD.mass_kg, PAYLOAD.com_m)
    qs = [
        [0.0, -1.2, 1.3, -1.6, -1.57, 0.0],
        [0.5, -2.0, 2.2, -1.0, -1.57, 0.0],
        [0.0, -0.6, 0.4, -1.2, 1.2, 0.0],
    ]
    worst_rigid = 0.0
    for q in qs:
        true = np.array([m.freq_hz for m in variant.true_modes(q, max_freq_hz=60.0)])
        for model, tolerance in ((hinged, 0.03), (rigid, None)):
            freq = np.sort(np.asarray(model.modes(robot, q))[:, 0]) / (2 * math.pi)
            error = np.abs(freq[: true.size] / true - 1.0)
            if tolerance is None:
                worst_rigid = max(worst_rigid, float(error.max()))
            else:
                assert error.max() < tolerance, (q, true, freq[: true.size])
    assert worst_rigid > 0.05


def test_map_file_with_link_hinges_round_trips_and_drives_the_shaper(tmp_path) -> None:
    known, _ = _known_maps(0)
    # The four lowest modes (the stiff links' highest hinge modes are overdamped).
    hinged = ModalMap(known.flex_joints, shaped_modes=4, link_hinges=known.link_hinges)
    path = tmp_path / "hinged.json"
    hinged.save(path)
    loaded = ModalMap.load(path)
    assert loaded.link_hinges == hinged.link_hinges
    robot = tvist.robots.ur5e(PAYLOAD.mass_kg, PAYLOAD.com_m)
    # The per-cycle provider builds the hinged arm itself from the map: the same modes as the
    # map evaluated on Robot.with_link_hinges.
    dynamics = tvist.ModalDynamics(robot, loaded)
    q = np.array([0.3, -1.4, 1.1, -1.2, -1.57, 0.0])
    np.testing.assert_allclose(dynamics.modes(q), loaded.modes(robot, q), rtol=1e-12)
    with pytest.raises(ValueError, match="link_hinges"):
        ModalMap(
            hinged.flex_joints,
            shaped_modes=2,
            link_hinges=[
                {
                    "link": 1,
                    "at_fraction": 1.5,
                    "stiffness_nm_per_rad": 1e5,
                    "damping_nms_per_rad": 1.0,
                }
            ],
        )


def _spectrum_errors(fields: dict, variant, poses) -> np.ndarray:
    """Relative error of every true mode below 60 Hz at ``poses`` against the fitted
    model's mode of the same frequency rank (every flexible coordinate's mode)."""
    hinges = fields.get("link_hinges")
    n = len(fields["flex_joints"]) + 2 * len(hinges or [])
    every = ModalMap(fields["flex_joints"], shaped_modes=n, link_hinges=hinges)
    errors = []
    for _, q, payload_kg, payload_com in poses:
        true = np.array(
            [m.freq_hz for m in variant.true_modes(q, payload_kg, payload_com, max_freq_hz=60.0)]
        )
        robot = tvist.robots.ur5e(payload_kg, payload_com)
        freq = np.sort(np.asarray(every.modes(robot, np.asarray(q)))[:, 0]) / (2 * math.pi)
        errors.extend(freq[: true.size] / true - 1.0)
    return np.array(errors)


@pytest.mark.slow
def test_the_fit_finds_bending_links_in_ringing_records() -> None:
    from shared_fits import demo_plan_poses
    from tvist.ident.all_modes_fit import fit_all_modes, fitted_map
    from tvist.sim.map_truth import held_out_poses
    from tvist.sim.ringing_records import ringing_records

    # Synthetic ringing records (every mode below 60 Hz of the twin's eigen-analysis, with
    # identification noise and outliers) of family variant 0, whose upper arm and forearm
    # bend, on the demo's 36-pose plan; the fit with and without candidate link hinges.
    variant = sample_variant("ur5e", 0)
    records = ringing_records(variant, demo_plan_poses(), seed=1)
    hinged = fit_all_modes(records, "ur5e")
    joints_only = fit_all_modes(records, "ur5e", candidate_links=())
    # Both bending links are kept by the likelihood-ratio test, with standard errors.
    assert hinged.statistics["bending_links"] == [1, 2]
    hinge_stiffness = [
        c for c in hinged.statistics["coefficients"] if "link" in c and c["what"] == "stiffness"
    ]
    assert len(hinge_stiffness) == 2 and all(c["se"] is not None for c in hinge_stiffness)
    # Held out (20 poses the fit never saw): every true mode below 60 Hz against the model's
    # mode of the same rank. With hinges within the acceptance floor (3 % RMS, 8 % max); the
    # joints alone absorb the bending into wrong stiffnesses (measured 5-13 % RMS on the
    # base and shoulder modes) and fail it.
    poses = held_out_poses()
    with_hinges = _spectrum_errors(hinged.map_fields, variant, poses)
    without = _spectrum_errors(joints_only.map_fields, variant, poses)
    assert np.sqrt(np.mean(with_hinges**2)) <= 0.03, with_hinges
    assert np.max(np.abs(with_hinges)) <= 0.08, with_hinges
    assert np.sqrt(np.mean(without**2)) > 0.03, without
    # The fitted map carries the hinges to the file.
    assert [h["link"] for h in fitted_map(hinged).link_hinges] == [1, 2]
