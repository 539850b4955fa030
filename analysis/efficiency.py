"""The whole-frame efficiency: one definition, computed from the codec's constants.

The paper: "a 4-bit identifier for the pattern type, followed by up to six 8-bit parameter
fields, forming a raw payload of 52 bits (zero-padded to match 56 bit BCH message length)
... resulting in a complete 100-bit transmission packet". The payload is what the operator
says: those 52 bits (:data:`codec.PAYLOAD_BITS`). Everything else is overhead: the 4 bits
the paper zero-pads (a CRC-4 in our codec, a check like the BCH parity, not information), the
16 parity bits, the 24-bit sync word and the 4 guard bits. So

    whole-frame efficiency = payload bits / frame bits = 52 / 100 = 0.52

``docs/protocol.md`` (section 4 and 5 (a)) and ``docs/results.md`` (the encoding section)
both quote :func:`whole_frame_text`; ``tests/analysis/test_efficiency.py`` checks that they
do and that nothing else is called the whole-frame efficiency.
"""

from __future__ import annotations

from codec import CODEWORD_BITS, FRAME_BITS, GUARD_BITS, MESSAGE_BITS, PAYLOAD_BITS, SYNC_BITS

#: Payload bits / frame bits for the codec's frame (dimensionless).
WHOLE_FRAME_EFFICIENCY = PAYLOAD_BITS / FRAME_BITS
#: Code rate k / n of the (72, 56) BCH code (the CRC-4 counts as message to the code).
CODE_RATE = MESSAGE_BITS / CODEWORD_BITS
#: Payload bits / codeword bits.
PAYLOAD_RATE = PAYLOAD_BITS / CODEWORD_BITS


def frame_bits_for(codeword_bits: int) -> int:
    """Bits on air for a frame carrying a codeword of ``codeword_bits``: sync + codeword +
    guard (100 for the (72, 56) code)."""
    return SYNC_BITS + codeword_bits + GUARD_BITS


def whole_frame_efficiency(codeword_bits: int = CODEWORD_BITS) -> float:
    """Payload bits / frame bits for a frame carrying a codeword of ``codeword_bits`` (the
    other T of the BER analysis have longer codewords, hence longer frames)."""
    return PAYLOAD_BITS / frame_bits_for(codeword_bits)


def whole_frame_text() -> str:
    """The figure as both docs print it: ``52/100 = 0.52``."""
    return f"{PAYLOAD_BITS}/{FRAME_BITS} = {WHOLE_FRAME_EFFICIENCY:g}"


DEFINITION = (
    f"whole-frame efficiency = payload bits / frame bits = {whole_frame_text()}: the payload "
    f"is the paper's 52-bit raw payload (the 4-bit pattern ID and six 8-bit fields); the "
    f"CRC-4 in the bits the paper zero-pads, the BCH parity, the sync word and the guard "
    f"bits are overhead"
)

__all__ = [
    "CODE_RATE",
    "DEFINITION",
    "PAYLOAD_RATE",
    "WHOLE_FRAME_EFFICIENCY",
    "frame_bits_for",
    "whole_frame_efficiency",
    "whole_frame_text",
]
