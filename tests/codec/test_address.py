"""Addressed frames (codec._address, codec._address_sync; docs/protocol.md, "Addressing"): the
layout, the address word, encode and decode as the console and as each vehicle, the receiver
on streams, and the bchlib oracle for the 80-bit code."""

from __future__ import annotations

import itertools
import random

import bchlib
import pytest

from codec import (
    ADDRESSED_FRAME_BITS,
    ADDRESSED_FRAME_BYTES,
    BROADCAST_ADDRESS,
    FLEET_DELIMITER,
    FRAME_BITS,
    MAX_ADDRESS,
    SYNC_WORD,
    UNCORRECTABLE,
    Accepted,
    AddressedDecoded,
    AddressedFrame,
    AddressedReceiver,
    DecodeError,
    EncodeError,
    Frame,
    FrameReceiver,
    MisaddressedError,
    Rejected,
    RejectReason,
    address_word,
    addressed_frame_of,
    decode_addressed_frame,
    decode_frame,
    encode_frame,
    payload_of,
    sections,
)
from codec._address import (
    ADDRESSED_CODE,
    ADDRESSED_CODEWORD_BITS,
    FLEET_SYNC_WORD,
    address_of_word,
    decode_addressed_message,
)
from tests.codec.helpers import random_command

SQUARE = encode_frame("square", speed=0.5, depth=2, side_span=12.34, direction="cw")
SURFACE = encode_frame("surface")
VEHICLES = range(1, MAX_ADDRESS + 1)


def to(address: int, enc: object = SQUARE) -> AddressedFrame:
    return addressed_frame_of(payload_of(enc.command), address)  # type: ignore[attr-defined]


def flipped(frame: AddressedFrame, *bits: int) -> AddressedFrame:
    """``frame`` with wire bits ``bits`` (0 = first sent) inverted."""
    return AddressedFrame(frame.value ^ sum(1 << (ADDRESSED_FRAME_BITS - 1 - b) for b in bits))


# --- layout -----------------------------------------------------------------------------------


def test_layout_and_the_worked_frame() -> None:
    frame = to(3)
    assert (ADDRESSED_FRAME_BITS, ADDRESSED_FRAME_BYTES, ADDRESSED_CODEWORD_BITS) == (108, 14, 80)
    assert (ADDRESSED_CODE.n, ADDRESSED_CODE.k, ADDRESSED_CODE.generator_poly) == (80, 64, 0x16F63)
    assert (
        frame.hex == "aaaa433c1321473000000f40ee0"
    )  # checked by hand: CRC 1111, bchlib parity 40ee
    assert frame.bits.startswith("1010101010101010" + "01000011" + "0011" + "1100" + "0001")
    assert frame.address == 3 and frame.to_bytes().hex() == frame.hex + "0"
    assert [len(g) for g in frame.grouped().split()] == [16, 8, 4, 4, 4, *[8] * 6, 4, 16, 4]
    names = [s.name for s in sections(SQUARE.command.pattern, addressed=True)]
    assert names[:5] == ["preamble", "delimiter", "address", "address_check", "pattern"]
    assert sum(s.length for s in sections(addressed=True)) == ADDRESSED_FRAME_BITS


def test_address_words_are_an_8_4_4_code() -> None:
    words = [address_word(a) for a in range(MAX_ADDRESS + 1)]
    assert words[BROADCAST_ADDRESS] == 0 and len(set(words)) == 16
    assert min((u ^ v).bit_count() for u, v in itertools.combinations(words, 2)) == 4
    for byte in range(256):
        assert address_of_word(byte) == (words.index(byte) if byte in words else None)


def test_the_two_sync_words_stay_apart_at_every_shift() -> None:
    """6 bits aligned, at least 4 at every shift of 1..15 (on the bits both windows hold)."""
    assert (FLEET_SYNC_WORD ^ SYNC_WORD).bit_count() == 6
    mask = (1 << 24) - 1
    for s in range(1, 16):
        known = mask & ~((1 << s) - 1)
        for a, b in ((FLEET_SYNC_WORD, SYNC_WORD), (SYNC_WORD, FLEET_SYNC_WORD)):
            assert (((a << s) ^ b) & known).bit_count() >= 4
            assert (((a << s) ^ a) & known).bit_count() >= 4
    assert FLEET_DELIMITER == 0x43


