"""The bridge server's log, as the real ``rosbridge_websocket`` node keeps it: every line a
session writes (:class:`~rosbridge.messages.LogLine`) and every connection change goes to the
Python log (``rosbridge.server``) and, INFO and up, to ``/rosout`` as an
``rcl_interfaces/msg/Log`` of the node :data:`~rosbridge.graph.BRIDGE_NODE`. That is where a
client learns what went wrong: nothing is sent back to it for a failed message.
"""

from __future__ import annotations

import logging
from collections.abc import Callable, Iterable
from typing import Final

from rosbridge.errors import JsonObject
from rosbridge.graph import BRIDGE_NODE, ROSOUT_TOPIC
from rosbridge.messages import LogLine
from rosbridge.wire import LOG_INFO, log_msg

logger = logging.getLogger("rosbridge.server")

#: rcl log levels -> Python's.
_LEVELS: Final = {20: logging.INFO, 30: logging.WARNING, 40: logging.ERROR}


class BridgeLog:
    """Writes the server's log lines; ``publish(topic, msg)`` puts a message on a topic for
    every subscriber, ``ros_time()`` stamps it."""

    def __init__(
        self, publish: Callable[[str, JsonObject], None], ros_time: Callable[[], float]
    ) -> None:
        self._publish = publish
        self._ros_time = ros_time
        self._in_rosout = False

    def lines(self, client: str, client_id: str, lines: Iterable[LogLine]) -> None:
        """A session's lines (``client``: its name in the Python log, ``client_id``: its
        session id, as the real server names clients on ``/rosout``)."""
        for line in lines:
            tag = f"[id: {line.op_id}] " if line.op_id is not None else ""
            level = _LEVELS.get(line.level, logging.INFO)
            logger.log(level, "client %s: %s%s", client, tag, line.text)
            self.rosout(line.level, f"[Client {client_id}] {tag}{line.text}")

    def node(self, client: str, text: str) -> None:
        """A line of the node's own about a client (connected, disconnected)."""
        logger.info("client %s: %s", client, text)
        self.rosout(LOG_INFO, text)

    def rosout(self, level: int, text: str) -> None:
        """Publish a log line on /rosout, as the real node's logger does (INFO and up). A line
        written while publishing one (a /rosout subscriber's own failure) is not published."""
        if self._in_rosout:
            return
        self._in_rosout = True
        try:
            msg = log_msg(self._ros_time(), level, BRIDGE_NODE.lstrip("/"), text)
            self._publish(ROSOUT_TOPIC, msg)
        finally:
            self._in_rosout = False
