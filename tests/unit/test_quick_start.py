"""The README's quick start, as tools/quick_start.py reads it: every command parses with the
real command line, the server starts it and a shaped run comes early (the first success)."""

from __future__ import annotations

import importlib.util
import shlex
from pathlib import Path

import numpy as np
import pytest

from tvist.cli import build_parser

ROOT = Path(__file__).resolve().parents[2]


def _tool():
    spec = importlib.util.spec_from_file_location("quick_start", ROOT / "tools" / "quick_start.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_continued_lines_are_joined_and_comments_dropped():
    readme = (
        "x\n<!-- [start:quick-start] -->\n```sh\n# a comment\nsource .venv/bin/activate\n"
        'python -c "a; \\\nb"\n\ntvist run m.csv --unshaped\n```\n<!-- [end:quick-start] -->\n'
    )
    assert _tool().quick_start_commands(readme) == [
        "source .venv/bin/activate",
        'python -c "a; b"',
        "tvist run m.csv --unshaped",
    ]


def test_a_block_ending_inside_a_continued_line_is_refused():
    readme = "[start:quick-start]\n```sh\ntvist run \\\n```\n[end:quick-start]"
    with pytest.raises(ValueError, match="continued line"):
        _tool().quick_start_commands(readme)


def test_every_readme_command_parses_and_a_shaped_move_comes_first():
    tool = _tool()
    commands = tool.quick_start_commands((ROOT / "README.md").read_text())
    assert commands[0] == "source .venv/bin/activate"
    tvist_lines = [shlex.split(c) for c in commands if c.startswith("tvist ")]
    assert [c for c in commands[1:] if not c.startswith(("tvist ", "python -c "))] == []
    parser = build_parser()
    for argv in tvist_lines:
        parser.parse_args(argv[1:])  # exits (SystemExit) on an unknown flag or command
    assert sum(c.startswith(tool.SERVER) for c in commands) == 1
    # The first success: a shaped run before the campaign (which keeps the arm busy minutes).
    first_shaped = tool._first_shaped_run(commands)
    campaign = next(i for i, c in enumerate(commands) if c.startswith("tvist campaign"))
    assert "--paper-map" in commands[first_shaped] and first_shaped < campaign


def test_the_quick_starts_python_lines_run(tmp_path):
    """The ``python -c`` lines (the move files the runs read) run as written: a change of an
    API they call fails here, not in a newcomer's first minutes."""
    import subprocess
    import sys

    commands = _tool().quick_start_commands((ROOT / "README.md").read_text())
    python_lines = [shlex.split(c)[1:] for c in commands if c.startswith("python -c ")]
    assert python_lines
    for argv in python_lines:
        done = subprocess.run(
            [sys.executable, *argv], cwd=tmp_path, capture_output=True, text=True, timeout=120
        )
        assert done.returncode == 0, done.stderr
    move = np.loadtxt(tmp_path / "q1-q2.csv", delimiter=",")
    assert move.ndim == 2 and move.shape[1] == 6 and len(move) > 100
