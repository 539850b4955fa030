"""The relay's tables' SQL (migration 0008): the ``outbox`` of commands a console without a
transmitter hands to the one that holds it, and the ``transmitters`` those consoles hold.

A row is written ``waiting`` by the shore (:func:`put`, committed); a console with the
transmitter takes the oldest waiting one (:func:`claim`: ``SELECT ... FOR UPDATE SKIP LOCKED``
inside its transaction, so two such consoles never take the same row and a row being decided
is skipped, not waited for) and decides it in the same transaction: :func:`taken` with the
command record it made, or :func:`refused` with the status and reason. The shore that stops
waiting :func:`withdraw`\\ s a row still waiting and not being decided. A row is only ever
decided once: every decision is conditional on ``state = 'waiting'``.

Times that judge (a row's age, a transmitter last seen) are on the database's clock
(:attr:`backend.mission_log.database.LogDatabase.now_s_sql`), the same for every console.
"""

from __future__ import annotations

import json
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any, Final, Literal

from backend.mission_log.store import MissionLog, now_iso

OutboxState = Literal["waiting", "taken", "refused", "withdrawn"]
STATES: Final[tuple[OutboxState, ...]] = ("waiting", "taken", "refused", "withdrawn")


@dataclass(frozen=True)
class OutboxRow:
    """One relayed command (times: ``created_s``, ``decided_s`` s since 1970 on the database's
    clock; ``created_at`` ISO 8601 UTC on the writing console's)."""

    id: int
    created_at: str
    created_s: float
    console: str
    operator: str
    vehicle: str
    origin: str
    kind: str
    pattern: str
    params: dict[str, Any]
    override: bool
    #: With ``override``: the soft violations (check, parameter) the operator accepted.
    accepted: frozenset[tuple[str, str]] | None
    copies: int | None
    retry_of: int | None
    state: OutboxState
    command_id: int | None = None
    status: int | None = None
    reason: str | None = None
    detail: Any = None
    decided_by: str | None = None
    decided_s: float | None = None


def _row(values: Mapping[str, Any]) -> OutboxRow:
    fields = {k: values[k] for k in OutboxRow.__dataclass_fields__}
    fields["params"] = json.loads(fields["params"])
    fields["override"] = bool(fields["override"])
    accepted = fields["accepted"]
    fields["accepted"] = (
        None if accepted is None else frozenset((c, p) for c, p in json.loads(accepted))
    )
    fields["detail"] = None if fields["detail"] is None else json.loads(fields["detail"])
    return OutboxRow(**fields)


def put(
    log: MissionLog,
    *,
    console: str,
    operator: str,
    vehicle: str,
    origin: str,
    kind: str,
    pattern: str,
    params: Mapping[str, Any],
    override: bool,
    copies: int | None,
    retry_of: int | None,
    accepted: frozenset[tuple[str, str]] = frozenset(),
) -> OutboxRow:
    """Write a ``waiting`` row (committed); returns it. ``accepted``: with ``override``, the
    soft violations (check, parameter) the operator accepted.

    Raises:
        LogWriteError: the log cannot be written (no row).
    """
    with log.connection() as db, db.writing():
        new_id = db.insert(
            "INSERT INTO outbox (created_at, created_s, console, operator, vehicle, origin, "
            "kind, pattern, params, override, accepted, copies, retry_of, state) "
            f"VALUES (?, {db.now_s_sql}, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, 'waiting')",
            (
                now_iso(),
                console,
                operator,
                vehicle,
                origin,
                kind,
                pattern,
                json.dumps(dict(params)),
                int(override),
                json.dumps(sorted(accepted)) if override else None,
                copies,
                retry_of,
            ),
        )
        got = db.execute("SELECT * FROM outbox WHERE id = ?", (new_id,)).fetchone()
    return _row(got)


def get(log: MissionLog, row_id: int) -> OutboxRow | None:
    """Row ``row_id`` as committed (None: no such row)."""
    with log.connection() as db, db.writing():
        got = db.execute("SELECT * FROM outbox WHERE id = ?", (row_id,)).fetchone()
    return None if got is None else _row(got)


def claim(
    log: MissionLog,
    vehicles: Sequence[str],
    *,
    foreign_after_s: float | None = None,
    others: Sequence[str] = (),
) -> tuple[OutboxRow, float] | None:
    """Inside the caller's transaction (:meth:`MissionLog.transaction`): the oldest row waiting
    for one of ``vehicles`` that no other transaction holds, locked until the transaction ends,
    and the database's clock (None: none waits). With ``foreign_after_s``, also a row for any
    other vehicle but ``others`` (the vehicles other transmitting consoles have) that waited
    at least that long (s, the database's clock): the caller refuses it, naming its own."""
    marks = ", ".join("?" * len(vehicles))
    which = f"vehicle IN ({marks})"
    args: tuple[str | float, ...] = tuple(vehicles)
    with log.connection() as db, db.writing():
        if foreign_after_s is not None:
            theirs = f" AND vehicle NOT IN ({', '.join('?' * len(others))})" if others else ""
            which = f"({which} OR (created_s <= {db.now_s_sql} - ?{theirs}))"
            args = (*args, foreign_after_s, *others)
        got = db.execute(
            f"SELECT *, {db.now_s_sql} AS now_s FROM outbox WHERE state = 'waiting' "
            f"AND {which} ORDER BY id LIMIT 1{db.skip_locked}",
            args,
        ).fetchone()
    return None if got is None else (_row(got), float(got["now_s"]))


