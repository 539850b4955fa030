"""The command manager with a fleet on one transmitter (issue 23, item 4), on the manual clock:
each frame addressed to its vehicle, copies of different vehicles interleaved and each
vehicle's spaced as before, a Surface first, the supersede rule per vehicle, a Surface to all
(one address-0 frame, one record per vehicle) superseding every vehicle's and split when one
vehicle gets a newer command, acknowledgements settled among their vehicle's records, and the
airtime budget of what is queued.

Every frame on the wire is decoded with the codec to read its address and command: the rule
"never a copy of an older command for a vehicle after the first copy of a newer one" is
checked from the wire, not from the records."""

from __future__ import annotations

import asyncio
import itertools
from collections.abc import Awaitable, Callable
from pathlib import Path
from typing import Any

import pytest

from backend.commands.airtime import airtime_budget_s
from backend.commands.manager import CommandManager, FleetMember
from backend.mission_log.store import FINAL_STATES as FINAL
from backend.mission_log.store import MissionLog
from backend.telemetry import TelemetryHub
from codec import decode_addressed_frame, encode_frame
from station.link import Capability, Link
from tests.backend.commands.test_manager import FakeLink, RecordingHub
from tests.manual_clock import ManualClock

Params = dict[str, Any]
CIRCLE: Params = {"speed": 0.18, "depth": 3, "radius": 5, "direction": "cw"}
HOVER: Params = {"duration": 60, "depth": 2, "heading": 90}
SQUARE: Params = {"speed": 0.18, "depth": 2, "side_span": 6, "direction": "cw"}
NAMES = ("auv1", "auv2", "auv3")
COPY_INTERVAL_S = 1.0
SURFACE_REPEAT_S = 2.0
AIRTIME_S = 100 / 36000
ONE_WAY = Capability.NONE
TWO_WAY = Capability.ACKS_AND_TELEMETRY


class VehicleSide(Link):
    """What a fleet's vehicle reports over (here: only its capability)."""

    def __init__(self, capability: Capability) -> None:
        super().__init__("fake://vehicle")
        self.capability = capability


class FleetRig:
    def __init__(self, tmp_path: Path, capability: Capability, ber: float = 1e-2) -> None:
        self.log = MissionLog(tmp_path / "missions.sqlite3")
        self.dive = self.log.new_dive("fake")
        self.clock = ManualClock()
        self.link = FakeLink(ONE_WAY, self.clock)  # the one transmitter
        self.hub = RecordingHub()
        self.cm = CommandManager(
            self.log,
            self.link,
            self.hub,
            dive=lambda: self.dive,
            operator="op",
            ack_timeout_s=5.0,
            surface_repeat_s=SURFACE_REPEAT_S,
            max_sends_per_minute=30,
            copy_interval_s=COPY_INTERVAL_S,
            link_ber=lambda: (ber, 0.0),
            airtime_s=AIRTIME_S,
            clock=self.clock,
            fleet=[
                FleetMember(name, i + 1, VehicleSide(capability), TelemetryHub())
                for i, name in enumerate(NAMES)
            ],
        )

    async def send(
        self, vehicle: str, pattern: str, params: dict[str, Any], copies: int | None = None
    ) -> dict[str, Any]:
        """A command as the command service hands it over: its frame addressed."""
        enc = encode_frame(pattern, params, address=NAMES.index(vehicle) + 1)
        return await self.cm.submit(enc, copies=copies, vehicle=vehicle)

    async def surface(self, vehicle: str = "all") -> list[dict[str, Any]]:
        address = 0 if vehicle == "all" else NAMES.index(vehicle) + 1
        enc = encode_frame("surface", {}, address=address)
        return await self.cm.submit_all(enc, kind="surface", origin="surface", vehicle=vehicle)

    def wire(self) -> list[tuple[float, int, str, dict[str, Any]]]:
        """Every frame on the wire, decoded: (time, address, pattern, params)."""
        out = []
        for t, hex_ in self.link.frames:
            d = decode_addressed_frame(hex_)
            out.append((t, d.address, d.command.pattern.name, dict(d.command.params)))
        return out

    def state(self, command_id: int) -> str:
        record = self.log.command(command_id)
        assert record is not None
        return str(record["state"])

    async def until(self, probe: Callable[[], bool], within_s: float = 120.0) -> float:
        return await self.clock.advance_until(probe, within_s)


def run(
    tmp_path: Path, capability: Capability, scenario: Callable[[FleetRig], Awaitable[None]]
) -> FleetRig:
    rig = FleetRig(tmp_path, capability)

    async def main() -> None:
        try:
            await scenario(rig)
        finally:
            await rig.cm.close()
            rig.log.close()

    asyncio.run(main())
    return rig


