"""The command manager against an in-memory link: every transition of the lifecycle as the
manager drives it, superseding, Surface (joined, bounded, reset, shutdown) and retries.

Time is a :class:`tests.manual_clock.ManualClock` moved by the test, with the console's default
intervals: copies and timeouts happen at their exact times, and "nothing more went out" is
proved by moving the clock past every timer that could have sent it (no real waiting)."""

from __future__ import annotations

import asyncio
import itertools
import logging
from collections.abc import Awaitable, Callable, Coroutine
from pathlib import Path
from typing import Any

import pytest

from backend.commands.health import assess
from backend.commands.manager import MIN_SURFACE_COPIES, CommandManager, RateLimited
from backend.commands.records import CommandRecords
from backend.messages import CommandMessage, News
from backend.mission_log.store import MissionLog
from backend.telemetry import TelemetryHub
from codec import Encoded, Frame, copies_for, delivery_probability, encode_frame
from station.link import Capability, Link
from tests.backend.conftest import command_fields
from tests.manual_clock import ManualClock

CIRCLE = encode_frame("circle", {"speed": 0.18, "depth": 3, "radius": 5, "direction": "cw"})
HOVER = encode_frame("hover", {"duration": 60, "depth": 2, "heading": 90})
SURFACE = encode_frame("surface", {})
#: The console's defaults (backend/settings.py), on the manual clock (s).
COPY_INTERVAL_S = 1.0
SURFACE_REPEAT_S = 2.0
ACK_TIMEOUT_S = 5.0
AIRTIME_S = 100 / 36000


class FakeLink(Link):
    """Frames out into a list (in order, with their time on ``clock``); ``fail`` makes them
    fail."""

    def __init__(self, capability: Capability, clock: ManualClock) -> None:
        super().__init__("fake://vehicle")
        self.capability = capability
        self.clock = clock
        self.frames: list[tuple[float, str]] = []
        self.fail: str | None = None

    @property
    def connected(self) -> bool:
        return True

    async def transmit(self, frame: Frame) -> str | None:
        await asyncio.sleep(0)
        if self.fail is not None:
            return self.fail
        self.frames.append((self.clock.monotonic(), frame.hex))
        return None

    def count(self, enc: Encoded) -> int:
        return sum(h == enc.frame.hex for _, h in self.frames)


class RecordingHub(TelemetryHub):
    """Keeps every command state it is asked to announce."""

    def __init__(self) -> None:
        super().__init__()
        self.states: dict[int, list[str]] = {}

    def publish(self, event: News) -> None:
        if isinstance(event, CommandMessage):
            record = event.command
            self.states.setdefault(record.id, []).append(record.state)


class Rig:
    def __init__(
        self,
        tmp_path: Path,
        capability: Capability,
        ber: float = 1e-2,
        where: Path | str | None = None,
    ) -> None:
        """``where``: the log (default: a SQLite file in ``tmp_path``)."""
        self.log = MissionLog(where or tmp_path / "missions.sqlite3")
        self.dive = self.log.new_dive("fake")
        self.clock = ManualClock()
        self.link = FakeLink(capability, self.clock)
        self.hub = RecordingHub()
        self.ber = ber
        self.cm = CommandManager(
            self.log,
            self.link,
            self.hub,
            dive=lambda: self.dive,
            operator="op",
            ack_timeout_s=ACK_TIMEOUT_S,
            surface_repeat_s=SURFACE_REPEAT_S,
            max_sends_per_minute=5,
            copy_interval_s=COPY_INTERVAL_S,
            link_ber=lambda: (self.ber, 0.0),
            airtime_s=AIRTIME_S,
            clock=self.clock,
        )

    async def surface(self) -> dict[str, Any]:
        """A Surface, as the command service hands it to the manager."""
        return await self.cm.submit(encode_frame("surface", {}), kind="surface", origin="surface")

    def state(self, command_id: int) -> str:
        record = self.log.command(command_id)
        assert record is not None
        return str(record["state"])

    def record(self, command_id: int) -> dict[str, Any]:
        record = self.log.command(command_id)
        assert record is not None
        return record

    async def until(self, probe: Callable[[], bool], within_s: float = 60.0) -> float:
        """Move the clock timer by timer until ``probe()`` holds; the clock seconds it took."""
        return await self.clock.advance_until(probe, within_s)

    async def until_state(self, command_id: int, *states: str, within_s: float = 60.0) -> float:
        return await self.until(lambda: self.state(command_id) in states, within_s)

    def ack(self, enc: Encoded, outcome: str = "accepted", reason: str | None = None) -> None:
        self.cm.on_mission(
            {
                "frame_hex": enc.frame.hex,
                "outcome": outcome,
                "reason": reason,
                "detail": None if reason is None else f"{reason} detail",
                "active": None,
            }
        )


