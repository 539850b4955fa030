"""The console's fixtures (:mod:`tests.backend.conftest`) for the command line's tests, and
the mission log on both back-ends (``log_backend``; the same PostgreSQL server)."""

from tests.backend.conftest import client, log_backend, make_client, pg_server

__all__ = ["client", "log_backend", "make_client", "pg_server"]
