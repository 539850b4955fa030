"""Waiting, before a one-shot publish, until the vehicle subscribes to the topic (sans-IO).

On a real rosbridge_server a client's ``advertise`` creates a new ROS publisher; a vehicle
subscriber that DDS has not matched to it yet misses what is published at once (ros2/ros2#698;
``docs/vehicle.md``). So a one-shot sender asks rosapi who subscribes to the topic
(``/rosapi/subscribers``, args ``{"topic": ...}``, answer ``{"subscribers": [node names]}``)
and publishes as soon as it lists a node other than the bridge's own (a client's subscription
makes the bridge a subscriber: :mod:`rosbridge.bridge_node`), asking again every
:data:`POLL_S` while it does not.
When rosapi cannot tell (the service fails, or does not answer), it waits out the bound after
advertising. If rosapi keeps saying nobody subscribes, the bound ends the wait too and the
sender publishes anyway, with :attr:`SubscriberWait.warning` set.

:class:`SubscriberWait` says when to ask and reads the answers; the transport
(:mod:`rosbridge.transport`) asks and decides how long to wait from
:meth:`SubscriberWait.timeout_s`. Times are ``time.monotonic()`` seconds.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any, Final

from rosbridge.bridge_node import node_names, others

#: The rosapi service listing a topic's subscribers (``rosapi_msgs/srv/Subscribers``).
SUBSCRIBERS_SERVICE: Final = "/rosapi/subscribers"
#: How long a one-shot sender waits for the subscriber after advertising, by default (s).
DEFAULT_SUBSCRIBER_WAIT_S: Final = 1.0
#: How often it asks again while the answer is "nobody" (s).
POLL_S: Final = 0.1


def subscribers_of(values: object) -> list[str] | None:
    """The node names in a ``/rosapi/subscribers`` answer; None if it holds no such list."""
    return node_names(values, "subscribers")


class SubscriberWait:
    """One wait for a subscriber to ``topic``, at most ``bound_s`` from ``now_s``."""

    def __init__(self, topic: str, bound_s: float, now_s: float, poll_s: float = POLL_S) -> None:
        self.topic = topic
        self.bound_s = bound_s
        self.deadline_s = now_s + bound_s
        self.poll_s = poll_s
        #: The last answer: the subscribers' node names (None: no usable answer yet).
        self.subscribers: list[str] | None = None
        #: Why rosapi cannot tell (the service failed or answered something else).
        self.cannot_tell: str | None = None
        self._ask_at_s: float | None = now_s

    @property
    def present(self) -> bool:
        """A node other than the bridge subscribes (the bridge only relays to its clients)."""
        return bool(others(self.subscribers or ()))

    @property
    def request(self) -> tuple[str, dict[str, str]]:
        """The service to call and its args."""
        return SUBSCRIBERS_SERVICE, {"topic": self.topic}

    def done(self, now_s: float) -> bool:
        return self.present or now_s >= self.deadline_s

    def ask(self, now_s: float) -> bool:
        """Whether to send :attr:`request` now (at once, then after each "nobody"); its answer
        goes to :meth:`answer`, waited for at most :meth:`timeout_s`."""
        if self._ask_at_s is None or now_s < self._ask_at_s or self.done(now_s):
            return False
        self._ask_at_s = None  # again only once this one is answered
        return True

    def answer(self, message: Mapping[str, Any] | None, now_s: float) -> None:
        """The ``service_response`` to the request; ``None``: none came (the wait then runs to
        its bound)."""
        if message is None:
            return
        values = message.get("values")
        if message.get("result") is False:
            self.cannot_tell = f"{SUBSCRIBERS_SERVICE} failed: {str(values)[:120]}"
            return
        subscribers = subscribers_of(values)
        if subscribers is None:
            self.cannot_tell = f"{SUBSCRIBERS_SERVICE} answered without a list: {values!r:.120}"
            return
        self.subscribers = subscribers
        if not self.present:
            self._ask_at_s = now_s + self.poll_s

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
