"""The tests' PostgreSQL server (:mod:`tests.backend.conftest`'s ``pg_server``, one per
worker) for the benchmarks that need one (``control_sync``, ``relay``)."""

from tests.backend.conftest import pg_server

__all__ = ["pg_server"]
