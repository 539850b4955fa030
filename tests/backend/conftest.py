"""Shared fixtures of the console tests: the light app (``client``: the console on an
in-memory vehicle link, ``tests/agent_link.py``), the whole training console (``client`` of a
test marked ``training``, and ``make_client``: the simulated vehicle at 50x behind its
rosbridge), the operator token, and polling helpers with deadlines (no fixed long sleeps).

A test takes the light app unless it needs the simulator (a vehicle that moves, its telemetry
stream, the training controls and datum) or a real transport.

The mission log's tests run on both back-ends through ``log_backend`` (a SQLite file, or a
fresh database on the worker's PostgreSQL server ``pg_server``: ``tests/pg_server.py``, one per
xdist worker, started at its first use; without PostgreSQL installed those tests fail saying
how to install it). Tests marked ``training`` or
using ``make_client`` are ``console`` tests (and so ``slow``: not in ``make test-fast``):
``tests/conftest.py``."""

from __future__ import annotations

import os
import time
from collections.abc import Callable, Iterator
from contextlib import ExitStack
from pathlib import Path
from typing import Any, Literal, Protocol, TypeVar

import pytest
from fastapi.testclient import TestClient

from backend.app import create_app
from backend.clock import SYSTEM_CLOCK, Clock
from backend.console import Console
from backend.mission_log.store import FINAL_STATES
from backend.settings import Settings
from codec import encode_frame
from tests.agent_link import TARGET, AgentLink
from tests.backend.log_backend import KINDS, LogBackend
from tests.manual_clock import ManualClock
from tests.pg_server import PgServer, PostgresMissing

TOKEN = "x" * 20
WRONG_TOKEN = "y" * 20
AUTH = {"Authorization": f"Bearer {TOKEN}"}
WRONG_AUTH = {"Authorization": f"Bearer {WRONG_TOKEN}"}
#: The simulator's speed-up in these tests (the maximum).
TIME_SCALE = 50.0

CIRCLE: dict[str, Any] = {"speed": 0.18, "depth": 3, "radius": 5, "direction": "cw"}
SQUARE: dict[str, Any] = {"speed": 0.18, "depth": 2, "side_span": 6, "direction": "cw"}
FINAL = tuple(sorted(FINAL_STATES))

T = TypeVar("T")


class MakeClient(Protocol):
    def __call__(self, *, viewer: bool = False, **overrides: Any) -> TestClient: ...


class MakeLightClient(Protocol):
    def __call__(
        self, link: AgentLink | None = None, *, clock: Clock = ..., **overrides: Any
    ) -> TestClient: ...


def clear_nemesys_env(monkeypatch: pytest.MonkeyPatch) -> None:
    """No NEMESYS_* variable of the caller's shell leaks into the settings under test."""
    for name in list(os.environ):
        if name.startswith("NEMESYS_"):
            monkeypatch.delenv(name)


def settings_for(db_path: Path, **overrides: Any) -> Settings:
    values: dict[str, Any] = {
        "token": TOKEN,
        "db_path": db_path,
        "viewer_port": 0,
        "sim_time_scale": TIME_SCALE,
        "allowed_hosts": ["testserver"],  # Starlette's TestClient's Host
        **overrides,
    }
    return Settings(**values)


#: This process's PostgreSQL server, once started: one for every conftest that takes
#: ``pg_server`` from here (tests/cli's too), stopped by the first of them at the session's end.
_PG_SERVER: list[PgServer] = []


@pytest.fixture(scope="session")
def pg_server() -> Iterator[PgServer]:
    """This worker's PostgreSQL server (a temporary directory, a free loopback port)."""
    if not _PG_SERVER:
        try:
            _PG_SERVER.append(PgServer())
        except PostgresMissing as err:
            pytest.fail(str(err), pytrace=False)
    yield _PG_SERVER[0]
    _PG_SERVER[0].stop()  # again by another conftest's: does nothing


@pytest.fixture
def shared_url(pg_server: PgServer) -> Iterator[str]:
    """A fresh database on this worker's PostgreSQL (dropped after), for consoles that share
    one mission log."""
    name = pg_server.new_database()
    yield pg_server.url(name)
    pg_server.drop_database(name)


@pytest.fixture(params=KINDS)
def log_backend(request: pytest.FixtureRequest, tmp_path: Path) -> Iterator[LogBackend]:
    """The mission log on SQLite, then on PostgreSQL (a fresh database, dropped after)."""
    if request.param == "sqlite":
        yield LogBackend("sqlite", tmp_path)
        return
    server: PgServer = request.getfixturevalue("pg_server")
    name = server.new_database()
    yield LogBackend("postgresql", tmp_path, server.url(name))
    server.drop_database(name)


@pytest.fixture
def pg_log(request: pytest.FixtureRequest, tmp_path: Path) -> Iterator[LogBackend]:
    """The mission log on PostgreSQL only, for what several consoles on one log do (a SQLite
    log has one console and one writer): a fresh database, dropped after."""
    server: PgServer = request.getfixturevalue("pg_server")
    name = server.new_database()
    yield LogBackend("postgresql", tmp_path, server.url(name))
    server.drop_database(name)


