"""The emulated ME channel: validation, timing, range, loss, bit errors and bursts."""

from __future__ import annotations

import math
import random

import pytest

import codec
from analysis.ber import wilson as wilson_interval
from sim.channel import ChannelConfig, ChannelStats, Delivery, MEChannel

#: Two-sided 99.9 % normal quantile: a correct channel fails a statistical check 1 run in 1000
#: (and the seeds are fixed, so a passing test keeps passing).
Z = 3.29
FRAME = codec.FRAME_BITS


def wilson(k: int, n: int, z: float = Z) -> tuple[float, float]:
    """Wilson score interval for a binomial proportion k/n, at 99.9 % by default."""
    return wilson_interval(k, n, z)


def random_frames(count: int, seed: int) -> list[int]:
    rng = random.Random(seed)
    return [rng.getrandbits(FRAME) for _ in range(count)]


# --- configuration ---------------------------------------------------------------------------


def test_defaults() -> None:
    cfg = ChannelConfig()
    assert cfg.bitrate_bps == 36_000 == codec.DEFAULT_BITRATE_BPS
    assert cfg.range_m == 730.0
    assert (cfg.ber, cfg.burst_rate, cfg.loss, cfg.delay_s) == (0.0, 0.0, 0.0, 0.0)
    assert cfg.burst_length_bits == 8


@pytest.mark.parametrize(
    ("field", "value", "allowed"),
    [
        ("bitrate_bps", 0.0, "(0, inf)"),
        ("bitrate_bps", -9600.0, "(0, inf)"),
        ("bitrate_bps", math.inf, "(0, inf)"),
        ("bitrate_bps", math.nan, "(0, inf)"),
        ("range_m", -1.0, "[0, inf]"),
        ("range_m", math.nan, "[0, inf]"),
        ("ber", -1e-9, "[0, 0.5]"),
        ("ber", 0.51, "[0, 0.5]"),
        ("ber", math.nan, "[0, 0.5]"),
        ("burst_rate", -0.1, "[0, 1]"),
        ("burst_rate", 1.01, "[0, 1]"),
        ("burst_length_bits", 0, "[1, 100]"),
        ("burst_length_bits", 101, "[1, 100]"),
        ("loss", -0.5, "[0, 1]"),
        ("loss", 1.5, "[0, 1]"),
        ("delay_s", -0.001, "[0, inf)"),
        ("delay_s", math.inf, "[0, inf)"),
    ],
)
def test_out_of_range_values_name_the_field_and_range(
    field: str, value: float, allowed: str
) -> None:
    with pytest.raises(ValueError, match=field) as info:
        ChannelConfig(**{field: value})  # type: ignore[arg-type]
    assert allowed in str(info.value)


@pytest.mark.parametrize(
    ("field", "value"),
    [
        ("ber", "0.1"),
        ("loss", None),
        ("burst_rate", True),
        ("burst_length_bits", 8.0),
        ("burst_length_bits", True),
    ],
)
def test_wrong_types_are_refused(field: str, value: object) -> None:
    with pytest.raises(ValueError, match=field):
        ChannelConfig(**{field: value})  # type: ignore[arg-type]


def test_edge_values_are_accepted() -> None:
    ChannelConfig(ber=0.5, burst_rate=1.0, loss=1.0, burst_length_bits=1, range_m=0.0)
    ChannelConfig(burst_length_bits=100, range_m=math.inf, bitrate_bps=1, delay_s=3.0)


def test_replace_revalidates() -> None:
    import dataclasses

    with pytest.raises(ValueError, match="ber"):
        dataclasses.replace(ChannelConfig(), ber=0.7)


# --- timing ----------------------------------------------------------------------------------


def test_airtime_matches_the_codec() -> None:
    channel = MEChannel()
    assert channel.airtime_s() == 100 / 36_000 == codec.airtime_s()
    assert ChannelConfig(bitrate_bps=9600).airtime_s(FRAME) == codec.airtime_s(9600, FRAME)
    assert channel.airtime_s(13) == codec.airtime_s(bits=13)


