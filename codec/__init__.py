"""NemeSys mission codec: command dictionary, 100-bit BCH frames and frame sync. Sans-IO.

Pure Python, no numpy (the batch path for Monte Carlo analysis lives in :mod:`codec.batch`
and is imported separately), so the vehicle can import it within its memory budget.

Typical use::

    from codec import encode_frame, decode_frame
    enc = encode_frame("circle", speed=0.5, depth=2, radius=5, direction="cw")
    enc.frame.bits            # 100 '0'/'1' characters
    dec = decode_frame(enc.frame.bits)
    dec.command.params, dec.corrected
"""

from codec._bch import BCHCode, TableDecoder
from codec._dictionary import (
    DICTIONARY,
    FIELDS_PER_FRAME,
    PATTERN_ID_BITS,
    PATTERNS,
    Command,
    CommandDictionary,
    Pattern,
)
from codec._errors import UNCORRECTABLE, CodecError, DecodeError, EncodeError, RejectReason
from codec._fields import Field
from codec._frame import (
    CODE,
    CODEWORD_BITS,
    CRC_BITS,
    CRC_POLY,
    DEFAULT_BITRATE_BPS,
    DEFAULT_SYNC_TOLERANCE,
    DELIMITER,
    DELIMITER_BITS,
    FAST_DECODER,
    FRAME_BITS,
    FRAME_BYTES,
    GUARD_BITS,
    MESSAGE_BITS,
    PARITY_BITS,
    PAYLOAD_BITS,
    PREAMBLE,
    PREAMBLE_BITS,
    SYNC_BITS,
    SYNC_WORD,
    Decoded,
    Frame,
    command_of_message,
    crc4,
    decode_codeword,
)
from codec._scales import FIELD_BITS, ChoiceScale, NumericScale, ParamValue, Segment
from codec._sync import Accepted, Event, FrameReceiver, Rejected, receive_frame

TYPE_CHECKING = False
if TYPE_CHECKING:
    from codec._address import (
        ADDRESSED_FRAME_BITS,
        ADDRESSED_FRAME_BYTES,
        BROADCAST_ADDRESS,
        FLEET_DELIMITER,
        MAX_ADDRESS,
        AddressedDecoded,
        AddressedFrame,
        MisaddressedError,
        address_word,
        addressed_frame_of,
        check_address,
        check_vehicle_address,
        decode_addressed_codeword,
    )
    from codec._address_sync import AddressedReceiver
    from codec._delivery import (
        MAX_COPIES,
        binomial_cdf,
        copies_for,
        delivery_probability,
        frame_success_probability,
    )
    from codec._describe import describe_dictionary, describe_pattern, markdown_tables
    from codec._number_text import ASCII_DIGITS, int_from_text, number_from_text
    from codec._parse import decode_addressed_frame, decode_frame, parse_frame
    from codec._snap import Snap
    from codec._wire import (
        Encoded,
        Section,
        airtime_s,
        encode_frame,
        frame_of,
        make_command,
        message_of,
        payload_of,
        sections,
    )

