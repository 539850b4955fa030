"""The rosbridge v2 ``auth`` op, sans-IO: how the training bridge takes frames only from its own
console.

The protocol's ``auth`` message carries ``mac``, ``client``, ``dest``, ``rand``, ``t``,
``level`` and ``end`` (ROSBRIDGE_PROTOCOL.md). The ROS 2 rosbridge_server dropped it (with
rosauth); the simulator's bridge takes it back only when it is given a secret, as the console's
training bridge is (a new one per start, shared with the console in memory). ``mac`` is the
HMAC-SHA256, keyed with that secret, of the other fields joined by ``|``; the message is good
from ``t`` to ``end`` (seconds of the server's clock). Until a client authenticates it may
subscribe and call services, but not publish: a local process cannot retask the training
vehicle behind the operator's back.
"""

from __future__ import annotations

import hashlib
import hmac
import secrets
import time
from collections.abc import Callable, Mapping
from typing import Any, Final

#: How long an ``auth`` message stays good (s).
AUTH_VALID_S: Final = 60.0
#: The fields the MAC covers, in order.
_FIELDS: Final = ("client", "dest", "rand", "t", "level", "end")


def auth_mac(secret: str, fields: Mapping[str, Any]) -> str:
    """The ``mac`` of an ``auth`` message with these fields."""
    text = "|".join(str(fields[name]) for name in _FIELDS)
    return hmac.new(secret.encode(), text.encode(), hashlib.sha256).hexdigest()


def auth_message(secret: str, client: str, dest: str, now_s: float) -> dict[str, Any]:
    """The ``auth`` message a client sends first (``now_s``: the wall clock, s)."""
    fields: dict[str, Any] = {
        "client": client,
        "dest": dest,
        "rand": secrets.token_hex(8),
        "t": round(now_s, 3),
        "level": "operator",
        "end": round(now_s + AUTH_VALID_S, 3),
    }
    return {"op": "auth", "mac": auth_mac(secret, fields), **fields}


def check_auth(secret: str, message: Mapping[str, Any], now_s: float) -> str | None:
    """``None`` when ``message`` authenticates with ``secret`` at ``now_s``, else why not."""
    if any(name not in message for name in (*_FIELDS, "mac")):
        return "auth needs mac, client, dest, rand, t, level and end"
    mac = message["mac"]
    if not isinstance(mac, str) or not hmac.compare_digest(mac, auth_mac(secret, message)):
        return "auth refused: wrong mac"
    t, end = message["t"], message["end"]
    numbers = all(isinstance(v, int | float) and not isinstance(v, bool) for v in (t, end))
    if not numbers or not t - 5.0 <= now_s <= end:
        return "auth refused: outside its validity (t .. end)"
    return None


class AuthGate:
    """One client's authentication with the bridge's ``secret``: refused publishes until a
    good ``auth`` message (``clock``: the wall clock, s)."""

    def __init__(self, secret: str, clock: Callable[[], float] = time.time) -> None:
        self._secret = secret
        self._clock = clock
        self.authenticated = False

    def take(self, message: Mapping[str, Any]) -> str | None:
        """An ``auth`` message: ``None`` when it authenticates the client, else why not."""
        problem = check_auth(self._secret, message, self._clock())
        self.authenticated = self.authenticated or problem is None
        return problem

    def refusal(self, topic: str) -> str | None:
        """Why a publish on ``topic`` is refused now (``None``: it is not)."""
        if self.authenticated:
            return None
        return (
            f"publish on {topic} refused: this training bridge takes messages only from its "
            "console (auth first)"
        )
