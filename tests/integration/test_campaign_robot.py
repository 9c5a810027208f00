"""``tvist campaign --robot-ip`` as an operator runs it: the plan is checked before the robot
moves, one prompt per payload change (none with ``--yes``), a one-line error without a
terminal, and every run's logs in a folder of their own.

The robot is a stand-in for ur_rtde's control interface that records what it is told, and
for the RTDE recorder (it writes a marker where it is told to record); nothing here needs a
robot or a twin."""

from __future__ import annotations

import io
import sys
import types

import pytest

from tvist.cli import main

#: The plan of the tests: one payload, every 8th pose: 7 poses at 7 radii.
PLAN = ["--payloads", "5", "--every", "8", "--duration", "0.2", "--no-workspace-cover"]


class _Control:
    def __init__(self, ip: str) -> None:
        self.calls: list[tuple] = []
        _Control.last = self

    def moveJ(self, q, speed, accel):  # noqa: N802 (ur_rtde's name)
        self.calls.append(("moveJ", list(q)))
        return True

    def setPayload(self, mass, cog):  # noqa: N802
        self.calls.append(("setPayload", mass, list(cog)))
        return True


class _Recorder:
    """Stands in for tvist.live.RtdeRecorder: writes a marker where it is told to record."""

    def __init__(self, host, path, fields, frequency_hz) -> None:
        if path is None:  # the check that the controller sends data
            return
        with open(path, "w") as fh:
            fh.write(f"marker of {path}\n")

    def __enter__(self):
        return self

    def __exit__(self, *exc) -> None:
        pass

    def wait_controller_time(self, seconds: float) -> None:
        """The campaign's waits (on the controller's clock) take no time here."""


def _no_identification(*logs, key, **_):
    """The stand-in's logs hold no data: each pose is recorded without modes."""
    return types.SimpleNamespace(to_dict=lambda: {"key": key, "modes": []})


@pytest.fixture
def fake_robot(monkeypatch):
    """ur_rtde replaced by the stand-in; the campaign's waits take no time and its poses are
    recorded without identification."""
    monkeypatch.setitem(
        sys.modules, "rtde_control", types.SimpleNamespace(RTDEControlInterface=_Control)
    )
    monkeypatch.setattr("tvist.live.RtdeRecorder", _Recorder)
    monkeypatch.setattr("tvist.ident.campaign.identify_pose", _no_identification)
    _Control.last = None
    return _Control


def test_unfittable_plan_is_refused_before_the_robot_is_contacted(fake_robot, tmp_path, capsys):
    out = tmp_path / "c.jsonl"
    args = ["campaign", "--robot-ip", "192.0.2.1", "--out", str(out), "--yes"]
    assert main([*args, "--every", "13", "--payloads", "5", "--no-workspace-cover"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1
    assert "4 reachable poses" in err and "needs at least 6" in err and "--every" in err
    assert fake_robot.last is None  # never connected, nothing moved
    assert not (tmp_path / "logs").exists()


@pytest.mark.slow
def test_one_prompt_per_payload_change(fake_robot, tmp_path, monkeypatch):
    prompts = []
    monkeypatch.setattr("builtins.input", lambda text="": prompts.append(text) or "")
    out = tmp_path / "c.jsonl"
    args = ["campaign", "--robot-ip", "192.0.2.1", "--out", str(out)]
    assert main([*args, "--payloads", "5", "1", "--every", "8", "--duration", "0.2"]) == 0
    # Two payloads (13 poses): two prompts, lightest payload first.
    assert len(prompts) == 2
    assert "1 kg" in prompts[0] and "5 kg" in prompts[1]
    payloads = [c[1] for c in fake_robot.last.calls if c[0] == "setPayload"]
    assert payloads == [1.0, 5.0]


def test_yes_runs_without_prompts(fake_robot, tmp_path, monkeypatch):
    def no_prompt(text=""):
        raise AssertionError(f"prompted: {text}")

    monkeypatch.setattr("builtins.input", no_prompt)
    assert (
        main(
            [
                "campaign",
                "--robot-ip",
                "192.0.2.1",
                "--out",
                str(tmp_path / "c.jsonl"),
                *PLAN,
                "--yes",
            ]
        )
        == 0
    )
    moves = [c for c in fake_robot.last.calls if c[0] == "moveJ"]
    assert moves  # it ran


def test_no_terminal_is_one_line_naming_yes(fake_robot, tmp_path, monkeypatch, capsys):
    monkeypatch.setattr(sys, "stdin", io.StringIO(""))  # input() meets the end of input
    out = tmp_path / "c.jsonl"
    assert main(["campaign", "--robot-ip", "192.0.2.1", "--out", str(out), *PLAN]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "--yes" in err and "Traceback" not in err
    assert not [c for c in fake_robot.last.calls if c[0] == "moveJ"]  # asked before moving


@pytest.mark.slow
def test_each_run_keeps_its_own_logs(fake_robot, tmp_path):
    out = tmp_path / "c.jsonl"
    args = ["campaign", "--robot-ip", "192.0.2.1", "--out", str(out), *PLAN, "--yes"]
    assert main(args) == 0
    first = sorted((tmp_path / "logs").rglob("*.csv"))
    contents = {p: p.read_text() for p in first}
    assert len(first) == 21  # 7 poses, base, shoulder and elbow (the default --excite)
    assert main([*args, "--overwrite"]) == 0
    every = sorted((tmp_path / "logs").rglob("*.csv"))
    assert len(every) == 42
    assert {p: p.read_text() for p in first} == contents  # the first run's logs untouched
    assert len({p.parent for p in every}) == 2
    # Run again without --overwrite: every pose is done, the campaign resumes with nothing
    # to move.
    assert main(args) == 0
    assert not [c for c in fake_robot.last.calls if c[0] == "moveJ"]
    assert len(sorted((tmp_path / "logs").rglob("*.csv"))) == 42