def test_zero_ber_delivers_exactly_and_on_time() -> None:
    channel = MEChannel(seed=3)
    for i, bits in enumerate(random_frames(200, seed=1)):
        t_s = 0.5 * i
        d = channel.transmit(bits, FRAME, t_s, distance_m=100.0)
        assert d == Delivery(bits, FRAME, t_s + 100 / 36_000, 0, False)
    s = channel.stats
    assert (s.frames_in, s.frames_delivered, s.bits_sent, s.bits_flipped) == (200, 200, 20_000, 0)
    assert channel.measured_ber == 0.0


def test_delay_is_added_to_the_airtime() -> None:
    channel = MEChannel(ChannelConfig(delay_s=0.25, bitrate_bps=1000))
    d = channel.transmit(1, FRAME, 10.0, 0.0)
    assert d is not None
    assert d.arrive_t_s == pytest.approx(10.0 + 0.1 + 0.25, abs=1e-12)


# --- range and loss --------------------------------------------------------------------------


def test_range_cut_off() -> None:
    channel = MEChannel(ChannelConfig(range_m=730.0))
    bits = random_frames(1, seed=2)[0]
    delivered = channel.transmit(bits, FRAME, 0.0, 729.0)
    assert delivered is not None
    assert delivered.bits == bits
    assert channel.transmit(bits, FRAME, 0.0, 730.0) is not None  # at the range: still heard
    assert channel.transmit(bits, FRAME, 0.0, 731.0) is None
    s = channel.stats
    assert (s.frames_in, s.frames_delivered, s.frames_lost_range, s.frames_lost_random) == (
        3,
        2,
        1,
        0,
    )


def test_random_loss_rate_is_within_its_confidence_interval() -> None:
    loss = 0.3
    n = 20_000
    channel = MEChannel(ChannelConfig(loss=loss), seed=11)
    frames = random_frames(n, seed=12)
    lost = 0
    for bits in frames:
        d = channel.transmit(bits, FRAME, 0.0, 10.0)
        if d is None:
            lost += 1
        else:
            assert d.bits == bits  # loss alone never corrupts
    lo, hi = wilson(lost, n)
    assert lo <= loss <= hi
    assert 0.29 < lost / n < 0.31  # the interval is narrow enough to mean something
    s = channel.stats
    assert (s.frames_lost_random, s.frames_delivered, s.frames_lost_range) == (lost, n - lost, 0)
    assert s.bits_sent == (n - lost) * FRAME  # lost frames expose no bits


def test_loss_one_loses_everything() -> None:
    channel = MEChannel(ChannelConfig(loss=1.0))
    assert all(channel.transmit(0, FRAME, 0.0, 0.0) is None for _ in range(100))


# --- independent bit errors ------------------------------------------------------------------


@pytest.mark.parametrize(("ber", "frames"), [(1e-3, 20_000), (1e-2, 5_000), (1e-1, 2_000)])
def test_measured_ber_is_within_its_confidence_interval(ber: float, frames: int) -> None:
    channel = MEChannel(ChannelConfig(ber=ber), seed=int(1 / ber))
    flipped = 0
    for bits in random_frames(frames, seed=5):
        d = channel.transmit(bits, FRAME, 0.0, 1.0)
        assert d is not None
        assert d.flipped == (d.bits ^ bits).bit_count()
        assert not d.burst
        flipped += d.flipped
    n = frames * FRAME
    lo, hi = wilson(flipped, n)
    assert lo <= ber <= hi
    assert hi - lo < 0.2 * ber  # at least ~1000 errors: the check has teeth
    s = channel.stats
    assert (s.bits_sent, s.bits_flipped) == (n, flipped)
    assert channel.measured_ber == s.measured_ber == flipped / n


def test_half_ber_is_a_coin_per_bit() -> None:
    channel = MEChannel(ChannelConfig(ber=0.5), seed=9)
    for _ in range(500):
        channel.transmit(0, FRAME, 0.0, 0.0)
    s = channel.stats
    lo, hi = wilson(s.bits_flipped, s.bits_sent)
    assert lo <= 0.5 <= hi


