"""The one transmitter's turns and its schedule's arithmetic (backend/commands/airtime.py): a
Surface first among those waiting, then in the order they asked; a waiter cancelled as its turn
came passes it on; the airtime budget of copies spaced per command, a frame at a time."""

from __future__ import annotations

import asyncio

import pytest

from backend.commands.airtime import (
    IN_TURN,
    SURFACE_FIRST,
    Queued,
    TransmitTurns,
    airtime_budget_s,
    copies_out_s,
)

A = 0.003  # one frame's airtime (s)


def test_waiters_are_served_surface_first_then_in_order() -> None:
    async def main() -> list[str]:
        turns = TransmitTurns()
        order: list[str] = []
        release = asyncio.Event()

        async def frame(name: str, priority: int) -> None:
            async with turns.turn(priority):
                order.append(name)
                if name == "first":
                    await release.wait()

        tasks = [asyncio.create_task(frame("first", IN_TURN))]
        await asyncio.sleep(0)
        assert turns.locked()
        for name, priority in (("b", IN_TURN), ("c", IN_TURN), ("surface", SURFACE_FIRST)):
            tasks.append(asyncio.create_task(frame(name, priority)))
            await asyncio.sleep(0)
        release.set()
        await asyncio.gather(*tasks)
        assert not turns.locked()
        return order

    assert asyncio.run(main()) == ["first", "surface", "b", "c"]


def test_a_waiter_cancelled_gives_its_turn_to_the_next() -> None:
    async def main() -> list[str]:
        turns = TransmitTurns()
        order: list[str] = []
        release = asyncio.Event()

        async def frame(name: str) -> None:
            async with turns.turn():
                order.append(name)
                if name == "first":
                    await release.wait()

        first = asyncio.create_task(frame("first"))
        await asyncio.sleep(0)
        gone = asyncio.create_task(frame("gone"))
        last = asyncio.create_task(frame("last"))
        await asyncio.sleep(0)
        gone.cancel()
        release.set()
        await asyncio.gather(first, last)
        with pytest.raises(asyncio.CancelledError):
            await gone
        assert not turns.locked()
        return order

    assert asyncio.run(main()) == ["first", "last"]


def test_copies_are_spaced_per_command_and_a_surface_goes_first_when_due_together() -> None:
    circle = Queued(copies_left=2, due_in_s=0.0, interval_s=1.0, airtime_s=A)
    surface = Queued(copies_left=1, due_in_s=0.0, interval_s=2.0, airtime_s=A, surface=True)
    ends = copies_out_s([circle, surface])
    # the Surface's copy first [0, A]; the circle's [A, 2A], its second 1 s after it ends
    assert ends == pytest.approx([2 * A + 1.0 + A, A])
    assert airtime_budget_s([circle, surface]) == pytest.approx(1.0 + 3 * A)


def test_until_acknowledged_and_nothing_queued_count_nothing() -> None:
    repeating = Queued(copies_left=None, due_in_s=0.0, interval_s=2.0, airtime_s=A, surface=True)
    assert copies_out_s([repeating]) == [0.0]
    assert airtime_budget_s([]) == 0.0
    later = Queued(copies_left=1, due_in_s=5.0, interval_s=1.0, airtime_s=A)
    assert airtime_budget_s([repeating, later]) == pytest.approx(5.0 + A)
