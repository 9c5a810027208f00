"""One spelling and one unit per quantity across the command line, and the small things a new
user trips over: flag names, units in help texts, printed frequencies, the documentation's command
list, status names, maps of another robot, the approach move, running a shaped file."""

from __future__ import annotations

import argparse
import re
import subprocess
import sys
import warnings
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

import tvist
import tvist.cli.live
from tvist.cli import COMMANDS, build_parser, main

ROOT = Path(__file__).resolve().parents[2]


def _tvist(*argv: str) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "tvist.cli", *argv], capture_output=True, text=True, timeout=300
    )


def _subparsers() -> dict[str, argparse.ArgumentParser]:
    parser = build_parser()
    action = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    return dict(action.choices)


# --------------------------------------------------------------------------- --dt-s


@pytest.mark.parametrize("command", ["shape", "run", "zero-delay"])
def test_control_period_is_dt_s_everywhere_and_dt_warns(command):
    # The project's convention puts the unit in the name (dt_s): --dt-s is the flag of every
    # command with a control period; --dt still parses to the same value, with a warning.
    base = {"shape": ["shape", "m.csv", "--out", "o.csv"], "run": ["run", "m.csv"]}
    base["run"] += ["--robot-ip", "127.0.0.1"]
    argv = base.get(command, [command])
    parser = build_parser()
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # the current name never warns
        assert parser.parse_args([*argv, "--dt-s", "0.004"]).dt_s == 0.004
    with pytest.warns(FutureWarning, match="--dt is deprecated, use --dt-s"):
        assert parser.parse_args([*argv, "--dt", "0.004"]).dt_s == 0.004


def test_the_deprecated_dt_warning_is_one_line_on_the_command_line(move_csv, tmp_path):
    argv = ["shape", str(move_csv), "--out", str(tmp_path / "o.csv"), "--modes", "8:0.1"]
    done = _tvist(*argv)
    assert done.returncode == 0 and "deprecated" not in done.stderr
    done = _tvist(*argv, "--dt", "0.002")
    assert done.returncode == 0, done.stderr
    assert done.stderr.strip() == "tvist: warning: --dt is deprecated, use --dt-s"


# --------------------------------------------------------------------------- Hz and rad/s


@pytest.mark.parametrize("command", ["shape", "run"])
def test_help_says_modes_are_in_hz_and_the_api_in_rad_s(command):
    text = " ".join(_subparsers()[command].format_help().split())
    assert "undamped natural frequency in Hz (not rad/s)" in text
    assert "rad/s in the Python API" in text


def test_constant_modes_warns_on_a_frequency_that_looks_like_hz():
    # 8 rad/s is 1.27 Hz, below any robot arm's mode: most likely 8 Hz typed as rad/s.
    with pytest.warns(UserWarning, match=r"8\.0+ rad/s, i\.e\. 1\.273 Hz, below 2 Hz") as caught:
        modes = tvist.ConstantModes([(8.0, 0.1)])
    assert "2*pi times the frequency in Hz" in str(caught[0].message)
    assert modes.modes == [(8.0, 0.1)]  # warned, not refused: a soft mount can ring this low
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        tvist.ConstantModes([(2 * np.pi * 8.0, 0.1), (2 * np.pi * 2.0, 0.05)])  # 8 Hz, 2 Hz


def test_shape_prints_undamped_frequencies_as_modes_takes_them(move_csv, tmp_path, capsys):
    # ζ 0.3 makes the damped frequency 4.6 % lower (7.63 Hz): the printed value must be the
    # undamped 8.00 Hz that --modes took, labelled as such.
    out = tmp_path / "o.csv"
    assert main(["shape", str(move_csv), "--out", str(out), "--modes", "8:0.3"]) == 0
    text = capsys.readouterr().out
    assert "f_n 8.00 Hz / ζ 0.300" in text
    assert "7.63" not in text


# --------------------------------------------------------------------------- help and documentation


@pytest.mark.parametrize(
    "command", ["fit-map", "shape", "run", "record", "identify", "twin-server", "zero-delay"]
)
def test_every_default_is_shown_in_help(command):
    # A default that matters (a value, not "off" or "absent") is written in the option's help.
    parser = _subparsers()[command]
    for action in parser._actions:
        if action.default in (None, False, argparse.SUPPRESS) or not action.option_strings:
            continue
        if action.help == argparse.SUPPRESS:
            continue
        assert "default" in (action.help or ""), (command, action.option_strings)


def test_fit_map_help_shows_where_the_map_goes():
    assert "map file to write (default out/map.json)" in _subparsers()["fit-map"].format_help()