def test_errors_hit_every_bit_position_evenly() -> None:
    """No off-by-one at either end of the frame: each position flips about as often."""
    channel = MEChannel(ChannelConfig(ber=0.1), seed=21)
    counts = [0] * FRAME
    frames = 3_000
    for _ in range(frames):
        d = channel.transmit(0, FRAME, 0.0, 0.0)
        assert d is not None
        assert d.bits >> FRAME == 0
        for pos in range(FRAME):
            counts[pos] += (d.bits >> (FRAME - 1 - pos)) & 1
    for count in counts:
        lo, hi = wilson(count, frames, z=4.0)  # 100 positions: a wider interval each
        assert lo <= 0.1 <= hi


def test_short_messages_and_the_msb_convention() -> None:
    channel = MEChannel(ChannelConfig(ber=0.3), seed=4)
    for _ in range(200):
        d = channel.transmit(0b101, 3, 0.0, 0.0)
        assert d is not None
        assert 0 <= d.bits < 8
        assert d.n_bits == 3


# --- bursts ----------------------------------------------------------------------------------


def test_bursts_stay_within_a_window_of_burst_length_bits() -> None:
    length = 8
    channel = MEChannel(ChannelConfig(burst_rate=1.0, burst_length_bits=length), seed=8)
    firsts: set[int] = set()
    lasts: set[int] = set()
    flipped = 0
    frames = 3_000
    for bits in random_frames(frames, seed=9):
        d = channel.transmit(bits, FRAME, 0.0, 0.0)
        assert d is not None
        assert d.burst
        mask = d.bits ^ bits
        flipped += d.flipped
        if mask:
            first = FRAME - mask.bit_length()  # wire position of the first flipped bit
            last = FRAME - 1 - ((mask & -mask).bit_length() - 1)
            assert last - first < length
            firsts.add(first)
            lasts.add(last)
    assert 0 in firsts  # a window can start at the first bit ...
    assert FRAME - 1 in lasts  # ... and end at the last
    assert channel.stats.bursts == frames
    lo, hi = wilson(flipped, frames * length)  # each bit of the window flips with p = 0.5
    assert lo <= 0.5 <= hi


def test_burst_rate_is_within_its_confidence_interval() -> None:
    rate = 0.2
    n = 10_000
    channel = MEChannel(ChannelConfig(burst_rate=rate, burst_length_bits=12), seed=31)
    hit = 0
    for bits in random_frames(n, seed=32):
        d = channel.transmit(bits, FRAME, 0.0, 0.0)
        assert d is not None
        if d.burst:
            hit += 1
        else:
            assert d.bits == bits and d.flipped == 0
    lo, hi = wilson(hit, n)
    assert lo <= rate <= hi
    assert channel.stats.bursts == hit


def test_a_burst_longer_than_the_message_covers_it_only() -> None:
    channel = MEChannel(ChannelConfig(burst_rate=1.0, burst_length_bits=50), seed=1)
    masks = 0
    for _ in range(200):
        d = channel.transmit(0, 10, 0.0, 0.0)
        assert d is not None
        assert d.bits < 1 << 10
        masks |= d.bits
    assert masks == (1 << 10) - 1


def test_bursts_and_independent_errors_combine() -> None:
    channel = MEChannel(ChannelConfig(ber=0.01, burst_rate=0.5, burst_length_bits=16), seed=2)
    for _ in range(3_000):
        channel.transmit(0, FRAME, 0.0, 0.0)
    s = channel.stats
    # 1 % independent plus half the frames with ~8 of 100 bits: about 5 %
    expected = 0.01 + 0.5 * 8 / 100 * (1 - 2 * 0.01)
    lo, hi = wilson(s.bits_flipped, s.bits_sent)
    assert lo <= expected <= hi


# --- determinism and run-time changes ---------------------------------------------------------


