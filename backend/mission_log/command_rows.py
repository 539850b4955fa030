"""A command as the mission log stores it: which columns hold JSON or booleans, which an update
may set, the log's wire order, and a row read back as a dict (the store's SQL is
:mod:`backend.mission_log.store`; a dict made typed is :mod:`backend.mission_log.records`).
"""

from __future__ import annotations

import json
from collections.abc import Mapping
from typing import Any

from backend.commands.lifecycle import TERMINAL, State

#: Columns holding JSON text.
JSON_COLUMNS = ("params", "requested", "ack", "overrides")
#: Columns holding booleans (integers 0/1, on PostgreSQL too: one schema for both).
BOOL_COLUMNS = ("two_way",)
#: Columns a command update may set.
UPDATABLE = frozenset(
    {
        "state",
        "attempts",
        "sent_at",
        "acked_at",
        "ack",
        "reason",
        "copies",
        "copies_sent",
        "p_delivered",
        "ber",
        "two_way",
        "superseded_by",
        "first_sent_at",
    }
)
#: Wire order: by the time a command's first copy left (one never sent: when it was made).
WIRE_ORDER = "COALESCE(first_sent_at, created_at) {0}, id {0}"
STATES = tuple(State)
FINAL_STATES = frozenset(str(s) for s in TERMINAL)


def column_value(column: str, value: Any) -> Any:
    """``value`` as the column holds it (JSON text for a JSON column, 0/1 for a boolean)."""
    if column in JSON_COLUMNS:
        return json.dumps(value)
    if column in BOOL_COLUMNS and value is not None:
        return int(bool(value))
    return value


def checked_update(fields: dict[str, Any]) -> dict[str, Any]:
    """``fields`` of a command update, its state as text; ``ValueError`` naming a column an
    update may not set, or a state that does not exist, and what is allowed."""
    unknown = set(fields) - UPDATABLE
    if unknown:
        raise ValueError(f"cannot update {sorted(unknown)}; allowed: {sorted(UPDATABLE)}")
    if "state" in fields:
        if fields["state"] not in STATES:
            allowed = ", ".join(STATES)
            raise ValueError(f"unknown state {fields['state']!r}; allowed: {allowed}")
        fields["state"] = str(fields["state"])
    return fields


def commands_query(
    *,
    state: str | None,
    pattern: str | None,
    target: str | None,
    dive: int | None,
    vehicle: str | None = None,
    since: str | None,
    until: str | None,
    limit: int,
    oldest_first: bool,
) -> tuple[str, list[Any]]:
    """The SELECT of the commands matching every filter given (None: any), in wire order
    (newest first unless ``oldest_first``), at most ``limit``; and its arguments."""
    filters = (
        ("state = ?", state),
        ("pattern = ?", pattern),
        ("target = ?", target),
        ("dive = ?", dive),
        ("vehicle = ?", vehicle),
        ("created_at >= ?", since),
        ("created_at <= ?", until),
    )
    where = [clause for clause, value in filters if value is not None]
    args: list[Any] = [value for _, value in filters if value is not None]
    sql = "SELECT * FROM commands"
    if where:
        sql += " WHERE " + " AND ".join(where)
    sql += " ORDER BY " + WIRE_ORDER.format("ASC" if oldest_first else "DESC") + " LIMIT ?"
    args.append(limit)
    return sql, args


def command_row(row: Mapping[str, Any]) -> dict[str, Any]:
    """A command's row as a dict: its JSON columns parsed, its booleans as bool; ``vehicle``
    only where it names one (a fleet's: without a fleet the record is as it always was)."""
    out = dict(row)
    if out.get("vehicle", "") is None:
        del out["vehicle"]
    for col in JSON_COLUMNS:
        if out.get(col) is not None:
            out[col] = json.loads(out[col])
    for col in BOOL_COLUMNS:
        if out.get(col) is not None:
            out[col] = bool(out[col])
    return out
