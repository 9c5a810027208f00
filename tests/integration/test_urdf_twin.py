"""The flexible twins of the URDF arms (FR3, iiwa14): their true modes against an independent
eigen-analysis, the campaign and modal fit on one of them, and the demo moves' poses."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest

from pinocchio_reference import flexible_joint_modes, urdf_pinocchio_model
from tvist.experiments.motions import PAYLOAD_COM_M, demo_payload_kg, demo_poses
from tvist.ident.pose_plan import workspace_poses
from tvist.robots import Payload, params, shipped_urdf
from tvist.sim import Twin, default_flex

ARMS = ("fr3", "iiwa14")


@pytest.mark.parametrize("name", ARMS)
def test_twin_modes_equal_pinocchio_eigen_analysis(name):
    """Every mode of the twin's linearisation (MuJoCo's mass matrix, the twin's equilibrium
    solver and finite-difference gravity stiffness) against pinocchio's mass matrix, gravity
    and analytic gravity derivative of the same URDF read by pinocchio's own parser, with the
    gear laws written out in the reference and scipy.linalg.eig: at the demo poses and two
    random workspace poses, with the demo payload."""
    payload_kg = demo_payload_kg(name)
    twin = Twin(name, payload_kg=payload_kg, payload_com_m=PAYLOAD_COM_M)
    path, _, tip = shipped_urdf(name)
    payload = Payload(payload_kg, PAYLOAD_COM_M)
    poses = [*demo_poses(name).values(), *workspace_poses(name, 2, seed=11)]
    for q in poses:
        model = urdf_pinocchio_model(path, tip, payload)
        ref = flexible_joint_modes(
            twin.params, payload, default_flex(name), q, twin.gravity_m_s2, model=model
        )
        np.testing.assert_allclose(twin.equilibrium(q), ref.q_link, rtol=0, atol=1e-10)
        analysis = twin.modal_analysis(q)
        # As for the UR twin (tests/integration/test_sim.py): the central-difference gravity
        # stiffness rounds at ~1e-8 N m/rad against stiffnesses >= 100 N m/rad, the equilibria
        # agree to ~1e-13 rad; 1e-7 relative is far above both and far below any modelling change.
        np.testing.assert_allclose(analysis.wn_rad_s, ref.wn_rad_s, rtol=1e-7)
        np.testing.assert_allclose(analysis.zeta, ref.zeta, rtol=1e-7)


@pytest.mark.parametrize("name", ARMS)
def test_urdf_arm_twin_rings_below_60_hz_only_in_its_four_flexible_joints(name):
    """The design of the default flexibility: over the workspace, with no payload and the
    demo payload, every mode below 60 Hz (the band the demo shapes) is one of the four
    flexible joints' (it stores most of its strain energy in joints 1-4): the stiff joints
    5-7 ring only above it, and no mode passes 640 Hz (the 0.5 ms physics step's stability
    limit, ``ω dt < 2``)."""
    from tvist.sim.family import modes_of

    for payload_kg in (0.0, demo_payload_kg(name)):
        twin = Twin(name, payload_kg=payload_kg, payload_com_m=PAYLOAD_COM_M)
        for q in workspace_poses(name, 6, seed=12):
            modes = modes_of(twin, q)
            assert modes[-1].freq_hz < 640.0
            for mode in modes:
                proximal = float(np.sum(mode.joint_shares[:4]))
                if mode.freq_hz < 60.0:
                    assert proximal > 0.5, (mode.freq_hz, mode.joint_shares)


def test_shipped_arms_are_robots_by_name():
    """``params("fr3")`` is the shipped URDF's chain with the maker's rated payload."""
    fr3 = params("fr3")
    assert fr3.n_dof == 7 and fr3.placements is not None and fr3.max_payload_kg == 3.0
    assert params("iiwa14").max_payload_kg == 14.0
    with pytest.raises(ValueError, match="fr3"):
        params("nope")


#: The map's modes against the twin's: 3 % RMS over the held-out poses, per mode (the
#: acceptance of a map in the generalization harness, tvist.experiments.generalization).
MAP_RMS_PERCENT = 3.0


@pytest.mark.slow
def test_modal_fit_on_a_small_fr3_campaign_recovers_its_lowest_modes(tmp_path):
    """A small campaign on the FR3's twin (2 random workspace poses per payload, 0 and 3 kg,
    plus the workspace's extreme inertias; 4 s excitations of the harness's joints, noisy
    accelerometer), identified and fitted with every identified mode: the fit keeps the arm's
    four proximal joints as candidates, and the shaped modes of its map are the twin's true
    modes at workspace poses none of the campaign's (the harness's evaluation poses): by
    frequency rank, each within :data:`MAP_RMS_PERCENT` RMS."""
    import math

    from tvist.experiments.generalization import (
        HarnessSettings,
        evaluation_poses,
        frequency_errors,
        matching_true_modes,
        shaped_mode_names,
    )
    from tvist.ident.all_modes_fit import fit_all_modes, fitted_map
    from tvist.ident.campaign import run_campaign
    from tvist.robots import Robot
    from tvist.sim.family import modes_of

    settings = HarnessSettings(robot="fr3", every=26, at_move_poses=False)
    records = run_campaign(
        settings.plan(),
        tmp_path / "poses.jsonl",
        robot_name="fr3",
        duration_s=settings.duration_s,
        progress=False,
        joints=settings.excited_joints,
    )
    fit = fit_all_modes(records, "fr3")
    assert set(fit.statistics["flexible_joints"]) <= {0, 1, 2, 3}
    modal = fitted_map(fit)
    names = shaped_mode_names(json_document(modal, tmp_path))
    assert len(names) >= 2
    payload_kg = demo_payload_kg("fr3")
    robot = Robot(params("fr3"), Payload(payload_kg, PAYLOAD_COM_M))
    twin = Twin("fr3", payload_kg=payload_kg, payload_com_m=PAYLOAD_COM_M)
    q_eval = evaluation_poses("fr3", None)
    predicted = np.asarray(modal.modes_many(robot, q_eval))[:, :, 0] / (2 * math.pi)
    if names[0][0] == "rank":
        predicted = np.sort(predicted, axis=1)
    true_hz = np.array(
        [[m.freq_hz for m in matching_true_modes(names, modes_of(twin, q))] for q in q_eval]
    )
    for error in frequency_errors(predicted, true_hz):
        assert error["n_poses"] == len(q_eval)
        assert error["rms_percent"] <= MAP_RMS_PERCENT, error


def json_document(modal, tmp_path) -> dict:
    """The map file's JSON document, as a user's map file is read."""
    import json

    path = tmp_path / "map.json"
    modal.save(path)
    return json.loads(path.read_text())


def test_demo_for_an_arm_without_a_default_twin_is_refused_in_one_line(capsys, tmp_path):
    from tvist.cli import main

    assert main(["demo", "--robot", "gen3", "--out", str(tmp_path)]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("tvist demo: error: --robot gen3: tvist has no twin of robot")
    assert "\n" not in err
    assert main(["demo", "--robot", "ur6e", "--out", str(tmp_path)]) == 2
    assert "unknown robot 'ur6e'" in capsys.readouterr().err


def test_twin_server_for_an_arm_without_a_twin_is_refused_in_one_line():
    # Refused before any port is bound (the time-out only ends a server that did start).
    cli = [sys.executable, "-m", "tvist.cli", "twin-server", "--robot", "ur5"]
    cli += ["--host", "127.0.0.1"]
    done = subprocess.run(cli, capture_output=True, text=True, timeout=120)
    assert done.returncode == 2
    err = done.stderr.strip()
    assert err.startswith("tvist twin-server: error: --robot ur5: tvist has no twin of robot")
    assert "\n" not in err and "ur5e" in err