def test_the_80_bit_code_is_bchlibs() -> None:
    """bchlib.BCH(2, m=8) on 8 data bytes is the (80, 64) code: the same parity, and the same
    decisions on words with 0-4 errors."""
    oracle = bchlib.BCH(2, m=8)
    rng = random.Random(5)
    for _ in range(300):
        message = rng.getrandbits(64)
        codeword = ADDRESSED_CODE.encode(message)
        assert oracle.encode(message.to_bytes(8, "big")) == (codeword & 0xFFFF).to_bytes(2, "big")
        errors = sum(1 << i for i in rng.sample(range(80), rng.randrange(5)))
        received = codeword ^ errors
        data = bytearray((received >> 16).to_bytes(8, "big"))
        ecc = bytearray((received & 0xFFFF).to_bytes(2, "big"))
        nerr = oracle.decode(data, ecc)
        got, corrected = decode_addressed_message(received)
        assert corrected == (nerr if nerr >= 0 else UNCORRECTABLE)
        if nerr >= 0:
            oracle.correct(data, ecc)
            assert got == int.from_bytes(data, "big")
        assert (got, corrected) == ADDRESSED_CODE.decode(received)


# --- encode ---------------------------------------------------------------------------------


def test_encode_frame_with_an_address() -> None:
    enc = encode_frame("square", speed=0.5, depth=2, side_span=12.34, direction="cw", address=3)
    assert isinstance(enc.frame, AddressedFrame) and enc.frame == to(3)
    assert enc.snaps == SQUARE.snaps and enc.command == SQUARE.command
    assert type(encode_frame("surface").frame) is Frame  # no address: today's frame


@pytest.mark.parametrize("bad", [16, -1, 255, True, 2.0])
def test_an_address_out_of_range_is_refused_naming_the_range(bad: object) -> None:
    with pytest.raises(EncodeError, match=r"allowed 0 \(all vehicles\) or 1 to 15"):
        encode_frame("surface", address=bad)  # type: ignore[arg-type]


# --- decode as the console and as each vehicle ------------------------------------------------


def test_every_address_round_trips_through_the_console_view() -> None:
    rng = random.Random(2)
    for address in range(MAX_ADDRESS + 1):
        command = random_command(rng)
        frame = addressed_frame_of(payload_of(command), address)
        for form in (frame, frame.hex, frame.bits, frame.to_bytes(), frame.value):
            dec = decode_addressed_frame(form)
            assert (dec.command, dec.address, dec.corrected) == (command, address, 0)


def test_each_vehicle_takes_its_own_and_broadcast_frames_only() -> None:
    for sent, vehicle in itertools.product(range(MAX_ADDRESS + 1), VEHICLES):
        frame = to(sent)
        if sent in (vehicle, BROADCAST_ADDRESS):
            dec = decode_frame(frame.hex, vehicle=vehicle)
            assert isinstance(dec, AddressedDecoded) and dec.address == sent
        else:
            with pytest.raises(MisaddressedError) as err:
                decode_frame(frame.hex, vehicle=vehicle)
            assert err.value.reason is RejectReason.OTHER_VEHICLE
            assert err.value.address == sent
            assert str(err.value) == f"addressed to vehicle {sent}, not to this vehicle ({vehicle})"


def test_unaddressed_frames_at_a_vehicle_with_an_address() -> None:
    """Only the single-vehicle Surface is obeyed; anything else names no vehicle."""
    assert decode_frame(SURFACE.frame.hex, vehicle=4).command == SURFACE.command
    with pytest.raises(MisaddressedError, match="an unaddressed frame \\(square\\)"):
        decode_frame(SQUARE.frame.hex, vehicle=4)
    # and without a vehicle, decode_frame is today's: 100 bits only
    assert decode_frame(SQUARE.frame.hex).command == SQUARE.command
    with pytest.raises(DecodeError) as err:
        decode_frame(to(3).hex)
    assert err.value.reason is RejectReason.MALFORMED


