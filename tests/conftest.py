"""Suite-wide pytest hooks and fixtures.

The helper modules in ``tests/support`` are importable by name from every tier through the
``pythonpath`` option in pyproject.toml (set before this file is loaded)."""

import faulthandler
import signal
import sys
from pathlib import Path

import numpy as np
import pytest

import twin_server_fixture
from ci_dependencies import pytest_make_collect_report, pytest_runtest_makereport
from cpp_programs import built_programs

__all__ = [
    "pytest_collection_modifyitems",
    "pytest_runtest_protocol",
    "pytest_make_collect_report",
    "pytest_runtest_makereport",
]


TESTS = Path(__file__).resolve().parent

#: The tiers, one folder each; every test in a folder gets the folder's marker.
TIERS = ("unit", "integration", "reference")

#: Tests outside the realtime modules that open a socket (paths relative to tests/, a file or
#: one test's node id). Every realtime test is also ``network``: the twin server it drives
#: listens on loopback ports.
NETWORK = (
    "unit/test_twin_plant.py::test_server_names_a_taken_port",
    "integration/test_recorder_rate.py",
)


def _is_realtime_module(module: object) -> bool:
    """A module that uses the twin server's test helpers (``twin_server_fixture``) or says so
    itself (``REALTIME = True``)."""
    return getattr(module, "REALTIME", False) or any(
        getattr(v, "__module__", None) == twin_server_fixture.__name__
        for v in vars(module).values()
    )


def _relative_node_id(item: pytest.Item) -> str | None:
    """``tier/test_file.py::test_name[...]`` relative to tests/, or None outside tests/."""
    try:
        path = item.path.resolve().relative_to(TESTS).as_posix()
    except ValueError:
        return None
    return "::".join([path, *item.nodeid.split("::")[1:]])


def _is_network(node_id: str) -> bool:
    return any(
        node_id == entry or node_id.startswith(entry + "::") or node_id.startswith(entry + "[")
        for entry in NETWORK
    )


def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    """Mark each test with its tier (its folder under tests/), ``realtime`` and ``network``.

    ``realtime``: every test of a module that uses the twin server's test helpers or sets
    ``REALTIME = True``: the server keeps real time at 500 Hz, and a CPU-bound test on another
    worker next to it makes its moves late (a Ctrl-C test found its 3 s move already over).
    ``make pytest`` runs them in one process after the parallel part."""
    for item in items:
        module = getattr(item, "module", None)
        realtime = module is not None and _is_realtime_module(module)
        if realtime:
            item.add_marker(pytest.mark.realtime)
        node_id = _relative_node_id(item)
        if node_id is None:
            continue
        tier = node_id.split("/", 1)[0]
        if tier in TIERS:
            item.add_marker(getattr(pytest.mark, tier))
        if realtime or _is_network(node_id):
            item.add_marker(pytest.mark.network)


#: A realtime test (set-up and tear-down included) still running after this long ends its
#: process, with every thread's stack on stderr (s). pytest-timeout (1200 s, pyproject.toml)
#: fails it first if it can: its timer is a Python thread, which never runs while a C++ call
#: holds the interpreter, and ur_rtde's constructors do while they wait for the server (the
#: first data package: no time limit). faulthandler's watchdog is a C thread; under xdist the
#: controller reports the test whose worker ended ("worker crashed while running ...").
HANG_EXIT_S = 1500


def _stderr_fd(config: pytest.Config) -> int:
    """The terminal's stderr for faulthandler (the one pytest's own faulthandler plugin
    writes to), not the per-test capture, which is lost when the process ends."""
    try:
        from _pytest.faulthandler import fault_handler_stderr_fd_key

        return config.stash[fault_handler_stderr_fd_key]
    except (ImportError, KeyError):  # another pytest, or -p no:faulthandler
        return sys.__stderr__.fileno()


