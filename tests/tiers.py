"""What puts a test in the slow tier besides its own marks (see ``tests/conftest.py``)."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, TypeVar

F = TypeVar("F", bound=Callable[..., Any])


def slow_fixture(func: F) -> F:
    """Mark a fixture that takes seconds to build (put it under ``@pytest.fixture``): every
    test that uses it is ``slow``, so ``make test-fast`` does not pay for it."""
    func.slow_fixture = True  # type: ignore[attr-defined]
    return func


def is_slow_fixture(func: object) -> bool:
    return getattr(func, "slow_fixture", False) is True
