"""Frame sync on a continuous bit stream: offsets, noise, damage, and chunking invariance."""

from __future__ import annotations

import itertools
import random
from dataclasses import dataclass

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from codec import (
    CODE,
    CODEWORD_BITS,
    DEFAULT_SYNC_TOLERANCE,
    FRAME_BITS,
    GUARD_BITS,
    SYNC_BITS,
    UNCORRECTABLE,
    Accepted,
    Command,
    Decoded,
    DecodeError,
    FrameReceiver,
    RejectReason,
    frame_of,
)
from tests.codec.helpers import (
    accepted,
    chunked,
    crafted_frame,
    feed_pieces,
    frame_bits,
    random_bits,
    random_command,
    rejected,
    summary,
    sync_distance,
)

Summary = tuple[object, ...]


@dataclass
class Stream:
    """A bit stream and the events a correct receiver reports for it."""

    bits: str = ""
    expected: list[Summary] | None = None
    frame_offsets: list[int] | None = None

    def add_noise(self, rng: random.Random, n: int) -> None:
        self.bits += random_bits(rng, n)

    def add_frame(
        self,
        command: Command,
        *,
        header: tuple[int, ...] = (),
        codeword: tuple[int, ...] = (),
        guard: bool = True,
        accept: bool = True,
    ) -> int:
        if self.expected is None:
            self.expected, self.frame_offsets = [], []
        assert self.frame_offsets is not None
        offset = len(self.bits)
        self.frame_offsets.append(offset)
        self.bits += frame_bits(command, header=header, codeword=codeword, guard=guard)
        if accept:
            self.expected.append(("accepted", offset, command, len(codeword), len(header)))
        return offset


def uncorrectable(rng: random.Random, command: Command, weight: int = 3) -> tuple[int, ...]:
    """Codeword error positions that the BCH decoder reports as uncorrectable."""
    cw = frame_of(command).codeword
    while True:
        positions = tuple(rng.sample(range(CODEWORD_BITS), weight))
        error = sum(1 << p for p in positions)
        if CODE.decode(cw ^ error)[1] == UNCORRECTABLE:
            return positions


def events_of(bits: str, **kwargs: int) -> list[Summary]:
    return feed_pieces([bits], **kwargs)


def assert_finds(stream: Stream, events: list[Summary]) -> None:
    """Every expected frame accepted, nothing else accepted, no rejection at a frame."""
    assert stream.expected is not None and stream.frame_offsets is not None
    assert accepted(events) == stream.expected
    good = {s[1] for s in stream.expected}
    for event in rejected(events):
        assert event[1] not in good


# --- basics ------------------------------------------------------------------------------------


def test_one_frame_alone(rng: random.Random) -> None:
    command = random_command(rng)
    receiver = FrameReceiver()
    assert receiver.sync_tolerance == DEFAULT_SYNC_TOLERANCE == 2
    events = receiver.feed_bits(frame_of(command).bits)
    assert events == [Accepted(0, Decoded(command, 0, 0))]
    assert receiver.position == FRAME_BITS
    assert receiver.pending_bits == GUARD_BITS  # only the guard bits are left


def test_frame_without_guard_at_the_very_end(rng: random.Random) -> None:
    command = random_command(rng)
    bits = random_bits(rng, 13) + frame_bits(command, guard=False)
    assert events_of(bits) == [("accepted", 13, command, 0, 0)]


@pytest.mark.parametrize(
    "offset", [0, 1, 2, 3, 5, 7, 8, 9, 15, 16, 17, 23, 24, 31, 32, 64, 99, 257]
)
def test_frame_at_any_offset(rng: random.Random, offset: int) -> None:
    for _ in range(5):
        stream = Stream()
        stream.add_noise(rng, offset)
        stream.add_frame(random_command(rng))
        stream.add_noise(rng, rng.randrange(0, 80))
        assert_finds(stream, events_of(stream.bits))


