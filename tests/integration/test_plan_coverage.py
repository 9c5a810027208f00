"""A campaign plan covers the joint-axis inertias of the workspace and of the user's poses:
a map is identified only over the inertias of its poses (it holds its modes at the bounds of
that range elsewhere), so the moves it will shape must lie within them."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from tvist.cli import main
from tvist.ident.pose_plan import covered_joints, plan_poses
from tvist.robots import Payload, Robot, params
from tvist.trajectory import PAPER_POSES

COM_M = (0.0, 0.0, 0.05)
#: The joints whose inertias a UR5e's plan covers: base, shoulder, elbow.
COVERED = covered_joints("ur5e")
#: Stretched straight up: the smallest base inertia of a stretched arm.
UPRIGHT = np.array([0.0, -math.pi / 2, 0.0, -math.pi / 2, 0.0, 0.0])
#: Folded further than the workspace's 150° (Q3) elbow: a smaller shoulder inertia than any
#: workspace pose has.
FOLDED_160 = np.array([math.pi / 2, -math.pi / 2, 2.9, -math.pi / 2, 0.0, 0.0])


def _range(poses, payload_kg):
    robot = Robot(params("ur5e"), Payload(payload_kg, COM_M))
    q = np.array([p.q for p in poses if p.q is not None and p.payload_kg == payload_kg])
    inertia = robot.joint_inertia_many(q)[:, COVERED]
    return robot, inertia.min(axis=0), inertia.max(axis=0)


def _workspace_sample(robot: Robot, n: int, seed: int) -> np.ndarray:
    """The test's own draw of the workspace: upper arm at or above the shoulder, elbow from
    stretched to Q3's 150°, wrists anywhere, flange above the mounting plane."""
    rng = np.random.default_rng(seed)
    q = np.zeros((n, 6))
    q[:, 1] = rng.uniform(-math.pi, 0.0, n)
    q[:, 2] = rng.uniform(0.0, 5 * math.pi / 6, n)
    q[:, 3:] = rng.uniform(-math.pi, math.pi, (n, 3))
    return q[robot.flange_pose_many(q)[:, 2, 3] > 0.0]


@pytest.mark.parametrize("payload_kg", [0.0, 5.0])
def test_a_reduced_default_plan_covers_the_workspace_inertias(payload_kg):
    """Every 8th of Algorithm 1's poses alone spans J_0 0.54-5.9 kg m² at 5 kg, while the
    demo's own start pose Q1 has 8.94 and the arm stretched up 0.25: the plan adds the
    workspace's extreme poses. Checked on the paper's poses, the arm stretched up and 3000
    workspace poses drawn here, all within the plan's range (no tolerance: the plan's
    extremes are refined optima of the inertia, a random pose does not pass them)."""
    poses = plan_poses("ur5e", payloads_kg=(0.0, 5.0), every=8)
    robot, lo, hi = _range(poses, payload_kg)
    q = np.vstack([*PAPER_POSES.values(), UPRIGHT, _workspace_sample(robot, 3000, seed=7)])
    inertia = robot.joint_inertia_many(q)[:, COVERED]
    assert np.all(inertia >= lo) and np.all(inertia <= hi), (lo, hi, inertia.min(0), inertia.max(0))
    # The additions are the workspace poses ("-W"), at most the two extremes per joint.
    added = [p for p in poses if p.payload_kg == payload_kg and "-W" in p.key]
    assert 1 <= len(added) <= 2 * len(COVERED)


def test_cover_poses_are_added_only_where_they_extend_the_range():
    """``--cover`` poses Q1 and Q3 span the inertias of a pose between them (same wrist,
    shoulder and elbow between theirs): the plan takes Q1 and Q3 and leaves that one out.
    With the default plan, Q3 lies within the workspace's range and is not added, while a
    pose folded beyond the workspace is."""
    between = np.array([0.0, -3 * math.pi / 4, math.pi / 3, -math.pi / 2, 0.0, 0.0])
    robot = Robot(params("ur5e"), Payload(5.0, COM_M))
    j = robot.joint_inertia_many(np.array([PAPER_POSES["Q1"], PAPER_POSES["Q3"], between]))
    assert np.all(j[2] >= np.minimum(j[0], j[1])) and np.all(j[2] <= np.maximum(j[0], j[1]))

    cover = np.array([PAPER_POSES["Q1"], PAPER_POSES["Q3"], between])
    poses = plan_poses("ur5e", payloads_kg=(5.0,), every=0, cover_q=cover)
    assert sorted(p.key for p in poses) == ["m5kg-C0", "m5kg-C1"]

    poses = plan_poses(
        "ur5e", payloads_kg=(5.0,), every=8, cover_q=np.array([PAPER_POSES["Q3"], FOLDED_160])
    )
    given = [p for p in poses if "-C" in p.key]
    assert [p.key for p in given] == ["m5kg-C1"]
    np.testing.assert_array_equal(given[0].q, FOLDED_160)
    _, lo, hi = _range(poses, 5.0)
    inertia = robot.joint_inertia_many(np.array([PAPER_POSES["Q3"], FOLDED_160]))
    assert np.all(inertia[:, COVERED] >= lo) and np.all(inertia[:, COVERED] <= hi)


