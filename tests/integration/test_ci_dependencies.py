"""A missing optional test dependency skips locally but fails the suite in CI."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

TESTS = Path(__file__).resolve().parents[1]


def run_pytest(folder: Path, ci: str | None, *files: str) -> subprocess.CompletedProcess:
    env = {k: v for k, v in os.environ.items() if k != "CI"}
    if ci is not None:
        env["CI"] = ci
    env["PYTHONPATH"] = os.pathsep.join([str(TESTS / "support"), env.get("PYTHONPATH", "")])
    return subprocess.run(
        [sys.executable, "-m", "pytest", "-q", "-rA", "-p", "no:cacheprovider", *files],
        cwd=folder,
        env=env,
        capture_output=True,
        text=True,
        timeout=120,
    )


@pytest.fixture
def suite(tmp_path: Path) -> Path:
    """A small suite with the project's hooks: a module and a test that need missing
    modules, a test skipped for another reason, and a passing test."""
    (tmp_path / "conftest.py").write_text((TESTS / "conftest.py").read_text())
    (tmp_path / "test_needs_module.py").write_text(
        "import pytest\n"
        "missing = pytest.importorskip('tvist_module_that_does_not_exist')\n"
        "def test_a():\n    pass\n"
    )
    (tmp_path / "test_other.py").write_text(
        "import pytest\n"
        "def test_inside():\n    pytest.importorskip('tvist_other_missing_module')\n"
        "@pytest.mark.skip(reason='not on this platform')\n"
        "def test_skipped_on_purpose():\n    pass\n"
        "def test_ok():\n    pass\n"
    )
    return tmp_path


def test_missing_dependency_skips_outside_ci(suite: Path) -> None:
    result = run_pytest(suite, None, "test_needs_module.py", "test_other.py")
    assert result.returncode == 0, result.stdout + result.stderr
    assert "1 passed, 3 skipped" in result.stdout


@pytest.mark.parametrize("ci", ["true", "1"])
def test_missing_dependency_fails_in_ci(suite: Path, ci: str) -> None:
    # A module-level import is a collection error, which stops the run (exit code 2).
    module = run_pytest(suite, ci, "test_needs_module.py", "test_other.py")
    assert module.returncode == 2, module.stdout + module.stderr
    assert "ERROR test_needs_module.py - a test dependency is missing in CI" in module.stdout
    assert "tvist_module_that_does_not_exist" in module.stdout
    # One inside a test fails that test; the deliberate skip stays a skip.
    inside = run_pytest(suite, ci, "test_other.py")
    assert inside.returncode == 1, inside.stdout + inside.stderr
    assert "1 failed, 1 passed, 1 skipped" in inside.stdout, inside.stdout
    assert "tvist_other_missing_module" in inside.stdout


def test_ci_false_is_not_ci(suite: Path) -> None:
    assert run_pytest(suite, "false", "test_needs_module.py", "test_other.py").returncode == 0
