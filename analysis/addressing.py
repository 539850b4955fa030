"""Addressed frames, measured before chosen: how each way of addressing a vehicle on the shared
ME link lets a vehicle execute a frame meant for another, and what it costs
(``nemesys analyze addressing``; docs/protocol.md, "Addressing").

The designs (:data:`DESIGNS`), each a t = 2 BCH code over GF(2^8) with 16 parity bits behind
the 16-bit preamble and an 8-bit delimiter, 4 guard bits after:

* ``a``: per-vehicle delimiters alone, today's 72-bit codeword. Vehicle v's delimiter is
  0x7C XOR its [8, 4, 4] address word, so any two differ in 4 or 8 bits (the most 16 bytes
  can), and address 0 (all) keeps 0x7C.
* ``b76``: a 4-bit address inside the protected message, BCH(76, 60), CRC-4 over address and
  payload; its own delimiter (0x43).
* ``b80r``: BCH(80, 64), a 4-bit address and a reserved nibble that must be zero.
* ``b80h``: BCH(80, 64), the address as an [8, 4, 4] word (the address, then its check
  nibble): the codec's layout (:mod:`codec._address`).
* ``cseed``: the address folded into the CRC only (its seed): today's layout, the CRC-4
  computed over the (unsent) address and the payload.
* ``ccoset``: the address folded into the codeword (a per-vehicle coset): BCH(76, 60) whose 4
  address bits are never sent; the receiver puts its own back before decoding.

**The analytic figure.** The code is linear and the decoder bounded-distance, so what a
receiver makes of a corrupted frame depends only on the error pattern ``e``: it corrects to
the codeword ``sent + d``, where ``d = e + f`` and ``f`` is the correction (weight <= 2). The
frame is taken as addressed to this vehicle (or to all) exactly when ``d``'s *key* (its BCH
syndrome, CRC check, reserved bits and address-word bits, each linear in ``d``) equals a
target key fixed by the two addresses. So, with ``N(W, t)`` the number of weight-``W``
vectors of key ``t`` (counted exactly for ``W <= w_exact`` by meeting in the middle: the
lower and upper halves of ``d``'s positions with equal keys) and the error patterns within
distance 2 of each (:func:`reach`)::

    P(misaddressed) = P(sync) * sum_t sum_W N(W, t) * reach(W, p, n)

Weights above ``w_exact`` are estimated as random vectors (:func:`tail_count`); the dictionary's
checks are left out (an upper bound: they only reject more; the Monte Carlo, which has them,
reports both). The addressed vehicle loses its frame unless the sync holds and the codeword
has at most 2 errors.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from functools import cached_property
from typing import Final, Literal

import numpy as np
from numpy.typing import NDArray

from codec import (
    CRC_POLY,
    DEFAULT_BITRATE_BPS,
    DEFAULT_SYNC_TOLERANCE,
    DELIMITER,
    FLEET_DELIMITER,
    GUARD_BITS,
    MAX_ADDRESS,
    PAYLOAD_BITS,
    PREAMBLE,
    SYNC_BITS,
    BCHCode,
    address_word,
)
from codec._gf2 import poly_mod

#: The bit error rates of the comparison (the issue's and the research's).
BERS: Final = (1e-3, 1e-2, 3e-2, 5e-2)
#: Misaddressed acceptance required at BER 1e-2: 1e-8, and 400 times below the single-vehicle
#: frame's wrong-command rate (2.45e-6, docs/results.md), whichever is lower.
TODAYS_WRONG_COMMAND: Final = 2.45e-6
REQUIRED: Final = min(1e-8, TODAYS_WRONG_COMMAND / 400)
REQUIRED_AT_BER: Final = 1e-2
#: Weights counted exactly (above: :func:`tail_count`).
W_EXACT: Final = 8
CRC_BITS: Final = 4
PARITY_BITS: Final = 16

AddressMode = Literal["delimiter", "word", "crc", "coset"]


@dataclass(frozen=True)
class Design:
    """One way to address vehicles (see the module doc).

    Attributes:
        key: short name (``b80h``).
        label: what it is, for the table.
        mode: where the address goes: ``delimiter`` (the sync word), ``word`` (sent inside
            the BCH message), ``crc`` (unsent, in the CRC only), ``coset`` (unsent, in the BCH
            message and the CRC).
        word_bits: bits of the sent address word (0, 4, or 8 for the [8, 4, 4] word).
        reserved_bits: sent message bits that must be zero.
    """

    key: str
    label: str
    mode: AddressMode
    word_bits: int = 0
    reserved_bits: int = 0
    sync_tolerance: int = DEFAULT_SYNC_TOLERANCE
    _cache: dict[str, object] = field(default_factory=dict, compare=False, repr=False)

    @property
    def virtual_bits(self) -> int:
        """Address bits never sent (the ``crc`` and ``coset`` modes)."""
        return 4 if self.mode in ("crc", "coset") else 0

    @property
    def k_sent(self) -> int:
        """Message bits sent: address word, reserved, payload, CRC."""
        return self.word_bits + self.reserved_bits + PAYLOAD_BITS + CRC_BITS

    @cached_property
    def code(self) -> BCHCode:
        """The BCH code; in the ``coset`` mode its message starts with the unsent address."""
        return BCHCode(t=2, k=self.k_sent + (self.virtual_bits if self.mode == "coset" else 0))

    @property
    def n_sent(self) -> int:
        """Codeword bits on the wire."""
        return self.k_sent + PARITY_BITS

    @property
    def frame_bits(self) -> int:
        return SYNC_BITS + self.n_sent + GUARD_BITS

    def airtime_ms(self, bitrate_bps: float = DEFAULT_BITRATE_BPS) -> float:
        return 1e3 * self.frame_bits / bitrate_bps

    def word(self, address: int) -> int:
        """The sent address word of ``address`` (0 when there is none)."""
        if self.word_bits == 8:
            return address_word(address)
        return address if self.word_bits == 4 else 0

    def sync_word(self, address: int) -> int:
        """The 24-bit sync word of a frame to ``address``."""
        if self.mode == "delimiter":
            return (PREAMBLE << 8) | (DELIMITER ^ address_word(address))
        return (PREAMBLE << 8) | FLEET_DELIMITER

    # --- keys: every check after the correction, as one linear map --------------------------

    @property
    def key_shifts(self) -> tuple[int, int, int]:
        """Where the CRC check, the reserved bits and the address word sit in a key (the BCH
        syndrome is bits 0-15)."""
        return PARITY_BITS, PARITY_BITS + CRC_BITS, PARITY_BITS + CRC_BITS + self.reserved_bits

    def position_keys(self) -> NDArray[np.int64]:
        """The key of a single 1 at each sent codeword position (0: the last parity bit)."""
        crc_at, reserved_at, word_at = self.key_shifts
        payload_end = CRC_BITS + PAYLOAD_BITS  # message bits below the reserved ones
        keys = np.zeros(self.n_sent, dtype=np.int64)
        for i in range(self.n_sent):
            key = self.code.remainder(1 << i)
            j = i - PARITY_BITS  # message bit, 0 = the CRC's last
            if j >= 0:
                key |= poly_mod(1 << j, CRC_POLY) << crc_at  # the CRC covers every message bit
                if payload_end <= j < payload_end + self.reserved_bits:
                    key |= 1 << (reserved_at + j - payload_end)
                elif j >= payload_end + self.reserved_bits:
                    key |= 1 << (word_at + j - payload_end - self.reserved_bits)
            keys[i] = key
        return keys

    def virtual_key(self, address: int) -> int:
        """The key of the unsent address bits holding ``address`` (``crc``, ``coset``)."""
        if not self.virtual_bits:
            return 0
        key = 0
        for v in range(self.virtual_bits):
            if address >> v & 1:
                if self.mode == "coset":
                    key ^= self.code.remainder(1 << (self.n_sent + v))
                key ^= poly_mod(1 << (self.k_sent + v), CRC_POLY) << PARITY_BITS
        return key

    def targets(self, sent: int, receiver: int) -> tuple[int, ...]:
        """The keys of ``d`` that make vehicle ``receiver`` take a frame to ``sent`` as its own
        or as to all (``delimiter`` mode: any valid codeword, key 0, its sync decides)."""
        if self.mode == "delimiter":
            return (0,)
        word_at = self.key_shifts[2]
        return tuple(
            ((self.word(sent) ^ self.word(h)) << word_at) ^ self.virtual_key(sent ^ h)
            for h in (receiver, 0)
        )

    def fixed_bits(self, target: int) -> tuple[int, int]:
        """For :func:`tail_count`: (ones the target puts in the address word, key bits other
        than the word's that a random vector must match)."""
        word_at = self.key_shifts[2]
        return (target >> word_at).bit_count(), word_at


#: The designs compared, in the table's order.
DESIGNS: Final = (
    Design("a", "(a) per-vehicle delimiters alone, 72-bit codeword", "delimiter"),
    Design("b76", "(b) 4-bit address in BCH(76,60), own delimiter", "word", word_bits=4),
    Design(
        "b80r",
        "(b) 4-bit address + zero nibble in BCH(80,64)",
        "word",
        word_bits=4,
        reserved_bits=4,
    ),
    Design("b80h", "(b) [8,4,4] address word in BCH(80,64)", "word", word_bits=8),
    Design("cseed", "(c) address as the CRC-4's seed, 72-bit codeword", "crc"),
    Design("ccoset", "(c) per-vehicle coset: unsent address in BCH(76,60)", "coset"),
)
#: The codec's layout (codec._address).
CODEC_DESIGN: Final = "b80h"


def design(key: str) -> Design:
    for d in DESIGNS:
        if d.key == key:
            return d
    raise KeyError(f"unknown design {key!r}: one of {', '.join(d.key for d in DESIGNS)}")


def pairs() -> list[tuple[int, int]]:
    """Every (sender's address, another vehicle's address), 1-15."""
    return [(b, a) for b in range(1, MAX_ADDRESS + 1) for a in range(1, MAX_ADDRESS + 1) if a != b]


# --- counting the vectors of each key --------------------------------------------------------


def _subsets(n: int, size: int) -> NDArray[np.int16]:
    if size == 0:
        return np.zeros((1, 0), dtype=np.int16)
    flat = np.fromiter(
        itertools.chain.from_iterable(itertools.combinations(range(n), size)), np.int16
    )
    return flat.reshape(-1, size)


def _keys_of(keys: NDArray[np.int64], subsets: NDArray[np.int16]) -> NDArray[np.int64]:
    out = np.zeros(subsets.shape[0], dtype=np.int64)
    for j in range(subsets.shape[1]):
        out ^= keys[subsets[:, j]]
    return out


def _halves(
    keys: NDArray[np.int64], weight: int
) -> tuple[NDArray[np.int16], NDArray[np.int64], NDArray[np.int16], NDArray[np.int64]]:
    """The lower halves (``weight // 2`` positions) and their keys, the upper halves sorted by
    key and their keys."""
    n = keys.shape[0]
    low_size = weight // 2
    low = _subsets(n, low_size)
    high = _subsets(n, weight - low_size)
    high_keys = _keys_of(keys, high)
    order = np.argsort(high_keys, kind="stable")
    return low, _keys_of(keys, low), high[order], high_keys[order]


def _matches(
    halves: tuple[NDArray[np.int16], NDArray[np.int64], NDArray[np.int16], NDArray[np.int64]],
    target: int,
) -> tuple[NDArray[np.int64], NDArray[np.int64]]:
    """Rows of the lower and upper halves that make a set of key ``target``, each set once: all
    of the lower half's positions below all of the upper's."""
    low, low_keys, high, high_keys = halves
    want = low_keys ^ target
    first = np.searchsorted(high_keys, want, "left")
    found = np.searchsorted(high_keys, want, "right") - first
    rows = np.repeat(np.arange(want.shape[0]), found)
    at = np.repeat(first - np.cumsum(found) + found, found) + np.arange(int(found.sum()))
    low_max = low.max(axis=1) if low.shape[1] else np.full(low.shape[0], -1, dtype=np.int16)
    ordered = low_max[rows] < high.min(axis=1)[at]
    return rows[ordered], at[ordered]


def count_keys(keys: NDArray[np.int64], weight: int, targets: Iterable[int]) -> dict[int, int]:
    """``N(weight, t)`` for each target ``t``: the sets of ``weight`` positions whose keys XOR
    to ``t``, found by meeting in the middle (:func:`_matches`)."""
    if weight == 0:  # the empty set: key 0
        return {t: int(t == 0) for t in targets}
    halves = _halves(keys, weight)
    return {t: int(_matches(halves, t)[0].shape[0]) for t in targets}


def vectors_of(keys: NDArray[np.int64], weight: int, target: int) -> list[tuple[int, ...]]:
    """The sets :func:`count_keys` counts, as sorted positions."""
    halves = _halves(keys, weight)
    rows, at = _matches(halves, target)
    low, _, high, _ = halves
    return [
        tuple(sorted((*low[r].tolist(), *high[a].tolist()))) for r, a in zip(rows, at, strict=True)
    ]


def tail_count(d: Design, weight: int, target: int) -> float:
    """``N(weight, target)`` estimated as random vectors: the target's address-word bits fixed,
    the other positions carrying the rest of the weight, and the other key bits matched with
    probability 2^-(their number)."""
    ones, other_bits = d.fixed_bits(target)
    free = d.n_sent - d.word_bits
    rest = weight - ones
    if not 0 <= rest <= free:
        return 0.0
    return math.comb(free, rest) / 2.0**other_bits


def reach(weight: int, p: float, n: int) -> float:
    """Probability that independent errors at ``p`` on ``n`` bits leave the word within
    distance 2 of one given vector of ``weight`` (the decoder then corrects to it)."""
    total = 0.0
    for inside in range(3):  # errors of the vector not made (corrected back)
        for outside in range(3 - inside):  # errors beside it (corrected away)
            if inside <= weight and outside <= n - weight:
                flips = weight - inside + outside
                total += (
                    math.comb(weight, inside)
                    * math.comb(n - weight, outside)
                    * p**flips
                    * (1 - p) ** (n - flips)
                )
    return total


@dataclass(frozen=True)
class Enumeration:
    """The exact counts of a design: ``counts[W][t]`` for ``W <= w_exact``."""

    design: Design
    w_exact: int
    counts: dict[int, dict[int, int]]

    def acceptance(self, p: float, targets: Sequence[int]) -> float:
        """Probability that the codeword decodes to one of ``targets`` (distinct vectors'
        reaches are disjoint: their distance is at least 5)."""
        n = self.design.n_sent
        total = 0.0
        for t in targets:
            for w in range(self.w_exact + 1):
                total += self.counts[w].get(t, 0) * reach(w, p, n)
            for w in range(self.w_exact + 1, n + 1):
                total += tail_count(self.design, w, t) * reach(w, p, n)
        return total


def enumerate_design(d: Design, w_exact: int = W_EXACT) -> Enumeration:
    """Count the vectors of every target key up to weight ``w_exact`` (cached per design)."""
    cached = d._cache.get(f"enum{w_exact}")
    if isinstance(cached, Enumeration):
        return cached
    keys = d.position_keys()
    targets = sorted({t for b, a in pairs() for t in d.targets(b, a)})
    counts = {w: count_keys(keys, w, targets) for w in range(w_exact + 1)}
    found = Enumeration(d, w_exact, counts)
    d._cache[f"enum{w_exact}"] = found
    return found


# --- sync, and the figures per design ------------------------------------------------------


def sync_probability(sent: int, targets: Sequence[int], p: float, tolerance: int) -> float:
    """Probability that the 24-bit sync word ``sent``, each bit flipped with probability
    ``p``, arrives within ``tolerance`` bits of one of ``targets``: exact, by the number of
    flips in each class of positions (which targets each position differs from)."""
    classes: dict[tuple[int, ...], int] = {}
    for i in range(SYNC_BITS):
        sig = tuple((sent ^ t) >> i & 1 for t in targets)
        classes[sig] = classes.get(sig, 0) + 1
    sigs = list(classes)
    total = 0.0
    for flips in itertools.product(*(range(classes[s] + 1) for s in sigs)):
        distances = [
            sum(classes[s] - f if s[k] else f for s, f in zip(sigs, flips, strict=True))
            for k in range(len(targets))
        ]
        if min(distances) <= tolerance:
            weight = 1.0
            for s, f in zip(sigs, flips, strict=True):
                weight *= math.comb(classes[s], f) * p**f * (1 - p) ** (classes[s] - f)
            total += weight
    return total


@dataclass(frozen=True)
class Figures:
    """A design's analytic figures at one bit error rate (per frame)."""

    ber: float
    misaddressed_mean: float  # over every ordered pair of vehicles
    misaddressed_max: float  # the worst pair
    lost: float


def figures(d: Design, ber: float, w_exact: int = W_EXACT) -> Figures:
    """Misaddressed acceptance (mean and worst pair) and the addressed vehicle's loss."""
    enum = enumerate_design(d, w_exact)
    n = d.n_sent
    clean = sum(math.comb(n, i) * ber**i * (1 - ber) ** (n - i) for i in range(3))
    if d.mode == "delimiter":  # the sync decides; any valid codeword is executed
        codeword = enum.acceptance(ber, (0,))
        syncs: dict[tuple[int, int, int], float] = {}  # by the three sync words' differences
        values = []
        for b, a in pairs():
            sent, targets = d.sync_word(b), (d.sync_word(a), d.sync_word(0))
            shape = (sent ^ targets[0], sent ^ targets[1], 0)
            if shape not in syncs:
                syncs[shape] = sync_probability(sent, targets, ber, d.sync_tolerance)
            values.append(syncs[shape] * codeword)
        own_targets = (d.sync_word(1), d.sync_word(0))
        own = sync_probability(d.sync_word(1), own_targets, ber, d.sync_tolerance)
    else:
        own = sync_probability(d.sync_word(0), (d.sync_word(0),), ber, d.sync_tolerance)
        reached = {
            t: enum.acceptance(ber, (t,)) for t in {t for b, a in pairs() for t in d.targets(b, a)}
        }
        values = [own * sum(reached[t] for t in d.targets(b, a)) for b, a in pairs()]
    return Figures(ber, float(np.mean(values)), max(values), 1.0 - own * clean)


def chosen(at_required: dict[str, Figures]) -> str:
    """The design that meets :data:`REQUIRED` for the worst pair (its figures at
    :data:`REQUIRED_AT_BER`, by key) with the fewest frame bits, then the least loss: the
    codec's (:data:`CODEC_DESIGN`)."""
    if any(f.ber != REQUIRED_AT_BER for f in at_required.values()):
        raise ValueError(f"the requirement is at BER {REQUIRED_AT_BER:g}")
    meeting = [d for d in DESIGNS if at_required[d.key].misaddressed_max <= REQUIRED]
    if not meeting:
        raise ValueError("no design meets the requirement")
    best = min(meeting, key=lambda d: (d.frame_bits, at_required[d.key].lost))
    return best.key
