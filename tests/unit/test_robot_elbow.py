"""The robot's elbow: stated in the robot data (or found from the joint axes), and read by the
identification's defaults (excited joints, covered inertias, the jump check's neighbours).

On a UR the elbow is joint 2; on the FR3 and the iiwa14 joint 2 turns the upper arm about its
own axis and the elbow is joint 3.
"""

from __future__ import annotations

import argparse
import math

import numpy as np
import pytest

from tvist.cli import main
from tvist.cli.plan import excited_from_args
from tvist.ident.excited import default_excited_joints, excited_joints
from tvist.ident.pose_checks import JUMP_REASON, flag_jumps
from tvist.ident.pose_plan import CampaignPose, covered_joints, pose_excitations
from tvist.robots import RobotParams, dh_urdf, elbow_by_axes, names, params, urdf_params
from tvist.robots.urdf import SHIPPED_URDFS, shipped_urdf

SEVEN_JOINT_ARMS = ("fr3", "iiwa14")


@pytest.mark.parametrize("name", names())
def test_a_ur_elbow_is_joint_2(name):
    assert params(name).elbow_joint == 2
    assert default_excited_joints(name) == (0, 1, 2)
    assert covered_joints(name) == (0, 1, 2)


@pytest.mark.parametrize("name", SEVEN_JOINT_ARMS)
def test_fr3_and_iiwa14_excite_their_elbow_joint_3_by_default(name):
    assert params(name).elbow_joint == 3
    assert default_excited_joints(name) == (0, 1, 3)
    assert excited_joints(None, name) == (0, 1, 3)
    assert covered_joints(name) == (0, 1, 3)


@pytest.mark.parametrize("name", list(SHIPPED_URDFS))
def test_the_axis_rule_finds_each_shipped_arms_stated_elbow(name):
    """Read without the stated elbow, each shipped URDF's elbow is the first joint after the
    shoulder with an axis parallel to the shoulder's at q = 0: the one its entry states."""
    path, base, tip = shipped_urdf(name)
    with pytest.warns() if name == "gen3" else _no_warning():  # gen3: continuous joints
        found = urdf_params(path, base, tip).elbow_joint
    assert found == SHIPPED_URDFS[name][4] == params(name).elbow_joint


class _no_warning:
    def __enter__(self):
        return self

    def __exit__(self, *exc):
        return False


def test_the_axis_rule_on_a_ur_urdf_finds_joint_2(tmp_path):
    """A UR5e written as URDF (every joint axis z, placed by the DH steps) and read back."""
    path = tmp_path / "ur5e.urdf"
    path.write_text(dh_urdf(params("ur5e")))
    assert urdf_params(path, "base_link", "flange").elbow_joint == 2


def _planar_params(alpha, elbow=None) -> RobotParams:
    n = len(alpha)
    return RobotParams(
        name="arm",
        description="test arm",
        source="test",
        d_m=[0.1] * n,
        a_m=[0.3] * n,
        alpha_rad=alpha,
        mass_kg=[1.0] * n,
        com_m=[[0.0, 0.0, 0.0]] * n,
        inertia_kg_m2=[[0.01, 0.01, 0.01, 0.0, 0.0, 0.0]] * n,
        inertia_source="test",
        joint_limits_rad=[[-math.pi, math.pi]] * n,
        max_velocity_rad_s=[1.0] * n,
        max_payload_kg=1.0,
        elbow_joint=elbow,
    )


def test_an_arm_without_a_joint_parallel_to_the_shoulder_has_no_elbow():
    """Axes z, -y, -z and one 45° from -z (each turned about x from the one before by 90°,
    90°, 45°): none after the shoulder parallel to it, no elbow; a stated elbow is kept; one
    that is not after the shoulder is refused."""
    alpha = [math.pi / 2, math.pi / 2, math.pi / 4, 0.0]
    arm = _planar_params(alpha)
    assert arm.elbow_joint is None and elbow_by_axes(arm) is None
    assert _planar_params(alpha, elbow=3).elbow_joint == 3
    # A third 90° turn brings joint 3's axis back to the shoulder's (y, antiparallel).
    assert _planar_params([math.pi / 2] * 3 + [0.0]).elbow_joint == 3
    # alpha_1 = 0: joint 2's axis is the shoulder's.
    assert _planar_params([math.pi / 2, 0.0, math.pi / 2, 0.0]).elbow_joint == 2
    for bad in (1, 4, 2.5):
        with pytest.raises(ValueError, match="elbow_joint"):
            _planar_params([math.pi / 2, 0.0, 0.0, 0.0], elbow=bad)


