"""A missing optional test dependency skips locally but fails the suite in CI."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

TESTS = Path(__file__).resolve().parent


def run_pytest(folder: Path, ci: str | None) -> subprocess.CompletedProcess:
    env = {k: v for k, v in os.environ.items() if k != "CI"}
    if ci is not None:
        env["CI"] = ci
    env["PYTHONPATH"] = os.pathsep.join([str(TESTS), env.get("PYTHONPATH", "")])
    return subprocess.run(
        [sys.executable, "-m", "pytest", "-q", "-rA", "-p", "no:cacheprovider", str(folder)],
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
    result = run_pytest(suite, ci=None)
    assert result.returncode == 0, result.stdout + result.stderr
    assert "1 passed, 3 skipped" in result.stdout


@pytest.mark.parametrize("ci", ["true", "1"])
def test_missing_dependency_fails_in_ci(suite: Path, ci: str) -> None:
    result = run_pytest(suite, ci=ci)
    assert result.returncode == 1, result.stdout + result.stderr
    # The module-level import is a collection error, the one inside a test a failure; the
    # deliberate skip stays a skip.
    assert "1 failed, 1 passed, 1 skipped, 1 error" in result.stdout, result.stdout
    assert "tvist_module_that_does_not_exist" in result.stdout
    assert "tvist_other_missing_module" in result.stdout
    assert "test dependency is missing in CI" in result.stdout


def test_ci_false_is_not_ci(suite: Path) -> None:
    assert run_pytest(suite, ci="false").returncode == 0