def run(tmp_path: Path, capability: Capability, scenario: Callable[[Rig], Awaitable[None]]) -> Rig:
    rig = Rig(tmp_path, capability)

    async def main() -> None:
        try:
            await scenario(rig)
        finally:
            await rig.cm.close()

    coro: Coroutine[Any, Any, None] = main()
    asyncio.run(coro)
    return rig


ONE_WAY = Capability.NONE
TWO_WAY = Capability.ACKS_AND_TELEMETRY


# --- one-way links ----------------------------------------------------------------------------


def test_one_way_sends_copies_chosen_from_the_ber_then_ends_sent(tmp_path: Path) -> None:
    async def scenario(rig: Rig) -> None:
        rec = await rig.cm.submit(CIRCLE)
        r = copies_for(1e-2, 0.999)
        assert r == 3 and rec["copies"] == r and rec["state"] == "queued"
        assert rec["two_way"] is False and rec["ber"] == 1e-2
        took_s = await rig.until_state(rec["id"], "sent")
        done = rig.record(rec["id"])
        assert done["copies_sent"] == r and done["attempts"] == r
        assert done["p_delivered"] == pytest.approx(delivery_probability(1e-2, r))
        assert rig.link.count(CIRCLE) == r
        times = [t for t, _ in rig.link.frames]
        assert all(b - a == COPY_INTERVAL_S for a, b in itertools.pairwise(times))
        assert took_s == (r - 1) * COPY_INTERVAL_S  # sent once the last copy is out
        assert rig.clock.pending() == []  # nothing left that could send again
        assert rig.hub.states[rec["id"]] == ["queued", *["transmitted"] * r, "sent"]
        totals = rig.cm.ledger.totals()
        assert totals.dive.frames == r and totals.dive.sent == r

    run(tmp_path, ONE_WAY, scenario)


def test_operator_copies_override(tmp_path: Path) -> None:
    async def scenario(rig: Rig) -> None:
        rec = await rig.cm.submit(CIRCLE, copies=5)
        await rig.until_state(rec["id"], "sent")
        assert rig.link.count(CIRCLE) == 5 and rig.record(rec["id"])["copies_sent"] == 5

    run(tmp_path, ONE_WAY, scenario)


def test_no_copy_leaves_the_station_failed(tmp_path: Path) -> None:
    async def scenario(rig: Rig) -> None:
        rig.link.fail = "connection refused"
        rec = await rig.cm.submit(CIRCLE, copies=2)
        await rig.until_state(rec["id"], "failed")
        done = rig.record(rec["id"])
        assert done["attempts"] == 2 and done["copies_sent"] == 0 and done["p_delivered"] == 0
        assert "connection refused" in done["reason"]
        assert rig.hub.states[rec["id"]] == ["queued", "queued", "queued", "failed"]

    run(tmp_path, ONE_WAY, scenario)


def test_some_copies_failing_still_ends_sent_with_what_went_out(tmp_path: Path) -> None:
    async def scenario(rig: Rig) -> None:
        rig.link.fail = "timeout"
        rec = await rig.cm.submit(CIRCLE, copies=3)
        await rig.until(lambda: rig.record(rec["id"])["attempts"] == 1)
        rig.link.fail = None
        await rig.until_state(rec["id"], "sent")
        done = rig.record(rec["id"])
        assert done["attempts"] == 3 and done["copies_sent"] == 2 and done["reason"] is None
        assert done["p_delivered"] == pytest.approx(delivery_probability(1e-2, 2))

    run(tmp_path, ONE_WAY, scenario)