@pytest.fixture
def make_client(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Iterator[MakeClient]:
    """Build a started app (lifespan running) with test settings; stopped at teardown."""
    clear_nemesys_env(monkeypatch)
    stack = ExitStack()
    count = 0

    def make(*, viewer: bool = False, **overrides: Any) -> TestClient:
        nonlocal count
        count += 1
        overrides.setdefault("db_path", tmp_path / f"missions-{count}.sqlite3")
        settings = settings_for(**overrides)
        client = TestClient(create_app(settings, viewer=viewer))
        stack.enter_context(client)
        return client

    with stack:
        yield make


@pytest.fixture
def make_light_client(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Iterator[MakeLightClient]:
    """Build a started light app: the console (vehicle mode, no viewer) on ``link`` (default:
    a two-way :class:`AgentLink`), command delivery on ``clock``; stopped at teardown."""
    clear_nemesys_env(monkeypatch)
    stack = ExitStack()
    count = 0

    def make(
        link: AgentLink | None = None, *, clock: Clock = SYSTEM_CLOCK, **overrides: Any
    ) -> TestClient:
        nonlocal count
        count += 1
        overrides.setdefault("db_path", tmp_path / f"light-{count}.sqlite3")
        overrides.setdefault("target", TARGET)
        settings = settings_for(**overrides)
        app = create_app(settings, viewer=False, link=link or AgentLink(), clock=clock)
        client = TestClient(app)
        stack.enter_context(client)
        return client

    with stack:
        yield make


@pytest.fixture
def client(request: pytest.FixtureRequest, make_light_client: MakeLightClient) -> TestClient:
    """The light app: the console on an in-memory two-way vehicle link (the onboard agent of
    a vehicle holding still), no simulator. For a test marked ``training``: the console in
    training mode, the simulated vehicle at 50x."""
    if request.node.get_closest_marker("training") is not None:
        make: MakeClient = request.getfixturevalue("make_client")
        return make()
    return make_light_client()


def advance(client: TestClient, clock: ManualClock, seconds: float) -> None:
    """Move a started app's command clock ``seconds`` forward, on the app's event loop (every
    copy, repeat and timeout due on the way happens, in order)."""
    client.portal.call(clock.advance, seconds)  # type: ignore[union-attr]


def console_of(client: TestClient) -> Console:
    """The running console behind a started test client (call into it with
    ``client.portal.call``: it lives on the app's event loop)."""
    console: Console = client.app.state.console  # type: ignore[attr-defined]
    return console


def wait_until(
    probe: Callable[[], T | Literal[False] | None],
    timeout_s: float = 15.0,  # generous: a loaded 2-core machine
    interval_s: float = 0.02,
    what: str = "",
) -> T:
    """Poll ``probe`` until it returns something truthy (returned); fail at the deadline.
    ``False`` and ``None`` mean "not yet", so ``lambda: cond and value`` reads well."""
    deadline = time.monotonic() + timeout_s
    while True:
        value = probe()
        if value:
            return value
        if time.monotonic() > deadline:
            raise AssertionError(f"timed out after {timeout_s} s waiting for {what or probe}")
        time.sleep(interval_s)


def record(client: TestClient, command_id: int) -> dict[str, Any]:
    r = client.get(f"/api/commands/{command_id}")
    assert r.status_code == 200, r.text
    body: dict[str, Any] = r.json()
    return body


def wait_state(
    client: TestClient,
    command_id: int,
    states: tuple[str, ...] = FINAL,
    timeout_s: float = 15.0,
) -> dict[str, Any]:
    """The command's record once its state is one of ``states``."""

    def probe() -> dict[str, Any] | None:
        rec = record(client, command_id)
        return rec if rec["state"] in states else None

    return wait_until(probe, timeout_s, what=f"command {command_id} in {states}")


def send(
    client: TestClient, pattern: str = "circle", params: dict[str, Any] | None = None
) -> dict[str, Any]:
    """POST a command with the operator token; returns the 202 record."""
    r = client.post(
        "/api/commands",
        json={"pattern": pattern, "params": CIRCLE if params is None else params},
        headers=AUTH,
    )
    assert r.status_code == 202, r.text
    body: dict[str, Any] = r.json()
    return body


def loc_of(response_json: Any) -> list[Any]:
    """The ``loc`` of the first validation error of a 422 answer."""
    detail = response_json["detail"]
    assert isinstance(detail, list) and detail, response_json
    loc: list[Any] = detail[0]["loc"]
    return loc


def command_fields(pattern: str = "circle", **params: Any) -> dict[str, Any]:
    """A command record's fields as the console writes them (for the log's own tests)."""
    values = params if params or pattern != "circle" else CIRCLE
    enc = encode_frame(pattern, values)
    return {
        "operator": "operator",
        "target": "sim",
        "kind": "command",
        "pattern": enc.command.pattern.name,
        "pattern_id": enc.command.pattern.id,
        "params": dict(enc.command.params),
        "requested": dict(values),
        "bits": enc.frame.bits,
        "hex": enc.frame.hex,
    }
