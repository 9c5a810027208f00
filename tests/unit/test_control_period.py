"""The control period's one home, the robot data: every shipped robot states it, a robot file
may omit it, bad values are refused, and what runs on a robot defaults to its period."""

from __future__ import annotations

import dataclasses
import json
import math

import numpy as np
import pytest

import tvist
from tvist import cartesian, robots
from tvist.cli import main
from tvist.robots import params, robot_file, shipped_urdf, urdf_params, write_robot_file
from tvist.trajectory import PAPER_POSES

#: The makers' published rates: the e-Series controller at 500 Hz, the CB-series at 125 Hz;
#: libfranka, FRI and the Kortex low-level API at 1 kHz.
PUBLISHED_PERIODS_S = {
    "ur3e": 0.002,
    "ur5e": 0.002,
    "ur10e": 0.002,
    "ur16e": 0.002,
    "ur20": 0.002,
    "ur3": 0.008,
    "ur5": 0.008,
    "ur10": 0.008,
    "fr3": 0.001,
    "iiwa14": 0.001,
    "gen3": 0.001,
}


def test_every_shipped_robot_states_its_control_period():
    shipped = (*robots.names(), *robots.SHIPPED_URDFS)
    assert sorted(shipped) == sorted(PUBLISHED_PERIODS_S)
    for name in shipped:
        assert params(name).control_period_s == PUBLISHED_PERIODS_S[name], name


def test_the_shipped_file_states_the_period_in_every_entry():
    doc = json.loads(tvist._core.ROBOT_DATA_JSON)
    assert "control_period_s" in doc["conventions"]
    periods = {name: entry["control_period_s"] for name, entry in doc["robots"].items()}
    assert periods == {n: PUBLISHED_PERIODS_S[n] for n in robots.names()}


def _unstated(name: str = "ur5e") -> robots.RobotParams:
    return dataclasses.replace(params(name), control_period_s=None)


@pytest.mark.parametrize("bad", [0.0, -0.002, math.nan, math.inf])
def test_robot_params_refuse_a_period_that_is_not_a_time(bad):
    with pytest.raises(ValueError, match="ur5e: control_period_s must be finite and > 0"):
        dataclasses.replace(params("ur5e"), control_period_s=bad)


def test_sample_period_is_dt_s_or_the_robots_or_an_error_naming_the_robot():
    ur5e = params("ur5e")
    assert ur5e.sample_period_s() == ur5e.control_period_s
    assert ur5e.sample_period_s(0.004) == 0.004
    assert _unstated().sample_period_s(0.004) == 0.004
    with pytest.raises(ValueError, match=r"ur5e: .*no control period.*pass dt_s"):
        _unstated().sample_period_s()


def test_a_robot_file_may_omit_the_period_and_keeps_it_when_written(tmp_path):
    path, base, tip = shipped_urdf("fr3")
    without = tmp_path / "without.json"
    write_robot_file(urdf_params(path, base, tip, name="arm"), without)
    assert "control_period_s" not in json.loads(without.read_text())["robots"]["arm"]
    assert robot_file(without).control_period_s is None
    stated = tmp_path / "stated.json"
    write_robot_file(urdf_params(path, base, tip, name="arm", control_period_s=0.001), stated)
    assert robot_file(stated).control_period_s == 0.001


@pytest.mark.parametrize("bad", [0, -0.001, "0.001"])
def test_a_robot_file_with_a_bad_period_is_refused_by_the_core(tmp_path, bad):
    path, base, tip = shipped_urdf("fr3")
    out = tmp_path / "arm.json"
    write_robot_file(urdf_params(path, base, tip, name="arm"), out)
    doc = json.loads(out.read_text())
    doc["robots"]["arm"]["control_period_s"] = bad
    out.write_text(json.dumps(doc))
    with pytest.raises(ValueError, match="arm: control_period_s must be a finite number"):
        robot_file(out)


def test_robot_file_command_writes_the_period_it_is_given(tmp_path, capsys):
    path, base, tip = shipped_urdf("fr3")
    args = ["robot-file", str(path), "--base-link", base, "--tip-link", tip, "--name", "arm"]
    assert main([*args, "--out", str(tmp_path / "a.json")]) == 0
    assert robot_file(tmp_path / "a.json").control_period_s is None
    assert main([*args, "--out", str(tmp_path / "b.json"), "--control-period-s", "0.001"]) == 0
    assert robot_file(tmp_path / "b.json").control_period_s == 0.001
    capsys.readouterr()
    assert main([*args, "--out", str(tmp_path / "c.json"), "--control-period-s", "0"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "control_period_s must be finite and > 0" in err[0], err


@pytest.mark.parametrize(
    "argv",
    [
        ["shape", "in.csv", "--out", "out.csv", "--modes", "2:0.1"],
        ["zero-delay", "--reference", "min_jerk"],
    ],
)
def test_the_cli_refuses_a_robot_without_a_period_naming_dt_s(monkeypatch, capsys, argv):
    monkeypatch.setattr(robots, "params", lambda name: _unstated(name))
    assert main(argv) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "ur5e has no control period" in err[0] and "--dt-s" in err[0], err


def test_the_cli_default_dt_s_is_the_robots_period():
    from tvist.cli import build_parser
    from tvist.cli.args import dt_s_from_args

    parser = build_parser()
    for robot in ("ur5e", "ur10", "fr3"):
        args = parser.parse_args(["shape", "in.csv", "--out", "o.csv", "--robot", robot])
        assert args.dt_s is None
        assert dt_s_from_args(args) == params(robot).control_period_s
    args = parser.parse_args(["shape", "in.csv", "--out", "o.csv", "--dt-s", "0.004"])
    assert dt_s_from_args(args) == 0.004


def test_robot_bearing_functions_default_to_the_robots_period():
    robot = robots.ur5e()
    traj, _ = cartesian.straight_line(robot, PAPER_POSES["Q1"], (0.05, 0.0, 0.0), 0.2)
    assert traj.dt_s == params("ur5e").control_period_s
    with pytest.raises(ValueError, match="pass dt_s"):
        cartesian.straight_line(robots.Robot(_unstated()), PAPER_POSES["Q1"], (0.05, 0, 0), 0.2)


def test_the_twin_runs_at_its_robots_period():
    from tvist.sim import Twin
    from tvist.sim.twin_plant import TwinPlant
    from tvist.urserver.controller import TwinController

    twin = Twin("ur5e")
    period = params("ur5e").control_period_s
    record = twin.run(np.tile(PAPER_POSES["Q1"], (5, 1)))
    np.testing.assert_array_equal(record.timestamp, period * np.arange(5))
    assert TwinPlant(twin, PAPER_POSES["Q1"]).dt_s == period
    assert TwinController(twin, PAPER_POSES["Q1"]).dt_s == period