IDLE = {
    "zeros": "0" * 64,
    "ones": "1" * 64,
    "alternating 10": "10" * 32,
    "alternating 01": "01" * 32,
    "long preamble": "10" * 31 + "1",  # odd length: the frame's preamble continues it
    "delimiter-like": "01111100" * 8,
    "near sync word": "1010101010101010" + "01100000",  # 3 bits off: not a candidate
}


@pytest.mark.parametrize("idle", list(IDLE.values()), ids=list(IDLE))
def test_structured_noise_before_and_after(rng: random.Random, idle: str) -> None:
    command = random_command(rng)
    for lead in (idle, idle[:-1], idle[: len(idle) // 2]):
        bits = lead + frame_of(command).bits + idle
        assert events_of(bits) == [("accepted", len(lead), command, 0, 0)]


@pytest.mark.parametrize("wrong", [0, 1, 2])
def test_false_sync_does_not_swallow_the_next_frame(rng: random.Random, wrong: int) -> None:
    """A sync word in the noise (0-2 bits off) is tried, rejected, and the search resumes in
    time for a real frame that starts anywhere inside its would-be codeword."""
    false_sync = format(0xAAAA7C ^ sum(1 << p for p in rng.sample(range(24), wrong)), "024b")
    for gap in (0, 1, 2, 8, 9, 40, 71, 72, 80):
        command = random_command(rng)
        bits = "0" * 10 + false_sync + random_bits(rng, gap) + frame_of(command).bits
        events = events_of(bits)
        assert events[0][:2] == ("rejected", 10)
        assert accepted(events) == [("accepted", 34 + gap, command, 0, 0)]


def test_noise_before_between_and_after(rng: random.Random) -> None:
    for _ in range(20):
        stream = Stream()
        for _ in range(6):
            stream.add_noise(rng, rng.randrange(0, 200))
            stream.add_frame(random_command(rng), guard=rng.random() < 0.5)
        stream.add_noise(rng, rng.randrange(0, 200))
        events = events_of(stream.bits)
        assert_finds(stream, events)


@pytest.mark.parametrize("guard", [True, False], ids=["with guard", "no guard"])
def test_back_to_back_frames(rng: random.Random, guard: bool) -> None:
    stream = Stream()
    stream.add_noise(rng, 11)
    for _ in range(8):
        stream.add_frame(random_command(rng), guard=guard)
    events = events_of(stream.bits)
    assert events == stream.expected
    step = FRAME_BITS if guard else FRAME_BITS - GUARD_BITS
    assert stream.frame_offsets == list(range(11, 11 + 8 * step, step))


def test_back_to_back_identical_frames(rng: random.Random) -> None:
    command = random_command(rng)
    bits = frame_of(command).bits[:96] * 5
    assert events_of(bits) == [("accepted", 96 * i, command, 0, 0) for i in range(5)]


# --- errors in the header and the codeword -------------------------------------------------------


def test_every_single_header_error_is_tolerated(rng: random.Random) -> None:
    for position in range(SYNC_BITS):
        stream = Stream()
        stream.add_noise(rng, 40)
        stream.add_frame(random_command(rng), header=(position,), codeword=(position,))
        stream.add_noise(rng, 40)
        assert_finds(stream, events_of(stream.bits))


def test_every_pair_of_header_errors_is_tolerated(rng: random.Random) -> None:
    prefix = random_bits(rng, 40)
    command = random_command(rng)
    for pair in itertools.combinations(range(SYNC_BITS), 2):
        bits = prefix + frame_bits(command, header=pair) + "0000"
        assert accepted(events_of(bits)) == [("accepted", 40, command, 0, 2)], pair


def test_three_header_errors_lose_only_that_frame(rng: random.Random) -> None:
    for _ in range(30):
        stream = Stream()
        stream.add_noise(rng, 30)
        header = tuple(rng.sample(range(SYNC_BITS), 3))
        lost = stream.add_frame(random_command(rng), header=header, accept=False)
        stream.add_noise(rng, rng.randrange(0, 30))
        stream.add_frame(random_command(rng))
        events = events_of(stream.bits)
        assert_finds(stream, events)
        assert lost not in [s[1] for s in accepted(events)]


@pytest.mark.parametrize("tolerance", [0, 1, 2, 3, 4])
def test_sync_tolerance_setting(rng: random.Random, tolerance: int) -> None:
    """Up to ``tolerance`` wrong header bits are accepted, more are not.

    The errors are put in the first preamble bits: beyond 2 errors, errors elsewhere can make
    a copy of the header shifted by 2, 6 or 8 bits look closer than the real one (the
    delimiter keeps those shifts 5 bits away), which the default tolerance of 2 rules out.
    """
    command = random_command(rng)
    for wrong in range(6):
        bits = "0" * 50 + frame_bits(command, header=tuple(range(wrong))) + "0" * 50
        found = accepted(events_of(bits, sync_tolerance=tolerance))
        if wrong <= tolerance:
            assert found == [("accepted", 50, command, 0, wrong)]
        else:
            assert found == []


def test_lookahead_prefers_the_best_aligned_offset(rng: random.Random) -> None:
    """With a tolerance of 4, the window 2 bits early can be a candidate (the delimiter keeps
    it 5 bits away, one header error makes it 4); the receiver must take the real, better
    aligned frame 2 bits later without trying the early one."""
    command = random_command(rng)
    bits = "0000000010" + frame_bits(command, header=(14,)) + "0" * 30
    early = int(bits[8:32], 2)
    assert sync_distance(early) == 4
    events = events_of(bits, sync_tolerance=4)
    assert events == [("accepted", 10, command, 0, 1)]


@pytest.mark.parametrize("tolerance", [-1, 5, 24])
def test_sync_tolerance_range(tolerance: int) -> None:
    with pytest.raises(ValueError):
        FrameReceiver(sync_tolerance=tolerance)


def test_correctable_codeword_errors_are_reported(rng: random.Random) -> None:
    stream = Stream()
    for _ in range(30):
        stream.add_noise(rng, rng.randrange(0, 20))
        n = rng.randrange(3)
        stream.add_frame(
            random_command(rng),
            header=tuple(rng.sample(range(SYNC_BITS), rng.randrange(3))),
            codeword=tuple(rng.sample(range(CODEWORD_BITS), n)),
        )
    assert_finds(stream, events_of(stream.bits))


def test_damaged_codeword_is_rejected_and_the_next_frame_found(rng: random.Random) -> None:
    for gap in (0, 1, 17):
        stream = Stream()
        stream.add_noise(rng, 25)
        bad = random_command(rng)
        bad_offset = stream.add_frame(bad, codeword=uncorrectable(rng, bad), accept=False)
        stream.add_noise(rng, gap)
        stream.add_frame(random_command(rng))
        events = events_of(stream.bits)
        assert_finds(stream, events)
        reject = [s for s in rejected(events) if s[1] == bad_offset]
        assert len(reject) == 1
        assert reject[0][2] is RejectReason.UNCORRECTABLE


def test_heavily_damaged_frames_are_never_accepted(rng: random.Random) -> None:
    """200 frames with 3 to 8 wrong codeword bits the decoder cannot correct, between good
    ones: each is one Rejected at its offset, never an Accepted."""
    stream = Stream()
    bad_offsets = []
    for _ in range(200):
        stream.add_noise(rng, rng.randrange(0, 40))
        bad = random_command(rng)
        errors = uncorrectable(rng, bad, weight=rng.randint(3, 8))
        bad_offsets.append(stream.add_frame(bad, codeword=errors, accept=False))
        stream.add_frame(random_command(rng), guard=False)
    events = events_of(stream.bits)
    assert_finds(stream, events)
    reasons = {s[1]: s[2] for s in rejected(events)}
    for offset in bad_offsets:
        assert reasons[offset] is RejectReason.UNCORRECTABLE


@pytest.mark.parametrize(
    ("value", "reason"),
    [
        (crafted_frame(9, ()), RejectReason.UNKNOWN_PATTERN),
        (crafted_frame(3, (50, 20, 100, 0), crc_xor=1), RejectReason.CRC_MISMATCH),
        (crafted_frame(0, (50, 20, 60, 250)), RejectReason.FIELD_OUT_OF_RANGE),
        (crafted_frame(15, (0, 0, 1)), RejectReason.UNUSED_FIELD_SET),
    ],
    ids=["unknown pattern", "crc", "field", "unused"],
)
def test_invalid_frames_in_a_stream(rng: random.Random, value: int, reason: RejectReason) -> None:
    good = random_command(rng)
    bits = random_bits(rng, 33) + format(value, "0100b") + frame_of(good).bits
    events = events_of(bits)
    assert events[0][:3] == ("rejected", 33, reason)
    assert accepted(events) == [("accepted", 133, good, 0, 0)]


# --- chunking -------------------------------------------------------------------------------------


def mixed_stream(rng: random.Random) -> Stream:
    """Noise, good frames, header and codeword errors, a damaged frame, back-to-back frames."""
    stream = Stream()
    stream.add_noise(rng, 57)
    stream.add_frame(random_command(rng))
    stream.add_frame(random_command(rng), guard=False)
    stream.add_noise(rng, 3)
    stream.add_frame(random_command(rng), header=(0, 23), codeword=(1, 70))
    stream.add_noise(rng, 120)
    bad = random_command(rng)
    stream.add_frame(bad, codeword=uncorrectable(rng, bad), accept=False)
    stream.add_frame(random_command(rng), header=(10,), codeword=(33,), guard=False)
    stream.add_frame(random_command(rng))
    stream.add_noise(rng, 41)
    return stream


def test_chunking_gives_identical_events(rng: random.Random) -> None:
    stream = mixed_stream(rng)
    bits = stream.bits
    whole = events_of(bits)
    assert_finds(stream, whole)
    assert len(rejected(whole)) >= 1
    assert feed_pieces(list(bits)) == whole  # one bit at a time
    for _ in range(10):
        sizes = [rng.randint(1, 130) for _ in range(rng.randint(1, 8))]
        assert feed_pieces(chunked(bits, sizes)) == whole, sizes
    # Lists of ints, in odd chunks.
    receiver = FrameReceiver()
    events = []
    for piece in chunked(bits, [7, 1, 29]):
        events += receiver.feed_bits([int(c) for c in piece])
    assert [summary(e) for e in events] == whole
    assert receiver.position == len(bits)


def test_long_stream_in_one_feed(rng: random.Random) -> None:
    """Thousands of bits at once give the same events as bit-by-bit and chunked feeding."""
    stream = Stream()
    for i in range(40):
        stream.add_noise(rng, rng.randrange(0, 150))
        command = random_command(rng)
        if i % 7 == 3:
            stream.add_frame(command, codeword=uncorrectable(rng, command), accept=False)
        else:
            stream.add_frame(command, header=(i % 24,), codeword=(i % 72,), guard=i % 2 == 0)
    bits = stream.bits
    assert len(bits) > 5000
    whole = events_of(bits)
    assert_finds(stream, whole)
    assert feed_pieces(list(bits)) == whole
    assert feed_pieces(chunked(bits, [1023, 1, 1025, 2048, 3])) == whole


def test_feed_bytes_matches_feed_bits(rng: random.Random) -> None:
    stream = mixed_stream(rng)
    bits = stream.bits + "0" * (-len(stream.bits) % 8)
    data = int(bits, 2).to_bytes(len(bits) // 8, "big")
    whole = events_of(bits)
    for size in (1, 2, 5, 13, len(data)):
        receiver = FrameReceiver()
        events = []
        for i in range(0, len(data), size):
            events += receiver.feed_bytes(data[i : i + size])
        assert [summary(e) for e in events] == whole
        assert receiver.position == len(bits)
    receiver = FrameReceiver()
    events = receiver.feed_bytes(bytearray(data[:20])) + receiver.feed_bytes(memoryview(data[20:]))
    assert [summary(e) for e in events] == whole


def test_partial_frame_waits_for_its_codeword(rng: random.Random) -> None:
    command = random_command(rng)
    bits = frame_of(command).bits
    receiver = FrameReceiver()
    assert receiver.feed_bits("0" * 20 + bits[:60]) == []
    assert receiver.position == 80
    assert receiver.pending_bits >= 60  # the header and part of the codeword are held
    assert receiver.feed_bits(bits[60:95]) == []
    assert receiver.feed_bits(bits[95:]) == [Accepted(20, Decoded(command, 0, 0))]
    assert receiver.position == 120


def test_noise_is_not_hoarded(rng: random.Random) -> None:
    receiver = FrameReceiver()
    for _ in range(100):
        receiver.feed_bits("0" * 100)
        assert receiver.pending_bits < SYNC_BITS + 8
    assert receiver.position == 10_000


@pytest.mark.parametrize(
    "bad", ["0120", "01x", "0b01", ["0", 1], [0, 2], [True, 0], [0.0], [None]], ids=repr
)
def test_feed_bits_refuses_non_bits_and_consumes_nothing(rng: random.Random, bad: object) -> None:
    command = random_command(rng)
    bits = frame_of(command).bits
    receiver = FrameReceiver()
    receiver.feed_bits(bits[:50])
    with pytest.raises(DecodeError) as err:
        receiver.feed_bits(bad)  # type: ignore[arg-type]
    assert err.value.reason is RejectReason.MALFORMED
    assert receiver.position == 50
    assert receiver.feed_bits(bits[50:]) == [Accepted(0, Decoded(command, 0, 0))]


def test_feed_bits_text_forms() -> None:
    receiver = FrameReceiver()
    assert receiver.feed_bits("") == []
    assert receiver.feed_bits([]) == []
    assert receiver.position == 0
    assert receiver.feed_bits("0101 0101_01") == []
    assert receiver.position == 10
    assert receiver.feed_bits(iter([1, 0, 1])) == []
    assert receiver.position == 13


# --- property: random layouts, random chunking ---------------------------------------------------


@st.composite
def layouts(draw: st.DrawFn) -> tuple[Stream, list[int]]:
    rng = random.Random(draw(st.integers(0, 2**32 - 1), label="seed"))
    stream = Stream()
    for _ in range(draw(st.integers(1, 4), label="frames")):
        stream.add_noise(rng, draw(st.integers(0, 120), label="noise"))
        header = draw(st.sets(st.integers(0, SYNC_BITS - 1), max_size=2), label="header")
        codeword = draw(st.sets(st.integers(0, CODEWORD_BITS - 1), max_size=2), label="codeword")
        stream.add_frame(
            random_command(rng),
            header=tuple(sorted(header)),
            codeword=tuple(sorted(codeword)),
            guard=draw(st.booleans(), label="guard"),
        )
    stream.add_noise(rng, draw(st.integers(0, 120), label="tail"))
    sizes = draw(st.lists(st.integers(1, 64), min_size=1, max_size=6), label="chunks")
    return stream, sizes


@settings(max_examples=150, deadline=None)
@given(layout=layouts())
def test_any_layout_any_chunking(layout: tuple[Stream, list[int]]) -> None:
    stream, sizes = layout
    whole = events_of(stream.bits)
    assert_finds(stream, whole)
    assert feed_pieces(chunked(stream.bits, sizes)) == whole