def newer_rule_holds(wire: list[tuple[float, int, str, dict[str, Any]]], order: list[Any]) -> None:
    """No frame of an older command for a vehicle after the first frame of a newer one for
    it. ``order``: the commands in the order they were sent, each ``(address, pattern,
    params)`` (address 0 is every vehicle's)."""
    for vehicle in (1, 2, 3):
        mine = [i for i, (a, *_rest) in enumerate(order) if a in (0, vehicle)]
        firsts = {
            i: next((k for k, f in enumerate(wire) if (f[1], f[2], f[3]) == order[i]), len(wire))
            for i in mine
        }
        for older, newer in itertools.combinations(mine, 2):
            late = [k for k, f in enumerate(wire) if (f[1], f[2], f[3]) == order[older]]
            assert all(k < firsts[newer] for k in late), (
                f"vehicle {vehicle}: a copy of {order[older]} after {order[newer]}'s first"
            )


def test_each_frame_carries_its_vehicles_address_and_the_record_names_it(
    tmp_path: Path,
) -> None:
    async def scenario(rig: FleetRig) -> None:
        rec = await rig.send("auv2", "circle", CIRCLE, copies=1)
        assert rec["vehicle"] == "auv2" and len(rec["bits"]) == 108
        await rig.until(lambda: rig.state(rec["id"]) == "sent")
        assert [(a, p) for _, a, p, _ in rig.wire()] == [(2, "circle")]
        assert rig.cm.vehicles["auv2"].last_sent is not None
        assert rig.cm.vehicles["auv1"].last_sent is None

    run(tmp_path, ONE_WAY, scenario)


def test_copies_of_different_vehicles_interleave_each_spaced_as_before(tmp_path: Path) -> None:
    async def scenario(rig: FleetRig) -> None:
        recs = [await rig.send(n, "circle", CIRCLE, copies=3) for n in NAMES]
        await rig.until(lambda: all(rig.state(r["id"]) == "sent" for r in recs))
        wire = rig.wire()
        assert [a for _, a, _, _ in wire] == [1, 2, 3] * 3  # a frame at a time, in turn
        for address in (1, 2, 3):
            times = [t for t, a, _, _ in wire if a == address]
            assert all(b - a == COPY_INTERVAL_S for a, b in itertools.pairwise(times))

    run(tmp_path, ONE_WAY, scenario)


def test_a_newer_command_supersedes_only_its_own_vehicles(tmp_path: Path) -> None:
    async def scenario(rig: FleetRig) -> None:
        a1 = await rig.send("auv1", "circle", CIRCLE, copies=5)
        a2 = await rig.send("auv2", "hover", HOVER, copies=5)
        await rig.until(lambda: len(rig.link.frames) >= 4)
        b1 = await rig.send("auv1", "square", SQUARE, copies=2)
        await rig.until(lambda: rig.state(a2["id"]) == "sent" and rig.state(b1["id"]) == "sent")
        assert rig.state(a1["id"]) == "superseded"
        assert rig.log.command(a1["id"])["superseded_by"] == b1["id"]  # type: ignore[index]
        assert rig.log.command(a2["id"])["copies_sent"] == 5  # type: ignore[index]
        order = [(1, "circle", CIRCLE), (2, "hover", HOVER), (1, "square", SQUARE)]
        newer_rule_holds(rig.wire(), [_snapped(o) for o in order])

    run(tmp_path, ONE_WAY, scenario)


def _snapped(command: tuple[int, str, dict[str, Any]]) -> tuple[int, str, dict[str, Any]]:
    """A command as the wire carries it (its values snapped)."""
    address, pattern, params = command
    return address, pattern, dict(encode_frame(pattern, params).command.params)


def test_surface_to_all_is_one_frame_one_record_per_vehicle_superseding_all(
    tmp_path: Path,
) -> None:
    async def scenario(rig: FleetRig) -> None:
        running = [await rig.send(n, "circle", CIRCLE, copies=10) for n in NAMES]
        await rig.until(lambda: len(rig.link.frames) >= 3)
        records = await rig.surface("all")
        assert [r["vehicle"] for r in records] == list(NAMES)
        assert len({r["hex"] for r in records}) == 1
        assert decode_addressed_frame(records[0]["hex"]).address == 0
        await rig.until(lambda: all(rig.state(r["id"]) == "sent" for r in records))
        assert all(rig.state(r["id"]) == "superseded" for r in running)
        wire = rig.wire()
        first = next(k for k, f in enumerate(wire) if f[2] == "surface")
        assert all(f[2] == "surface" and f[1] == 0 for f in wire[first:])
        # one frame for all: each record counts every copy of it
        copies = sum(f[2] == "surface" for f in wire)
        sent = [rig.log.command(r["id"]) for r in records]
        assert all(r is not None and r["copies_sent"] == copies for r in sent)

    run(tmp_path, ONE_WAY, scenario)


