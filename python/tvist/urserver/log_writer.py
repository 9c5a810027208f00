"""The twin server's log, written by a thread of its own so that no log call ever blocks.

The server logs from its tick and from its client threads, some of them holding the lock the
tick needs. Written directly, a log line to a pipe nobody empties (a terminal paused with
Ctrl-S, ``tvist twin-server | less`` left on a page, a parent process that stopped reading)
blocks in ``write`` under that lock, and the whole server stops: no data packages, no
replies, and ur_rtde clients wait for it. Here a log call only puts the record in a bounded
queue (dropping it, counted, if the queue is full); one writer thread formats and writes.
"""

from __future__ import annotations

import logging
import queue
import threading

#: Records queued for the writer at most; more are dropped (and counted) until it catches up.
MAX_QUEUED_RECORDS = 10_000


class _QueueHandler(logging.Handler):
    """Puts each record in the writer's queue without ever waiting."""

    def __init__(self, records: queue.Queue) -> None:
        super().__init__()
        self._records = records
        self.dropped = 0

    def emit(self, record: logging.LogRecord) -> None:
        try:
            self._records.put_nowait(record)
        except queue.Full:
            self.dropped += 1


class LogWriter:
    """Route the root logger's records through a queue to ``handler``, written by a daemon
    thread (:meth:`close` flushes what it can within a time limit)."""

    def __init__(self, handler: logging.Handler, level: int = logging.INFO) -> None:
        self._records: queue.Queue = queue.Queue(MAX_QUEUED_RECORDS)
        self._handler = handler
        self._enqueue = _QueueHandler(self._records)
        root = logging.getLogger()
        root.addHandler(self._enqueue)
        root.setLevel(level)
        self._thread = threading.Thread(target=self._write, name="log-writer", daemon=True)
        self._thread.start()

    @property
    def dropped(self) -> int:
        """Records dropped because the queue was full."""
        return self._enqueue.dropped

    def _write(self) -> None:
        while (record := self._records.get()) is not None:
            self._handler.handle(record)

    def close(self, timeout_s: float = 2.0) -> bool:
        """Stop routing records, let the writer write those queued (``timeout_s`` at most:
        a blocked output must not keep the process from exiting); True if it finished."""
        logging.getLogger().removeHandler(self._enqueue)
        try:
            self._records.put(None, timeout=timeout_s)
        except queue.Full:
            return False
        self._thread.join(timeout_s)
        return not self._thread.is_alive()
