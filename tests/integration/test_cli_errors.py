"""User errors on the command line: one line naming the problem, exit code 2, no traceback;
``--debug`` shows the traceback; ``--version``."""

from __future__ import annotations

import subprocess
import sys

import pytest

from tvist.cli import main


def _run(*argv: str) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "tvist.cli", *argv], capture_output=True, text=True, timeout=120
    )


def test_a_missing_file_is_one_line_with_exit_code_2(tmp_path):
    missing = tmp_path / "no_such_log.csv"
    done = _run("identify", str(missing), "--joint", "0")
    assert done.returncode == 2
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1, done.stderr
    assert lines[0].startswith("tvist identify: error: ")
    assert str(missing) in lines[0]
    assert "Traceback" not in done.stderr


@pytest.mark.slow
def test_debug_shows_the_traceback_wherever_it_is_given(tmp_path):
    missing = str(tmp_path / "no_such_log.csv")
    for argv in (
        ("--debug", "identify", missing, "--joint", "0"),
        ("identify", missing, "--joint", "0", "--debug"),
    ):
        done = _run(*argv)
        assert done.returncode != 0
        assert "Traceback" in done.stderr
        assert "FileNotFoundError" in done.stderr


def test_a_value_error_from_the_library_is_reported_not_raised(tmp_path, capsys):
    bad = tmp_path / "bad.csv"
    bad.write_text("timestamp,target_q_0\n0.0,1.0\n")
    code = main(["identify", str(bad), "--joint", "0"])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2
    assert len(err) == 1 and err[0].startswith("tvist identify: error: ")


def test_version():
    from importlib.metadata import version

    done = _run("--version")
    assert done.returncode == 0
    assert done.stdout.strip() == f"tvist {version('tvist')}"


def test_a_bug_is_not_disguised_as_a_user_error(monkeypatch):
    import tvist.cli as cli

    def broken(_args):
        raise ZeroDivisionError("a bug")

    parser = cli.build_parser()
    args = parser.parse_args(["identify", "x.csv", "--joint", "0"])
    monkeypatch.setattr(cli, "build_parser", lambda: _Fixed(parser, args, broken))
    with pytest.raises(ZeroDivisionError):
        cli.main(["identify", "x.csv", "--joint", "0"])


class _Fixed:
    """A parser stand-in that returns ``args`` with ``func`` replaced."""

    def __init__(self, parser, args, func):
        self.args = args
        self.args.func = func

    def parse_args(self, _argv):
        return self.args
