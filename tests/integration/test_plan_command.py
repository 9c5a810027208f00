"""``tvist plan``: a campaign plan for one's own robot, checked before anything moves."""

from __future__ import annotations

import json

import numpy as np
import pytest

from tvist.cli import main
from tvist.cli.shape import read_trajectory_csv
from tvist.ident.pose_plan import (
    campaign_poses,
    plan_poses,
    plan_shortfall,
    pose_excitations,
    user_poses,
)
from tvist.robots import Robot, params
from tvist.trajectory import PAPER_POSES
from tvist.units import check_trajectory
from tvist.urserver.move_program import parse_move_program


@pytest.mark.slow
def test_plan_writes_programs_and_trajectories_payload_by_payload(tmp_path, capsys):
    out = tmp_path / "plan"
    cover = tmp_path / "mine.csv"
    np.savetxt(cover, [PAPER_POSES["Q2"]], delimiter=",")
    args = ["plan", "--payloads", "3", "0", "--every", "16", "--duration", "2"]
    args += ["--no-workspace-cover"]  # (tests/integration/test_plan_coverage.py)
    assert main([*args, "--cover", str(cover), "--out", str(out)]) == 0
    text = capsys.readouterr().out
    plan = json.loads((out / "plan.json").read_text())
    keys = [p["key"] for p in plan["poses"]]
    # Every 16th of the 104 poses (7), then the user's pose with each payload (stretched out,
    # it extends their inertia range); lightest payload first, so the payload changes once.
    expected = [p.key for p in campaign_poses("ur5e", payloads_kg=[3.0, 0.0])[::16]]
    expected += ["m3kg-C0", "m0kg-C0"]
    assert sorted(keys) == sorted(expected)
    masses = [p["payload_kg"] for p in plan["poses"]]
    assert masses == sorted(masses) and plan["payloads_kg"] == [0.0, 3.0]
    assert "0 kg, 3 kg" in text and "busy" in text
    # The pose given with --cover is kept as given.
    mine = next(p for p in plan["poses"] if p["key"] == "m0kg-C0")
    np.testing.assert_allclose(mine["q"], PAPER_POSES["Q2"], atol=1e-12)
    # Each excitation: a program the twin runs (approach to the pose, then the moves) and
    # the same excitation sampled, as the campaign draws it for the pose.
    poses = campaign_poses("ur5e", payloads_kg=[3.0, 0.0])
    pose = next(p for p in poses if p.key == keys[0])
    excitations = pose_excitations(pose, 2.0)
    for entry, excitation in zip(plan["poses"][0]["excitations"], excitations, strict=True):
        assert entry["joint"] == excitation.joint and entry["seed"] == excitation.seed
        _, steps = parse_move_program((out / entry["script"]).read_text())
        np.testing.assert_allclose(steps[0].q, excitation.q0, atol=5e-7)  # 6 decimals
        targets = [s.q[excitation.joint] for s in steps if s.q is not None][1:]
        np.testing.assert_allclose(targets, [m.q_to_rad for m in excitation.moves], atol=5e-7)
        trajectory = read_trajectory_csv(out / entry["trajectory"])
        np.testing.assert_allclose(trajectory.Q, excitation.q, atol=5e-10)  # 9 decimals
        np.testing.assert_allclose(trajectory.times_s, excitation.t_s, atol=5e-10)
    n_excitations = sum(len(p["excitations"]) for p in plan["poses"])
    # Base, shoulder and elbow at every pose (the default --excite).
    assert plan["excited_joints"] == [0, 1, 2]
    assert n_excitations == 3 * len(keys)
    assert len(list(out.glob("*.script"))) == n_excitations


def test_plan_busy_time_adds_excitations_and_approaches(tmp_path):
    """The time printed is the excitations' own length plus the approach moves between
    them (movej trapezoids at the approach limits), recomputed here from plan.json."""
    out = tmp_path / "plan"
    args = ["plan", "--payloads", "5", "--every", "8", "--duration", "1", "--no-workspace-cover"]
    assert main([*args, "--out", str(out), "--approach-speed", "0.5"]) == 0
    plan = json.loads((out / "plan.json").read_text())
    excitations = [
        (pose, e)
        for pose in campaign_poses("ur5e", payloads_kg=[5.0])[::8]
        for e in pose_excitations(pose, 1.0)
    ]
    total = sum(e.duration_s for _, e in excitations)
    a = plan["approach_accel_rad_s2"]
    for (_, before), (_, after) in zip(excitations, excitations[1:], strict=False):
        distance = float(np.max(np.abs(after.q0 - before.q[-1])))
        v = min(0.5, np.sqrt(distance * a))
        total += distance / v + v / a if distance > 0 else 0.0
    assert plan["busy_s"] == pytest.approx(total, rel=1e-12)


