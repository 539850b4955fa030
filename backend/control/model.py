"""Control as the API and ``/ws`` show it: one :class:`ControlView` per vehicle."""

from __future__ import annotations

from datetime import UTC, datetime
from typing import Literal

from pydantic import BaseModel, Field

from backend.mission_log.control import ControlRow, Outcome


class ControlRequestView(BaseModel):
    """A request for control waiting for the owner's grant or refusal."""

    console: str
    operator: str | None
    at: str = Field(description="when it was made (ISO 8601, UTC, the database's clock)")


class ControlView(BaseModel):
    """Who is in control of a vehicle (``GET /api/control``)."""

    vehicle: str = Field(description='the vehicle\'s name ("nemesys" without a fleet)')
    console: str | None = Field(description="the console in control (null: nobody)")
    operator: str | None = Field(description="its operator (null: nobody)")
    epoch: int = Field(description="grows at every change of who is in control")
    takeover_allowed: bool = Field(description="the owner lets another console take over")
    since: str | None = Field(
        description="when the console took control, or nobody had it since (ISO 8601, UTC)"
    )
    request: ControlRequestView | None = Field(
        default=None, description="a request waiting for the owner's answer (null: none)"
    )
    implicit: bool = Field(
        default=False,
        description="this console is in control without a record: the one console of a "
        "SQLite log (it never refuses a send for control)",
    )


class ControlResult(BaseModel):
    """``POST /api/control``: what the action did, and the vehicle's control after it."""

    outcome: Outcome = Field(
        description="granted, pending (waits for the owner), refused, released, taken_over, "
        "unchanged (already so)"
    )
    control: ControlView


def iso(seconds: float | None) -> str | None:
    """Seconds since 1970 as ISO 8601 (UTC, milliseconds), as the log writes times."""
    if seconds is None:
        return None
    return datetime.fromtimestamp(seconds, UTC).isoformat(timespec="milliseconds")


def control_view(
    row: ControlRow, now_s: float, timeout_s: float, *, implicit_owner: tuple[str, str] | None
) -> ControlView:
    """``row`` as shown at ``now_s`` (a control whose heartbeat timed out is nobody's);
    ``implicit_owner`` (console, operator): who is in control when nobody is recorded (a
    SQLite log's one console), None on PostgreSQL."""
    owner = row.owner(now_s, timeout_s)
    request = None
    if row.request_console is not None and owner is not None:
        at = iso(row.request_s) or ""
        request = ControlRequestView(
            console=row.request_console, operator=row.request_operator, at=at
        )
    if owner is None and implicit_owner is not None:
        console, operator = implicit_owner
        return ControlView(
            vehicle=row.vehicle,
            console=console,
            operator=operator,
            epoch=row.epoch,
            takeover_allowed=False,
            since=None,
            implicit=True,
        )
    return ControlView(
        vehicle=row.vehicle,
        console=owner,
        operator=row.operator if owner is not None else None,
        epoch=row.epoch,
        takeover_allowed=row.takeover_allowed if owner is not None else False,
        since=iso(_since(row, owner, timeout_s)),
        request=request,
    )


def _since(row: ControlRow, owner: str | None, timeout_s: float) -> float | None:
    """Since when ``owner`` has control, or nobody has (a timed-out control not yet released
    in the table: since its heartbeat timed out)."""
    if owner is None and row.console is not None:
        return None if row.heartbeat_s is None else row.heartbeat_s + timeout_s
    return row.since_s


ControlAction = Literal["request", "grant", "refuse", "release", "takeover"]
