"""Waiting, before a one-shot publish, until the vehicle subscribes to the topic (sans-IO).

On a real rosbridge_server a client's ``advertise`` creates a new ROS publisher; a vehicle
subscriber that DDS has not matched to it yet misses what is published at once (ros2/ros2#698;
``docs/vehicle.md``). So a one-shot sender asks rosapi who subscribes to the topic
(``/rosapi/subscribers``, args ``{"topic": ...}``, answer ``{"subscribers": [node names]}``)
and publishes as soon as the list is not empty, asking again every :data:`POLL_S` while it is.
When rosapi cannot tell (the service fails, or does not answer), it waits out the bound after
advertising. If rosapi keeps saying nobody subscribes, the bound ends the wait too and the
sender publishes anyway, with :attr:`SubscriberWait.warning` set.

:class:`SubscriberWait` makes the requests and reads the answers; the transport (sync or
asyncio) sends them and decides how long to block from :meth:`SubscriberWait.timeout_s`.
Times are ``time.monotonic()`` seconds.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any, Final

from rosbridge.client import ClientProtocol

#: The rosapi service listing a topic's subscribers (``rosapi_msgs/srv/Subscribers``).
SUBSCRIBERS_SERVICE: Final = "/rosapi/subscribers"
#: How long a one-shot sender waits for the subscriber after advertising, by default (s).
DEFAULT_SUBSCRIBER_WAIT_S: Final = 1.0
#: How often it asks again while the answer is "nobody" (s).
POLL_S: Final = 0.1


def subscribers_of(values: object) -> list[str] | None:
    """The node names in a ``/rosapi/subscribers`` answer; None if it holds no such list."""
    subscribers = values.get("subscribers") if isinstance(values, Mapping) else None
    if not isinstance(subscribers, list) or not all(isinstance(s, str) for s in subscribers):
        return None
    return list(subscribers)


class SubscriberWait:
    """One wait for a subscriber to ``topic``, at most ``bound_s`` from ``now_s``."""

    def __init__(
        self,
        protocol: ClientProtocol,
        topic: str,
        bound_s: float,
        now_s: float,
        poll_s: float = POLL_S,
    ) -> None:
        self.topic = topic
        self.bound_s = bound_s
        self.deadline_s = now_s + bound_s
        self.poll_s = poll_s
        #: The last answer: the subscribers' node names (None: no usable answer yet).
        self.subscribers: list[str] | None = None
        #: Why rosapi cannot tell (the service failed or answered something else).
        self.cannot_tell: str | None = None
        self._protocol = protocol
        self._id: str | None = None
        self._ask_at_s: float | None = now_s

    @property
    def present(self) -> bool:
        return bool(self.subscribers)

    def done(self, now_s: float) -> bool:
        return self.present or now_s >= self.deadline_s

    def ask(self, now_s: float) -> str | None:
        """The request to send now, if it is time to ask (at once, then after each "nobody")."""
        if self._ask_at_s is None or now_s < self._ask_at_s or self.done(now_s):
            return None
        self._ask_at_s = None  # again only once this one is answered
        self._id, text = self._protocol.call_service(SUBSCRIBERS_SERVICE, {"topic": self.topic})
        return text

    def offer(self, message: Mapping[str, Any], now_s: float) -> bool:
        """Take a server message; True when it was the answer to the pending request."""
        if (
            self._id is None
            or message.get("op") != "service_response"
            or message.get("id") != self._id
        ):
            return False
        self._id = None
        values = message.get("values")
        if message.get("result") is False:
            self.cannot_tell = f"{SUBSCRIBERS_SERVICE} failed: {str(values)[:120]}"
            return True
        subscribers = subscribers_of(values)
        if subscribers is None:
            self.cannot_tell = f"{SUBSCRIBERS_SERVICE} answered without a list: {values!r:.120}"
            return True
        self.subscribers = subscribers
        if not subscribers:
            self._ask_at_s = now_s + self.poll_s
        return True

    def timeout_s(self, now_s: float) -> float:
        """How long to wait for a message before calling :meth:`ask` again (>= 0)."""
        until = self.deadline_s
        if self._ask_at_s is not None:
            until = min(until, self._ask_at_s)
        return max(0.0, until - now_s)

    @property
    def warning(self) -> str | None:
        """Set when rosapi kept saying nobody subscribes until the bound: the frame went out
        anyway and may be lost."""
        if self.present or self.cannot_tell is not None or self.subscribers is None:
            return None
        return f"no subscriber to {self.topic} after {self.bound_s:g} s: the frame may be lost"

    @property
    def note(self) -> str | None:
        """What the wait found, when it was not a subscriber (None when it was)."""
        if self.present:
            return None
        if self.warning is not None:
            return self.warning
        why = self.cannot_tell or f"no answer from {SUBSCRIBERS_SERVICE}"
        return f"{why}: published {self.bound_s:g} s after advertising {self.topic}"
