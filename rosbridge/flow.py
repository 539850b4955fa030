"""Text in and out of a rosbridge session, sans-IO (the caller passes the time).

:class:`IncomingBuffer` splits what a client sends into JSON values the way the real server's
``Protocol.incoming`` does (a text that does not parse is kept and joined with the next one;
several objects in one text are taken one by one). :class:`MessageHandler` paces one
subscription as the real server's ``subscription_modifiers`` do (``throttle_rate``,
``queue_length``), and :class:`Subscription` holds one topic's (and its ``compression``);
:class:`Defragmenter` reassembles incoming ``fragment`` ops as its ``defragmentation``
capability does.
"""

from __future__ import annotations

import json
import math
from collections import deque
from dataclasses import dataclass, field
from typing import Any, Final

from rosbridge.compression import strongest
from rosbridge.errors import BridgeError, FragmentError
from rosbridge.messages import Fragment


class MessageHandler:
    """Pacing of one subscription, as the real ``subscription_modifiers``: with no queue a
    message goes out if ``throttle_rate`` ms have passed since the last one sent, otherwise
    it is dropped; with ``queue_length`` > 0 messages wait in a queue keeping the newest
    ``queue_length``, and the oldest goes out whenever ``throttle_rate`` ms have passed.
    It paces messages, not texts: a message is encoded when it goes out, as the real server
    applies the compression then."""

    def __init__(self) -> None:
        self.throttle_s = 0.0
        self.queue: deque[Any] | None = None
        self.last = -math.inf

    def configure(self, throttle_ms: int, queue_length: int) -> None:
        if queue_length < 0:
            raise ValueError("maxlen must be non-negative")
        self.throttle_s = throttle_ms / 1000.0
        self.queue = deque(self.queue or (), maxlen=queue_length) if queue_length else None

    def handle(self, message: Any, now: float) -> list[Any]:
        if self.queue is None:
            if now >= self.last + self.throttle_s:
                self.last = now
                return [message]
            return []
        self.queue.append(message)
        return self.poll(now)

    def poll(self, now: float) -> list[Any]:
        out: list[Any] = []
        while self.queue and now >= self.last + self.throttle_s:
            self.last = now
            out.append(self.queue.popleft())
            if self.throttle_s > 0:
                break
        return out


@dataclass(slots=True)
class Subscription:
    """One client's subscriptions to one topic: every id's (``throttle_rate`` ms,
    ``queue_length``, ``compression``), paced together by the smallest of each and
    compressed the strongest way any asked (as the real server)."""

    expanded: str
    type: str
    #: id -> (throttle_rate, queue_length, compression)
    options: dict[Any, tuple[int, int, str]] = field(default_factory=dict)
    handler: MessageHandler = field(default_factory=MessageHandler)
    compression: str = "none"

    def update(self) -> None:
        values = list(self.options.values())
        self.handler.configure(min(v[0] for v in values), min(v[1] for v in values))
        self.compression = strongest(v[2] for v in values)


@dataclass(slots=True)
class _Pending:
    total: Any
    parts: dict[Any, str]
    last: float
    size: int = 0


