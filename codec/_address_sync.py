"""Frame sync for a vehicle with an address: :class:`AddressedReceiver`.

It works as :class:`codec.FrameReceiver` (sans-IO, any chunking, the same events), looking
at every bit offset for two sync words: the addressed frame's (delimiter 0x43, an 80-bit
codeword follows) and the single-vehicle frame's (0x7C, 72 bits). The two differ in 6 bits
aligned and in at least 4 at every shift of 1..15 bits, and each differs from its own shifts
in at least 4, so the receiver takes, on a candidate, the best-matching offset and word among
the next :data:`LOOKAHEAD` bits, as the single-vehicle receiver does.

* An addressed frame is decoded as this vehicle (:func:`codec._address.decode_addressed_codeword`):
  to it or to all (address 0) it is accepted; to another it is rejected ``other_vehicle``.
* An unaddressed frame is accepted only if it is surface: Surface in the single-vehicle form
  is obeyed by every vehicle that hears it. Any other unaddressed command is rejected
  ``other_vehicle`` (it names no vehicle, so none of a fleet may run it).
* A frame that decoded but is not for this vehicle was a frame all the same: the search
  resumes after its codeword. A frame that failed to decode resumes one bit later, so a false
  sync in noise never swallows the real frame that follows it.

Loaded only by a vehicle with an address (the onboard agent imports it on first use).
"""

from __future__ import annotations

from codec._address import (
    ADDRESSED_CODEWORD_BITS,
    FLEET_SYNC_WORD,
    MisaddressedError,
    check_vehicle_address,
    decode_addressed_codeword,
)
from codec._dictionary import DICTIONARY, CommandDictionary
from codec._errors import DecodeError, RejectReason
from codec._fastpath import LOOKAHEAD
from codec._frame import (
    CODEWORD_BITS,
    DEFAULT_SYNC_TOLERANCE,
    SYNC_BITS,
    SYNC_WORD,
    Decoded,
    decode_codeword,
)
from codec._sync import Accepted, Event, Rejected

TYPE_CHECKING = False
if TYPE_CHECKING:
    from collections.abc import Iterable

#: The unaddressed command every vehicle obeys.
SURFACE = "surface"

_SYNC_MASK = (1 << SYNC_BITS) - 1
#: Header + codeword of each kind of frame: what must have arrived before it is decoded.
_NEEDED_ADDRESSED = SYNC_BITS + ADDRESSED_CODEWORD_BITS
_NEEDED_SINGLE = SYNC_BITS + CODEWORD_BITS
_DECIDE = SYNC_BITS + LOOKAHEAD
_SLICE_BITS = 1024


class AddressedReceiver:
    """Finds, decodes and checks frames for vehicle ``address`` in a bit stream.

    Args:
        address: this vehicle's address, 1-15.
        sync_tolerance: wrong bits allowed in preamble + delimiter (0..2: the two sync words
            differ in at least 4 bits at every shift, so at most 2 keeps them apart).
        dictionary: the command dictionary frames are checked against.

    Raises:
        ValueError: an address or tolerance out of range, naming what is allowed.
    """

    __slots__ = ("_base", "_buf", "_len", "address", "dictionary", "sync_tolerance")

    def __init__(
        self,
        address: int,
        *,
        sync_tolerance: int = DEFAULT_SYNC_TOLERANCE,
        dictionary: CommandDictionary = DICTIONARY,
    ) -> None:
        self.address = check_vehicle_address(address)
        if type(sync_tolerance) is not int or not 0 <= sync_tolerance <= 2:
            raise ValueError("sync_tolerance must be 0..2 with addressed frames")
        self.sync_tolerance = sync_tolerance
        self.dictionary = dictionary
        self._buf = 0  # unconsumed bits, oldest in the most significant place
        self._len = 0
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
        raw = bytes(data)
        return self._feed(int.from_bytes(raw, "big"), 8 * len(raw))

    def _feed(self, value: int, count: int) -> list[Event]:
        events: list[Event] = []
        while count > 0:  # in slices, as FrameReceiver: shifting a huge int is slow
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
        # Every decision depends only on bits pos .. pos + 32 and the codeword after the
        # chosen offset, all arrived: any chunking of the stream gives the same events.
        while length - pos >= _DECIDE:
            shift = length - SYNC_BITS
            window = (buf >> (shift - pos)) & _SYNC_MASK
            addressed = (window ^ FLEET_SYNC_WORD).bit_count()
            single = (window ^ SYNC_WORD).bit_count()
            if addressed > tol and single > tol:
                pos += 1
                continue
            best, best_dist, best_addressed = pos, min(addressed, single), addressed <= single
            for cand in range(pos + 1, pos + LOOKAHEAD + 1):
                window = (buf >> (shift - cand)) & _SYNC_MASK
                for is_addressed, word in ((True, FLEET_SYNC_WORD), (False, SYNC_WORD)):
                    d = (window ^ word).bit_count()
                    if d < best_dist:
                        best, best_dist, best_addressed = cand, d, is_addressed
            needed = _NEEDED_ADDRESSED if best_addressed else _NEEDED_SINGLE
            if length - best < needed:
                break  # wait for the rest of the codeword
            pos = best
            codeword = (buf >> (length - pos - needed)) & ((1 << (needed - SYNC_BITS)) - 1)
            try:
                if best_addressed:
                    decoded: Decoded = decode_addressed_codeword(
                        codeword, self.address, self.dictionary, best_dist
                    )
                else:
                    decoded = decode_codeword(codeword, self.dictionary, best_dist)
                    if decoded.command.pattern.name != SURFACE:
                        raise MisaddressedError(
                            f"an unaddressed frame ({decoded.command.pattern.name}): this "
                            f"vehicle (address {self.address}) takes frames addressed to it or "
                            "to all, and unaddressed only surface",
                            None,
                        )
            except MisaddressedError as err:
                events.append(Rejected(self._base + pos, err))
                # a frame, not for this vehicle: skip it (but an address word that is no
                # address is a miscorrection, searched past one bit later like the others)
                pos += needed if err.address is not None or not best_addressed else 1
                continue
            except DecodeError as err:
                events.append(Rejected(self._base + pos, err))
                pos += 1
                continue
            events.append(Accepted(self._base + pos, decoded))
            pos += needed
        self._base += pos
        self._len = length - pos
        self._buf = buf & ((1 << self._len) - 1)
        return events
