"""The receiver's straight line (a frame at a byte boundary, fed as bytes) agrees with the
bit-level path on every frame of the codec tests: clean, with 1, 2 and 3 codeword errors and
0 to 3 header errors, at bit offsets 0 to 7 (unaligned streams take the bit-level path), after
pending bits, in modem-style streams, and for every rejection reason.

"Agrees" means the same events (offsets, accepted commands with their corrected and sync
error counts, rejections with the same reason, field and message) and the same receiver state
afterwards. Each comparison also checks that the straight line was really taken where it
must be, so that agreement is not reached by never using it.
"""

from __future__ import annotations

import pickle
import random
from collections.abc import Sequence
from dataclasses import dataclass, field

import pytest

from codec import (
    DICTIONARY,
    FRAME_BITS,
    FRAME_BYTES,
    SYNC_BITS,
    Accepted,
    Command,
    CommandDictionary,
    Decoded,
    DecodeError,
    Event,
    Field,
    FrameReceiver,
    NumericScale,
    Pattern,
    Rejected,
    RejectReason,
    Segment,
    decode_frame,
    encode_frame,
    frame_of,
    receive_frame,
)
from codec._fastpath import SHIFT_DISTANCE, _decline, shift_distance, straight_line
from tests.codec.helpers import flip_frame, random_command
from tests.codec.test_frame import CRAFTED

#: Every frame the codec tests build on purpose: each pattern at its defaults, the crafted
#: frames of every rejection reason, random valid commands.
FRAMES: list[tuple[str, int]] = [
    *(
        (f"{name} defaults", encode_frame(name, p.defaults).frame.value)
        for name, p in DICTIONARY.items()
    ),
    *((name, value) for name, value, _, _ in CRAFTED),
    *((f"random command {i}", frame_of(random_command(random.Random(i))).value) for i in range(6)),
]


@dataclass
class Spy:
    """Wraps a receiver's straight line and counts what it decided."""

    line: object
    taken: list[Decoded] = field(default_factory=list)
    declined: int = 0

    def __call__(self, raw: bytes, tolerance: int) -> Decoded | None:
        assert callable(self.line)
        decoded: Decoded | None = self.line(raw, tolerance)
        if decoded is None:
            self.declined += 1
        else:
            self.taken.append(decoded)
        return decoded


def receivers(tolerance: int = 2) -> tuple[FrameReceiver, FrameReceiver, Spy]:
    """A receiver with the straight line (spied on) and one on the bit-level path only."""
    fast = FrameReceiver(sync_tolerance=tolerance)
    spy = Spy(fast._straight)
    fast._straight = spy
    return fast, FrameReceiver(sync_tolerance=tolerance, fast_path=False), spy


def feed_both(chunks: Sequence[bytes | str], tolerance: int = 2) -> tuple[list[Event], Spy]:
    """Feed the same chunks (bytes, or '0'/'1' text) to both receivers; assert identical
    events and state after each."""
    fast, slow, spy = receivers(tolerance)
    assert fast._straight is not None and slow._straight is None
    events: list[Event] = []
    for chunk in chunks:
        if isinstance(chunk, str):
            got, want = fast.feed_bits(chunk), slow.feed_bits(chunk)
        else:
            got, want = fast.feed_bytes(chunk), slow.feed_bytes(chunk)
        assert got == want
        assert [type(e) for e in got] == [type(e) for e in want]
        assert (fast.position, fast.pending_bits, fast._buf) == (
            slow.position,
            slow.pending_bits,
            slow._buf,
        )
        events += got
    return events, spy


