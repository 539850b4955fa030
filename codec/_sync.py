"""Incremental frame synchronisation: a sans-IO receiver for a continuous bit stream.

Feed it bits or bytes in any chunking; it returns :class:`Accepted` and :class:`Rejected`
events. It looks for the 24-bit sync word (preamble + delimiter) at every bit offset,
tolerating up to ``sync_tolerance`` wrong bits. Because the preamble alternates, a copy of the
sync word shifted by an even number of bits also comes close; the delimiter keeps every such
shift at least 4 bits away, and the receiver, on a candidate, takes the best-matching offset
among the next :data:`_LOOKAHEAD` bits before decoding. A candidate that then fails to decode
is reported as :class:`Rejected` and the search resumes one bit later, so a false sync in
noise never swallows the real frame that follows it. After an accepted frame the search
resumes right after its codeword (the guard bits are not needed).

The common case, a frame delivered as bytes whose first byte starts the preamble (a modem's
13 bytes), takes a straight line instead (:mod:`codec._fastpath`): sync, BCH, CRC and
dictionary checks by table on the bytes as they are. It only accepts; anything else (sync
beyond the tolerance or at another bit offset, an uncorrectable word, a failed check) goes
through the bit-level path, so both report the same events at the same offsets
(``fast_path=False`` forces the bit-level path; the tests compare the two).
"""

from __future__ import annotations

from codec._dictionary import DICTIONARY, CommandDictionary
from codec._errors import DecodeError, RejectReason
from codec._fastpath import ALIGNED_BYTES, LOOKAHEAD, SHIFT_DISTANCE, straight_line
from codec._frame import (
    CODEWORD_BITS,
    DEFAULT_SYNC_TOLERANCE,
    FRAME_BYTES,
    SYNC_BITS,
    SYNC_WORD,
    Decoded,
    decode_codeword,
)
from codec._record import Record, init, slot_setters

TYPE_CHECKING = False
if TYPE_CHECKING:
    from collections.abc import Iterable

_SYNC_MASK = (1 << SYNC_BITS) - 1
_CODEWORD_MASK = (1 << CODEWORD_BITS) - 1
#: Header + codeword: what must have arrived before a candidate can be decoded.
_NEEDED = SYNC_BITS + CODEWORD_BITS
#: Offsets after a candidate also compared, to pick the best-aligned one (the delimiter span).
_LOOKAHEAD = LOOKAHEAD
#: Fewest pending bits the scan decides on (a sync word and its look-ahead).
_DECIDE = SYNC_BITS + _LOOKAHEAD
#: Longest piece of input scanned at once (see ``_feed``).
_SLICE_BITS = 1024


class Accepted(Record):
    """A frame decoded and checked; ``offset`` is the stream index of its first bit."""

    __slots__ = ("decoded", "offset")
    offset: int
    decoded: Decoded

    def __init__(self, offset: int, decoded: Decoded) -> None:
        init(self, "offset", offset)
        init(self, "decoded", decoded)


class Rejected(Record):
    """A sync word was found at ``offset`` but the frame failed a check (``error.reason``)."""

    __slots__ = ("error", "offset")
    offset: int
    error: DecodeError

    def __init__(self, offset: int, error: DecodeError) -> None:
        init(self, "offset", offset)
        init(self, "error", error)


Event = Accepted | Rejected

_new = object.__new__
_set_offset, _set_decoded = slot_setters(Accepted, "offset", "decoded")


def receive_frame(data: bytes | bytearray | memoryview) -> list[Event]:
    """The events a new :class:`FrameReceiver` (default tolerance and dictionary) reports for
    ``data`` fed at once: what the onboard agent runs for each received frame.

    A modem's 13 bytes that take the straight line need no receiver (its construction and
    state are a fifth of the decode's time); everything else goes through one, so the events
    are exactly ``FrameReceiver().feed_bytes(data)``'s (``tests/codec/test_sync.py``).
    """
    raw = data if type(data) is bytes else bytes(data)
    if len(raw) == FRAME_BYTES:
        decoded = (DICTIONARY.straight_line or straight_line(DICTIONARY))(
            raw, DEFAULT_SYNC_TOLERANCE
        )
        if decoded is not None:
            event = _new(Accepted)
            _set_offset(event, 0)
            _set_decoded(event, decoded)
            return [event]
        # Declined: where a new receiver goes next, without trying the straight line again.
        return FrameReceiver(fast_path=False).feed_bytes(raw)
    return FrameReceiver().feed_bytes(raw)


