"""The console's fixtures (:mod:`tests.backend.conftest`) for the command line's tests."""

from tests.backend.conftest import client, make_client

__all__ = ["client", "make_client"]
