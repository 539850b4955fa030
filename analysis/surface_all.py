"""``nemesys analyze surface-all``: how long it takes to get Surface to every vehicle of a fleet
on a one-way ME link (no acknowledgement), and what one Surface to all saves over a Surface
per vehicle.

One Surface-all frame (address 0, docs/protocol.md "Addressing": every vehicle takes it) is
sent ``k`` times; each vehicle hears every copy through its own channel, so a vehicle misses a
copy with the addressed frame's loss ``q`` at the link's bit error rate, independently of the
other vehicles and of its other copies (copies spaced longer than a burst)::

    P(every one of N vehicles took at least one copy) = (1 - q^k)^N

``q`` is the codec's figure: the 24 sync bits within the sync tolerance and the 80-bit
addressed codeword within the BCH code's 2 corrections
(:func:`codec.frame_success_probability` with :data:`codec._address.ADDRESSED_CODEWORD_BITS`;
4.8 % at BER 10^-2, the lost-frame column of ``nemesys analyze addressing``). The fewest
``k`` reaching the target is the answer, and the time is ``k`` frames back to back at the
link's frame time (108 bits: 3.000 ms at 36 kb/s).

The comparison: a Surface addressed to each vehicle in turn, ``r`` copies each, reaches all N
with ``(1 - q^r)^N``, so ``r = k`` and it takes ``N`` times the frames. A Monte Carlo checks
the Surface-all figure through the codec's own numpy decoder (:mod:`codec.batch_addressed`):
every trial sends ``k`` copies to each of the N vehicles with independent bit errors, and a
vehicle counts only a copy it decodes, as its own address, to the very Surface sent.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Final, TextIO

import numpy as np

from analysis._markdown import num, table
from analysis.ber_analytic import wilson
from codec import (
    ADDRESSED_FRAME_BITS,
    BROADCAST_ADDRESS,
    DEFAULT_BITRATE_BPS,
    FRAME_BITS,
    airtime_s,
    encode_frame,
    frame_success_probability,
)
from codec._address import ADDRESSED_CODEWORD_BITS
from codec.batch import ACCEPTED, inject_errors
from codec.batch_addressed import decode_addressed_frames

#: The issue's figure: N = 1, 5, 10 vehicles at BER 10^-2, every one reached at p >= 0.999.
FLEET_SIZES: Final = (1, 5, 10)
BER: Final = 1e-2
TARGET: Final = 0.999
#: Monte Carlo trials per fleet size (each trial: k copies to each of N vehicles).
DEFAULT_TRIALS: Final = 50_000
QUICK_TRIALS: Final = 5_000
#: Most copies looked for (a target no number of copies reaches is an error).
MAX_COPIES: Final = 1000
#: The normal quantile of a two-sided 99.9 % interval (the Monte Carlo's agreement check).
Z999: Final = 3.29


def addressed_loss(ber: float) -> float:
    """Probability that one vehicle misses one addressed frame at ``ber`` (the codec's sync and
    BCH figures for the 80-bit addressed codeword)."""
    return 1.0 - frame_success_probability(ber, codeword_bits=ADDRESSED_CODEWORD_BITS)


def p_all(loss: float, copies: int, vehicles: int) -> float:
    """P(each of ``vehicles`` took at least one of ``copies``), each copy missed with ``loss``
    independently by each vehicle."""
    return (1.0 - loss**copies) ** vehicles


def copies_for_all(loss: float, vehicles: int, target: float = TARGET) -> int:
    """The fewest copies of one frame that every one of ``vehicles`` takes with probability
    ``target`` or more.

    Raises:
        ValueError: ``target`` not in (0, 1), ``vehicles`` < 1, or ``loss`` so high that
            :data:`MAX_COPIES` do not reach it.
    """
    if not 0.0 < target < 1.0:
        raise ValueError(f"target must be in (0, 1), got {target!r}")
    if vehicles < 1:
        raise ValueError(f"vehicles must be at least 1, got {vehicles}")
    for k in range(1, MAX_COPIES + 1):
        if p_all(loss, k, vehicles) >= target:
            return k
    raise ValueError(f"{MAX_COPIES} copies do not reach {target} with loss {loss:g} per copy")


@dataclass(frozen=True)
class Row:
    """One fleet size: Surface all against a Surface per vehicle, and the Monte Carlo."""

    vehicles: int
    copies: int  # of the Surface-all frame
    p_all: float  # analytic, with ``copies``
    per_vehicle_frames: int  # a Surface to each vehicle, ``copies`` each
    per_vehicle_p: float
    frame_s: float
    trials: int
    mc_delivered: int  # trials in which every vehicle took a copy

    @property
    def seconds(self) -> float:
        return self.copies * self.frame_s

    @property
    def per_vehicle_seconds(self) -> float:
        return self.per_vehicle_frames * self.frame_s

    @property
    def mc_interval(self) -> tuple[float, float]:
        return wilson(self.mc_delivered, self.trials)


@dataclass(frozen=True)
class Report:
    ber: float
    target: float
    bitrate_bps: float
    loss: float  # one addressed frame, one vehicle
    unaddressed_loss: float  # today's 100-bit frame (a single-vehicle Surface)
    rows: tuple[Row, ...]


def monte_carlo(
    ber: float, copies: int, vehicles: int, trials: int, rng: np.random.Generator
) -> int:
    """Trials (of ``trials``) in which each of ``vehicles`` (addresses 1..N) decoded at least
    one of ``copies`` Surface-all frames, each copy with its own bit errors at ``ber``."""
    sent = encode_frame("surface", address=BROADCAST_ADDRESS).frame.to_bytes()
    clean = decode_addressed_frames(np.frombuffer(sent, dtype=np.uint8)[None, :], vehicle=1)
    message = clean.message[0]
    delivered = 0
    per_trial = vehicles * copies
    chunk = max(1, (1 << 20) // per_trial)  # about a million frames at a time
    addresses = np.repeat(np.arange(1, vehicles + 1), copies)
    done = 0
    while done < trials:
        n = min(chunk, trials - done)
        frames = np.tile(np.frombuffer(sent, dtype=np.uint8), (n * per_trial, 1))
        inject_errors(frames, ber, rng, n_bits=ADDRESSED_FRAME_BITS)
        got = decode_addressed_frames(frames, vehicle=np.tile(addresses, n))
        ok = (got.status == ACCEPTED) & (got.message == message) & (got.address == 0)
        delivered += int(ok.reshape(n, vehicles, copies).any(axis=2).all(axis=1).sum())
        done += n
    return delivered


def run(
    trials: int = DEFAULT_TRIALS,
    seed: int = 0,
    ber: float = BER,
    target: float = TARGET,
    sizes: Sequence[int] = FLEET_SIZES,
    bitrate_bps: float = DEFAULT_BITRATE_BPS,
) -> Report:
    """The figures for each fleet size in ``sizes`` (see the module doc)."""
    rng = np.random.default_rng(seed)
    loss = addressed_loss(ber)
    frame_s = airtime_s(bitrate_bps, ADDRESSED_FRAME_BITS)
    rows = []
    for n in sizes:
        k = copies_for_all(loss, n, target)
        rows.append(
            Row(
                vehicles=n,
                copies=k,
                p_all=p_all(loss, k, n),
                per_vehicle_frames=n * k,
                per_vehicle_p=p_all(loss, k, n),
                frame_s=frame_s,
                trials=trials,
                mc_delivered=monte_carlo(ber, k, n, trials, rng),
            )
        )
    unaddressed = 1.0 - frame_success_probability(ber)
    return Report(ber, target, bitrate_bps, loss, unaddressed, tuple(rows))


def format_report(report: Report) -> str:
    frame_ms = 1e3 * airtime_s(report.bitrate_bps, ADDRESSED_FRAME_BITS)
    lines = [
        f"Surface to every vehicle of a fleet on a one-way link at BER {report.ber:g}, "
        f"each vehicle reached with p >= {report.target:g}",
        "",
        f"One vehicle misses one addressed frame with q = {report.loss:.4f} (the codec's sync "
        f"and BCH(80, 64) figures); frames back to back, {frame_ms:.3f} ms each "
        f"({ADDRESSED_FRAME_BITS} bits at {report.bitrate_bps:g} b/s).",
        "",
    ]
    rows = []
    for r in report.rows:
        low, high = r.mc_interval
        rows.append(
            [
                str(r.vehicles),
                str(r.copies),
                f"{1e3 * r.seconds:.1f} ms",
                num(r.p_all, 6),
                str(r.per_vehicle_frames),
                f"{1e3 * r.per_vehicle_seconds:.1f} ms",
                num(r.per_vehicle_p, 6),
                f"{r.mc_delivered / r.trials:.5f} ({low:.5f}-{high:.5f})",
            ]
        )
    headers = [
        "N",
        "Surface all: copies",
        "time",
        "P(all N)",
        "a Surface per vehicle: frames",
        "time",
        "P(all N)",
        f"Surface all, Monte Carlo ({report.rows[0].trials:,} trials, 95 %)",
    ]
    lines.append(table(headers, rows))
    best_unaddressed = [
        copies_for_all(report.unaddressed_loss, r.vehicles, report.target) for r in report.rows
    ]
    frame100_ms = 1e3 * airtime_s(report.bitrate_bps, FRAME_BITS)
    lines += [
        "",
        "A Surface per vehicle needs as many copies of each as Surface all needs in all "
        "((1 - q^r)^N either way), so it takes N times the airtime.",
        f"For comparison, the single-vehicle Surface ({FRAME_BITS} bits, which every vehicle "
        f"of a fleet also takes) is missed with q = {report.unaddressed_loss:.4f}: "
        + ", ".join(
            f"N = {r.vehicles}: {k} copies, {k * frame100_ms:.1f} ms"
            for r, k in zip(report.rows, best_unaddressed, strict=True)
        )
        + ".",
    ]
    return "\n".join(lines) + "\n"


def main(out: TextIO, trials: int | None = None, seed: int = 0, quick: bool = False) -> int:
    """Print the figures; 0 when the Monte Carlo agrees (every size's analytic P(all N) inside
    the Monte Carlo's 99.9 % interval), else 1."""
    report = run(trials or (QUICK_TRIALS if quick else DEFAULT_TRIALS), seed)
    out.write(format_report(report))
    bounds = [wilson(r.mc_delivered, r.trials, z=Z999) for r in report.rows]
    agree = all(low <= r.p_all <= high for r, (low, high) in zip(report.rows, bounds, strict=True))
    if not agree:
        out.write("\nThe Monte Carlo disagrees with the analytic figure (99.9 % interval).\n")
    return 0 if agree else 1


__all__ = [
    "Report",
    "Row",
    "addressed_loss",
    "copies_for_all",
    "format_report",
    "main",
    "monte_carlo",
    "p_all",
    "run",
]