__all__ = [
    "ADDRESSED_FRAME_BITS",
    "ADDRESSED_FRAME_BYTES",
    "ASCII_DIGITS",
    "BROADCAST_ADDRESS",
    "CODE",
    "CODEWORD_BITS",
    "CRC_BITS",
    "CRC_POLY",
    "DEFAULT_BITRATE_BPS",
    "DEFAULT_SYNC_TOLERANCE",
    "DELIMITER",
    "DELIMITER_BITS",
    "DICTIONARY",
    "FAST_DECODER",
    "FIELDS_PER_FRAME",
    "FIELD_BITS",
    "FLEET_DELIMITER",
    "FRAME_BITS",
    "FRAME_BYTES",
    "GUARD_BITS",
    "MAX_ADDRESS",
    "MAX_COPIES",
    "MESSAGE_BITS",
    "PARITY_BITS",
    "PATTERNS",
    "PATTERN_ID_BITS",
    "PAYLOAD_BITS",
    "PREAMBLE",
    "PREAMBLE_BITS",
    "SYNC_BITS",
    "SYNC_WORD",
    "UNCORRECTABLE",
    "Accepted",
    "AddressedDecoded",
    "AddressedFrame",
    "AddressedReceiver",
    "BCHCode",
    "ChoiceScale",
    "CodecError",
    "Command",
    "CommandDictionary",
    "DecodeError",
    "Decoded",
    "EncodeError",
    "Encoded",
    "Event",
    "Field",
    "Frame",
    "FrameReceiver",
    "MisaddressedError",
    "NumericScale",
    "ParamValue",
    "Pattern",
    "RejectReason",
    "Rejected",
    "Section",
    "Segment",
    "Snap",
    "TableDecoder",
    "address_word",
    "addressed_frame_of",
    "airtime_s",
    "binomial_cdf",
    "check_address",
    "check_vehicle_address",
    "command_of_message",
    "copies_for",
    "crc4",
    "decode_addressed_codeword",
    "decode_addressed_frame",
    "decode_codeword",
    "decode_frame",
    "delivery_probability",
    "describe_dictionary",
    "describe_pattern",
    "encode_frame",
    "frame_of",
    "frame_success_probability",
    "int_from_text",
    "make_command",
    "markdown_tables",
    "message_of",
    "number_from_text",
    "parse_frame",
    "payload_of",
    "receive_frame",
    "sections",
]

# Encoding, one-frame decode (of any accepted form), the listing helpers and the delivery
# arithmetic are imported on first use: the console needs them, the vehicle does not; so are
# addressed frames (docs/protocol.md, "Addressing"): a vehicle with no address never loads them
# (``nemesys bench reconfig`` measures its memory). (Hidden from the type checker, which sees
# the imports above, so that a misspelt name imported from codec is still an error and not an
# ``object``.)
_LAZY = {
    "ADDRESSED_FRAME_BITS": "codec._address",
    "ADDRESSED_FRAME_BYTES": "codec._address",
    "BROADCAST_ADDRESS": "codec._address",
    "FLEET_DELIMITER": "codec._address",
    "MAX_ADDRESS": "codec._address",
    "AddressedDecoded": "codec._address",
    "AddressedFrame": "codec._address",
    "MisaddressedError": "codec._address",
    "address_word": "codec._address",
    "addressed_frame_of": "codec._address",
    "check_address": "codec._address",
    "check_vehicle_address": "codec._address",
    "decode_addressed_codeword": "codec._address",
    "AddressedReceiver": "codec._address_sync",
    "describe_dictionary": "codec._describe",
    "describe_pattern": "codec._describe",
    "markdown_tables": "codec._describe",
    "MAX_COPIES": "codec._delivery",
    "binomial_cdf": "codec._delivery",
    "copies_for": "codec._delivery",
    "delivery_probability": "codec._delivery",
    "frame_success_probability": "codec._delivery",
    "Snap": "codec._snap",
    "ASCII_DIGITS": "codec._number_text",
    "int_from_text": "codec._number_text",
    "number_from_text": "codec._number_text",
    "Encoded": "codec._wire",
    "Section": "codec._wire",
    "airtime_s": "codec._wire",
    "decode_addressed_frame": "codec._parse",
    "decode_frame": "codec._parse",
    "encode_frame": "codec._wire",
    "frame_of": "codec._wire",
    "make_command": "codec._wire",
    "message_of": "codec._wire",
    "parse_frame": "codec._parse",
    "payload_of": "codec._wire",
    "sections": "codec._wire",
}

if not TYPE_CHECKING:

    def __getattr__(name: str) -> object:
        module_name = _LAZY.get(name)
        if module_name is None:
            raise AttributeError(f"module 'codec' has no attribute {name!r}")
        import sys

        __import__(module_name)  # not importlib: it loads warnings, on the onboard path too
        value = getattr(sys.modules[module_name], name)
        globals()[name] = value
        return value
