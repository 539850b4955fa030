"""The Monte Carlo of the addressing comparison (:mod:`analysis.addressing`): frames of every
design encoded, corrupted and decoded by numpy, vectorised and seeded.

Each frame carries a random valid command (:class:`analysis.ber_montecarlo.CommandTables`) from
a random vehicle ``b`` (1-15) and is received, with the same bit errors, by another random
vehicle ``a`` (it must refuse it) and by ``b`` (it must execute it). Errors are independent on
every frame bit (sync, codeword, guard) at a bit error rate, or a burst: a window of ``L``
consecutive codeword bits in which each bit flips with probability 1/2
(:func:`analysis.ber_montecarlo.inject_burst`, as ``nemesys analyze ber``).

:class:`Engine` runs any design from its description (the analytic figure's own model, in
frames). The codec's design also runs through the codec's own numpy twin of the addressed
frame (:mod:`codec.batch_addressed`) in :func:`run_codec`; the tests check that the two make
the same frames.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Final

import numpy as np
from numpy.typing import NDArray

from analysis.addressing import CRC_BITS, PARITY_BITS, Design
from analysis.ber_montecarlo import CommandTables, inject_burst
from codec import CRC_POLY, PAYLOAD_BITS, SYNC_BITS
from codec._gf2 import ChunkedRemainder
from codec.batch import ACCEPTED, inject_errors
from codec.batch_addressed import (
    OTHER_VEHICLE,
    addressed_messages,
    decode_addressed_frames,
    encode_addressed,
)

U8 = NDArray[np.uint8]
U64 = NDArray[np.uint64]
Bool = NDArray[np.bool_]

#: Frames per numpy batch.
CHUNK: Final = 1 << 16
_ONE: Final = np.uint64(1)
_PAYLOAD_MASK: Final = np.uint64((1 << PAYLOAD_BITS) - 1)


@dataclass
class Counts:
    """Outcomes of ``frames`` frames: ``misaddressed`` taken by the other vehicle after the
    BCH, CRC and address checks, ``executed`` of those also passing the dictionary's (what
    the vehicle runs), ``lost`` not executed as sent by the vehicle they were for."""

    frames: int = 0
    misaddressed: int = 0
    executed: int = 0
    lost: int = 0

    def add(self, other: Counts) -> None:
        self.frames += other.frames
        self.misaddressed += other.misaddressed
        self.executed += other.executed
        self.lost += other.lost


def _np_tables(remainder: ChunkedRemainder) -> NDArray[np.int64]:
    return np.array([list(t) for t in remainder.tables], dtype=np.int64)


def _remainder(tables: NDArray[np.int64], columns: U8) -> NDArray[np.int64]:
    out = np.zeros(columns.shape[0], dtype=np.int64)
    for j in range(tables.shape[0]):
        out ^= tables[j][columns[:, j]]
    return out


def _bytes_of(values: U64, n_bytes: int) -> U8:
    """Each uint64 as ``n_bytes`` big-endian bytes (its low ``8 n_bytes`` bits)."""
    raw = values.astype(">u8").view(np.uint8).reshape(-1, 8)
    return raw[:, 8 - n_bytes :]


class Engine:
    """Encodes, and decodes as any vehicle, the frames of one design."""

    def __init__(self, design: Design) -> None:
        self.d = design
        code = design.code
        self.n_bytes = (design.n_sent + 7) // 8
        self.k_bytes = (code.k + 7) // 8
        self.frame_bytes = (design.frame_bits + 7) // 8
        self.parity = _np_tables(ChunkedRemainder(code.generator_poly, code.k, PARITY_BITS))
        self.syndrome = _np_tables(ChunkedRemainder(code.generator_poly, design.n_sent))
        self.virtual = np.array(
            [
                code.remainder(h << design.n_sent) if design.mode == "coset" else 0
                for h in range(16)
            ],
            dtype=np.int64,
        )
        checked = design.k_sent + design.virtual_bits
        self.crc = _np_tables(ChunkedRemainder(CRC_POLY, checked))
        self.crc_bytes = (checked + 7) // 8
        self.words = np.array([design.word(h) for h in range(16)], dtype=np.uint64)
        self.syncs = np.array([design.sync_word(h) for h in range(16)], dtype=np.int64)
        self.patterns, self.corrected = self._corrections()

    def _corrections(self) -> tuple[U8, NDArray[np.int8]]:
        """Syndrome -> the error pattern of weight <= 2 among the sent bits (as bytes), and
        its weight (-1: none)."""
        n = self.d.n_sent
        single = np.array([self.d.code.remainder(1 << i) for i in range(n)], dtype=np.int64)
        unit = np.zeros((n, self.n_bytes), dtype=np.uint8)
        for i in range(n):
            unit[i, self.n_bytes - 1 - i // 8] = 1 << (i % 8)
        size = 1 << PARITY_BITS
        patterns = np.zeros((size, self.n_bytes), dtype=np.uint8)
        weight = np.full(size, -1, dtype=np.int8)
        weight[0] = 0
        weight[single] = 1
        patterns[single] = unit
        for i in range(n - 1):
            syndrome = single[i] ^ single[i + 1 :]
            weight[syndrome] = 2
            patterns[syndrome] = unit[i] ^ unit[i + 1 :]
        return patterns, weight

    def encode(self, senders: NDArray[np.int64], payloads: U64) -> U8:
        """Packed frames (N, bytes) of ``payloads`` from ``senders`` (addresses 1-15)."""
        d = self.d
        n = payloads.shape[0]
        word = self.words[senders] << np.uint64(PAYLOAD_BITS + d.reserved_bits)
        body = (word | payloads) << np.uint64(CRC_BITS)  # the CRC's bits still zero
        virtual = senders.astype(np.uint64) << np.uint64(d.k_sent)
        checked = body | virtual if d.virtual_bits else body
        message = body | _remainder(self.crc, _bytes_of(checked, self.crc_bytes)).astype(np.uint64)
        full = message | virtual if d.mode == "coset" else message
        parity = _remainder(self.parity, _bytes_of(full, self.k_bytes)).astype(np.uint64)
        bits = np.zeros((n, d.frame_bits), dtype=np.uint8)
        sync = self.syncs[senders]
        for i in range(SYNC_BITS):
            bits[:, i] = (sync >> (SYNC_BITS - 1 - i)) & 1
        for i in range(d.k_sent):
            bits[:, SYNC_BITS + i] = ((message >> np.uint64(d.k_sent - 1 - i)) & _ONE).astype(
                np.uint8
            )
        for i in range(PARITY_BITS):
            bits[:, SYNC_BITS + d.k_sent + i] = ((parity >> np.uint64(15 - i)) & _ONE).astype(
                np.uint8
            )
        return np.packbits(bits, axis=1)

    def decode(self, frames: U8, vehicle: NDArray[np.int64]) -> tuple[Bool, U64, NDArray[np.int64]]:
        """As ``vehicle`` (per frame): (taken after the sync, BCH, CRC and address checks, its
        payload, the address it was taken as: the vehicle's, 0, or -1 when not taken)."""
        d = self.d
        bits = np.unpackbits(frames, axis=1)[:, : d.frame_bits]
        weights = np.int64(1) << np.arange(SYNC_BITS - 1, -1, -1, dtype=np.int64)
        sync = bits[:, :SYNC_BITS].astype(np.int64) @ weights
        pad = np.zeros((frames.shape[0], 8 * self.n_bytes - d.n_sent), dtype=np.uint8)
        codeword = np.packbits(
            np.concatenate([pad, bits[:, SYNC_BITS : SYNC_BITS + d.n_sent]], axis=1), axis=1
        )
        sent_syndrome = _remainder(self.syndrome, codeword)
        taken = np.zeros(frames.shape[0], dtype=np.bool_)
        payload = np.zeros(frames.shape[0], dtype=np.uint64)
        taken_as = np.full(frames.shape[0], -1, dtype=np.int64)
        hypotheses = [vehicle, np.zeros_like(vehicle)]
        for h in hypotheses if d.mode != "word" else hypotheses[:1]:
            syndrome = sent_syndrome ^ self.virtual[h]
            fixed = codeword ^ self.patterns[syndrome]
            message = np.zeros(frames.shape[0], dtype=np.uint64)
            for j in range(self.n_bytes - 2):
                message = (message << np.uint64(8)) | fixed[:, j].astype(np.uint64)
            checked = message
            if d.virtual_bits:
                checked = message | (h.astype(np.uint64) << np.uint64(d.k_sent))
            crc_ok = _remainder(self.crc, _bytes_of(checked, self.crc_bytes)) == 0
            ok = (self.corrected[syndrome] >= 0) & crc_ok
            above = np.uint64(CRC_BITS + PAYLOAD_BITS)
            reserved = (message >> above) & np.uint64((1 << d.reserved_bits) - 1)
            word = message >> (above + np.uint64(d.reserved_bits))
            ok &= reserved == 0
            if d.mode == "word":
                to_h = np.where(word == self.words[vehicle], vehicle, -1)
                to_h = np.where(word == self.words[0], 0, to_h)
                ok &= to_h >= 0
            else:
                to_h = h
            if d.mode == "delimiter":
                near = np.bitwise_count(sync ^ self.syncs[h]) <= d.sync_tolerance
            else:
                near = np.bitwise_count(sync ^ self.syncs[0]) <= d.sync_tolerance
            ok &= near
            new = ok & ~taken
            payload = np.where(new, (message >> np.uint64(CRC_BITS)) & _PAYLOAD_MASK, payload)
            taken_as = np.where(new, to_h, taken_as)
            taken |= ok
        return taken, payload, taken_as


def _corrupt(
    frames: U8,
    n_codeword: int,
    frame_bits: int,
    errors: str,
    level: float,
    rng: np.random.Generator,
) -> None:
    if errors == "independent":
        inject_errors(frames, level, rng, n_bits=frame_bits)
    else:
        inject_burst(frames, n_codeword, int(level), rng)


def _vehicles(rng: np.random.Generator, n: int) -> tuple[NDArray[np.int64], NDArray[np.int64]]:
    """Random senders 1-15, and for each a random other vehicle."""
    senders = rng.integers(1, 16, n)
    others = (senders + rng.integers(0, 14, n)) % 15 + 1
    return senders, others


def run_design(
    design: Design,
    frames: int,
    errors: str,
    level: float,
    rng: np.random.Generator,
    commands: CommandTables | None = None,
) -> Counts:
    """Monte Carlo of one design under one error condition (see the module doc)."""
    engine = Engine(design)
    commands = commands or CommandTables()
    counts = Counts()
    while counts.frames < frames:
        n = min(CHUNK, frames - counts.frames)
        senders, others = _vehicles(rng, n)
        payloads = commands.draw(rng, n)
        sent = engine.encode(senders, payloads)
        _corrupt(sent, design.n_sent, design.frame_bits, errors, level, rng)
        taken, received, _ = engine.decode(sent, others)
        mine, own, taken_as = engine.decode(sent, senders)
        executed = taken & commands.check(received)
        # a frame is the sender's own when it decodes to what was sent, to its address (its
        # delimiter's or the broadcast one: the codeword is the same)
        good = mine & (own == payloads)
        if design.mode != "delimiter":
            good &= taken_as == senders
        counts.add(
            Counts(
                n,
                int(np.count_nonzero(taken)),
                int(np.count_nonzero(executed)),
                n - int(np.count_nonzero(good)),
            )
        )
    return counts


def run_codec(
    frames: int,
    errors: str,
    level: float,
    rng: np.random.Generator,
    commands: CommandTables | None = None,
) -> Counts:
    """The same for the codec's addressed frame, through :mod:`codec.batch_addressed` (the
    codec's checks, in its order: an ``other_vehicle`` frame stops before the dictionary)."""
    from codec import ADDRESSED_FRAME_BITS
    from codec._address import ADDRESSED_CODEWORD_BITS

    commands = commands or CommandTables()
    counts = Counts()
    while counts.frames < frames:
        n = min(CHUNK, frames - counts.frames)
        senders, others = _vehicles(rng, n)
        payloads = commands.draw(rng, n)
        sent = encode_addressed(addressed_messages(senders, payloads))
        _corrupt(sent, ADDRESSED_CODEWORD_BITS, ADDRESSED_FRAME_BITS, errors, level, rng)
        theirs = decode_addressed_frames(sent, vehicle=others)
        mine = decode_addressed_frames(sent, vehicle=senders)
        passed = (theirs.status != OTHER_VEHICLE) & (theirs.address >= 0)
        own = (mine.message >> np.uint64(CRC_BITS)) & _PAYLOAD_MASK
        good = (mine.status == ACCEPTED) & (own == payloads) & (mine.address == senders)
        counts.add(
            Counts(
                n,
                int(np.count_nonzero(passed)),
                int(np.count_nonzero(theirs.status == ACCEPTED)),
                n - int(np.count_nonzero(good)),
            )
        )
    return counts
