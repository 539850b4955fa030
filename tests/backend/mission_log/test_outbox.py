"""The relay's tables (migration 0008, ``backend/mission_log/outbox.py``) on both back-ends:
a row written waiting, claimed oldest first for the claiming console's vehicles, decided once
(taken with its record, refused with status, reason and violations, withdrawn only while it
waits); on PostgreSQL a row claimed by one transaction is skipped by another (``SKIP
LOCKED``), not waited for, and not withdrawn under it, and every write is notified; the
transmitters' presence upserted and read newest first on the database's clock."""

from __future__ import annotations

import json
from typing import Any

import psycopg
import pytest

from backend.mission_log import outbox
from backend.mission_log.store import MissionLog
from tests.backend.conftest import CIRCLE, command_fields
from tests.backend.log_backend import LogBackend


def put(log: MissionLog, vehicle: str = "nemesys", **fields: Any) -> outbox.OutboxRow:
    values: dict[str, Any] = {
        "console": "shore",
        "operator": "bob",
        "vehicle": vehicle,
        "origin": "api",
        "kind": "command",
        "pattern": "circle",
        "params": CIRCLE,
        "override": False,
        "copies": None,
        "retry_of": None,
        **fields,
    }
    return outbox.put(log, **values)


def test_a_row_is_written_waiting_and_read_back_as_written(log_backend: LogBackend) -> None:
    log = log_backend.open()
    try:
        row = put(log, override=True, copies=3, origin="ws")
        assert row.state == "waiting" and row.console == "shore" and row.operator == "bob"
        assert row.params == CIRCLE and row.override is True and row.copies == 3
        assert row.origin == "ws" and row.command_id is None and row.decided_by is None
        assert outbox.get(log, row.id) == row
        assert outbox.get(log, row.id + 1) is None
    finally:
        log.close()


def test_claims_are_oldest_first_for_the_consoles_vehicles_and_decided_once(
    log_backend: LogBackend,
) -> None:
    log = log_backend.open()
    try:
        other = put(log, vehicle="nemesys-2")
        first, second = put(log), put(log, pattern="surface", params={})
        dive = log.new_dive("sim")
        record = log.insert_command(dive, command_fields())
        with log.transaction():
            got = outbox.claim(log, ["nemesys"])
            assert got is not None
            row, now_s = got
            assert row == first and 0 <= now_s - row.created_s < 60
            outbox.taken(log, row.id, record["id"], "ship")
        with log.transaction():
            got = outbox.claim(log, ["nemesys"])
            assert got is not None and got[0] == second
            violations = {"message": "limit violation", "violations": [{"param": "depth"}]}
            outbox.refused(log, second.id, "ship", 422, "too deep", violations)
        with log.transaction():
            assert outbox.claim(log, ["nemesys"]) is None  # the other vehicle's is not ours
        taken, refused = outbox.get(log, first.id), outbox.get(log, second.id)
        assert taken is not None and refused is not None
        assert taken.state == "taken" and taken.command_id == record["id"]
        assert taken.decided_by == "ship" and taken.decided_s is not None
        assert refused.state == "refused" and refused.status == 422
        assert refused.reason == "too deep" and refused.detail == violations
        with log.transaction(), pytest.raises(RuntimeError, match="was not waiting"):
            outbox.taken(log, second.id, record["id"], "ship")  # decided once
        assert not outbox.withdraw(log, first.id, "shore", "late")  # decided: stays so
        assert outbox.withdraw(log, other.id, "shore", "no answer in 5 s")
        withdrawn = outbox.get(log, other.id)
        assert withdrawn is not None and withdrawn.state == "withdrawn"
        assert withdrawn.reason == "no answer in 5 s" and withdrawn.decided_by == "shore"
    finally:
        log.close()