def test_excite_chooses_the_joints_keeping_the_base_and_shoulder_excitations(tmp_path):
    """``--excite 0,1,3``: base, shoulder and wrist 1 at every pose; the base and shoulder
    excitations are those of a plan of theirs alone (same seeds, same samples)."""
    args = ["plan", "--payloads", "5", "--every", "8", "--duration", "1", "--no-workspace-cover"]
    plans = {}
    for excite in ("0,1", "0,1,3"):
        out = tmp_path / excite
        assert main([*args, "--excite", excite, "--out", str(out)]) == 0
        plans[excite] = json.loads((out / "plan.json").read_text())
    assert plans["0,1,3"]["excited_joints"] == [0, 1, 3]
    for two, three in zip(plans["0,1"]["poses"], plans["0,1,3"]["poses"], strict=True):
        assert [e["joint"] for e in three["excitations"]] == [0, 1, 3]
        for a, b in zip(two["excitations"], three["excitations"], strict=False):
            assert (a["joint"], a["seed"], a["duration_s"]) == (
                b["joint"],
                b["seed"],
                b["duration_s"],
            )
            csv_a, csv_b = (tmp_path / e / x["trajectory"] for e, x in (("0,1", a), ("0,1,3", b)))
            assert csv_a.read_text() == csv_b.read_text()
    pose = campaign_poses("ur5e", payloads_kg=[5.0])[0]
    wrist = pose_excitations(pose, 1.0, (0, 1, 3))[2]
    elbow = pose_excitations(pose, 1.0, (0, 1, 2))[2]
    assert wrist.joint == 3 and elbow.joint == 2 and wrist.seed != elbow.seed


@pytest.mark.parametrize("value", ["7", "x", "1,2", "0,1,4", "0,,1"])
def test_bad_excite_values_are_one_line(value, tmp_path, capsys):
    out = tmp_path / "plan"
    assert main(["plan", "--excite", value, "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith(f"tvist plan: error: --excite {value}: "), err
    assert "0,1,2" in err[0] and not out.exists()


def test_campaign_refuses_a_bad_excite_on_one_line(tmp_path, capsys):
    out = tmp_path / "c.jsonl"
    assert main(["campaign", "--sim", "--excite", "0,2", "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("tvist campaign: error: --excite 0,2: the base")
    assert not out.exists()


@pytest.mark.slow
def test_every_excitation_of_the_default_plan_stays_within_limits_and_above_the_table():
    """Algorithm 2's ±10° of the elbow and of wrist 1 (the same random excitation as the
    base's and shoulder's) at every pose of the default UR5e plan: inside the joint limits
    (the elbow's ±180°: the plan's elbow reaches 150°) and the flange centre above the
    mounting plane throughout (the shoulder's own excitation, excited since the paper, dips
    2 cm below it at one workspace pose, m3kg-W4; the elbow and wrist 1 stay above)."""
    robot_params = params("ur5e")
    robot = Robot(robot_params)
    for pose in plan_poses("ur5e"):
        if pose.q is None:
            continue
        for excitation in pose_excitations(pose, 8.0, (0, 1, 2, 3))[2:]:
            check_trajectory(excitation.q, excitation.dt_s, robot_params, what=pose.key)
            z = robot.flange_pose_many(np.ascontiguousarray(excitation.q))[:, 2, 3]
            assert z.min() > 0.0, (pose.key, excitation.joint, z.min())


@pytest.mark.parametrize(
    ("flags", "reason"),
    [
        (["--every", "13", "--payloads", "5", "--no-workspace-cover"], "4 reachable poses"),
        pytest.param(
            ["--every", "200", "--payloads", "0", "1", "3", "5", "--no-workspace-cover"],
            "2 reachable",
            marks=pytest.mark.slow,
        ),
    ],
)
def test_unfittable_plan_is_refused_with_its_reason(flags, reason, tmp_path, capsys):
    assert main(["plan", *flags, "--out", str(tmp_path / "plan")]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1
    assert reason in err and "needs at least 6" in err and "--every" in err
    assert not (tmp_path / "plan").exists()


@pytest.mark.slow
def test_cover_poses_in_degrees_are_refused(tmp_path, capsys):
    cover = tmp_path / "mine.csv"
    np.savetxt(cover, [PAPER_POSES["Q2"], np.degrees(PAPER_POSES["Q2"])], delimiter=",")
    assert main(["plan", "--cover", str(cover), "--out", str(tmp_path / "plan")]) == 2
    err = capsys.readouterr().err
    assert "--cover" in err and "row 2" in err and "look like degrees" in err
    assert not (tmp_path / "plan").exists()


def test_poses_at_one_radius_with_one_payload_are_refused():
    """Six poses that differ only in the base angle: enough of them, but the shoulder's
    inertia is the same in all, so the map's stiffness terms cannot be told apart. (A plan
    takes only the --cover poses that extend its inertia range, so 'tvist plan' makes no
    such plan; the check stands for any list of poses.)"""
    q = np.tile(PAPER_POSES["Q2"], (6, 1))
    q[:, 0] = np.linspace(-1.0, 1.0, 6)
    reason = plan_shortfall(user_poses("ur5e", q, "cover", payloads_kg=[5.0]))
    assert "from the shoulder axis with 5 kg" in reason and "two radii or payloads" in reason
