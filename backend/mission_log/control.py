"""Who is in control of each vehicle: the ``control`` table's SQL (migration 0007).

One row per vehicle (created at its first use): the console and operator in control (none:
nobody), an ``epoch`` that grows at every change of who is in control, whether the owner
allows a takeover, since when, the owner's last heartbeat and the one request waiting for
the owner's answer. Every action is one transaction: the row is locked (``FOR UPDATE`` on
PostgreSQL; SQLite's write lock holds the file), a control whose heartbeat is older than the
timeout is released first, then the action is decided on what the row says now and written
with its event (kind ``control``) — so two consoles acting at once are served one after the
other, and an event is never written without its change or the other way round.

Time is the database's clock (seconds since 1970: :attr:`LogDatabase.now_s_sql`), the same
for every console whatever its own clock says: a heartbeat is judged by the clock that
stamped it.

The rules (MAVLink's operator control, and Cockpit's "control you already have is never taken
from you"): a request for a vehicle nobody controls is granted at once; for a controlled one
it waits for the owner's grant or refusal (a newer request replaces it); a takeover only where
the owner allows it; only the owner grants, refuses or releases. A refused action changes
nothing and raises :class:`ControlRefused` naming why.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, replace
from typing import Any, Final, Literal

from backend.mission_log.store import MissionLog

Action = Literal["request", "grant", "refuse", "release", "takeover"]
ACTIONS: Final[tuple[Action, ...]] = ("request", "grant", "refuse", "release", "takeover")
#: What an action did (``timed_out``: the owner's heartbeat stopped).
Outcome = Literal[
    "granted", "pending", "refused", "released", "taken_over", "unchanged", "timed_out"
]
#: The events' kind.
EVENT_KIND: Final = "control"


class ControlRefused(Exception):
    """An action the rules do not allow (nothing was changed): the message says why and what
    to do instead."""


@dataclass(frozen=True)
class Actor:
    """Who acts: a console and its operator."""

    console: str
    operator: str


@dataclass(frozen=True)
class ControlRow:
    """A vehicle's row (times: seconds since 1970 on the database's clock)."""

    vehicle: str
    console: str | None = None
    operator: str | None = None
    epoch: int = 0
    takeover_allowed: bool = False
    since_s: float | None = None
    heartbeat_s: float | None = None
    request_console: str | None = None
    request_operator: str | None = None
    request_s: float | None = None

    def owner(self, now_s: float, timeout_s: float) -> str | None:
        """The console in control at ``now_s`` (None: nobody, or its heartbeat is older than
        ``timeout_s``)."""
        if self.console is None or self.expired(now_s, timeout_s):
            return None
        return self.console

    def expired(self, now_s: float, timeout_s: float) -> bool:
        return self.console is not None and (
            self.heartbeat_s is None or self.heartbeat_s < now_s - timeout_s
        )


@dataclass(frozen=True)
class ControlChange:
    """One change of a vehicle's control, as written: the row before and after, and its
    event (the mission log's row)."""

    action: Action | Literal["timeout"]
    outcome: Outcome
    by: Actor | None
    before: ControlRow
    after: ControlRow
    event: dict[str, Any]


#: The row's columns, in :class:`ControlRow`'s order.
COLUMNS: Final = (
    "vehicle",
    "console",
    "operator",
    "epoch",
    "takeover_allowed",
    "since_s",
    "heartbeat_s",
    "request_console",
    "request_operator",
    "request_s",
)


def _row(values: Mapping[str, Any]) -> ControlRow:
    fields = {c: values[c] for c in COLUMNS}
    fields["takeover_allowed"] = bool(fields["takeover_allowed"])
    return ControlRow(**fields)


def now_s(log: MissionLog) -> float:
    """The database's clock (s since 1970)."""
    with log.connection() as db, db.writing():
        return float(db.execute(f"SELECT {db.now_s_sql} AS now_s").fetchone()["now_s"])


def rows(log: MissionLog) -> tuple[dict[str, ControlRow], float]:
    """Every vehicle's row, and the database's clock as they were read (for who is in control
    now: :meth:`ControlRow.owner`)."""
    with log.connection() as db, db.writing():
        got = db.execute(f"SELECT *, {db.now_s_sql} AS now_s FROM control").fetchall()
    if not got:
        return {}, now_s(log)
    return {r["vehicle"]: _row(r) for r in got}, float(got[0]["now_s"])


def row(log: MissionLog, vehicle: str) -> tuple[ControlRow, float]:
    """``vehicle``'s row (a default one when it has none yet) and the database's clock."""
    with log.connection() as db, db.writing():
        got = db.execute(
            f"SELECT *, {db.now_s_sql} AS now_s FROM control WHERE vehicle = ?", (vehicle,)
        ).fetchone()
        if got is None:
            clock = db.execute(f"SELECT {db.now_s_sql} AS now_s").fetchone()["now_s"]
            return ControlRow(vehicle), float(clock)
    return _row(got), float(got["now_s"])


def act(
    log: MissionLog,
    dive: int,
    vehicle: str,
    action: Action,
    by: Actor,
    timeout_s: float,
    takeover_allowed: bool | None = None,
) -> list[ControlChange]:
    """Do ``action`` on ``vehicle``'s control for ``by`` (one transaction; events in
    ``dive``); returns the changes written: a timeout found on the way, then the action's.
    ``takeover_allowed``: the owner's choice, taken when ``by`` is or becomes the owner.

    Raises:
        ControlRefused: the rules do not allow it (nothing written).
        LogWriteError: the log cannot be written (nothing written).
    """
    with log.transaction(), log.connection() as db, db.writing():
        db.execute(
            "INSERT INTO control (vehicle) VALUES (?) ON CONFLICT (vehicle) DO NOTHING", (vehicle,)
        )
        got = db.execute(
            f"SELECT *, {db.now_s_sql} AS now_s FROM control WHERE vehicle = ?{db.for_update}",
            (vehicle,),
        ).fetchone()
        now, current = float(got["now_s"]), _row(got)
        changes: list[ControlChange] = []
        if current.expired(now, timeout_s):
            changes.append(_write(log, dive, _timed_out(current, now, timeout_s), now))
            current = changes[-1].after
        decided = decide(current, action, by, now, takeover_allowed)
        changes.append(_write(log, dive, decided, now))
    return changes


@dataclass(frozen=True)
class _Decided:
    action: Action | Literal["timeout"]
    outcome: Outcome
    by: Actor | None
    before: ControlRow
    after: ControlRow
    detail: str


def decide(
    r: ControlRow, action: Action, by: Actor, now: float, takeover_allowed: bool | None
) -> _Decided:
    """The rules (the module's docstring) on a row whose expired control is already released."""
    v, me = r.vehicle, by.console
    owner = f"console {r.console!r} (operator {r.operator!r})"
    who = f"console {me!r} (operator {by.operator!r})"
    allowed = r.takeover_allowed if takeover_allowed is None else takeover_allowed
    mine = _handed(r, me, by.operator, now, takeover_allowed=bool(takeover_allowed))
    if action in ("request", "takeover") and r.console is None:
        return _Decided(
            action, "granted", by, r, mine, f"{who} took control of {v} (nobody had it)"
        )
    if action in ("request", "takeover") and r.console == me:
        after = replace(r, takeover_allowed=allowed)
        detail = f"{who} already has control of {v}"
        if allowed != r.takeover_allowed:  # the owner's choice changed: said as such
            detail = (
                f"{who}, in control of {v}, {'now' if allowed else 'no longer'} allows a takeover"
            )
        return _Decided(action, "unchanged", by, r, after, detail)
    if action == "request":
        after = replace(r, request_console=me, request_operator=by.operator, request_s=now)
        detail = f"{who} asks {owner} for control of {v}"
        return _Decided(action, "pending", by, r, after, detail)
    if action == "takeover":
        if not r.takeover_allowed:
            raise ControlRefused(
                f"{owner} is in control of {v} and does not allow a takeover: request control "
                "and wait for its answer"
            )
        return _Decided(
            action, "taken_over", by, r, mine, f"{who} took control of {v} from {owner}"
        )
    if r.console != me:
        holder = "nobody is" if r.console is None else f"{owner} is"
        raise ControlRefused(
            f"only the console in control can {action}: {holder} in control of {v}"
        )
    if action == "release":
        after = _handed(r, None, None, now)
        return _Decided(action, "released", by, r, after, f"{who} released control of {v}")
    if r.request_console is None:
        raise ControlRefused(f"no request for control of {v} is waiting for an answer")
    asker = f"console {r.request_console!r} (operator {r.request_operator!r})"
    if action == "refuse":
        after = replace(r, request_console=None, request_operator=None, request_s=None)
        return _Decided(action, "refused", by, r, after, f"{who} refused {asker} control of {v}")
    after = _handed(r, r.request_console, r.request_operator, now)
    return _Decided(action, "granted", by, r, after, f"{who} granted {asker} control of {v}")


def _handed(
    r: ControlRow,
    console: str | None,
    operator: str | None,
    now: float,
    *,
    takeover_allowed: bool = False,
) -> ControlRow:
    """``r`` handed to ``console`` (None: to nobody) at ``now`` (database clock, s): the next
    epoch, a first heartbeat when someone holds it, and any waiting request answered."""
    return replace(
        r,
        console=console,
        operator=operator,
        epoch=r.epoch + 1,
        since_s=now,
        heartbeat_s=None if console is None else now,
        takeover_allowed=takeover_allowed,
        request_console=None,
        request_operator=None,
        request_s=None,
    )


def _timed_out(r: ControlRow, now: float, timeout_s: float) -> _Decided:
    after = _handed(r, None, None, now)
    age = "never" if r.heartbeat_s is None else f"{now - r.heartbeat_s:.1f} s ago"
    detail = (
        f"control of {r.vehicle} released: console {r.console!r} (operator {r.operator!r}) "
        f"last beat {age}, over the {timeout_s:g} s timeout"
    )
    return _Decided("timeout", "timed_out", None, r, after, detail)


def _write(log: MissionLog, dive: int, d: _Decided, now: float) -> ControlChange:
    """The row as decided and its event (inside :func:`act`'s transaction)."""
    a = d.after
    with log.connection() as db:
        db.execute(
            "UPDATE control SET console = ?, operator = ?, epoch = ?, takeover_allowed = ?, "
            "since_s = ?, heartbeat_s = ?, request_console = ?, request_operator = ?, "
            "request_s = ? WHERE vehicle = ?",
            (
                a.console,
                a.operator,
                a.epoch,
                int(a.takeover_allowed),
                a.since_s,
                a.heartbeat_s,
                a.request_console,
                a.request_operator,
                a.request_s,
                a.vehicle,
            ),
        )
    data = {
        "vehicle": a.vehicle,
        "action": d.action,
        "outcome": d.outcome,
        "by_console": d.by.console if d.by else None,
        "by_operator": d.by.operator if d.by else None,
        "console": a.console,
        "operator": a.operator,
        "epoch": a.epoch,
        "takeover_allowed": a.takeover_allowed,
        "request_console": a.request_console,
        "db_time_s": now,
    }
    event = log.add_event(dive, EVENT_KIND, d.detail, data)
    return ControlChange(d.action, d.outcome, d.by, d.before, a, event)


def expired(log: MissionLog, timeout_s: float) -> list[str]:
    """The vehicles whose control has timed out and is not yet released (a read)."""
    found, now = rows(log)
    return [v for v, r in found.items() if r.expired(now, timeout_s)]


def release_expired(
    log: MissionLog, dive: int, vehicle: str, timeout_s: float
) -> ControlChange | None:
    """Release ``vehicle``'s control if its heartbeat is older than ``timeout_s`` (one
    transaction; another console may have done it first: None)."""
    with log.transaction(), log.connection() as db, db.writing():
        got = db.execute(
            f"SELECT *, {db.now_s_sql} AS now_s FROM control WHERE vehicle = ?{db.for_update}",
            (vehicle,),
        ).fetchone()
        if got is None:
            return None
        now, current = float(got["now_s"]), _row(got)
        if not current.expired(now, timeout_s):
            return None
        return _write(log, dive, _timed_out(current, now, timeout_s), now)


def heartbeat(log: MissionLog, console: str, timeout_s: float) -> list[str]:
    """Refresh the heartbeat of every vehicle ``console`` controls and has not lost to the
    timeout; returns those vehicles."""
    with log.transaction(), log.connection() as db, db.writing():
        db.execute(
            f"UPDATE control SET heartbeat_s = {db.now_s_sql} WHERE console = ? "
            f"AND heartbeat_s >= {db.now_s_sql} - ?",
            (console, timeout_s),
        )
        got = db.execute(
            f"SELECT vehicle FROM control WHERE console = ? AND heartbeat_s >= {db.now_s_sql} - ?",
            (console, timeout_s),
        ).fetchall()
    return [r["vehicle"] for r in got]
