"""Schemathesis against a live console: the real ``nemesys console`` (uvicorn, the simulated
vehicle, a temporary mission log) fuzzed over loopback from its own ``/openapi.json``, once with
the operator token and once without.

Every phase of a schemathesis run (probing, coverage, fuzzing, stateful) runs on every operation
of the document (nothing is excluded; ``/ws`` is not in it), bounded to ``MAX_EXAMPLES`` examples
an operation and seeded (``SEED``, derandomized, no example database, no cache of earlier runs):
the run repeats itself, but for what the live simulator answers differently from one run to the
next. The checks:

* ``not_a_server_error``: no 5xx;
* ``status_code_conformance``: every status is documented for its operation;
* ``response_schema_conformance``: every body validates against its documented schema;
* ``content_type_conformance``: every body has a documented media type.

The test fails on any failure of those, on any error schemathesis reports (a request it could
not make, an operation it could not test), on any operation left untested, and on any exception
in the console's log; it prints a summary (requests, statuses, failures by check, time): run
with ``-s`` or ``-rP`` to see it when it passes.

With the token the fuzzer does real operator actions against the simulator (sends, Surface,
retries, resets, scenarios, script runs, the link and training settings): on a temporary
database, on loopback. Rate limiting (429) is a documented answer; the Host header is the
loopback one schemathesis takes from the URL, so the Host guard lets every request in.
"""

from __future__ import annotations

import time
from collections import Counter
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import pytest
import schemathesis
from schemathesis import Case, HookContext, Response
from schemathesis.config import SchemathesisConfig
from schemathesis.engine import StopReason, events, from_schema
from schemathesis.engine.recorder import CheckFailureInfo

from bench._server import ConsoleProcess, start_console
from tests.backend.conftest import TOKEN, clear_nemesys_env

#: The fuzzer against a live console (~30 s): make test, not make test-fast.
pytestmark = pytest.mark.schemathesis

#: Examples an operation (each phase); the whole test (both runs) takes about 25 s here.
MAX_EXAMPLES = 25
SEED = 20260513
CHECKS = (
    "not_a_server_error",
    "status_code_conformance",
    "response_schema_conformance",
    "content_type_conformance",
)
#: A request that takes longer is an error of the run (the console answers in milliseconds).
REQUEST_TIMEOUT_S = 10
#: Failures described in full in the assertion message.
SHOWN = 10
LOOPBACK = {"NO_PROXY": "127.0.0.1,localhost", "no_proxy": "127.0.0.1,localhost"}


@dataclass
class Tally:
    """What a schemathesis run did: every response by status and operation, every failed
    check, every error; and its time."""

    responses: Counter[int] = field(default_factory=Counter)
    by_operation: dict[str, Counter[int]] = field(default_factory=dict)
    failures: Counter[str] = field(default_factory=Counter)
    described: list[str] = field(default_factory=list)
    errors: list[str] = field(default_factory=list)
    stop_reason: StopReason | None = None
    elapsed_s: float = 0.0

    @property
    def requests(self) -> int:
        return sum(self.responses.values())

    @property
    def server_errors(self) -> int:
        return sum(n for status, n in self.responses.items() if status >= 500)

    def count(self, _context: HookContext, case: Case[Any], response: Response) -> None:
        """``after_call``: every answered request, whatever the phase."""
        self.responses[response.status_code] += 1
        self.by_operation.setdefault(case.operation.label, Counter())[response.status_code] += 1

    def failure(self, label: str, name: str, info: CheckFailureInfo) -> None:
        self.failures[name] += 1
        if len(self.described) < SHOWN:
            failure = info.failure
            self.described.append(
                f"{label}: {name}: {failure.title}: {failure.message}\n    {info.code_sample}"
            )

    def summary(self, who: str) -> str:
        statuses = " ".join(f"{s}: {n}" for s, n in sorted(self.responses.items()))
        failed = ", ".join(f"{name}: {self.failures[name]}" for name in CHECKS)
        return (
            f"schemathesis {who}: {self.requests} requests on {len(self.by_operation)} "
            f"operations in {self.elapsed_s:.1f} s ({self.stop_reason}); "
            f"5xx: {self.server_errors}; statuses {statuses}; "
            f"failures by check: {failed}; errors: {len(self.errors)}"
        )