def test_a_newer_command_supersedes_one_still_repeating(tmp_path: Path) -> None:
    async def scenario(rig: Rig) -> None:
        old = await rig.cm.submit(CIRCLE, copies=20)
        await rig.until(lambda: rig.link.count(CIRCLE) >= 2)
        new = await rig.cm.submit(HOVER, copies=2)
        assert rig.state(old["id"]) == "superseded"  # at once, before any hover frame
        await rig.until_state(new["id"], "sent")
        gone = rig.record(old["id"])
        assert gone["superseded_by"] == new["id"] and f"command {new['id']}" in gone["reason"]
        hexes = [h for _, h in rig.link.frames]
        first_new = hexes.index(HOVER.frame.hex)
        assert CIRCLE.frame.hex not in hexes[first_new:]
        assert gone["copies_sent"] == rig.link.count(CIRCLE) < 20

    run(tmp_path, ONE_WAY, scenario)


def test_surface_on_a_one_way_link_is_bounded(tmp_path: Path) -> None:
    async def scenario(rig: Rig) -> None:
        rec = await rig.surface()
        expected = copies_for(1e-2, 0.999999, minimum=MIN_SURFACE_COPIES)
        assert rec["copies"] == expected >= MIN_SURFACE_COPIES
        await rig.until_state(rec["id"], "sent")
        assert rig.link.count(SURFACE) == expected
        assert rig.record(rec["id"])["p_delivered"] >= 0.999999
        rig.ber = 0.0  # a clean link still gets the minimum
        assert rig.cm.surface_copies_now() == MIN_SURFACE_COPIES

    run(tmp_path, ONE_WAY, scenario)


def test_surface_pressed_during_a_surface_joins_it(tmp_path: Path) -> None:
    async def scenario(rig: Rig) -> None:
        first = await rig.surface()
        await rig.until(lambda: rig.link.count(SURFACE) >= 1)
        presses = await asyncio.gather(*(rig.surface() for _ in range(20)))
        assert {p["id"] for p in presses} == {first["id"]}
        await rig.until_state(first["id"], "sent")
        done = rig.record(first["id"])
        assert done["copies"] == done["copies_sent"] == rig.link.count(SURFACE)
        assert done["copies"] > first["copies"]
        assert len(rig.log.commands()) == 1  # one record, never an orphan queued

    run(tmp_path, ONE_WAY, scenario)


def test_a_command_supersedes_a_repeating_surface(tmp_path: Path) -> None:
    async def scenario(rig: Rig) -> None:
        surface = await rig.surface()
        await rig.until(lambda: rig.link.count(SURFACE) >= 1)
        hover = await rig.cm.submit(HOVER, copies=1)
        await rig.until_state(hover["id"], "sent")
        assert rig.state(surface["id"]) == "superseded"
        await rig.clock.advance(2 * SURFACE_REPEAT_S)  # two more Surface intervals
        assert rig.clock.pending() == []
        hexes = [h for _, h in rig.link.frames]
        assert hexes[-1] == HOVER.frame.hex and hexes.count(SURFACE.frame.hex) == 1

    run(tmp_path, ONE_WAY, scenario)


def test_shutdown_during_repeats_interrupts(tmp_path: Path) -> None:
    ids: list[int] = []

    async def scenario(rig: Rig) -> None:
        rec = await rig.cm.submit(CIRCLE, copies=20)
        ids.append(rec["id"])
        await rig.until(lambda: rig.link.count(CIRCLE) >= 2)
        await rig.cm.close()
        out = rig.link.count(CIRCLE)
        await rig.clock.advance(5 * COPY_INTERVAL_S)
        assert rig.link.count(CIRCLE) == out  # nothing after shutdown
        assert rig.clock.pending() == []

    rig = run(tmp_path, ONE_WAY, scenario)
    done = rig.record(ids[0])
    assert done["state"] == "interrupted" and "shut down" in done["reason"]


