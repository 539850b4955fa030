"""The emulated magnetoelectric (ME) link in front of a simulated vehicle's receiver.

One :class:`MEChannel` per vehicle. The surface station's transmitter hands it each frame as it
goes on the air; the channel decides whether the frame arrives, flips bits, and says when the
last bit reaches the vehicle::

    channel = MEChannel(ChannelConfig(ber=1e-3, loss=0.05), seed=7)
    delivery = channel.transmit(frame.value, 100, t_s=12.0, distance_m=140.0)
    if delivery is not None:
        receiver.feed(delivery.bits, at=delivery.arrive_t_s)

Everything is applied to all ``n_bits`` of the frame (preamble, delimiter, codeword and guard
bits alike), in this order:

1. **Range.** A frame sent further than ``range_m`` is lost (``frames_lost_range``). A frame at
   exactly ``range_m`` arrives. No random number is drawn.
2. **Random loss.** With probability ``loss`` the frame is lost (``frames_lost_random``): the
   receiver never syncs to it. One uniform draw when ``loss > 0``.
3. **Independent bit errors.** Each bit flips with probability ``ber`` independently. The gaps
   between errors are drawn geometrically (``floor(log(U) / log(1 - ber))`` with U uniform on
   (0, 1]), which is exact for any ``ber`` in (0, 0.5] and costs one draw per error plus one,
   instead of one draw per bit.
4. **Bursts.** With probability ``burst_rate`` a burst hits the frame (one draw when
   ``burst_rate > 0``). The model is a *contiguous run*, not a Gilbert-Elliott chain: a window
   of ``burst_length_bits`` consecutive bits, its start uniform over the positions where it fits
   wholly inside the frame (the whole frame if the frame is shorter), in which every bit flips
   with probability 0.5 (one ``getrandbits``). A burst may therefore, rarely (2^-L), flip
   nothing; ``Delivery.burst`` and ``bursts`` still count it. Burst errors are XORed with the
   independent ones, so a bit hit by both ends up correct.

The bits are a Python ``int`` with the first bit on the wire most significant, as
:attr:`codec.Frame.value`. The arrival time is ``t_s + n_bits / bitrate_bps + delay_s`` (end of
the last bit plus propagation and processing delay).

Deterministic: one :class:`random.Random` per channel, seeded at construction; the same seed,
config changes and calls give the same deliveries.
"""

from __future__ import annotations

import math
import random
from dataclasses import dataclass, replace

from codec import DEFAULT_BITRATE_BPS, FRAME_BITS, airtime_s
from sim._checks import in_range, non_negative, positive

__all__ = [
    "DEFAULT_RANGE_M",
    "MAX_BER",
    "ChannelConfig",
    "ChannelStats",
    "Delivery",
    "MEChannel",
]

#: The paper's ME link range (m).
DEFAULT_RANGE_M = 730.0
#: Independent bit errors above 0.5 are an inverted channel, not a noisier one.
MAX_BER = 0.5
#: The longest burst: one frame.
MAX_BURST_LENGTH_BITS = FRAME_BITS


@dataclass(frozen=True, slots=True)
class ChannelConfig:
    """Settings of the emulated ME link. Invalid values raise ``ValueError`` naming the field.

    ``range_m`` may be ``math.inf`` (no range limit).
    """

    #: Link bit rate (b/s), in (0, inf).
    bitrate_bps: float = DEFAULT_BITRATE_BPS
    #: Frames sent further than this are lost (m), in [0, inf].
    range_m: float = DEFAULT_RANGE_M
    #: Probability that each bit flips independently, in [0, 0.5].
    ber: float = 0.0
    #: Probability per frame that a burst hits it, in [0, 1].
    burst_rate: float = 0.0
    #: Length of the burst window (bits), an int in [1, 100].
    burst_length_bits: int = 8
    #: Probability that a frame is lost entirely, in [0, 1].
    loss: float = 0.0
    #: Propagation and processing delay added to the airtime (s), in [0, inf).
    delay_s: float = 0.0

    def __post_init__(self) -> None:
        positive("bitrate_bps", self.bitrate_bps)
        in_range("range_m", self.range_m, 0.0, math.inf, "[0, inf]")
        in_range("ber", self.ber, 0.0, MAX_BER, f"[0, {MAX_BER}]")
        in_range("burst_rate", self.burst_rate, 0.0, 1.0, "[0, 1]")
        length = self.burst_length_bits
        if isinstance(length, bool) or not isinstance(length, int):
            raise ValueError(f"burst_length_bits must be an int, got {length!r}")
        if not 1 <= length <= MAX_BURST_LENGTH_BITS:
            raise ValueError(
                f"burst_length_bits must be in [1, {MAX_BURST_LENGTH_BITS}], got {length!r}"
            )
        in_range("loss", self.loss, 0.0, 1.0, "[0, 1]")
        non_negative("delay_s", self.delay_s)

    def airtime_s(self, n_bits: int = FRAME_BITS) -> float:
        """Time on the air for ``n_bits`` at this bit rate (s)."""
        return airtime_s(self.bitrate_bps, n_bits)


@dataclass(frozen=True, slots=True)
class Delivery:
    """A frame as it reaches the receiver."""

    #: The received bits, first bit most significant.
    bits: int
    #: How many bits ``bits`` holds.
    n_bits: int
    #: When the last bit has arrived (s): send time + airtime + delay.
    arrive_t_s: float
    #: How many bits differ from those sent.
    flipped: int
    #: Whether a burst hit the frame (even one that happened to flip nothing).
    burst: bool

    def to_bytes(self) -> bytes:
        """The bits packed MSB first, zero-padded to whole bytes (13 bytes for a frame)."""
        n_bytes = (self.n_bits + 7) // 8
        return (self.bits << (n_bytes * 8 - self.n_bits)).to_bytes(n_bytes, "big")