def taken(
    log: MissionLog,
    row_id: int,
    command_id: int,
    by: str,
    commands: Sequence[int] = (),
    handed_on: Sequence[int] = (),
) -> None:
    """The row is sent as command ``command_id`` (in the claim's transaction). ``commands``:
    every record it made when more than one (a fleet's Surface to all: one per vehicle, the
    first ``command_id``), kept in ``detail`` as ``{"commands": [ids]}``; ``handed_on``: the
    rows it wrote for other transmitting consoles' vehicles (a Surface to all), kept as
    ``{"handed_on": [row ids]}``."""
    said: dict[str, list[int]] = {}
    if len(commands) > 1:
        said["commands"] = list(commands)
    if handed_on:
        said["handed_on"] = list(handed_on)
    more = {"detail": json.dumps(said)} if said else {}
    _decide(log, row_id, "taken", by, command_id=command_id, **more)


def refused(
    log: MissionLog, row_id: int, by: str, status: int, reason: str, detail: Any = None
) -> None:
    """The row is refused by console ``by``: ``status`` (HTTP), ``reason`` in words and
    ``detail`` (the refusal's JSON) (in the claim's transaction)."""
    text = None if detail is None else json.dumps(detail)
    _decide(log, row_id, "refused", by, status=status, reason=reason, detail=text)


def _decide(log: MissionLog, row_id: int, state: OutboxState, by: str, **fields: Any) -> None:
    sets = "".join(f", {k} = ?" for k in fields)
    with log.connection() as db, db.writing():
        cur = db.execute(
            f"UPDATE outbox SET state = ?, decided_by = ?, decided_s = {db.now_s_sql}{sets} "
            "WHERE id = ? AND state = 'waiting'",
            (state, by, *fields.values(), row_id),
        )
    if cur.rowcount != 1:  # the claim holds the row: a second decision is our own bug
        raise RuntimeError(f"outbox row {row_id} was not waiting: not {state}")


def withdraw(log: MissionLog, row_id: int, by: str, reason: str) -> bool:
    """Withdraw row ``row_id`` if it still waits and no console is deciding it now (one
    statement, committed): True if withdrawn; False: decided, or being decided (read it
    again shortly)."""
    with log.connection() as db, db.writing():
        cur = db.execute(
            f"UPDATE outbox SET state = 'withdrawn', decided_by = ?, decided_s = {db.now_s_sql}, "
            "reason = ? WHERE id IN (SELECT id FROM outbox WHERE id = ? AND state = 'waiting'"
            f"{db.skip_locked})",
            (by, reason, row_id),
        )
    return cur.rowcount == 1


# --- the transmitters: which consoles hold one, and how their link is ---------------------


@dataclass(frozen=True)
class Transmitter:
    """A console holding a transmitter, as it last said (``seen_s``: the database's clock)."""

    console: str
    target: str
    health: dict[str, Any]
    seen_s: float


def beat_transmitter(log: MissionLog, console: str, target: str, health: Mapping[str, Any]) -> None:
    """Console ``console`` holds a transmitter to ``target`` whose link is ``health`` now
    (one upsert, committed)."""
    with log.connection() as db, db.writing():
        db.execute(
            "INSERT INTO transmitters (console, target, health, seen_s) "
            f"VALUES (?, ?, ?, {db.now_s_sql}) ON CONFLICT (console) DO UPDATE SET "
            "target = excluded.target, health = excluded.health, seen_s = excluded.seen_s",
            (console, target, json.dumps(dict(health))),
        )


def transmitters(log: MissionLog) -> tuple[list[Transmitter], float]:
    """Every console that said it holds a transmitter, the most recently seen first, and the
    database's clock."""
    with log.connection() as db, db.writing():
        got = db.execute(f"SELECT *, {db.now_s_sql} AS now_s FROM transmitters").fetchall()
        if not got:
            clock = db.execute(f"SELECT {db.now_s_sql} AS now_s").fetchone()["now_s"]
            return [], float(clock)
    found = [
        Transmitter(r["console"], r["target"], json.loads(r["health"]), float(r["seen_s"]))
        for r in got
    ]
    found.sort(key=lambda t: t.seen_s, reverse=True)
    return found, float(got[0]["now_s"])