def test_a_command_after_surface_to_all_splits_it_and_never_follows_an_address_0_copy(
    tmp_path: Path,
) -> None:
    async def scenario(rig: FleetRig) -> None:
        records = await rig.surface("all")
        await rig.until(lambda: len(rig.link.frames) >= 1)
        later = await rig.send("auv2", "hover", HOVER, copies=2)
        ended = [*records, later]
        await rig.until(lambda: all(rig.state(r["id"]) in FINAL for r in ended))
        states = {r["vehicle"]: rig.state(r["id"]) for r in records}
        assert states == {"auv1": "sent", "auv2": "superseded", "auv3": "sent"}
        wire = rig.wire()
        hover = next(k for k, f in enumerate(wire) if f[2] == "hover")
        assert not [f for f in wire[hover:] if f[1] == 0]  # no Surface to all after it
        rest = {f[1] for f in wire[hover:] if f[2] == "surface"}
        assert rest == {1, 3}  # the others' Surface went on, each addressed alone
        order = [(0, "surface", {}), (2, "hover", HOVER)]
        newer_rule_holds(wire, [_snapped(o) for o in order])

    run(tmp_path, ONE_WAY, scenario)


#: A command another console sharing the log wrote (its id: after every one of this console's).
ELSEWHERE = 10_000


def test_another_consoles_command_supersedes_only_that_vehicles_commands_here(
    tmp_path: Path,
) -> None:
    """Two transmitting consoles on one log (backend.control.sync): another console's command
    to auv2 ends this console's auv2 command, not auv1's nor auv3's."""

    async def scenario(rig: FleetRig) -> None:
        running = {n: await rig.send(n, "circle", CIRCLE, copies=10) for n in NAMES}
        await rig.until(lambda: len(rig.link.frames) >= 3)
        stopped = rig.cm.superseded_elsewhere(ELSEWHERE, "ship_b", "auv2")
        assert stopped == [running["auv2"]["id"]]
        record = rig.log.command(running["auv2"]["id"])
        assert record is not None and record["state"] == "superseded"
        assert record["superseded_by"] == ELSEWHERE and "console 'ship_b'" in record["reason"]
        sent = len(rig.link.frames)
        await rig.until(
            lambda: all(rig.state(running[n]["id"]) == "sent" for n in ("auv1", "auv3"))
        )
        assert [f for f in rig.wire()[sent:] if f[1] == 2] == []  # nothing more to auv2

    run(tmp_path, ONE_WAY, scenario)


def test_another_consoles_command_splits_a_surface_to_all_here(tmp_path: Path) -> None:
    async def scenario(rig: FleetRig) -> None:
        records = await rig.surface("all")
        await rig.until(lambda: len(rig.link.frames) >= 1)
        sent = len(rig.link.frames)
        rig.cm.superseded_elsewhere(ELSEWHERE, "ship_b", "auv1")
        await rig.until(lambda: all(rig.state(r["id"]) in FINAL for r in records))
        states = {r["vehicle"]: rig.state(r["id"]) for r in records}
        assert states == {"auv1": "superseded", "auv2": "sent", "auv3": "sent"}
        later = rig.wire()[sent:]
        assert later and {f[1] for f in later} == {2, 3}  # each alone: no address 0, none to 1

    run(tmp_path, ONE_WAY, scenario)


def test_another_consoles_command_without_a_vehicle_supersedes_every_command_here(
    tmp_path: Path,
) -> None:
    """A console without a fleet names no vehicle: as before, it supersedes everything."""

    async def scenario(rig: FleetRig) -> None:
        running = [await rig.send(n, "circle", CIRCLE, copies=10) for n in NAMES]
        await rig.until(lambda: len(rig.link.frames) >= 3)
        stopped = rig.cm.superseded_elsewhere(ELSEWHERE, "other", None)
        assert sorted(stopped) == sorted(r["id"] for r in running)

    run(tmp_path, ONE_WAY, scenario)


