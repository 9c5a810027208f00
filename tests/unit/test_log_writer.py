"""The twin server's log writer: a log call never waits for the output."""

from __future__ import annotations

import logging
import threading

import pytest

from tvist.urserver.log_writer import MAX_QUEUED_RECORDS, LogWriter

LOGGER = logging.getLogger("tvist.urserver.test_log_writer")


@pytest.fixture
def root_level():
    """The root logger's level, restored after the test (a LogWriter sets it)."""
    root = logging.getLogger()
    level = root.level
    yield
    root.setLevel(level)


class _Collect(logging.Handler):
    def __init__(self) -> None:
        super().__init__()
        self.messages: list[str] = []

    def emit(self, record: logging.LogRecord) -> None:
        self.messages.append(record.getMessage())


class _Blocked(logging.Handler):
    """An output nobody reads: every write waits until released."""

    def __init__(self) -> None:
        super().__init__()
        self.opened = threading.Event()

    def emit(self, record: logging.LogRecord) -> None:
        self.opened.wait()


def test_records_are_written_in_order_and_flushed_by_close(root_level) -> None:
    out = _Collect()
    writer = LogWriter(out)
    for i in range(100):
        LOGGER.info("line %d", i)
    assert writer.close()
    assert out.messages == [f"line {i}" for i in range(100)]
    assert writer.dropped == 0
    LOGGER.info("after close")  # no longer routed to the writer
    assert out.messages[-1] == "line 99"


def test_a_blocked_output_drops_records_instead_of_blocking_the_caller(root_level) -> None:
    out = _Blocked()
    writer = LogWriter(out)
    try:
        # Written directly, the first call would wait for ever. The writer takes at most one
        # record (then waits in the output); the queue holds MAX_QUEUED_RECORDS; the rest
        # (10 or 11) are dropped.
        for i in range(MAX_QUEUED_RECORDS + 11):
            LOGGER.warning("line %d", i)
        assert 10 <= writer.dropped <= 11
        assert not writer.close(timeout_s=0.05)  # the output is still blocked
    finally:
        out.opened.set()