class Defragmenter:
    """Incoming fragments of one client, by message id, as the real server keeps them.

    A fragment is kept if its ``num`` is new and at most ``total``, and ``total`` is the
    message's; once as many parts as ``total`` are in, they are joined **in the order
    received** (as the real server does: send fragments in order) and the text is returned.
    Lists idle for ``timeout_s`` are forgotten when the next fragment arrives. Unlike the real
    server (one table for all clients, unbounded), each client has its own table and at most
    ``limit`` characters are kept per message.
    """

    def __init__(self, limit: int, timeout_s: float) -> None:
        self.limit = limit
        self.timeout_s = timeout_s
        self._pending: dict[Any, _Pending] = {}

    def add(self, fragment: Fragment, now: float) -> tuple[str | None, list[str]]:
        """``(the reassembled text or None, warnings)``; raises :class:`BridgeError` for a
        fragment the real server refuses (it logs an error)."""
        warnings: list[str] = []
        for key, pending in list(self._pending.items()):
            if now - pending.last > self.timeout_s and fragment.id != key:
                del self._pending[key]
                warnings.append(f"fragment list {key} timed out.. -> removing it..")
        if None in (fragment.id, fragment.num, fragment.total, fragment.data):
            raise BridgeError("received invalid fragment!")
        try:
            pending = self._pending.setdefault(fragment.id, _Pending(fragment.total, {}, now))
            fits = fragment.num not in pending.parts and fragment.num <= pending.total
        except TypeError as exc:
            raise BridgeError(f"fragment: {exc}", fragment.id) from None
        if not fits or fragment.total != pending.total or not isinstance(fragment.data, str):
            raise BridgeError(f"error while trying to append fragment {fragment.num}")
        pending.size += len(fragment.data)
        if pending.size > self.limit:
            del self._pending[fragment.id]
            raise FragmentError(
                f"fragments of message {fragment.id!r} exceed {self.limit} characters: dropped",
                fragment.id,
            )
        pending.parts[fragment.num] = fragment.data
        pending.last = now
        if len(pending.parts) != pending.total:
            return None, warnings
        if not isinstance(pending.total, int):
            raise BridgeError(
                f"fragment: '{type(pending.total).__name__}' object cannot be interpreted as "
                "an integer",
                fragment.id,
            )
        missing = [i for i in range(pending.total) if i not in pending.parts]
        if missing:
            raise BridgeError(
                f"fragment #{missing[0]} for messageID {fragment.id} is missing! ", fragment.id
            )
        del self._pending[fragment.id]
        return "".join(pending.parts.values()), warnings


#: Nothing could be taken from the buffer.
NOTHING: Final = object()


#: Longest leftover (unparsed text) kept to be joined with the next text, characters.
LEFTOVER_LIMIT: Final = 65536
#: ``{`` positions tried when searching a buffer for an object.
MAX_STARTS: Final = 64

_DECODER: Final = json.JSONDecoder()


class IncomingBuffer:
    """What a client sent, taken apart as the real server's ``Protocol.incoming`` does.

    A text is appended to whatever is left over. If the whole buffer is JSON it is one
    message. Otherwise the buffer is searched from each ``{`` for a JSON object; the first
    one with an ``op`` is taken together with everything before it (leading garbage is
    dropped that way) and the rest stays for the next call. Text with no object stays in the
    buffer, and is joined with the next text (a message split over two texts gets through).

    Two quirks of the real server are kept, because a client can tell: an object *without*
    an ``op`` found by the search is taken without removing anything from the buffer (so
    that garbage stays in front of every later text), and nothing at all is answered for
    text that is not JSON. Unlike the real server, a leftover is bounded (``limit``
    characters: beyond, it is dropped and the new text kept) and the search tries the first
    :data:`MAX_STARTS` braces only (the real one is quadratic in the number of braces).
    """

    def __init__(self, limit: int = LEFTOVER_LIMIT) -> None:
        self.limit = limit
        self.buffer = ""
        self._previous = ""
        self.overflowed = False

    def add(self, text: str) -> None:
        """Append a received text (to the leftover, if it is not too long)."""
        self.overflowed = bool(self.buffer) and len(self.buffer) + len(text) > self.limit
        self.buffer = text if self.overflowed else self.buffer + text

    def take(self) -> object:
        """The next JSON value, or :data:`NOTHING`."""
        if not self.buffer:
            return NOTHING
        try:
            value = json.loads(self.buffer)
        except (ValueError, RecursionError):
            pass
        else:
            self.buffer = ""
            return value
        start = self.buffer.find("{")
        for _ in range(MAX_STARTS):
            if start < 0:
                break
            try:
                # The shortest slice from this brace that parses is the object raw_decode
                # reads (an object is self-delimiting): what the real server's search finds.
                value, end = _DECODER.raw_decode(self.buffer, start)
            except (ValueError, RecursionError):
                start = self.buffer.find("{", start + 1)
                continue
            if isinstance(value, dict) and value.get("op") is not None:
                self.buffer = self.buffer[end:]
            return value
        return NOTHING

    def more(self) -> bool:
        """After a message was handled: is there a new leftover to look at now? (The real
        server looks again only when the leftover changed since it last looked.)"""
        if self.buffer and self.buffer != self._previous:
            self._previous = self.buffer
            return True
        return False
