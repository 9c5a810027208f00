"""Suite-wide pytest hooks and fixtures."""

from pathlib import Path

import pytest

from ci_dependencies import pytest_make_collect_report, pytest_runtest_makereport
from cpp_programs import built_programs

__all__ = ["pytest_make_collect_report", "pytest_runtest_makereport"]


@pytest.fixture(scope="session")
def shape_with_map(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The C++ example ``examples/cpp/shape_with_map.cpp`` (``make cpp-example``), built once
    per test process (up to date in make test)."""
    (program,) = built_programs(
        "cpp-example", ["target/cpp/shape_with_map"], tmp_path_factory.mktemp("cpp")
    )
    return program


@pytest.fixture(scope="session")
def hpp_containers(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    """``tests/cpp/hpp_containers.cpp`` built as C++17 and C++20 (``make cpp-containers``),
    by standard."""
    standards = ("17", "20")
    programs = [f"target/cpp/hpp_containers_{s}" for s in standards]
    copies = built_programs("cpp-containers", programs, tmp_path_factory.mktemp("hpp"))
    return dict(zip(standards, copies, strict=True))