def test_the_command_line_reference_lists_every_command():
    # The hand-written list of docs/reference/cli.md (the generated part, every command's
    # help, is appended when the site is built and is not in the file).
    page = (ROOT / "docs" / "reference" / "cli.md").read_text()
    paragraph = " ".join(page.split("The command line: ", 1)[1].split("\n\n", 1)[0].split())
    listed = set(re.findall(r"`tvist ([a-z-]+)", paragraph))
    assert {name for name, _ in COMMANDS} <= listed


def test_the_install_instructions_say_to_activate_the_venv():
    readme = (ROOT / "README.md").read_text()
    install = readme.split("## Install and the two commands", 1)[1].split("\n## ", 1)[0]
    assert "source .venv/bin/activate" in install
    # The install page shows the same lines: it includes the README's (the docs build fails
    # if the README loses the marked section).
    page = (ROOT / "docs" / "install.md").read_text()
    from_a_clone = page.split("## From a clone", 1)[1].split("\n## ", 1)[0]
    assert '--8<-- "README.md:install"' in from_a_clone
    marked = readme.split("[start:install]", 1)[1].split("[end:install]", 1)[0]
    assert "source .venv/bin/activate" in marked


def test_a_shaped_file_is_run_with_unshaped_as_help_and_docs_say():
    shape_help = " ".join(_subparsers()["shape"].format_help().split())
    run_help = " ".join(_subparsers()["run"].format_help().split())
    assert "tvist run OUT --robot-ip IP --unshaped" in shape_help
    assert "for a file 'tvist shape' has shaped already" in run_help
    # The twin-server guide's commands and the README's quick start (which the docs' quick
    # start page includes).
    for page in ("docs/guides/twin-server.md", "README.md"):
        text = (ROOT / page).read_text()
        assert re.search(r"tvist run shaped\.csv --robot-ip \S+ --unshaped", text), page


# --------------------------------------------------------------------------- Status


def test_status_prints_flag_names():
    assert str(tvist.Status(0)) == "OK"
    assert str(tvist.Status.INPUT_HELD) == "INPUT_HELD"
    both = tvist.Status.INPUT_HELD | tvist.Status.DELAY_CLAMPED
    assert str(both) == "INPUT_HELD|DELAY_CLAMPED"
    assert f"{both}" == "INPUT_HELD|DELAY_CLAMPED"
    assert int(both) == 5  # still the core's bits
    # A shaper's status after a non-finite input sample.
    shaper = tvist.TvShaper(tvist.ConstantModes([(50.0, 0.1)]), 0.002, 1)
    shaper.reset(np.zeros(1))
    shaper.step(np.array([np.nan]))
    assert str(tvist.Status(shaper.last_status)) == "INPUT_HELD"


# --------------------------------------------------------------------------- other robot


def test_a_map_of_another_robot_is_refused_naming_the_flag_or_used_with_it(move_csv, tmp_path):
    # The paper's map is a UR5e's; shaping a UR10e with it needs --allow-other-robot.
    args = ["shape", str(move_csv), "--out", str(tmp_path / "o.csv"), "--paper-map"]
    args += ["--robot", "ur10e", "--payload-kg", "5"]
    refused = _tvist(*args)
    assert refused.returncode == 2
    lines = refused.stderr.strip().splitlines()
    assert len(lines) == 1 and "--allow-other-robot" in lines[0], refused.stderr
    assert "identified on ur5e, not on ur10e" in lines[0]
    assert not (tmp_path / "o.csv").exists()
    allowed = _tvist(*args, "--allow-other-robot")
    assert allowed.returncode == 0, allowed.stderr
    assert "warning: --allow-other-robot: a map identified on ur5e shapes the ur10e" in (
        allowed.stderr
    )
    assert (tmp_path / "o.csv").exists()


# --------------------------------------------------------------------------- run's approach


def test_run_says_how_it_approaches_the_first_row(move_csv, tmp_path, monkeypatch, capsys):
    # The unshaped moveJ to the first row is announced with its speed and acceleration.
    import tvist.live
    from tvist.live import LiveRun

    def fake_run(robot_ip, Q, log_path, **kwargs):  # noqa: N803
        return LiveRun(Path(log_path), 0.0, 1.0, len(Q), 0, 1.0, Q[-1])

    def fake_state(robot_ip):
        return SimpleNamespace(actual_q=np.zeros(6))

    monkeypatch.setattr(tvist.live, "run_shaped_move", fake_run)
    monkeypatch.setattr(tvist.cli.live, "_controller_ready", fake_state)
    argv = ["run", str(move_csv), "--robot-ip", "127.0.0.1", "--unshaped", "--tail", "0"]
    assert main([*argv, "--log", str(tmp_path / "log.csv")]) == 0
    out = capsys.readouterr().out
    assert "approach: moveJ to the first row at 0.5 rad/s, 0.5 rad/s² (not shaped" in out
