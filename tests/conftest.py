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
"""

from __future__ import annotations

import pytest

from tests.tiers import is_slow_fixture

#: Fixtures that put a test in a marker's kind.
FIXTURE_MARKERS = {"browser": "browser", "make_client": "console"}
#: Kinds that are never in the fast tier.
NOT_FAST = ("browser", "console", "interop", "schemathesis")


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