def test_a_row_for_a_vehicle_no_console_has_is_claimed_once_it_waited_never_anothers(
    log_backend: LogBackend,
) -> None:
    """The ship's claim with ``foreign_after_s`` (backend/relay/ship.py): its own and "all"
    at once; another vehicle's only once it waited that long and only if no other
    transmitting console has it (``others``). A Surface to all keeps every record's id."""
    log = log_backend.open()
    try:
        theirs, lost, everyone = put(log, "auv7"), put(log, "auv9"), put(log, "all")
        dive = log.new_dive("sim")
        ids = [log.insert_command(dive, command_fields())["id"] for _ in range(3)]
        mine = ["auv1", "auv2", "all"]
        with log.transaction():
            got = outbox.claim(log, mine, foreign_after_s=3600, others=["auv7"])
            assert got is not None and got[0] == everyone  # not waited long enough: ours only
            outbox.taken(log, everyone.id, ids[0], "ship", ids)
        with log.transaction():
            assert outbox.claim(log, mine, foreign_after_s=3600, others=["auv7"]) is None
        with log.transaction():
            got = outbox.claim(log, mine, foreign_after_s=0, others=["auv7"])
            assert got is not None and got[0] == lost  # auv7 is another console's
            outbox.refused(log, lost.id, "ship", 422, "no vehicle 'auv9'")
        with log.transaction():
            assert outbox.claim(log, mine, foreign_after_s=0, others=["auv7"]) is None
            assert outbox.claim(log, mine) is None  # without it: its vehicles only
        with log.transaction():
            got = outbox.claim(log, mine, foreign_after_s=0)
            assert got is not None and got[0] == theirs  # nobody else says it has auv7
        taken = outbox.get(log, everyone.id)
        assert taken is not None and taken.command_id == ids[0]
        assert taken.detail == {"commands": ids}
    finally:
        log.close()


def test_transmitters_are_upserted_and_read_newest_first(log_backend: LogBackend) -> None:
    log = log_backend.open()
    try:
        assert outbox.transmitters(log)[0] == []
        outbox.beat_transmitter(log, "ship", "sim", {"connected": True, "level": "green"})
        outbox.beat_transmitter(log, "ship-2", "tcp://gw:4001", {"connected": False})
        outbox.beat_transmitter(log, "ship", "sim", {"connected": True, "level": "amber"})
        found, now_s = outbox.transmitters(log)
        assert [t.console for t in found] == ["ship", "ship-2"]
        assert found[0].health == {"connected": True, "level": "amber"}
        assert all(0 <= now_s - t.seen_s < 60 for t in found)
    finally:
        log.close()


def test_a_claimed_row_is_skipped_by_another_console_and_not_withdrawn_under_it(
    pg_log: LogBackend,
) -> None:
    ship, ship2 = pg_log.open(), pg_log.open()
    try:
        row, later = put(ship), put(ship)
        with ship.transaction():
            got = outbox.claim(ship, ["nemesys"])
            assert got is not None and got[0].id == row.id
            with ship2.transaction():  # not waited for: the next one is there at once
                other = outbox.claim(ship2, ["nemesys"])
                assert other is not None and other[0].id == later.id
            assert not outbox.withdraw(ship2, row.id, "shore", "no answer")
        still = outbox.get(ship2, row.id)
        assert still is not None and still.state == "waiting"  # the claim ended undecided
    finally:
        ship.close()
        ship2.close()


def test_every_row_written_or_decided_is_notified_with_its_key(pg_log: LogBackend) -> None:
    log = pg_log.open()
    log.name_console("shore")
    try:
        with psycopg.connect(pg_log.url, autocommit=True) as listener:
            listener.execute("LISTEN nemesys_log")
            row = put(log)
            assert outbox.withdraw(log, row.id, "shore", "no answer")
            payloads = [json.loads(n.payload) for n in listener.notifies(timeout=5, stop_after=2)]
        assert payloads == [{"table": "outbox", "id": row.id, "console": "shore"}] * 2
    finally:
        log.close()
