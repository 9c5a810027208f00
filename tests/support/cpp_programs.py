"""The C and C++ programs the tests run, built by the Makefile's targets once per test process.

``make cpp-example`` and ``make cpp-containers`` relink their programs on every call. Under
pytest-xdist two workers would then relink a program while the other one runs it; so each
build (and any other command that writes into ``target/``) runs under an exclusive lock on
``target/.tests.lock``, and the tests run copies of the programs in their own temporary
directory, which no other build touches."""

from __future__ import annotations

import contextlib
import fcntl
import shutil
import subprocess
from collections.abc import Iterator, Sequence
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
TARGET = ROOT / "target"


@contextlib.contextmanager
def target_lock() -> Iterator[None]:
    """Hold the lock on ``target/`` (blocks while another test process holds it)."""
    TARGET.mkdir(exist_ok=True)
    with (TARGET / ".tests.lock").open("w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        try:
            yield
        finally:
            fcntl.flock(lock, fcntl.LOCK_UN)


def built_programs(make_target: str, programs: Sequence[str], into: Path) -> list[Path]:
    """Run ``make -s make_target`` and copy ``programs`` (paths under the repository) into
    ``into``; the copies, in the order given."""
    if shutil.which("make") is None:
        pytest.fail("make is needed to build the C and C++ programs")
    copies = []
    with target_lock():
        subprocess.run(["make", "-s", make_target], cwd=ROOT, check=True)
        for program in programs:
            copy = into / Path(program).name
            shutil.copy2(ROOT / program, copy)
            copies.append(copy)
    return copies