def _args(robot, excite=None) -> argparse.Namespace:
    return argparse.Namespace(robot=robot, excite=excite)


def test_excite_defaults_to_the_robots_elbow_and_still_overrides():
    assert excited_from_args(_args("ur5e")) == (0, 1, 2)
    assert excited_from_args(_args("fr3")) == (0, 1, 3)
    assert excited_from_args(_args("iiwa14", "0,1,2")) == (0, 1, 2)
    with pytest.raises(ValueError, match=r"^--excite 0,2: .*\(e\.g\. --excite 0,1,3\)$"):
        excited_from_args(_args("fr3", "0,2"))
    with pytest.raises(ValueError, match=r"^--robot ur6e: unknown robot"):
        excited_from_args(_args("ur6e"))


def test_plan_with_an_unknown_robot_is_one_line(tmp_path, capsys):
    assert main(["plan", "--robot", "ur6e", "--out", str(tmp_path / "plan")]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("tvist plan: error: --robot ur6e: unknown robot") and "\n" not in err


def test_an_fr3_pose_excites_its_elbow_by_default():
    """The elbow's excitation is joint 3's, with joint 3's seed (the one it has when joints
    are given)."""
    q = np.array([0.0, -0.3, 0.0, -2.0, 0.0, 1.8, 0.8])
    pose = CampaignPose("p", 0.0, (0.0, 0.0, 0.05), 0.0, 0.5, -1, q, seed=11)
    default = pose_excitations(pose, 1.0, robot_name="fr3")
    given = pose_excitations(pose, 1.0, (0, 1, 3))
    assert [e.joint for e in default] == [0, 1, 3]
    assert [e.seed for e in default] == [e.seed for e in given]


def test_jump_neighbours_compare_the_angles_up_to_the_robots_elbow():
    """Three poses alike in joints 0-2, the third 1 rad off in joint 3 with a mode 30 %
    higher: on a UR (elbow 2, joint 3 is wrist 1, not compared) the first two are its
    neighbours and its mode jumps; on an FR3 (elbow 3, compared) it has no neighbours within
    :data:`~tvist.ident.pose_checks.MAX_NEIGHBOUR_RAD` and nothing is flagged."""

    def record(q3, hz):
        q = [0.0, -0.5, 0.0, q3, 0.0, 1.8, 0.8]
        ring = {"wn_rad_s": 2 * math.pi * hz, "low_confidence": False, "reasons": []}
        return {"q": q, "payload_kg": 0.0, "ringing": [ring]}

    records = [record(-2.0, 10.0), record(-2.02, 10.1), record(-1.0, 13.0)]
    ur = [r["ringing"][0] for r in flag_jumps(records, "ur5e")]
    assert [m["low_confidence"] for m in ur] == [False, False, True]
    assert ur[2]["reasons"][0].startswith(JUMP_REASON)
    fr3 = [r["ringing"][0] for r in flag_jumps(records, "fr3")]
    assert not any(m["low_confidence"] for m in fr3)


def test_logs_are_named_by_the_robots_elbow():
    """A mode of the joint-3 log 5 % off the shoulder log's (standard errors 0.2 %): the
    shoulder's entry names the other log the elbow's on an FR3 (elbow 3), wrist 1's on a UR."""
    from tvist.ident.pose import cross_check_logs
    from tvist.ident.ringing import RingingMode

    def mode(log_joint, hz):
        wn = 2 * math.pi * hz
        return RingingMode(log_joint, wn, 0.05, 0.002 * wn, 0.005, 1.0, (1.0, 0.0, 0.0))

    ringing = [mode(1, 10.0), mode(3, 10.5)]
    fr3 = cross_check_logs(ringing, params("fr3").elbow_joint)[0]
    ur = cross_check_logs(ringing)[0]
    assert fr3.reasons[0].startswith("disagrees with the elbow log"), fr3.reasons
    assert ur.reasons[0].startswith("disagrees with the wrist 1 log"), ur.reasons