# The Ctrl-C tests (``tvist run``, ``tvist record``) send their child processes SIGINT. A
# process started with SIGINT ignored (a shell's background job: ``make test &``) passes the
# ignoring on to its children, and Python then installs no KeyboardInterrupt handler in them:
# they would never see the Ctrl-C. A handler here is reset to the default in each child.
if signal.getsignal(signal.SIGINT) is signal.SIG_IGN:
    signal.signal(signal.SIGINT, signal.default_int_handler)


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_protocol(item: pytest.Item, nextitem: pytest.Item | None):
    """Arm :data:`HANG_EXIT_S` around each realtime test."""
    armed = item.get_closest_marker("realtime") is not None
    if armed:
        faulthandler.dump_traceback_later(HANG_EXIT_S, exit=True, file=_stderr_fd(item.config))
    try:
        yield
    finally:
        if armed:
            faulthandler.cancel_dump_traceback_later()


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


@pytest.fixture()
def move_csv(tmp_path: Path) -> Path:
    """A 0.4 s min-jerk move of the first three joints of a UR5e from a mid-range pose, then
    0.2 s of rest: rows of 6 joint angles (rad) every 2 ms, no header."""
    t = np.arange(0.0, 0.6, 0.002)
    s = np.clip(t / 0.4, 0.0, 1.0)
    q = np.array([0.0, -1.6, 1.2, -1.2, 0.3, 0.0]) + np.outer(
        s**3 * (10 - 15 * s + 6 * s**2), [0.4, 0.3, -0.3, 0, 0, 0]
    )
    path = tmp_path / "move.csv"
    np.savetxt(path, q, delimiter=",")
    return path


@pytest.fixture()
def paper_move_csv(tmp_path: Path) -> tuple[Path, np.ndarray]:
    """The paper's Q1 -> Q3 double-S move every 2 ms with 0.02 s of rest before and after,
    written with a ``q0,...,q5`` header at 12 decimals; and the angles (rad) read back from
    that file."""
    from tvist.trajectory import PAPER_POSES, double_s  # imported by the tests that use it

    move = double_s(PAPER_POSES["Q1"], PAPER_POSES["Q3"], dt_s=0.002, t_pre_s=0.02, t_post_s=0.02)
    path = tmp_path / "move.csv"
    header = ",".join(f"q{j}" for j in range(6))
    np.savetxt(path, move.q, delimiter=",", header=header, comments="", fmt="%.12f")
    return path, np.loadtxt(path, delimiter=",", skiprows=1)


@pytest.fixture(scope="session")
def soft_elbow_fit(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """``tvist fit-map --kind modal`` (default robot, the UR5e) of the soft-elbow variant's
    ringing records at the demo plan's poses, made once per run (:mod:`shared_fits`): a
    folder with ``records.jsonl``, ``map.json`` and ``fit_map.json`` (exit code, printout)."""
    from shared_fits import SOFT_ELBOW_SEED, demo_plan_poses, shared_files, write_fit
    from tvist.sim.family import sample_variant
    from tvist.sim.ringing_records import ringing_records

    def make(folder: Path) -> None:
        variant = sample_variant("ur5e", SOFT_ELBOW_SEED)
        write_fit(folder, ringing_records(variant, demo_plan_poses(), seed=1))

    return shared_files(tmp_path_factory, "soft_elbow", make)


@pytest.fixture(scope="session")
def ur10e_twin_fit(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """``tvist fit-map --kind modal --robot ur10e`` of records of the UR10e twin's modes
    (every 4th campaign pose, no payload and 5 kg, :func:`shared_fits.twin_records`), made
    once per run: a folder with ``records.jsonl``, ``map.json`` and ``fit_map.json``."""
    from shared_fits import shared_files, twin_records, write_fit

    def make(folder: Path) -> None:
        records = twin_records("ur10e", (0.0, 5.0), every=4, seed=5)
        write_fit(folder, records, ["--robot", "ur10e"])

    return shared_files(tmp_path_factory, "ur10e_twin", make)


@pytest.fixture(scope="session")
def family_9_fit(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """``tvist fit-map --kind modal`` of ``family:ur5e:9``'s identified pose records
    (:data:`shared_fits.FAMILY_9_CAMPAIGN`), made once per run: a folder with
    ``records.jsonl``, ``map.json`` and ``fit_map.json`` (exit code, printout)."""
    from shared_fits import FAMILY_9_CAMPAIGN, shared_files, write_fit
    from tvist.ident.results_store import load_results

    def make(folder: Path) -> None:
        write_fit(folder, load_results(FAMILY_9_CAMPAIGN))

    return shared_files(tmp_path_factory, "family_9", make)
