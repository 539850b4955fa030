"""One-way delivery by repetition, measured through the training channel
(``nemesys analyze delivery``).

Checks :func:`codec.delivery_probability` (``1 - (1 - P1)^r``) by Monte Carlo through the
emulated ME link the simulator uses (:class:`sim.channel.MEChannel`: independent bit
errors at ``ber`` on all 100 frame bits, no bursts, no loss, in range) and the vehicle's onboard
decode (:func:`received_command`, the path of :meth:`onboard.agent.OnboardAgent.receive`:
the packed 13 bytes into a fresh :class:`codec.FrameReceiver`, which searches for the sync word
within its tolerance, then BCH, CRC-4 and the dictionary checks; the first accepted event).

A trial draws one random valid command (uniform pattern, uniform valid code in every field)
and sends the same encoded frame up to ``max(copies)`` times through the channel, each copy
corrupted independently. It is delivered with ``r`` copies when one of its first ``r`` copies
decodes to the sent command; a copy that decodes to a *different* command (which the CRC makes
rare) is not a success.

One pass serves every ``r``: the channel's copies are independent, so the first ``r`` copies
of a ``max(copies)``-copy trial are an ``r``-copy trial, and only the index of the first copy
that decodes matters. Copies after it are therefore not sent (their outcome changes no ``r``),
so a trial costs about ``1 / P1`` channel passes and decodes, not ``max(copies)``. The rows of
one BER share their trials (nested, hence correlated); different BERs use independent streams.

Each row gives the measured rate with its Wilson 95 % interval (:func:`analysis.ber.wilson`)
and whether ``p_delivered`` lies in it. Seeded: the same ``seed`` gives the same rows.
"""

from __future__ import annotations

import random
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Final, TextIO

from analysis.ber import Z95, wilson
from codec import (
    DICTIONARY,
    FRAME_BITS,
    Accepted,
    Command,
    CommandDictionary,
    Frame,
    FrameReceiver,
    delivery_probability,
    frame_of,
)
from sim.channel import ChannelConfig, MEChannel

#: The BERs of the research note's delivery arithmetic (0.9625 / 0.9986 / 0.99995 at 1e-2).
BERS: Final = (1e-2, 2e-2)
#: Copies per command compared (the console's repetition for a one-way link).
COPIES: Final = (1, 2, 3)
#: Trials per BER of the full run (about 7 s on this machine for the two BERs).
DEFAULT_TRIALS: Final = 100_000
#: Distance from the transmitter (m): well inside the link's range, so no frame is lost.
DISTANCE_M: Final = 0.0


@dataclass(frozen=True)
class DeliveryRow:
    """Delivery of one command sent ``copies`` times at bit-error rate ``ber``.

    ``rate = delivered / trials``; ``[low, high]`` its Wilson 95 % interval; ``p_delivered``
    the analytic ``codec.delivery_probability(ber, copies)``; ``agrees`` whether it lies in
    the interval.
    """

    ber: float
    copies: int
    trials: int
    delivered: int
    rate: float
    p_delivered: float
    low: float
    high: float
    agrees: bool


class CommandDraw:
    """Draws uniformly random valid commands of a dictionary (uniform pattern, then a
    uniform valid code in every field of it)."""

    def __init__(self, dictionary: CommandDictionary = DICTIONARY) -> None:
        self._choices = [
            (p, [[c for c in range(256) if f.scale.is_valid_code(c)] for f in p.fields])
            for p in dictionary.values()
        ]

    def __call__(self, rng: random.Random) -> Command:
        pattern, codes = rng.choice(self._choices)
        return Command(pattern, tuple(rng.choice(valid) for valid in codes))


def received_command(bits: int, dictionary: CommandDictionary = DICTIONARY) -> Command | None:
    """The command the onboard agent takes from ``bits`` (a 100-bit frame as received, first
    bit most significant), or ``None`` when it rejects the frame.

    The same steps as :meth:`onboard.agent.OnboardAgent.receive` up to the decoded command.
    """
    events = FrameReceiver(dictionary=dictionary).feed_bytes(Frame(bits).to_bytes())
    accepted = next((e for e in events if isinstance(e, Accepted)), None)
    return accepted.decoded.command if accepted is not None else None