@dataclass(slots=True)
class ChannelStats:
    """Counters since construction or :meth:`MEChannel.reset_stats`."""

    #: Frames handed to :meth:`MEChannel.transmit`.
    frames_in: int = 0
    #: Frames that arrived (possibly with errors).
    frames_delivered: int = 0
    #: Frames lost because the vehicle was out of range.
    frames_lost_range: int = 0
    #: Frames lost by the ``loss`` probability.
    frames_lost_random: int = 0
    #: Bits of the delivered frames (the bits exposed to errors).
    bits_sent: int = 0
    #: Bits flipped in the delivered frames (independent and burst errors).
    bits_flipped: int = 0
    #: Bursts that hit delivered frames.
    bursts: int = 0

    @property
    def measured_ber(self) -> float:
        """``bits_flipped / bits_sent``; 0.0 before any bit was delivered."""
        return self.bits_flipped / self.bits_sent if self.bits_sent else 0.0


class MEChannel:
    """One emulated ME link, seeded; see the module docstring for the model."""

    __slots__ = ("_config", "_inv_log_keep", "_rng", "_stats")

    def __init__(self, config: ChannelConfig | None = None, seed: int = 0) -> None:
        self._rng = random.Random(seed)
        self._stats = ChannelStats()
        self.set_config(config if config is not None else ChannelConfig())

    @property
    def config(self) -> ChannelConfig:
        return self._config

    @config.setter
    def config(self, config: ChannelConfig) -> None:
        self.set_config(config)

    def set_config(self, config: ChannelConfig) -> None:
        """Change the link's settings from the next frame on (the random stream continues)."""
        if not isinstance(config, ChannelConfig):
            raise TypeError(f"config must be a ChannelConfig, got {type(config).__name__}")
        self._config = config
        # 1 / log(1 - ber): turns a uniform draw into a geometric gap between bit errors.
        self._inv_log_keep = 1.0 / math.log1p(-config.ber) if config.ber > 0.0 else 0.0

    @property
    def stats(self) -> ChannelStats:
        """A snapshot of the counters (a copy: changing it does not change the channel's)."""
        return replace(self._stats)

    @property
    def measured_ber(self) -> float:
        """Bits flipped per bit delivered so far (0.0 before any delivery)."""
        return self._stats.measured_ber

    def reset_stats(self) -> None:
        self._stats = ChannelStats()

    def airtime_s(self, n_bits: int = FRAME_BITS) -> float:
        """Time on the air for ``n_bits`` at the current bit rate (s)."""
        return self._config.airtime_s(n_bits)

    def transmit(self, bits: int, n_bits: int, t_s: float, distance_m: float) -> Delivery | None:
        """Send ``n_bits`` bits (first bit most significant) at ``t_s`` over ``distance_m``.

        Returns what arrives, or ``None`` if the frame is lost (out of range or at random).
        """
        if n_bits < 1:
            raise ValueError(f"n_bits must be at least 1, got {n_bits}")
        if bits < 0 or bits >> n_bits:
            raise ValueError(f"bits must be a non-negative int of at most {n_bits} bits")
        if not distance_m >= 0.0:  # also refuses NaN
            raise ValueError(f"distance_m must be >= 0, got {distance_m!r}")
        cfg = self._config
        stats = self._stats
        rng = self._rng
        stats.frames_in += 1
        if distance_m > cfg.range_m:
            stats.frames_lost_range += 1
            return None
        if cfg.loss > 0.0 and rng.random() < cfg.loss:
            stats.frames_lost_random += 1
            return None

        errors = 0
        if cfg.ber > 0.0:
            # Geometric gaps: position of the next error after ``pos``. log1p(-u) with u in
            # [0, 1) is log(U) with U = 1 - u in (0, 1].
            inv = self._inv_log_keep
            log1p = math.log1p
            draw = rng.random
            pos = int(log1p(-draw()) * inv)
            while pos < n_bits:
                errors |= 1 << (n_bits - 1 - pos)
                pos += 1 + int(log1p(-draw()) * inv)
        burst = cfg.burst_rate > 0.0 and rng.random() < cfg.burst_rate
        if burst:
            length = min(cfg.burst_length_bits, n_bits)
            start = rng.randrange(n_bits - length + 1)  # first bit of the window
            errors ^= rng.getrandbits(length) << (n_bits - start - length)
            stats.bursts += 1

        flipped = errors.bit_count()
        stats.frames_delivered += 1
        stats.bits_sent += n_bits
        stats.bits_flipped += flipped
        arrive_t_s = t_s + cfg.airtime_s(n_bits) + cfg.delay_s
        return Delivery(bits ^ errors, n_bits, arrive_t_s, flipped, burst)

    def transmit_bytes(
        self, data: bytes, t_s: float, distance_m: float, n_bits: int = FRAME_BITS
    ) -> Delivery | None:
        """Send a packed frame: the first ``n_bits`` bits of ``data``, MSB first.

        ``data`` must be exactly ``ceil(n_bits / 8)`` bytes (13 for a frame); the pad bits at
        the end (4 for a frame) are not sent, so their value does not matter.
        """
        n_bytes = (n_bits + 7) // 8
        if len(data) != n_bytes:
            raise ValueError(f"data must be {n_bytes} bytes for {n_bits} bits, got {len(data)}")
        bits = int.from_bytes(data, "big") >> (n_bytes * 8 - n_bits)
        return self.transmit(bits, n_bits, t_s, distance_m)
