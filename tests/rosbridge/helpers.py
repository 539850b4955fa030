"""Helpers shared by the bridge tests: the worked example frame, an event loop on its own
thread (servers that blocking clients talk to), a roslibpy client and its inbox, a full
message definition split into its types, and a free loopback port."""

from __future__ import annotations

import asyncio
import contextlib
import re
import socket
import threading
from collections.abc import Coroutine, Iterator
from typing import Any, TypeVar

import roslibpy

T = TypeVar("T")

#: The 13 bytes of the worked example in docs/protocol.md (square, 0.5 m/s, 2 m, 12.5 m, cw).
EXAMPLE = bytes.fromhex("aaaa7c13214730000008915600")


class LoopThread:
    """An asyncio event loop running in a daemon thread: :meth:`run` a coroutine on it."""

    def __init__(self) -> None:
        self.loop = asyncio.new_event_loop()
        self._thread = threading.Thread(target=self.loop.run_forever, daemon=True)

    def start(self) -> None:
        self._thread.start()

    def run(self, coro: Coroutine[Any, Any, T], timeout_s: float = 5.0) -> T:
        """Run ``coro`` on the loop and wait for its result."""
        return asyncio.run_coroutine_threadsafe(coro, self.loop).result(timeout_s)

    def stop(self) -> None:
        self.loop.call_soon_threadsafe(self.loop.stop)
        self._thread.join(5)
        self.loop.close()


@contextlib.contextmanager
def ros_client(port: int) -> Iterator[Any]:
    """A connected roslibpy client (asyncio transport: the twisted reactor cannot restart)."""
    ros = roslibpy.Ros("127.0.0.1", port, transport="asyncio")
    ros.run(timeout=3)
    try:
        yield ros
    finally:
        ros.close()


class Inbox:
    """Thread-safe list of messages a roslibpy callback received."""

    def __init__(self) -> None:
        self._items: list[dict[str, Any]] = []
        self._cond = threading.Condition()

    def __call__(self, message: dict[str, Any]) -> None:
        with self._cond:
            self._items.append(dict(message))
            self._cond.notify_all()

    def wait(self, count: int = 1, timeout: float = 1.5) -> list[dict[str, Any]]:
        with self._cond:
            self._cond.wait_for(lambda: len(self._items) >= count, timeout)
            return list(self._items)

    def items(self) -> list[dict[str, Any]]:
        with self._cond:
            return list(self._items)


#: What rosapi puts between two message definitions in ``typedefs_full_text``.
_BETWEEN = re.compile(r"\n={80}\nMSG: (\S+)\n")


def definition_sections(text: str) -> list[tuple[str | None, str]]:
    """``(type or None for the root, its text)`` of a full message definition, split on its
    separators by rosapi's own layout (a blank line, 80 ``=``, ``MSG: pkg/Type``)."""
    parts = _BETWEEN.split(text)
    names: list[str | None] = [None, *parts[1::2]]
    return list(zip(names, parts[0::2], strict=True))


def free_port() -> int:
    """A 127.0.0.1 port nothing listens on (bound, then released)."""
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port: int = s.getsockname()[1]
    return port
