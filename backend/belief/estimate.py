"""A vehicle's belief from the evidence: the records, the vehicle's echoes, the mirrored plan,
the last fix and the link (pure: no clock, no console; :mod:`backend.belief.tracker` gathers
the evidence from the running console)."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from backend.belief.commands import Echo, epoch_s, one_way, two_way
from backend.belief.model import Belief, SentCommand, SurfaceBelief
from backend.belief.position import MIN_P, Fix, Start, believe_position
from backend.belief.reckoning import Current
from backend.chart.geo import Datum
from backend.commands.lifecycle import ON_ITS_WAY
from planner import Plan

__all__ = ["Evidence", "estimate", "surface_of"]

Record = Mapping[str, Any]


@dataclass(frozen=True, slots=True)
class Evidence:
    """What the console knows of one vehicle at ``now_s`` (console clock, epoch s)."""

    vehicle: str
    now_s: float
    #: Vehicle seconds per console second (the training simulator's time scale; else 1).
    time_scale: float
    #: The link acknowledges (two-way).
    two_way: bool
    #: This vehicle's records since it last started (training: this dive), oldest first on
    #: the wire.
    records: Sequence[Record]
    #: The command whose first copy left most recently, ``{id, pattern, params, ...}``.
    last_sent: Record | None
    #: The newest record the vehicle accepted (two-way).
    accepted: Record | None
    #: The vehicle's newest word on what it runs (None: none yet).
    echo: Echo | None
    #: The plan the vehicle flies, as the console mirrors it (None: none known).
    mirror: Plan | None
    fix: Fix | None
    start: Start
    current: Current
    datum: Datum | None
    #: How fast the vehicle may go when its plan is not known (m/s).
    top_speed_mps: float
    #: The vehicle's mission clock now, when the console knows it (the training simulator's).
    vehicle_now_s: float | None = None


def surface_of(records: Sequence[Record], now_s: float) -> SurfaceBelief:
    """The newest Surface of ``records`` (oldest first), from its record's state only."""
    found = next(
        (r for r in reversed(records) if r.get("kind") == "surface" or r["pattern"] == "surface"),
        None,
    )
    if found is None:
        return SurfaceBelief.model_validate(
            dict.fromkeys(SurfaceBelief.model_fields, None) | {"in_progress": False}
        )
    changed = epoch_s(found.get("updated_at"))
    return SurfaceBelief(
        in_progress=found["state"] in ON_ITS_WAY,
        id=found["id"],
        state=str(found["state"]),
        two_way=found.get("two_way"),
        copies=found.get("copies"),
        copies_sent=found.get("copies_sent"),
        p_delivered=found.get("p_delivered"),
        ber=found.get("ber"),
        reason=found.get("reason"),
        superseded_by=found.get("superseded_by"),
        changed_s=None if changed is None else max(0.0, now_s - changed),
    )


def estimate(ev: Evidence, seq: int = 0) -> Belief:
    """The belief from ``ev`` (see :mod:`backend.belief`)."""
    if ev.two_way:
        candidates = two_way(ev.records, ev.accepted, ev.echo, ev.now_s)
    else:
        candidates = one_way(ev.records, ev.echo, ev.now_s)
    position = believe_position(
        [c for c in candidates if c is candidates[0] or c.belief.p >= MIN_P or c.last_known],
        fix=ev.fix,
        start=ev.start,
        mirror=ev.mirror,
        now_s=ev.now_s,
        time_scale=ev.time_scale,
        current=ev.current,
        datum=ev.datum,
        top_speed_mps=ev.top_speed_mps,
        vehicle_now_s=ev.vehicle_now_s,
    )
    last = ev.last_sent
    return Belief(
        vehicle=ev.vehicle,
        seq=seq,
        two_way=ev.two_way,
        last_sent=None
        if last is None
        else SentCommand(id=last["id"], pattern=last["pattern"], params=last["params"]),
        command=candidates[0].belief,
        runner_up=candidates[1].belief if len(candidates) > 1 else None,
        position=position,
        surface=surface_of(ev.records, ev.now_s),
    )
