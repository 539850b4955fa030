"""A console app on a real uvicorn server in this process (a thread), on a free loopback
port: keep-alive connections, uvicorn's own logging (access lines, its formatters) and the
app's records all observable from the test, which a subprocess would hide."""

from __future__ import annotations

import logging
import socket
import threading
from collections.abc import Iterator
from contextlib import contextmanager

import httpx
import uvicorn
from fastapi import FastAPI

from .conftest import wait_until

#: The loggers uvicorn's configuration sets a level on (restored when the server stops).
UVICORN_LOGGERS = ("uvicorn", "uvicorn.error", "uvicorn.access", "uvicorn.asgi")


@contextmanager
def serve(app: FastAPI, *, log_level: str = "warning") -> Iterator[str]:
    """Run ``app`` under uvicorn until the block ends; yields its base URL."""
    levels = {name: logging.getLogger(name).level for name in UVICORN_LOGGERS}
    sock = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
    sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
    sock.bind(("127.0.0.1", 0))
    port = sock.getsockname()[1]
    config = uvicorn.Config(app, log_level=log_level, ws="websockets-sansio")
    server = uvicorn.Server(config)
    thread = threading.Thread(target=server.run, kwargs={"sockets": [sock]}, daemon=True)
    thread.start()
    try:
        wait_until(lambda: server.started or not thread.is_alive(), 60.0, what="uvicorn")
        assert server.started, "uvicorn did not start (the error is in the output above)"
        yield f"http://127.0.0.1:{port}"
    finally:
        server.should_exit = True
        thread.join(timeout=30)
        sock.close()
        for name, level in levels.items():
            logging.getLogger(name).setLevel(level)


def client_port(response: httpx.Response) -> int:
    """The local port of the connection that carried ``response``: equal for two responses
    when the second came on the same keep-alive connection."""
    address = response.extensions["network_stream"].get_extra_info("client_addr")
    port: int = address[1]
    return port
