"""Fixtures of the codec tests (helpers that are plain functions live in ``helpers.py``)."""

from __future__ import annotations

import random

import pytest


@pytest.fixture
def rng(request: pytest.FixtureRequest) -> random.Random:
    """A random stream seeded by the test's node id: different per test, same on every run."""
    return random.Random(request.node.nodeid)
