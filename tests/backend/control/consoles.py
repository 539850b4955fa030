"""Two consoles on one mission log, in this process: a page of each (:class:`Page`, its /ws
read in a thread with arrival times) and the database they share."""

from __future__ import annotations

import threading
import time
from collections.abc import Callable
from typing import Any

from fastapi.testclient import TestClient

from tests.backend.conftest import AUTH

#: The order of a command's states as a page sees them (a page may miss one that lasted
#: less than a re-read: it then sees a later one).
STATE_ORDER = {"queued": 0, "transmitted": 1}
FINAL_ORDER = 2


def order(state: str) -> int:
    return STATE_ORDER.get(state, FINAL_ORDER)


class Page:
    """A page of ``client``'s console: every ``/ws`` message, with the monotonic time it
    arrived, read in a thread (the console sends at least its link's health every second,
    so :meth:`close` returns within about a second)."""

    def __init__(self, client: TestClient) -> None:
        self.client = client
        self.messages: list[tuple[float, dict[str, Any]]] = []
        self._lock = threading.Lock()
        self._stop = threading.Event()
        self._ready = threading.Event()
        self._error: BaseException | None = None
        self._thread = threading.Thread(target=self._run, daemon=True, name="test page")
        self._thread.start()
        assert self._ready.wait(10), "the page's websocket did not open"

    def _run(self) -> None:
        try:
            with self.client.websocket_connect("/ws") as ws:
                self._ready.set()
                while not self._stop.is_set():
                    msg = ws.receive_json()
                    with self._lock:
                        self.messages.append((time.monotonic(), msg))
        except BaseException as err:  # said by close()
            self._error = err
            self._ready.set()

    def close(self) -> None:
        self._stop.set()
        self._thread.join(10)

    def seen(self, kind: str) -> list[tuple[float, dict[str, Any]]]:
        with self._lock:
            return [(t, m) for t, m in self.messages if m.get("type") == kind]

    def wait(
        self, kind: str, match: Callable[[dict[str, Any]], bool], timeout_s: float = 10.0
    ) -> tuple[float, dict[str, Any]]:
        """The first message of ``kind`` that ``match``\\ es (waiting for it)."""
        deadline = time.monotonic() + timeout_s
        while True:
            for t, m in self.seen(kind):
                if match(m):
                    return t, m
            assert self._error is None, self._error
            if time.monotonic() > deadline:
                raise AssertionError(f"no {kind} message matching in {timeout_s} s")
            time.sleep(0.01)

    def command_states(self, command_id: int) -> list[tuple[float, str]]:
        """The states of command ``command_id`` this page was told, with their times."""
        return [
            (t, m["command"]["state"])
            for t, m in self.seen("command")
            if m["command"]["id"] == command_id
        ]


def act(client: TestClient, action: str, **body: Any) -> Any:
    """``POST /api/control`` with the token; the response."""
    return client.post("/api/control", json={"action": action, **body}, headers=AUTH)


def owner(client: TestClient) -> tuple[str | None, str | None]:
    """(console, operator) in control of the one vehicle, as ``client``'s console says."""
    r = client.get("/api/control")
    assert r.status_code == 200, r.text
    (view,) = r.json()
    return view["console"], view["operator"]
