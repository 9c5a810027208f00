"""Suite-wide pytest hooks."""

from ci_dependencies import pytest_make_collect_report, pytest_runtest_makereport

__all__ = ["pytest_make_collect_report", "pytest_runtest_makereport"]