def test_rate_limit_never_applies_to_surface(tmp_path: Path) -> None:
    async def scenario(rig: Rig) -> None:
        for _ in range(5):
            await rig.cm.submit(CIRCLE, copies=1)
            await rig.clock.advance(10.0)
        with pytest.raises(RateLimited) as limited:
            await rig.cm.submit(CIRCLE, copies=1)
        assert limited.value.retry_after_s == pytest.approx(10.0)  # the first send's minute
        assert (await rig.surface())["kind"] == "surface"
        await rig.clock.advance(10.001)  # the first send is over a minute old: one more
        await rig.cm.submit(CIRCLE, copies=1)
        with pytest.raises(RateLimited):
            await rig.cm.submit(CIRCLE, copies=1)

    run(tmp_path, ONE_WAY, scenario)


# --- two-way links ----------------------------------------------------------------------------


def test_two_way_accepted(tmp_path: Path) -> None:
    async def scenario(rig: Rig) -> None:
        rec = await rig.cm.submit(CIRCLE)
        assert rec["copies"] == 1 and rec["two_way"] is True
        await rig.until(lambda: rig.link.count(CIRCLE) == 1)
        rig.ack(CIRCLE)
        assert rig.state(rec["id"]) == "acknowledged"
        assert rig.hub.states[rec["id"]] == ["queued", "transmitted", "acknowledged"]
        assert rig.cm.ledger.totals().recent.acknowledged == 1

    run(tmp_path, TWO_WAY, scenario)


def test_two_way_rejected_for_its_content(tmp_path: Path) -> None:
    async def scenario(rig: Rig) -> None:
        rec = await rig.cm.submit(CIRCLE, copies=3)
        await rig.until(lambda: rig.link.count(CIRCLE) == 1)
        rig.ack(CIRCLE, "rejected", "limit_violation")
        assert rig.state(rec["id"]) == "rejected"
        assert rig.record(rec["id"])["reason"].startswith("limit_violation")
        await rig.clock.advance(3 * COPY_INTERVAL_S)
        assert rig.link.count(CIRCLE) == 1  # no more copies of a rejected command
        assert rig.clock.pending() == []

    run(tmp_path, TWO_WAY, scenario)


def test_two_way_damaged_copy_waits_for_the_next(tmp_path: Path) -> None:
    async def scenario(rig: Rig) -> None:
        rec = await rig.cm.submit(CIRCLE, copies=3)
        await rig.until(lambda: rig.link.count(CIRCLE) == 1)
        rig.ack(CIRCLE, "rejected", "uncorrectable")
        assert rig.state(rec["id"]) == "transmitted"
        assert "damaged" in rig.record(rec["id"])["reason"]
        await rig.until(lambda: rig.link.count(CIRCLE) == 2)
        rig.ack(CIRCLE)
        assert rig.state(rec["id"]) == "acknowledged"

    run(tmp_path, TWO_WAY, scenario)


def test_two_way_timeout_after_the_last_copy(tmp_path: Path) -> None:
    async def scenario(rig: Rig) -> None:
        rec = await rig.cm.submit(CIRCLE, copies=2)
        took_s = await rig.until_state(rec["id"], "timed_out")
        # the timeout runs from the last copy (and its airtime), not the first
        assert took_s == pytest.approx(COPY_INTERVAL_S + ACK_TIMEOUT_S + AIRTIME_S)
        done = rig.record(rec["id"])
        assert done["copies_sent"] == 2 and "no acknowledgement" in done["reason"]
        late = rig.record(rec["id"])
        rig.ack(CIRCLE)  # a late acknowledgement never reopens a terminal record
        assert rig.record(rec["id"]) == late
        recent = rig.cm.ledger.totals().recent
        assert recent.timed_out == 2
        level, problems = assess(
            connected=True,
            connection_problem=None,
            capability=TWO_WAY,
            capability_problems=[],
            telemetry_age_s=0.1,
            recent=recent,
            unknown_recent=0,
        )
        assert level == "red" and "2 of the last 2 answered frames timed out" in problems[0]

    run(tmp_path, TWO_WAY, scenario)


