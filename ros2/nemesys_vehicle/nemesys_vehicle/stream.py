"""Frames out of a raw ME receiver byte stream, over any chunking.

A serial ME receiver delivers the demodulated bits as a continuous byte stream (MSB first):
noise between frames, frames not aligned to bytes, reads cut anywhere. :class:`FrameStream`
feeds it to the codec's :class:`codec.FrameReceiver` (frame sync at every bit offset) and, for
each frame the receiver synchronised on (decoded or not), cuts that frame's bits out of the
stream as the 13 bytes the frame topic carries. The onboard agent then processes them exactly
as a frame from the topic, so both inputs give the same acknowledgement for the same bits.

The 4 guard bits of a cut-out frame are zero (the receiver reports a frame as soon as its
codeword is in, before its guard bits; the agent ignores them anyway), so the result does not
depend on how the stream was chunked.

A vehicle with an address (a fleet's, docs/protocol.md "Addressing") syncs with the codec's
:class:`codec.AddressedReceiver` instead, on the 108-bit addressed frames as well as the
100-bit ones, and cuts each at its own length (14 or 13 bytes) by the sync word it starts with.
"""

from __future__ import annotations

from codec import (
    CODEWORD_BITS,
    GUARD_BITS,
    SYNC_BITS,
    SYNC_WORD,
    AddressedFrame,
    AddressedReceiver,
    Frame,
    FrameReceiver,
)
from codec._address import ADDRESSED_CODEWORD_BITS, FLEET_SYNC_WORD

#: Header plus codeword: the bits of a frame the receiver needs (the guard bits are not sent
#: on to the agent, see the module doc).
_FRAME_BODY_BITS = SYNC_BITS + CODEWORD_BITS
_FRAME_BODY_MASK = (1 << _FRAME_BODY_BITS) - 1
_ADDRESSED_BODY_BITS = SYNC_BITS + ADDRESSED_CODEWORD_BITS
_ADDRESSED_BODY_MASK = (1 << _ADDRESSED_BODY_BITS) - 1


class FrameStream:
    """Frame sync over a byte stream: bytes in, 13-byte frames out (14 for an addressed one,
    with an ``address``). No I/O, no threads."""

    def __init__(self, address: int | None = None) -> None:
        # the agent decodes every frame again with the default sync tolerance: the stream
        # must use the same, or a frame found here could fail sync there
        self.receiver: FrameReceiver | AddressedReceiver = (
            FrameReceiver() if address is None else AddressedReceiver(address)
        )
        self.address = address
        self._bits = 0  # stream bits the receiver may still report a frame in, oldest first
        self._len = 0  # how many
        self._base = 0  # stream offset of the oldest one
        self.bytes_in = 0
        self.frames_out = 0

    @property
    def pending_bits(self) -> int:
        """Bits held while waiting for the rest of a possible frame."""
        return self._len

    def feed(self, data: bytes) -> list[bytes]:
        """The frames found in the stream so far that ``data`` completed, oldest first."""
        if not data:
            return []
        n_bits = 8 * len(data)
        self.bytes_in += len(data)
        self._bits = (self._bits << n_bits) | int.from_bytes(data, "big")
        self._len += n_bits
        frames = [self._frame_at(event.offset) for event in self.receiver.feed_bytes(data)]
        self._keep_pending()
        self.frames_out += len(frames)
        return frames

    def _frame_at(self, offset: int) -> bytes:
        """The frame starting at stream bit ``offset`` (its header and codeword have arrived)."""
        start = self._len - (offset - self._base)
        if self.address is not None:
            sync = (self._bits >> (start - SYNC_BITS)) & ((1 << SYNC_BITS) - 1)
            if (sync ^ FLEET_SYNC_WORD).bit_count() < (sync ^ SYNC_WORD).bit_count():
                body = (self._bits >> (start - _ADDRESSED_BODY_BITS)) & _ADDRESSED_BODY_MASK
                return AddressedFrame(body << GUARD_BITS).to_bytes()
        body = (self._bits >> (start - _FRAME_BODY_BITS)) & _FRAME_BODY_MASK
        return Frame(body << GUARD_BITS).to_bytes()

    def _keep_pending(self) -> None:
        """Forget the bits the receiver has consumed: it reports no frame before them."""
        receiver = self.receiver
        keep_from = receiver.position - receiver.pending_bits
        self._len -= keep_from - self._base
        self._bits &= (1 << self._len) - 1
        self._base = keep_from