def _check(bers: Sequence[float], copies: Sequence[int], trials: int) -> None:
    if isinstance(trials, bool) or not isinstance(trials, int) or trials < 1:
        raise ValueError(f"trials must be an int >= 1, got {trials!r}")
    if not copies or any(isinstance(r, bool) or not isinstance(r, int) or r < 1 for r in copies):
        raise ValueError(f"copies must be ints >= 1, got {copies!r}")
    if not bers:
        raise ValueError("bers must not be empty")


def first_success(
    channel: MEChannel, command: Command, max_copies: int, dictionary: CommandDictionary
) -> int:
    """Send ``command``'s frame through ``channel`` until a copy decodes to it: the 1-based
    index of that copy, or 0 when none of ``max_copies`` does."""
    sent = frame_of(command).value
    for index in range(1, max_copies + 1):
        delivery = channel.transmit(sent, FRAME_BITS, t_s=0.0, distance_m=DISTANCE_M)
        if delivery is not None and received_command(delivery.bits, dictionary) == command:
            return index
    return 0


def _seed(seed: int, index: int, stream: str) -> int:
    """An independent 64-bit seed per (run seed, BER index, stream), the same on every run."""
    return random.Random(f"delivery/{seed}/{index}/{stream}").getrandbits(64)


def run(
    bers: Sequence[float] = BERS,
    copies: Sequence[int] = COPIES,
    trials: int = DEFAULT_TRIALS,
    seed: int = 0,
    dictionary: CommandDictionary = DICTIONARY,
) -> tuple[DeliveryRow, ...]:
    """Measure delivery at every ``ber`` (probability per bit) for every ``r`` in ``copies``.

    ``trials`` commands per BER, shared by its rows. Rows by BER, then ``r``, in the order given.

    Raises:
        ValueError: ``trials`` or a ``copies`` entry not an int >= 1, ``bers`` empty, or a BER
            the channel refuses (outside [0, 0.5]).
    """
    _check(bers, copies, trials)
    draw = CommandDraw(dictionary)
    max_copies = max(copies)
    rows: list[DeliveryRow] = []
    for index, ber in enumerate(bers):
        config = ChannelConfig(ber=ber, burst_rate=0.0, loss=0.0)
        channel = MEChannel(config, seed=_seed(seed, index, "channel"))
        rng = random.Random(_seed(seed, index, "commands"))
        # first[k]: trials whose first decoded copy was copy k (k = 0: none decoded)
        first = [0] * (max_copies + 1)
        for _ in range(trials):
            first[first_success(channel, draw(rng), max_copies, dictionary)] += 1
        for r in copies:
            delivered = sum(first[1 : r + 1])
            low, high = wilson(delivered, trials, Z95)
            p = delivery_probability(ber, r)
            rows.append(
                DeliveryRow(
                    ber=ber,
                    copies=r,
                    trials=trials,
                    delivered=delivered,
                    rate=delivered / trials,
                    p_delivered=p,
                    low=low,
                    high=high,
                    agrees=low <= p <= high,
                )
            )
    return tuple(rows)


def format_table(rows: Sequence[DeliveryRow]) -> str:
    """The rows as a Markdown table."""
    lines = [
        "| BER | r | trials | delivered | measured rate | p_delivered | 95 % interval | agrees |",
        "|---:|---:|---:|---:|---:|---:|---|:---:|",
    ]
    for w in rows:
        lines.append(
            f"| {w.ber:g} | {w.copies} | {w.trials} | {w.delivered} | {w.rate:.6f} | "
            f"{w.p_delivered:.6f} | [{w.low:.6f}, {w.high:.6f}] | "
            f"{'yes' if w.agrees else 'no'} |"
        )
    return "\n".join(lines) + "\n"


def main(out: TextIO, trials: int = DEFAULT_TRIALS, seed: int = 0) -> int:
    """Run :func:`run` at the default BERs and copies and print the table on ``out``.

    Returns 0 when every ``p_delivered`` lies in its interval, else 1.
    """
    rows = run(trials=trials, seed=seed)
    out.write(
        "One-way delivery by repetition: Monte Carlo through the training ME channel "
        "(independent bit errors, no bursts, no loss) and the onboard decode, against "
        "p_delivered = 1 - (1 - P1)^r (Wilson 95 % intervals, seed "
        f"{seed})\n\n"
    )
    out.write(format_table(rows))
    return 0 if all(w.agrees for w in rows) else 1