def as_bytes(bits: str) -> bytes:
    """'0'/'1' text, zero-padded to whole bytes."""
    bits += "0" * (-len(bits) % 8)
    return int(bits, 2).to_bytes(len(bits) // 8, "big") if bits else b""


def damaged(value: int, rng: random.Random, codeword: int, header: int) -> int:
    return flip_frame(
        value,
        header=rng.sample(range(SYNC_BITS), header),
        codeword=rng.sample(range(72), codeword),
    )


def reference(value: int, tolerance: int = 2) -> Decoded | DecodeError:
    try:
        return decode_frame(value, sync_tolerance=tolerance)
    except DecodeError as err:
        return err


@pytest.mark.parametrize(("value"), [v for _, v in FRAMES], ids=[n for n, _ in FRAMES])
def test_straight_line_agrees_with_the_bit_level_path(value: int) -> None:
    rng = random.Random(value)
    for codeword_errors in range(4):
        for header_errors in range(4):
            for offset in range(8):
                received = damaged(value, rng, codeword_errors, header_errors)
                lead = format(rng.getrandbits(offset), f"0{offset}b") if offset else ""
                data = as_bytes(lead + format(received, f"0{FRAME_BITS}b"))
                events, spy = feed_both([data])
                expected = reference(received)
                if offset == 0 and isinstance(expected, Decoded):
                    # A byte-aligned frame the reference accepts is the straight line's case
                    # (up to 2 header errors, within the look-ahead bound).
                    assert header_errors <= 2 <= SHIFT_DISTANCE // 2
                    assert spy.taken == [expected]
                    assert events[0] == Accepted(0, expected)
                if offset == 0 and isinstance(expected, DecodeError) and header_errors <= 2:
                    # The bit-level path reports it, with the reference's reason and field.
                    first = events[0]
                    assert isinstance(first, Rejected) and first.offset == 0
                    assert first.error == expected
                    assert spy.taken == []
                if offset:
                    # Byte 0 holds the lead and a shifted sync word: at least 4 bits off.
                    assert spy.taken == [] and spy.declined == 1


@pytest.mark.parametrize("tolerance", [0, 1, 2, 3, 4])
def test_every_sync_tolerance(tolerance: int) -> None:
    rng = random.Random(tolerance)
    taken = 0
    for _, value in FRAMES:
        for header_errors in range(5):
            received = damaged(value, rng, rng.randrange(3), header_errors)
            _, spy = feed_both([frame_bytes(received)], tolerance)
            taken += len(spy.taken)
            if spy.taken:
                assert header_errors <= min(tolerance, SHIFT_DISTANCE // 2)
    assert taken > 0


def frame_bytes(value: int) -> bytes:
    return (value << 4).to_bytes(FRAME_BYTES, "big")


def test_modem_stream_of_13_byte_frames() -> None:
    """Frames back to back as a modem delivers them: after the first, each arrives with the
    previous frame's 8 guard and pad bits pending, which the straight line steps over."""
    rng = random.Random(15)
    values = [v for _, v in FRAMES]
    stream = [
        damaged(rng.choice(values), rng, rng.randrange(4), rng.randrange(3)) for _ in range(60)
    ]
    chunks = [frame_bytes(v) for v in stream]
    events, spy = feed_both(chunks)
    expected_accepts = [d for d in map(reference, stream) if isinstance(d, Decoded)]
    assert len(spy.taken) == len(expected_accepts) > 10
    assert [e.decoded for e in events if isinstance(e, Accepted)] == expected_accepts
    # The whole stream in one piece, and cut at odd places, gives the same events.
    whole = b"".join(chunks)
    assert feed_both([whole])[0] == events
    assert feed_both([whole[i : i + 17] for i in range(0, len(whole), 17)])[0] == events


SYNC_TEXT = format(0xAAAA7C, "024b")


@pytest.mark.parametrize(
    "lead",
    ["1", "10", "1010101", "10101010" * 2, "0" * 8, "1" * 8, SYNC_TEXT[:22], SYNC_TEXT[:-1]],
    ids=repr,
)
def test_pending_bits_before_an_aligned_frame(lead: str) -> None:
    """Bits already pending when a byte-aligned frame arrives: a sync candidate among them
    sends the feed through the bit-level path, none lets the straight line take the frame."""
    for _, value in FRAMES[:9]:
        data = frame_bytes(value)
        head = lead + format(value >> (FRAME_BITS - SYNC_BITS), f"0{SYNC_BITS}b")
        candidate = any(
            (int(head[p : p + SYNC_BITS], 2) ^ 0xAAAA7C).bit_count() <= 2 for p in range(len(lead))
        )
        events, spy = feed_both([lead, data])
        assert spy.taken == ([] if candidate else [reference(value)])
        assert Accepted(len(lead), reference(value)) in events  # type: ignore[arg-type]
    assert candidate is lead.startswith(SYNC_TEXT[:20])


def test_every_reject_reason_is_compared() -> None:
    """Every reason of RejectReason: the stream reasons come out of both paths alike; a frame
    out of sync (NO_SYNC for decode_frame) gives neither path an event at its offset; bad
    input to feed_bits (MALFORMED) is refused by both."""
    seen: set[RejectReason] = set()
    rng = random.Random(3)
    for _, value in FRAMES:
        for codeword_errors in range(4):
            received = damaged(value, rng, codeword_errors, 0)
            events, _ = feed_both([frame_bytes(received)])
            seen |= {e.error.reason for e in events if isinstance(e, Rejected)}
    no_sync = damaged(FRAMES[0][1], rng, 0, 3)
    assert reference(no_sync) == DecodeError(
        RejectReason.NO_SYNC,
        "preamble + delimiter differ from the sync word in 3 bits (at most 2 tolerated)",
    )
    events, spy = feed_both([frame_bytes(no_sync)])
    assert not any(e.offset == 0 for e in events) and spy.taken == []
    seen.add(RejectReason.NO_SYNC)
    errors = []
    for receiver in (FrameReceiver(), FrameReceiver(fast_path=False)):
        with pytest.raises(DecodeError) as err:
            receiver.feed_bits("0120")
        errors.append(err.value)
    assert errors[0] == errors[1] and errors[0].reason is RejectReason.MALFORMED
    seen.add(RejectReason.MALFORMED)
    # other_vehicle is an addressed vehicle's (codec._address_sync): never this receiver's
    assert seen == set(RejectReason) - {RejectReason.OTHER_VEHICLE}


def test_shift_distance_is_the_delimiters_guarantee() -> None:
    # scripts/choose_delimiter.py: every shift by 1..15 bits differs in at least 4 known bits.
    assert SHIFT_DISTANCE == shift_distance(8) >= shift_distance(15) == 4


def test_straight_line_is_built_once_per_dictionary() -> None:
    line = straight_line(DICTIONARY)
    assert straight_line(DICTIONARY) is line is DICTIONARY.straight_line
    assert FrameReceiver()._straight is line


def test_accepted_records_are_ordinary_records() -> None:
    """The straight line fills its records through their slots: they compare, hash, repr and
    refuse assignment like records made by their constructors."""
    enc = encode_frame("circle", speed=0.5, depth=2, radius=5, direction="cw")
    (event,) = FrameReceiver().feed_bytes(enc.frame.to_bytes())
    made = Accepted(0, Decoded(Command(enc.command.pattern, enc.command.codes), 0, 0))
    assert event == made and hash(event) == hash(made) and repr(event) == repr(made)
    assert isinstance(event, Accepted)
    with pytest.raises(AttributeError):
        event.decoded.command.codes = ()


def test_random_streams_in_random_byte_chunks() -> None:
    """Noise, frames at any bit offset (some byte-aligned, some damaged) and chunks of any
    size: the two receivers never differ, and the straight line takes part."""
    rng = random.Random(2026)
    values = [v for _, v in FRAMES]
    taken = 0
    for _ in range(150):
        bits = ""
        for _ in range(rng.randint(1, 4)):
            gap = rng.choice([0, 0, 8, 16, rng.randrange(0, 90)])
            bits += format(rng.getrandbits(gap), f"0{gap}b") if gap else ""
            received = damaged(rng.choice(values), rng, rng.randrange(4), rng.randrange(4))
            bits += format(received << 4, f"0{8 * FRAME_BYTES}b")
        data = as_bytes(bits)
        cuts = sorted(rng.sample(range(1, len(data)), rng.randrange(0, 4)))
        chunks: list[bytes | str] = [
            data[a:b] for a, b in zip([0, *cuts], [*cuts, len(data)], strict=True)
        ]
        _, spy = feed_both(chunks, tolerance=rng.randrange(5))
        taken += len(spy.taken)
    assert taken > 0


def test_a_dictionary_with_too_many_field_sets_takes_the_bit_level_path() -> None:
    """Nine distinct sets of valid codes (plus "unused: zero") do not fit the one-byte field
    classes: the straight line declines every frame, and the events are still the same."""
    fields = tuple(
        Field(f"f{n}", f"f{n}", "", NumericScale((Segment("0", "1", n),), integer=True), 1, "")
        for n in range(2, 11)
    )
    wide = CommandDictionary(
        (
            Pattern(0, "first", "first", fields[:5], ""),
            Pattern(1, "second", "second", fields[5:], ""),
        )
    )
    assert straight_line(wide) is _decline
    for name, pattern in wide.items():
        value = encode_frame(name, pattern.defaults, dictionary=wide).frame.value
        for errors in range(3):
            data = frame_bytes(damaged(value, random.Random(errors), errors, 0))
            fast = FrameReceiver(dictionary=wide)
            slow = FrameReceiver(dictionary=wide, fast_path=False)
            events = fast.feed_bytes(data)
            assert events == slow.feed_bytes(data)
            assert isinstance(events[0], Accepted) and events[0].decoded.corrected == errors


def test_a_dictionary_pickles_without_its_straight_line() -> None:
    FrameReceiver().feed_bytes(frame_bytes(FRAMES[0][1]))
    assert DICTIONARY.straight_line is not None
    copy = pickle.loads(pickle.dumps(DICTIONARY))
    assert copy.straight_line is None and dict(copy) == dict(DICTIONARY)
    data = frame_bytes(FRAMES[0][1])
    assert FrameReceiver(dictionary=copy).feed_bytes(data) == FrameReceiver().feed_bytes(data)


@pytest.mark.slow  # 65535 frames through the bit-level path, ~1 s
def test_every_remainder_decides_as_the_bit_level_path() -> None:
    """The straight line writes the closed form and the CRC check out: for every non-zero
    codeword remainder, the frame of the all-zero message (straight, every code 0, a valid
    command) with those parity bits gets the same events on both paths; and every 1- and
    2-bit error pattern of a codeword is corrected alike."""
    clean = frame_of(Command(DICTIONARY["straight"], (0, 0, 0, 0))).value
    assert clean >> 4 & ((1 << 72) - 1) == 0  # message 0, parity 0
    straight = straight_line(DICTIONARY)
    taken = 0
    for syndrome in range(1, 1 << 16):
        data = ((clean | syndrome << 4) << 4).to_bytes(FRAME_BYTES, "big")
        fast = straight(data, 2)
        slow = FrameReceiver(fast_path=False).feed_bytes(data)
        if fast is None:
            assert not slow or not isinstance(slow[0], Accepted) or slow[0].offset != 0
        else:
            taken += 1
            assert slow and isinstance(slow[0], Accepted) and slow[0].decoded == fast, syndrome
    assert taken >= 16 + 16 * 15 // 2  # at least the errors in the parity bits alone
    value = frame_of(random_command(random.Random(3))).value
    for i in range(72):
        for j in range(i, 72):
            damaged = value ^ (1 << (4 + i)) ^ (1 << (4 + j) if j != i else 0)
            data = (damaged << 4).to_bytes(FRAME_BYTES, "big")
            fast = straight(data, 2)
            assert fast is not None and fast.corrected == (1 if i == j else 2), (i, j)
            (event,) = FrameReceiver(fast_path=False).feed_bytes(data)
            assert isinstance(event, Accepted) and event.decoded == fast


@pytest.mark.parametrize(("value"), [v for _, v in FRAMES], ids=[n for n, _ in FRAMES])
def test_receive_frame_is_a_new_receivers_events(value: int) -> None:
    """``receive_frame`` (the agent's call) gives exactly a new receiver's events for the
    buffer: 13 bytes accepted or rejected, with 0-3 codeword and 0-3 header errors, at bit
    offsets 0-7, shorter and longer buffers, and the other byte-like types."""
    rng = random.Random(value)
    taken = 0
    for codeword_errors in range(4):
        for header_errors in range(4):
            for offset in range(8):
                received = damaged(value, rng, codeword_errors, header_errors)
                lead = format(rng.getrandbits(offset), f"0{offset}b") if offset else ""
                data = as_bytes(lead + format(received, f"0{FRAME_BITS}b"))
                for buffer in (data, data[:12], data + data, bytearray(data), memoryview(data)):
                    got = receive_frame(buffer)
                    assert got == FrameReceiver().feed_bytes(buffer)
                    assert [type(e) for e in got] == [
                        type(e) for e in FrameReceiver(fast_path=False).feed_bytes(buffer)
                    ]
                taken += len(data) == FRAME_BYTES and isinstance(reference(received), Decoded)
    assert taken > 0 or isinstance(reference(value), DecodeError)  # accepted ones were fed