def test_at_poses_are_identified_even_where_they_lie_within_the_range():
    """``--at`` poses are where the user's moves stop: each is identified with every payload,
    also where the plan's range already holds its inertias (Q3 in the default plan, which
    ``--cover`` leaves out, as the test above shows)."""
    given = np.array([PAPER_POSES["Q3"], PAPER_POSES["Q1"]])
    poses = plan_poses("ur5e", payloads_kg=(0.0, 5.0), every=8, at_q=given)
    at = {p.key: p for p in poses if "-A" in p.key}
    assert sorted(at) == ["m0kg-A0", "m0kg-A1", "m5kg-A0", "m5kg-A1"]
    for key, p in at.items():
        np.testing.assert_array_equal(p.q, given[int(key[-1])])
    covered = plan_poses("ur5e", payloads_kg=(5.0,), every=8, cover_q=given[:1])
    assert not [p for p in covered if "-C" in p.key]
    assert len(poses) == len(plan_poses("ur5e", payloads_kg=(0.0, 5.0), every=8)) + 4


def test_plan_command_identifies_at_a_seven_joint_arms_poses(tmp_path, capsys):
    """``--at`` on an arm of 7 joints: rows of 7 angles (a row of 6 is refused naming the
    count the robot needs)."""
    from tvist.experiments.motions import demo_poses

    rows = list(demo_poses("fr3").values())
    at = tmp_path / "stops.csv"
    at.write_text("\n".join(",".join(f"{v:.6f}" for v in r) for r in rows) + "\n")
    out = tmp_path / "plan"
    args = ["plan", "--robot", "fr3", "--every", "0", "--at", str(at), "--payloads", "0", "3"]
    assert main([*args, "--duration", "1", "--out", str(out)]) == 0
    keys = sorted(p["key"] for p in json.loads((out / "plan.json").read_text())["poses"])
    assert keys == sorted(f"m{m}kg-A{i}" for m in (0, 3) for i in range(3))
    assert "6 poses at the --at poses" in capsys.readouterr().out
    at.write_text("0,0,0,-1.5,0,1.5\n")
    assert main([*args, "--out", str(tmp_path / "refused")]) == 2
    err = capsys.readouterr().err.strip()
    assert "--at" in err and "line 1 has 6 values" in err and "is 7" in err, err


def test_plan_command_covers_a_poses_file_with_a_header(tmp_path, capsys):
    cover = tmp_path / "moves.csv"
    rows = [PAPER_POSES["Q1"], PAPER_POSES["Q3"], [0.0, -2.356, 1.047, -1.571, 0.0, 0.0]]
    text = "q0,q1,q2,q3,q4,q5\n" + "\n".join(",".join(f"{v:.6f}" for v in r) for r in rows)
    cover.write_text(text + "\n")
    out = tmp_path / "plan"
    args = ["plan", "--every", "0", "--cover", str(cover)]  # the 4 default payloads
    assert main([*args, "--duration", "1", "--out", str(out)]) == 0
    keys = sorted(p["key"] for p in json.loads((out / "plan.json").read_text())["poses"])
    assert keys == sorted(f"m{m}kg-C{i}" for m in (0, 1, 3, 5) for i in (0, 1))
    assert "8 of the --cover poses" in capsys.readouterr().out


@pytest.mark.parametrize(
    ("content", "message"),
    [
        ("", "no poses"),
        ("q0,q1,q2,q3,q4,q5\n", "no poses"),
        ("0,-3.14,0,-1.57,0,0\n0,-1.57,2.6,-1.57,0\n", "line 2 has 5 values"),
        ("0,-3.14,0,-1.57,0,0\n0,-1.57,abc,-1.57,0,0\n", "line 2: 'abc' is not a number"),
        ("0;-3.14;0;-1.57;0;0\n", "line 1: '0;-3.14;0;-1.57;0;0' is not a number"),
        ("0,-3.14,0,-1.57,0,nan\n", "not 6 finite joint angles"),
        ("0,-3.14,0,-1.57,0,0\n0,-90,150,-90,0,0\n", "look like degrees"),
    ],
)
@pytest.mark.parametrize("flag", ["--cover", "--at"])
def test_bad_poses_files_are_one_line_errors(content, message, flag, tmp_path, capsys):
    cover = tmp_path / "moves.csv"
    cover.write_text(content)
    out = tmp_path / "plan"
    assert main(["plan", "--every", "0", flag, str(cover), "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and err.count(flag) == 1 and message in err, err
    assert not out.exists()


def test_a_missing_cover_file_is_a_one_line_error(tmp_path, capsys):
    args = ["campaign", "--sim", "--cover", str(tmp_path / "none.csv")]
    assert main([*args, "--out", str(tmp_path / "c.jsonl")]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "--cover" in err and "none.csv" in err
