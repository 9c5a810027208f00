"""Suite-wide pytest hooks and fixtures."""

from pathlib import Path

import pytest

import twin_server_fixture
from ci_dependencies import pytest_make_collect_report, pytest_runtest_makereport
from cpp_programs import built_programs

__all__ = [
    "pytest_collection_modifyitems",
    "pytest_make_collect_report",
    "pytest_runtest_makereport",
]


def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    """Mark ``realtime`` every test of a module that uses the twin server's test helpers
    (``twin_server_fixture``) or says so itself (``REALTIME = True``): the server
    keeps real time at 500 Hz, and a CPU-bound test on another worker next to it makes its
    moves late (a Ctrl-C test found its 3 s move already over). ``make pytest`` runs them in
    one process after the parallel part."""
    for item in items:
        module = getattr(item, "module", None)
        if module is not None and (
            getattr(module, "REALTIME", False)
            or any(
                getattr(v, "__module__", None) == twin_server_fixture.__name__
                for v in vars(module).values()
            )
        ):
            item.add_marker(pytest.mark.realtime)


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