def _run(seed: int) -> list[Delivery | None]:
    cfg = ChannelConfig(ber=0.02, burst_rate=0.3, loss=0.2)
    channel = MEChannel(cfg, seed=seed)
    return [channel.transmit(b, FRAME, float(i), 5.0) for i, b in enumerate(random_frames(300, 1))]


def test_same_seed_same_deliveries() -> None:
    assert _run(42) == _run(42)
    assert _run(42) != _run(43)


def test_config_changes_at_run_time() -> None:
    channel = MEChannel(ChannelConfig(ber=0.2), seed=0)
    for _ in range(50):
        channel.transmit(0, FRAME, 0.0, 0.0)
    assert channel.stats.bits_flipped > 0
    channel.set_config(ChannelConfig(ber=0.0))
    before = channel.stats.bits_flipped
    for bits in random_frames(50, seed=3):
        d = channel.transmit(bits, FRAME, 0.0, 0.0)
        assert d is not None and d.bits == bits
    assert channel.stats.bits_flipped == before  # counters carry on across the change
    channel.config = ChannelConfig(range_m=10.0)
    assert channel.config.range_m == 10.0
    assert channel.transmit(0, FRAME, 0.0, 11.0) is None
    with pytest.raises(TypeError):
        channel.set_config({"ber": 0.1})  # type: ignore[arg-type]


def test_stats_are_a_snapshot_and_can_be_reset() -> None:
    channel = MEChannel(ChannelConfig(ber=0.1), seed=0)
    channel.transmit(0, FRAME, 0.0, 0.0)
    snap = channel.stats
    snap.frames_in = 99
    assert channel.stats.frames_in == 1
    channel.reset_stats()
    assert channel.stats == ChannelStats()
    assert channel.measured_ber == 0.0


# --- packed frames and argument checks --------------------------------------------------------


def test_transmit_bytes_takes_the_first_100_bits_of_a_packed_frame() -> None:
    frame = codec.encode_frame("circle", speed=0.5, depth=2, radius=5, direction="cw").frame
    data = frame.to_bytes()
    assert len(data) == 13
    channel = MEChannel(seed=1)
    d = channel.transmit_bytes(data, 1.0, 50.0)
    assert d is not None
    assert d.bits == frame.value
    assert d.n_bits == FRAME
    assert d.to_bytes() == data
    assert d.arrive_t_s == 1.0 + codec.airtime_s()
    dirty = data[:-1] + bytes([data[-1] | 0x0F])  # the 4 pad bits are not on the wire
    d2 = channel.transmit_bytes(dirty, 1.0, 50.0)
    assert d2 is not None and d2.bits == frame.value
    with pytest.raises(ValueError, match="13 bytes"):
        channel.transmit_bytes(data + b"\x00", 1.0, 50.0)
    with pytest.raises(ValueError, match="13 bytes"):
        channel.transmit_bytes(data[:12], 1.0, 50.0)


def test_transmit_bytes_with_errors_matches_transmit() -> None:
    cfg = ChannelConfig(ber=0.05, burst_rate=0.5)
    a = MEChannel(cfg, seed=6)
    b = MEChannel(cfg, seed=6)
    for bits in random_frames(100, seed=7):
        packed = codec.Frame(bits).to_bytes()
        assert a.transmit_bytes(packed, 0.0, 0.0) == b.transmit(bits, FRAME, 0.0, 0.0)


@pytest.mark.parametrize(
    ("bits", "n_bits", "distance_m", "match"),
    [
        (0, 0, 0.0, "n_bits"),
        (1 << FRAME, FRAME, 0.0, "bits"),
        (-1, FRAME, 0.0, "bits"),
        (0, FRAME, -1.0, "distance_m"),
        (0, FRAME, math.nan, "distance_m"),
    ],
)
def test_bad_arguments_are_refused(bits: int, n_bits: int, distance_m: float, match: str) -> None:
    with pytest.raises(ValueError, match=match):
        MEChannel().transmit(bits, n_bits, 0.0, distance_m)
