"""Which of the vehicle's acknowledgements the console's link has delivered already.

An acknowledgement can reach the link more than once: a transient-local replay of
``/nemesys/mission`` on a new subscription, and the status's ``recent_acks`` (the vehicle
contract: its last acknowledgements, as published, so that one published while the console
reconnected is not lost). :class:`SeenAcks` tells a new one from a repeat by the vehicle's
``seq`` and ``t_s`` (:func:`ack_key`), over every connection of the link.
"""

from __future__ import annotations

from collections import deque
from typing import Any, Final

#: Acknowledgements remembered to drop one delivered again (recent_acks, a replay).
SEEN_ACKS: Final = 256


def ack_key(ack: dict[str, Any]) -> str | None:
    """What tells an acknowledgement apart from a repeat of it: the vehicle's ``seq`` and
    ``t_s`` (with its frame and outcome); None when it has no integer seq and numeric t_s."""
    seq, t_s = ack.get("seq"), ack.get("t_s")
    if not isinstance(seq, int) or isinstance(seq, bool) or not isinstance(t_s, int | float):
        return None
    return repr((seq, t_s, ack.get("frame_hex"), ack.get("outcome")))


class SeenAcks:
    """The acknowledgements delivered (their :func:`ack_key`), the newest ``size``."""

    def __init__(self, size: int = SEEN_ACKS) -> None:
        self._seen: deque[str] = deque(maxlen=size)
        #: A status's recent_acks was read once (the first predates the console).
        self._primed = False

    def first(self, ack: dict[str, Any]) -> bool:
        """Whether ``ack`` is to be delivered (noted as delivered now): not when it went
        already. One without a key (:func:`ack_key`) cannot be told from a repeat: it goes."""
        key = ack_key(ack)
        if key is None:
            return True
        if key in self._seen:
            return False
        self._seen.append(key)
        return True

    def missed(self, recent: list[Any]) -> list[dict[str, Any]]:
        """Of a status's ``recent_acks`` (oldest first), those not delivered, to go now
        through :meth:`first`. Those in the first status read predate the console: they are
        only noted. Entries without a key are left out (a repeat could not be told)."""
        acks = [a for a in recent if isinstance(a, dict) and ack_key(a) is not None]
        if not self._primed:
            self._primed = True
            self._seen.extend(key for a in acks if (key := ack_key(a)) is not None)
            return []
        return [a for a in acks if ack_key(a) not in self._seen]
