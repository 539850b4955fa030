"""The console's fixtures (:mod:`tests.backend.conftest`) for the station's tests that run one."""

from tests.backend.conftest import client, make_client

__all__ = ["client", "make_client"]
