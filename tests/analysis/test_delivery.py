"""``nemesys analyze delivery``: r copies through the training channel and the onboard decode
deliver as often as ``codec.delivery_probability`` says, and no more often than that.

The Monte Carlo runs once at :data:`TRIALS` commands per BER with a fixed seed (about 1.5 s),
so every figure is deterministic. Six 95 % intervals all covering their value is a chance
event (about 0.8 for a random seed: the Wilson interval's coverage is 0.95 per cell); seed 0
is one that does, and the sizes are chosen so that the worst cell (r = 3 at BER 1e-2, about
one failure expected) still has 0.98 coverage (at 3000 trials it has 0.85: one failure in 3000
already puts 0.99995 above the interval).
"""

from __future__ import annotations

import io
import random

import pytest

from analysis import delivery
from analysis.delivery import CommandDraw, DeliveryRow, received_command
from cli.main import main as cli_main
from codec import DICTIONARY, FRAME_BITS, SYNC_BITS, delivery_probability, encode_frame, frame_of
from sim.channel import Delivery, MEChannel
from tests.tiers import slow_fixture

TRIALS = 20_000
SEED = 0


@pytest.fixture(scope="module")
@slow_fixture  # a delivery analysis, ~0.7 s
def rows() -> tuple[DeliveryRow, ...]:
    return delivery.run((1e-2, 2e-2), (1, 2, 3), trials=TRIALS, seed=SEED)


def _flip(value: int, *positions: int) -> int:
    """``value`` (a frame) with the bits at ``positions`` (0 = first on the wire) flipped."""
    for pos in positions:
        value ^= 1 << (FRAME_BITS - 1 - pos)
    return value


def test_rows_cover_every_ber_and_copies(rows: tuple[DeliveryRow, ...]) -> None:
    assert [(w.ber, w.copies) for w in rows] == [(b, r) for b in (1e-2, 2e-2) for r in (1, 2, 3)]
    for w in rows:
        assert w.trials == TRIALS
        assert w.rate == w.delivered / w.trials
        assert w.p_delivered == delivery_probability(w.ber, w.copies)
        assert w.low <= w.rate <= w.high
        assert w.agrees == (w.low <= w.p_delivered <= w.high)


def test_measured_delivery_within_wilson_interval_of_the_formula(
    rows: tuple[DeliveryRow, ...],
) -> None:
    for w in rows:
        assert w.low <= w.p_delivered <= w.high, w
        assert w.agrees


def test_interval_excludes_the_formula_for_the_wrong_number_of_copies(
    rows: tuple[DeliveryRow, ...],
) -> None:
    # The check discriminates: each row's interval rules out the prediction for every other
    # r in 1..3, so a run that sent fewer or more copies than it claims would fail.
    for w in rows:
        for wrong in {1, 2, 3} - {w.copies}:
            p = delivery_probability(w.ber, wrong)
            assert not w.low <= p <= w.high, (w, wrong, p)


def test_more_copies_never_deliver_less(rows: tuple[DeliveryRow, ...]) -> None:
    # r copies reuse the first r copies of the same trials: delivered is nested in r.
    for ber in (1e-2, 2e-2):
        counts = [w.delivered for w in rows if w.ber == ber]
        assert counts == sorted(counts) and counts[0] < counts[-1]


def test_run_is_seeded() -> None:
    a = delivery.run((2e-2,), (1, 3), trials=400, seed=3)
    assert a == delivery.run((2e-2,), (1, 3), trials=400, seed=3)
    assert a != delivery.run((2e-2,), (1, 3), trials=400, seed=4)


def test_noiseless_channel_delivers_every_command_with_one_copy() -> None:
    (row,) = delivery.run((0.0,), (1,), trials=200, seed=1)
    assert row.delivered == 200 and row.p_delivered == 1.0 and row.agrees


@pytest.mark.parametrize(
    ("trials", "copies", "bers"),
    [(0, (1,), (1e-2,)), (True, (1,), (1e-2,)), (10, (0,), (1e-2,)), (10, (), (1e-2,))],
)
def test_run_refuses_bad_sizes(trials: int, copies: tuple[int, ...], bers: tuple[float]) -> None:
    with pytest.raises(ValueError, match=r"trials|copies"):
        delivery.run(bers, copies, trials=trials)


def test_run_refuses_a_ber_the_channel_refuses() -> None:
    with pytest.raises(ValueError, match="ber"):
        delivery.run((0.6,), (1,), trials=10)


def test_onboard_decode_tolerates_two_sync_and_two_codeword_errors() -> None:
    command = encode_frame("circle", speed=0.5, depth=2, radius=5, direction="cw").command
    sent = frame_of(command).value
    assert received_command(sent) == command
    assert received_command(_flip(sent, 3, 20, SYNC_BITS + 5, SYNC_BITS + 60)) == command
    assert received_command(_flip(sent, 96, 97, 98, 99)) == command  # guard bits are ignored
    assert received_command(_flip(sent, 1, 2, 3)) is None  # three sync errors
    assert received_command(_flip(sent, *(SYNC_BITS + i for i in (0, 9, 40)))) is None


def test_a_copy_decoding_to_another_command_is_not_delivered() -> None:
    sent = encode_frame("circle", speed=0.5, depth=2, radius=5, direction="cw").command
    other = encode_frame("circle", speed=0.5, depth=2, radius=5, direction="ccw").command
    assert received_command(frame_of(other).value) == other != sent

    class OtherChannel(MEChannel):
        """Delivers the frame of ``other`` whatever is sent (a CRC-escaping miscorrection)."""

        def transmit(self, bits: int, n_bits: int, t_s: float, distance_m: float) -> Delivery:
            return Delivery(frame_of(other).value, n_bits, t_s, 1, False)

    assert delivery.first_success(OtherChannel(), sent, 3, DICTIONARY) == 0
    assert delivery.first_success(MEChannel(), sent, 3, DICTIONARY) == 1


def test_command_draw_covers_the_dictionary() -> None:
    draw = CommandDraw()
    rng = random.Random(0)
    seen = {draw(rng).pattern.name for _ in range(500)}
    assert seen == set(DICTIONARY)


def test_main_prints_the_table_and_exit_status() -> None:
    out = io.StringIO()
    status = delivery.main(out, trials=300, seed=0)
    text = out.getvalue()
    header = (
        "| BER | r | trials | delivered | measured rate | p_delivered | 95 % interval | agrees |"
    )
    assert header in text
    body = [line for line in text.splitlines() if line.startswith("| 0.0")]
    assert len(body) == 6
    assert status == (0 if all(line.endswith("| yes |") for line in body) else 1)


def test_cli_analyze_delivery() -> None:
    out = io.StringIO()
    status = cli_main(["analyze", "delivery", "--trials", "300", "--seed", "0"], out)
    direct = io.StringIO()
    assert status == delivery.main(direct, trials=300, seed=0)
    assert out.getvalue() == direct.getvalue()
    assert cli_main(["analyze", "delivery", "--trials", "0"], io.StringIO()) == 2