def test_a_command_awaiting_its_ack_is_not_superseded(tmp_path: Path) -> None:
    async def scenario(rig: Rig) -> None:
        old = await rig.cm.submit(CIRCLE)
        await rig.until(lambda: rig.link.count(CIRCLE) == 1)
        new = await rig.cm.submit(HOVER)
        assert rig.state(old["id"]) == "transmitted"  # all its copies are out: it waits
        await rig.until(lambda: rig.link.count(HOVER) == 1)
        rig.ack(CIRCLE)
        rig.ack(HOVER)
        assert (rig.state(old["id"]), rig.state(new["id"])) == ("acknowledged", "acknowledged")

    run(tmp_path, TWO_WAY, scenario)


def test_two_way_surface_repeats_until_acknowledged(tmp_path: Path) -> None:
    async def scenario(rig: Rig) -> None:
        rig.cm.ack_timeout_s = 0.5  # per-copy timeouts (between repeats) must not end it
        rec = await rig.surface()
        assert rec["copies"] is None
        took_s = await rig.until(lambda: rig.link.count(SURFACE) >= 5)
        assert took_s == 4 * SURFACE_REPEAT_S
        assert rig.state(rec["id"]) == "transmitted"
        rig.ack(SURFACE)
        assert rig.state(rec["id"]) == "acknowledged"
        out = rig.link.count(SURFACE)
        await rig.clock.advance(5 * SURFACE_REPEAT_S)
        assert rig.link.count(SURFACE) == out
        assert rig.clock.pending() == []

    run(tmp_path, TWO_WAY, scenario)


def test_two_way_surface_is_superseded_by_a_newer_command(tmp_path: Path) -> None:
    async def scenario(rig: Rig) -> None:
        surface = await rig.surface()
        await rig.until(lambda: rig.link.count(SURFACE) >= 2)
        hover = await rig.cm.submit(HOVER)
        await rig.until(lambda: rig.link.count(HOVER) == 1)
        rig.ack(SURFACE)  # a late acknowledgement of a replaced Surface changes nothing
        assert rig.state(surface["id"]) == "superseded"
        rig.ack(HOVER)
        assert rig.state(hover["id"]) == "acknowledged"
        hexes = [h for _, h in rig.link.frames]
        assert SURFACE.frame.hex not in hexes[hexes.index(HOVER.frame.hex) :]

    run(tmp_path, TWO_WAY, scenario)


def test_reset_during_a_surface_stops_it_and_a_late_ack_changes_nothing(tmp_path: Path) -> None:
    async def scenario(rig: Rig) -> None:
        rec = await rig.surface()
        await rig.until(lambda: rig.link.count(SURFACE) >= 2)
        rig.cm.reset_vehicle()
        assert rig.state(rec["id"]) == "interrupted"
        assert "reset" in rig.record(rec["id"])["reason"]
        out = rig.link.count(SURFACE)
        await rig.clock.advance(5 * SURFACE_REPEAT_S)
        assert rig.link.count(SURFACE) == out
        assert rig.clock.pending() == []
        rig.ack(SURFACE)
        assert rig.state(rec["id"]) == "interrupted"
        assert rig.cm.ledger.totals().dive.frames == 0  # a new dive counts afresh

    run(tmp_path, TWO_WAY, scenario)


def test_a_record_that_does_not_fit_its_model_is_logged_not_raised(
    tmp_path: Path, caplog: pytest.LogCaptureFixture
) -> None:
    """Announcing a state change never stops a delivery: a record the page's message cannot
    carry (a bookkeeping bug) is logged, the state is written, the next one announced."""
    log = MissionLog(tmp_path / "missions.sqlite3")
    try:
        hub = RecordingHub()
        records = CommandRecords(log, hub)
        dive = log.new_dive("fake")
        odd = log.insert_command(dive, {**command_fields(), "kind": "mystery"})
        good = log.insert_command(dive, command_fields())
        with caplog.at_level(logging.ERROR, logger="backend.commands.manager"):
            records._update(odd["id"], attempts=1)
            records._update(good["id"], attempts=1)
        written = log.command(odd["id"])
        assert written is not None and written["attempts"] == 1
        assert hub.states == {good["id"]: ["queued"]}
        assert f"command {odd['id']} not announced" in caplog.text
    finally:
        log.close()