def test_errors_are_corrected_and_checked_in_order() -> None:
    frame = to(7)
    assert decode_frame(flipped(frame, 30, 90), vehicle=7).corrected == 2
    assert decode_frame(flipped(frame, 24, 0), vehicle=7).sync_errors == 1  # address bit fixed
    with pytest.raises(DecodeError) as err:
        decode_frame(flipped(frame, 30, 50, 90), vehicle=7)
    assert err.value.reason is RejectReason.UNCORRECTABLE
    with pytest.raises(DecodeError) as err:
        decode_frame(flipped(frame, 16, 17, 18), vehicle=7)
    assert err.value.reason is RejectReason.NO_SYNC
    with pytest.raises(ValueError, match="a vehicle's own address is 1 to 15"):
        decode_frame(frame, vehicle=0)


def test_a_valid_codeword_whose_address_word_is_no_address_is_refused() -> None:
    from codec._address import _CRC_CHECK

    covered = (0x35 << 52) | payload_of(SQUARE.command)  # 0x35: no address word
    message = (covered << 4) | _CRC_CHECK(covered << 4)
    value = (FLEET_SYNC_WORD << 84) | (ADDRESSED_CODE.encode(message) << 4)
    with pytest.raises(MisaddressedError, match="address word 00110101 is no address") as err:
        decode_addressed_frame(value)
    assert err.value.address is None


# --- the receiver ---------------------------------------------------------------------------


def test_the_receiver_on_a_mixed_stream_in_any_chunking() -> None:
    rng = random.Random(9)
    pieces = [
        ("noise", "".join(rng.choice("01") for _ in range(37))),
        ("mine", to(5).bits),
        ("other", to(6).bits),
        ("all", to(0).bits),
        ("single surface", SURFACE.frame.bits),
        ("single square", SQUARE.frame.bits),
        ("damaged", flipped(to(5), 30, 50, 90).bits),
        ("mine again", flipped(to(5), 40, 99).bits),
    ]
    stream = "".join(bits for _, bits in pieces)
    starts = list(itertools.accumulate([0] + [len(b) for _, b in pieces]))
    expected = [
        ("Accepted", starts[1], 5),
        ("Rejected", starts[2], "other_vehicle"),
        ("Accepted", starts[3], 0),
        ("Accepted", starts[4], None),
        ("Rejected", starts[5], "other_vehicle"),
        ("Rejected", starts[6], "uncorrectable"),
        ("Accepted", starts[7], 5),
    ]

    def summary(e: Accepted | Rejected) -> tuple[object, ...]:
        if isinstance(e, Accepted):
            return ("Accepted", e.offset, getattr(e.decoded, "address", None))
        return ("Rejected", e.offset, e.error.reason.value)

    whole = [summary(e) for e in AddressedReceiver(5).feed_bits(stream)]
    assert whole == expected
    for size in (1, 7, 64):
        rx = AddressedReceiver(5)
        events = [
            e for i in range(0, len(stream), size) for e in rx.feed_bits(stream[i : i + size])
        ]
        assert [summary(e) for e in events] == expected
    data = (stream + "0" * (-len(stream) % 8)).encode()
    as_bytes = int(data, 2).to_bytes(len(data) // 8, "big")
    assert [summary(e) for e in AddressedReceiver(5).feed_bytes(as_bytes)] == expected


def test_a_vehicle_with_no_address_never_takes_an_addressed_frame() -> None:
    for address in range(MAX_ADDRESS + 1):
        events = FrameReceiver().feed_bytes(to(address).to_bytes())
        assert not any(isinstance(e, Accepted) for e in events)
    assert FRAME_BITS == 100  # and its own frame is today's


@pytest.mark.parametrize(
    ("address", "tolerance", "match"), [(0, 2, "1 to 15"), (16, 2, "1 to 15"), (3, 3, "0..2")]
)
def test_receiver_arguments_are_checked(address: int, tolerance: int, match: str) -> None:
    with pytest.raises(ValueError, match=match):
        AddressedReceiver(address, sync_tolerance=tolerance)


def test_a_misaddressed_frame_is_skipped_whole() -> None:
    """A frame for another vehicle decoded fine: the search goes on after its codeword, so a
    sync-like pattern inside it is never a candidate."""
    events = AddressedReceiver(2).feed_bytes(to(9).to_bytes() + to(2).to_bytes())
    assert [type(e).__name__ for e in events] == ["Rejected", "Accepted"]
    assert isinstance(events[0], Rejected) and events[1].offset == 8 * ADDRESSED_FRAME_BYTES
