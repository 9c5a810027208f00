"""Under CI, a test skipped for a missing optional dependency fails instead.

``pytest.importorskip`` makes a test (or a whole module, such as the pinocchio cross-checks)
skip when a test dependency is not installed. On a developer's machine that is a
convenience; in CI (environment variable ``CI`` set to ``true``/``1``/``yes``) it would hide a
broken install and let the cross-checks silently not run, so there such a skip is turned into
a failure that names the missing module. Loaded by ``tests/conftest.py``.
"""

from __future__ import annotations

import os

import pytest

#: The start of the skip reason ``pytest.importorskip`` gives for a missing module.
_IMPORT_SKIP_REASON = "could not import"


def in_ci() -> bool:
    """True when the environment variable ``CI`` says the suite runs in CI."""
    return os.environ.get("CI", "").strip().lower() in {"1", "true", "yes"}


def _missing_dependency_reason(report) -> str | None:
    if not report.skipped:
        return None
    longrepr = report.longrepr
    reason = longrepr[2] if isinstance(longrepr, tuple) and len(longrepr) == 3 else str(longrepr)
    return reason if _IMPORT_SKIP_REASON in reason else None


def _fail_if_dependency_missing(report) -> None:
    reason = _missing_dependency_reason(report)
    if reason is not None and in_ci():
        report.outcome = "failed"
        report.longrepr = (
            f"a test dependency is missing in CI ({reason}); install the test extras "
            "(pip install '.[test]', as `make build` does) instead of skipping these tests"
        )


@pytest.hookimpl(wrapper=True)
def pytest_make_collect_report(collector):
    report = yield
    _fail_if_dependency_missing(report)
    return report


@pytest.hookimpl(wrapper=True)
def pytest_runtest_makereport(item, call):
    report = yield
    _fail_if_dependency_missing(report)
    return report
