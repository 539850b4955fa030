"""The codec's small error hierarchy.

``EncodeError``: the caller asked for something the dictionary cannot express (unknown pattern,
missing or unknown parameter, value outside a field's range). ``DecodeError``: the received bits
are not a frame the vehicle may execute; ``reason`` says which check failed. Nothing else leaves
the codec's public decode functions, whatever they are given.

:data:`UNCORRECTABLE` is the decoders' count of corrected bits for a word beyond their reach:
the table decoder (:mod:`codec._bch`) and the textbook one (:mod:`codec._berlekamp`) both return
it, so it lives below both.
"""

from __future__ import annotations

from codec.compat import StrEnum

#: ``n_corrected`` returned for a word the decoder cannot correct (galois' convention).
UNCORRECTABLE = -1


class CodecError(Exception):
    """Base class of every error the codec raises on purpose."""


class EncodeError(CodecError, ValueError):
    """A command cannot be encoded as requested.

    Attributes:
        field: the parameter at fault, or ``None`` when the pattern itself is at fault.
    """

    def __init__(self, message: str, *, field: str | None = None) -> None:
        super().__init__(message)
        self.field = field


class RejectReason(StrEnum):
    """Why a received frame was rejected. The value is the machine-readable code."""

    #: Not a frame at all: wrong length, characters other than 0/1 (or hex), wrong type.
    MALFORMED = "malformed"
    #: The preamble + delimiter differ from the sync word in more bits than tolerated.
    NO_SYNC = "no_sync"
    #: More bit errors in the codeword than the BCH code can correct.
    UNCORRECTABLE = "uncorrectable"
    #: The BCH decoder produced a codeword whose CRC-4 does not match: a miscorrection.
    CRC_MISMATCH = "crc_mismatch"
    #: The pattern ID is not in the command dictionary.
    UNKNOWN_PATTERN = "unknown_pattern"
    #: A field holds a code that its quantization does not define.
    FIELD_OUT_OF_RANGE = "field_out_of_range"
    #: A field the pattern does not use is not zero.
    UNUSED_FIELD_SET = "unused_field_set"
    #: An addressed frame for another vehicle, an address word that is no address, or (at a
    #: vehicle with an address) an unaddressed frame other than surface: docs/protocol.md,
    #: "Addressing". A vehicle with no address never gives it.
    OTHER_VEHICLE = "other_vehicle"


class DecodeError(CodecError):
    """A received frame was rejected; it must never be executed.

    Attributes:
        reason: which check failed.
        field: the field at fault for the field checks, else ``None``.
    """

    def __init__(self, reason: RejectReason, message: str, *, field: str | None = None) -> None:
        super().__init__(message)
        self.reason = reason
        self.field = field

    def __repr__(self) -> str:
        return f"DecodeError({self.reason.value}: {self})"

    # Value equality, so that receiver event lists can be compared (tests, replays).
    def __eq__(self, other: object) -> bool:
        if not isinstance(other, DecodeError):
            return NotImplemented
        return (self.reason, str(self), self.field) == (other.reason, str(other), other.field)

    def __hash__(self) -> int:
        return hash((self.reason, str(self), self.field))