def config(token: str | None) -> SchemathesisConfig:
    """The run: every phase, the four checks only, bounded and seeded."""
    data: dict[str, Any] = {
        "seed": SEED,
        "workers": 1,
        "request-timeout": REQUEST_TIMEOUT_S,
        # no cache of earlier runs (it replays their requests): every run starts afresh
        "cache": {"enabled": False},
        "generation": {"max-examples": MAX_EXAMPLES, "deterministic": True, "database": "none"},
        "checks": {"enabled": False, **{name: {"enabled": True} for name in CHECKS}},
    }
    if token is not None:
        data["headers"] = {"Authorization": f"Bearer {token}"}
    return SchemathesisConfig.from_dict(data)


def fuzz(console: ConsoleProcess, token: str | None) -> Tally:
    """Run schemathesis (``schemathesis.engine``, as ``st run`` does) on the console."""
    schema = schemathesis.openapi.from_url(f"{console.base_url}/openapi.json", config=config(token))
    tally = Tally()
    schema.hooks.register_hook_with_name(tally.count, "after_call")
    start = time.monotonic()
    for event in from_schema(schema).execute():
        if isinstance(event, events.ScenarioFinished):
            recorder = event.recorder
            for checks in recorder.checks.values():
                for check in checks:
                    if check.failure_info is not None:
                        tally.failure(recorder.label, check.name, check.failure_info)
        elif isinstance(event, events.NonFatalError):
            tally.errors.append(f"{event.label}: {event.info.title}: {event.info.message}")
        elif isinstance(event, events.FatalError):
            tally.errors.append(f"fatal: {event.exception!r}")
        elif isinstance(event, events.EngineFinished):
            tally.stop_reason = event.stop_reason
            for failure in event.failures:
                tally.failures["after the run"] += 1
                tally.described.append(f"after the run: {failure.title}: {failure.message}")
    tally.elapsed_s = time.monotonic() - start
    return tally


@pytest.fixture
def console(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Iterator[ConsoleProcess]:
    """``nemesys console`` in training mode on a temporary mission log; no proxy for loopback
    (schemathesis's requests read the environment)."""
    clear_nemesys_env(monkeypatch)
    for name, value in LOOPBACK.items():
        monkeypatch.setenv(name, value)
    with start_console(
        tmp_path / "console.log", TOKEN, "--db", str(tmp_path / "missions.sqlite3"), env=LOOPBACK
    ) as proc:
        yield proc


@pytest.mark.parametrize("with_token", [True, False], ids=["with-token", "without-token"])
def test_schemathesis_finds_nothing(console: ConsoleProcess, with_token: bool) -> None:
    """No server error, undocumented status, body outside its schema or undocumented media
    type on any operation, with the operator token and without."""
    token = console.token if with_token else None
    tally = fuzz(console, token)
    who = "with the token" if with_token else "without the token"
    summary = tally.summary(who)
    print(summary)

    with console.client() as http:
        spec = http.get("/openapi.json").json()
    operations = {
        f"{method.upper()} {path}": op
        for path, ops in spec["paths"].items()
        for method, op in ops.items()
    }
    detail = "\n".join([summary, *tally.described, *tally.errors])
    assert tally.stop_reason == StopReason.COMPLETED, detail
    assert not tally.errors, detail
    assert not tally.failures and tally.server_errors == 0, detail
    assert set(tally.by_operation) == set(operations), f"untested: {detail}"
    assert "Traceback" not in console.log_tail(lines=100_000), console.log_tail(lines=60)

    # the token is what opens the operator's operations: never without it, and with it they act
    locked = {label for label, op in operations.items() if "security" in op}
    opened = {label for label in locked if any(200 <= s < 300 for s in tally.by_operation[label])}
    if with_token:
        assert {"POST /api/surface", "POST /api/training/reset", "PUT /api/link"} <= opened
    else:
        assert not opened, opened
        for label in locked:  # (a body that is not JSON at all is a 422 before the token)
            assert {401, 403} & set(tally.by_operation[label]), label
