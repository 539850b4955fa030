"""The test tiers (markers registered in pyproject.toml).

``make test-fast`` runs ``pytest -m "not slow"``: unit tests and API tests on the light app,
no browser, no third-party interop client, no fuzzer, no whole console. ``slow`` is added here
to every test of those kinds, so a test names only what it is:

* ``browser``: uses the ``browser`` fixture (Chromium; ``tests/frontend``), added here;
* ``console``: starts a whole console in process (``make_client``: the training simulator
  behind its rosbridge, or a real transport), added here, as to every ``training`` test (its
  ``client`` is the training console: ``tests/backend/conftest.py``);
* ``interop``, ``schemathesis``: marked in their modules;
* ``slow``: marked on the test itself (a subprocess console, a benchmark run, real time),
  or added here to every test using a fixture marked by :func:`tests.tiers.slow_fixture`.

A test outside the slow tier that took more than :data:`FAST_TEST_BUDGET_S` is named at the
end of the run (a warning, not a failure: a loaded machine slows everything), so the fast tier
stays fast as tests are added.

``--vehicle-side`` collects only the vehicle side's tests (``tests/vehicle_side.py``), as
``make test-vehicle`` runs them on Python 3.10 and 3.12.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.tiers import is_slow_fixture
from tests.vehicle_side import is_vehicle_side

#: Fixtures that put a test in a marker's kind.
FIXTURE_MARKERS = {"browser": "browser", "make_client": "console"}
#: Kinds that are never in the fast tier.
NOT_FAST = ("browser", "console", "interop", "schemathesis")
#: Setup, call and teardown of a fast-tier test together (s).
FAST_TEST_BUDGET_S = 1.0
#: Seconds each fast-tier test took so far (setup + call + teardown), by node id.
_fast_times: dict[str, float] = {}


def pytest_addoption(parser: pytest.Parser) -> None:
    parser.addoption(
        "--vehicle-side",
        action="store_true",
        help="collect only the vehicle side's tests, as `make test-vehicle` runs them on "
        "Python 3.10 and 3.12 (tests/vehicle_side.py)",
    )


def pytest_ignore_collect(collection_path: Path, config: pytest.Config) -> bool | None:
    if config.getoption("vehicle_side") and not is_vehicle_side(collection_path):
        return True
    return None  # pytest's own rules (--ignore, norecursedirs) decide


def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    for item in items:
        names = getattr(item, "fixturenames", ())
        for fixture, marker in FIXTURE_MARKERS.items():
            if fixture in names:
                item.add_marker(marker)
        if item.get_closest_marker("training") is not None:
            item.add_marker("console")
        info = getattr(item, "_fixtureinfo", None)
        defs = info.name2fixturedefs.values() if info is not None else ()
        if any(is_slow_fixture(d.func) for chain in defs for d in chain):
            item.add_marker("slow")
        if any(item.get_closest_marker(kind) for kind in NOT_FAST):
            item.add_marker("slow")
    _longest_files_first(items)


#: The kinds of test whose files take longest, in that order (browser files run for minutes).
_LONG_KINDS = ("browser", "console", "slow")


def _longest_files_first(items: list[pytest.Item]) -> None:
    """Files of browser tests first, then of whole consoles, then the other slow ones, then
    the rest, each file kept whole and in its own order: the workers of ``make test``
    (xdist, one file at a time) start the long files early and end on short ones."""

    def rank(item: pytest.Item) -> int:
        kinds = [i for i, kind in enumerate(_LONG_KINDS) if item.get_closest_marker(kind)]
        return min(kinds, default=len(_LONG_KINDS))

    by_file: dict[str, int] = {}
    for item in items:
        path = str(item.path)
        by_file[path] = min(by_file.get(path, len(_LONG_KINDS)), rank(item))
    items.sort(key=lambda item: by_file[str(item.path)])


def pytest_runtest_logreport(report: pytest.TestReport) -> None:
    if "slow" not in report.keywords:
        _fast_times[report.nodeid] = _fast_times.get(report.nodeid, 0.0) + report.duration


def pytest_terminal_summary(terminalreporter: pytest.TerminalReporter) -> None:
    over = sorted(
        ((t, nodeid) for nodeid, t in _fast_times.items() if t > FAST_TEST_BUDGET_S),
        reverse=True,
    )
    if over:
        terminalreporter.section("fast-tier tests over budget")
        terminalreporter.write_line(
            f"{len(over)} tests not marked slow took more than {FAST_TEST_BUDGET_S:g} s: mark "
            "them @pytest.mark.slow, or make them faster (tests/conftest.py)"
        )
        for t, nodeid in over:
            terminalreporter.write_line(f"{t:6.2f} s  {nodeid}")