class FrameReceiver:
    """Finds, decodes and checks frames in a bit stream. No I/O, no threads.

    Args:
        sync_tolerance: wrong bits allowed in preamble + delimiter (0..4).
        dictionary: the command dictionary frames are checked against.
        fast_path: decode byte-aligned frames fed as bytes on the straight line; ``False``
            runs every bit through the bit-level path (same events, slower).
    """

    # Slots: the agent makes a receiver per frame, and slot attributes are quicker to set and
    # read on the per-frame path.
    __slots__ = ("_base", "_buf", "_len", "_straight", "dictionary", "sync_tolerance")

    def __init__(
        self,
        *,
        sync_tolerance: int = DEFAULT_SYNC_TOLERANCE,
        dictionary: CommandDictionary = DICTIONARY,
        fast_path: bool = True,
    ) -> None:
        if not 0 <= sync_tolerance <= 4:
            raise ValueError("sync_tolerance must be 0..4 (the delimiter guarantees 4)")
        self.sync_tolerance = sync_tolerance
        self.dictionary = dictionary
        self._straight = (
            (dictionary.straight_line or straight_line(dictionary)) if fast_path else None
        )
        self._buf = 0  # unconsumed bits, oldest in the most significant place
        self._len = 0  # number of bits in _buf
        self._base = 0  # stream offset of the oldest bit in _buf

    @property
    def position(self) -> int:
        """Total bits fed so far."""
        return self._base + self._len

    @property
    def pending_bits(self) -> int:
        """Bits held back while waiting for the rest of a possible frame."""
        return self._len

    def feed_bits(self, bits: str | Iterable[int]) -> list[Event]:
        """Feed bits: a string of '0'/'1' or an iterable of 0/1 ints, first bit first.

        Raises:
            DecodeError: ``MALFORMED`` if any element is not a bit; nothing is consumed.
        """
        if isinstance(bits, str):
            text = bits.replace(" ", "").replace("_", "")
            if text.strip("01"):
                raise DecodeError(RejectReason.MALFORMED, "bits must be '0' or '1'")
            return self._feed(int(text, 2) if text else 0, len(text))
        value = 0
        count = 0
        for bit in bits:
            if type(bit) is not int or bit not in (0, 1):
                raise DecodeError(RejectReason.MALFORMED, f"bits must be 0 or 1, got {bit!r}")
            value = (value << 1) | bit
            count += 1
        return self._feed(value, count)

    def feed_bytes(self, data: bytes | bytearray | memoryview) -> list[Event]:
        """Feed bytes, each sent MSB first."""
        raw = data if type(data) is bytes else bytes(data)
        size = len(raw)
        straight = self._straight
        if (
            straight is not None
            and size >= ALIGNED_BYTES
            and (not self._len or self._skip_pending(raw))
        ):
            decoded = straight(raw, self.sync_tolerance)
            if decoded is not None:
                event = _new(Accepted)
                _set_offset(event, self._base)
                _set_decoded(event, decoded)
                self._base += _NEEDED
                if size == FRAME_BYTES:  # the guard and pad bits: too few to decide on
                    self._buf = raw[ALIGNED_BYTES]
                    self._len = 8
                    return [event]
                return [event, *self._scan_rest(raw)]
        return self._feed(int.from_bytes(raw, "big"), 8 * size)

    def _skip_pending(self, raw: bytes) -> bool:
        """Drop the pending bits if the bit-level scan would pass over all of them without a
        sync candidate (so it would next look at ``raw[0]``); ``False`` if one is a candidate.
        """
        n = self._len
        if n == 0:
            return True
        if n >= _DECIDE:  # a candidate waiting for its codeword
            return False
        tol = self.sync_tolerance
        head = (self._buf << SYNC_BITS) | int.from_bytes(raw[:3], "big")
        for pos in range(n):
            if (((head >> (n - pos)) & _SYNC_MASK) ^ SYNC_WORD).bit_count() <= tol:
                return False
        self._base += n
        self._buf = self._len = 0
        return True

    def _scan_rest(self, raw: bytes) -> list[Event]:
        """After the straight line's frame: the bytes after its codeword, scanned on."""
        count = 8 * (len(raw) - ALIGNED_BYTES)
        rest = int.from_bytes(raw[ALIGNED_BYTES:], "big")
        if count < _DECIDE:  # what _scan would keep, deciding nothing
            self._buf, self._len = rest, count
            return []
        return self._feed(rest, count)

    def _feed(self, value: int, count: int) -> list[Event]:
        # Scan in slices so the working buffer stays short: shifting a big int costs time
        # proportional to its length, which would make one huge feed quadratic.
        events: list[Event] = []
        while count > 0:
            take = min(count, _SLICE_BITS)
            count -= take
            self._buf = (self._buf << take) | ((value >> count) & ((1 << take) - 1))
            self._len += take
            events += self._scan()
        return events

    def _scan(self) -> list[Event]:
        events: list[Event] = []
        buf, length, tol = self._buf, self._len, self.sync_tolerance
        pos = 0
        # Every decision below depends only on bits pos .. pos + 32 and the codeword, all of
        # which have arrived, so any chunking of the stream gives the same events.
        while length - pos >= _DECIDE:
            shift = length - SYNC_BITS
            dist = (((buf >> (shift - pos)) & _SYNC_MASK) ^ SYNC_WORD).bit_count()
            if dist > tol:
                pos += 1
                continue
            best, best_dist = pos, dist
            # No look-ahead offset can be strictly closer when 2 * dist <= SHIFT_DISTANCE.
            for cand in range(pos + 1, pos + _LOOKAHEAD + 1) if 2 * dist > SHIFT_DISTANCE else ():
                d = (((buf >> (shift - cand)) & _SYNC_MASK) ^ SYNC_WORD).bit_count()
                if d < best_dist:
                    best, best_dist = cand, d
            if length - best < _NEEDED:
                break  # wait for the rest of the codeword
            pos = best
            codeword = (buf >> (length - pos - _NEEDED)) & _CODEWORD_MASK
            try:
                decoded = decode_codeword(codeword, self.dictionary, best_dist)
            except DecodeError as err:
                events.append(Rejected(self._base + pos, err))
                pos += 1
                continue
            events.append(Accepted(self._base + pos, decoded))
            pos += _NEEDED
        self._base += pos
        self._len = length - pos
        self._buf = buf & ((1 << self._len) - 1)
        return events