def test_surface_goes_ahead_of_every_copy_waiting_for_the_transmitter(tmp_path: Path) -> None:
    async def scenario(rig: FleetRig) -> None:
        gate = asyncio.Event()
        send = rig.link.transmit

        async def held(frame: Any) -> str | None:  # a frame on the air until the gate opens
            await gate.wait()
            return await send(frame)

        rig.link.transmit = held  # type: ignore[method-assign]
        circles = [await rig.send(n, "circle", CIRCLE, copies=5) for n in ("auv1", "auv2")]
        await rig.clock.settle()
        assert rig.cm._tx_lock.locked()  # auv1's first copy is on the air, auv2's waits
        surface = await rig.surface("auv3")  # asked last
        await rig.clock.settle()
        gate.set()
        await rig.until(lambda: len(rig.link.frames) >= 3)
        assert [(f[1], f[2]) for f in rig.wire()[:3]] == [
            (1, "circle"),
            (3, "surface"),  # ahead of auv2's copy, which was waiting before it
            (2, "circle"),
        ]
        assert all(rig.state(c["id"]) == "transmitted" for c in circles)
        assert surface[0]["vehicle"] == "auv3"

    run(tmp_path, ONE_WAY, scenario)


def test_two_way_each_vehicle_settles_its_own_record(tmp_path: Path) -> None:
    async def scenario(rig: FleetRig) -> None:
        records = await rig.surface("all")
        assert all(r["copies"] is None and r["two_way"] for r in records)  # until acked
        await rig.until(lambda: len(rig.link.frames) >= 1)
        frame_hex = rig.link.frames[0][1]
        other = {"frame_hex": frame_hex, "outcome": "rejected", "reason": "other_vehicle"}
        rig.cm.on_mission(other, "auv1")  # says nothing of auv1's records
        assert rig.state(records[0]["id"]) == "transmitted"
        for name in NAMES:
            ack = {"frame_hex": frame_hex, "outcome": "accepted", "address": 0}
            rig.cm.on_mission({**ack, "active": {"pattern": "surface", "params": {}}}, name)
            await rig.clock.settle()
        assert [rig.state(r["id"]) for r in records] == ["acknowledged"] * 3
        await rig.clock.advance(10 * SURFACE_REPEAT_S)
        frames = len(rig.link.frames)
        await rig.clock.advance(10 * SURFACE_REPEAT_S)
        assert len(rig.link.frames) == frames  # every vehicle acknowledged: no more copies

    run(tmp_path, TWO_WAY, scenario)


def test_the_airtime_budget_counts_every_queued_copy_and_runs_down(tmp_path: Path) -> None:
    async def scenario(rig: FleetRig) -> None:
        for n in NAMES:
            await rig.send(n, "circle", CIRCLE, copies=3)
        ways = rig.cm.on_the_way()
        assert sorted(w.vehicles for w in ways) == [("auv1",), ("auv2",), ("auv3",)]
        airtime = 108 / 36000
        # 3 copies each, 1 s apart after each frame's end, three vehicles in turn
        expected = 2 * (COPY_INTERVAL_S + airtime) + 3 * airtime
        assert airtime_budget_s([w.queued for w in ways]) == pytest.approx(expected)
        await rig.until(lambda: len(rig.link.frames) >= 3)
        later = airtime_budget_s([w.queued for w in rig.cm.on_the_way()])
        assert 0 < later < expected
        await rig.until(lambda: not rig.cm.on_the_way())
        assert airtime_budget_s([w.queued for w in rig.cm.on_the_way()]) == 0.0

    run(tmp_path, ONE_WAY, scenario)


def test_an_unaddressed_encoding_is_the_single_vehicles(tmp_path: Path) -> None:
    """The single vehicle's manager is today's: no vehicle in its records."""

    async def scenario(rig: Any) -> None:
        rec = await rig.cm.submit(encode_frame("circle", CIRCLE))
        assert "vehicle" not in rec and len(rec["bits"]) == 100

    from tests.backend.commands.test_manager import run as run_single

    run_single(tmp_path, ONE_WAY, scenario)


def test_the_wire_check_finds_a_copy_of_an_older_command_after_a_newer_ones_first() -> None:
    older: tuple[int, str, Params] = (1, "circle", {"r": 1})
    newer: tuple[int, str, Params] = (0, "surface", {})
    good = [(0.0, 1, "circle", {"r": 1}), (1.0, 0, "surface", {}), (2.0, 2, "hover", {})]
    newer_rule_holds(good, [older, newer])
    late = [*good, (3.0, 1, "circle", {"r": 1})]
    with pytest.raises(AssertionError, match="vehicle 1"):
        newer_rule_holds(late, [older, newer])
