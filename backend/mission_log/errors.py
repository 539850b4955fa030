"""The mission log's write failure, shared by the store and its track buffer (which writes
through the store and keeps the points when a write fails)."""

from __future__ import annotations


class LogWriteError(Exception):
    """The mission log cannot be written (disk full, file or directory made read-only, locked
    by another process, I/O error, the PostgreSQL server gone): the database's ``reason``.
    ``outcome``: what the caller did about it (e.g. "nothing was transmitted"), added to the
    message."""

    def __init__(self, reason: str, outcome: str | None = None) -> None:
        super().__init__(reason)
        self.reason = reason
        self.outcome = outcome

    def __str__(self) -> str:
        tail = f"; {self.outcome}" if self.outcome else ""
        return f"the mission log cannot be written: {self.reason}{tail}"


class LogSchemaNewer(Exception):
    """The log is at migration ``at``, which this console does not know (a newer console
    migrated it: a database shared by consoles of different versions); this one knows up to
    ``head``. Nothing was changed."""

    def __init__(self, at: str, head: str) -> None:
        super().__init__(f"the log is at migration {at}, newer than this console's {head}")
        self.at = at
        self.head = head
