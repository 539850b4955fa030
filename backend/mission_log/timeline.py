"""A dive on one clock, for the replay's time slider: where the vehicle was, the command it was
running and the link's events, at any second of the dive.

The dive's clock counts seconds from its start: the vehicle's clock less its first track
point's (:mod:`backend.dives`). The log writes the link's events on the station's clock (a
copy sent, an acknowledgement received, a timeout: the console's monotonic-anchored UTC,
:data:`backend.clock.CONSOLE_UTC`, one clock for every stamp of the log); each track point
also keeps the station's clock when it arrived (``at``), which maps one clock onto the other
(linear between points, the track's mean rate beyond them). A dive without track points (a
one-way modem, no telemetry) counts station seconds from the dive's start. An acknowledgement
that carries the vehicle's own ``t_s`` is placed by it.
"""

from __future__ import annotations

import bisect
import math
from collections.abc import Callable, Mapping, Sequence
from datetime import datetime
from typing import Any

#: Relative tolerance when matching the command the vehicle reports to a logged one.
PARAM_TOLERANCE = 1e-6

Row = Mapping[str, Any]


def epoch_s(iso: str | None) -> float | None:
    """An ISO 8601 time (the log's) as POSIX seconds; None if absent or unreadable."""
    if not iso:
        return None
    try:
        return datetime.fromisoformat(iso).timestamp()
    except ValueError:
        return None


def dive_clock(rows: Sequence[Row], started_at: str) -> Callable[[str | None], float | None]:
    """Station time (ISO) -> seconds on the dive's clock (see the module's docstring)."""
    pairs = sorted((at, float(r["t_s"])) for r in rows if (at := epoch_s(r.get("at"))) is not None)
    start_t = float(rows[0]["t_s"]) if rows else 0.0
    if not pairs:
        zero = epoch_s(started_at) if not rows else None

        def station(iso: str | None) -> float | None:
            s = epoch_s(iso)
            return None if s is None or zero is None else s - zero

        return station
    ats = [a for a, _ in pairs]
    ts = [t for _, t in pairs]
    span = ats[-1] - ats[0]
    rate = (ts[-1] - ts[0]) / span if span > 0 else 1.0  # vehicle s per station s

    def vehicle(iso: str | None) -> float | None:
        s = epoch_s(iso)
        if s is None:
            return None
        if s <= ats[0]:
            t = ts[0] - (ats[0] - s) * rate
        elif s >= ats[-1]:
            t = ts[-1] + (s - ats[-1]) * rate
        else:
            k = bisect.bisect_right(ats, s)
            a0, a1, t0, t1 = ats[k - 1], ats[k], ts[k - 1], ts[k]
            t = t0 + (t1 - t0) * (s - a0) / (a1 - a0) if a1 > a0 else t0
        return t - start_t

    return vehicle


def _same_params(a: Mapping[str, Any], b: Mapping[str, Any]) -> bool:
    if set(a) != set(b):
        return False
    for key, x in a.items():
        y = b[key]
        if isinstance(x, int | float) and isinstance(y, int | float):
            if not math.isclose(float(x), float(y), rel_tol=PARAM_TOLERANCE, abs_tol=1e-9):
                return False
        elif x != y:
            return False
    return True


def running_command(active: Row | None, sent: Sequence[Row]) -> int | None:
    """The logged command the vehicle's reported ``active`` command is: the newest of
    ``sent`` (the dive's commands sent by then, oldest first) with its pattern and
    parameters; None when it runs none, or one this console did not send."""
    if not active:
        return None
    for record in reversed(sent):
        if record["pattern"] == active.get("pattern") and _same_params(
            record.get("params") or {}, active.get("params") or {}
        ):
            return int(record["id"])
    return None


def _command_text(r: Row) -> str:
    params = ", ".join(f"{k} {v}" for k, v in (r.get("params") or {}).items())
    name = "SURFACE" if r.get("kind") == "surface" else str(r["pattern"])
    return f"command {r['id']} {name}" + (f" ({params})" if params else "")


def link_events(
    commands: Sequence[Row],
    events: Sequence[Row],
    clock: Callable[[str | None], float | None],
    start_t_s: float | None,
) -> tuple[list[dict[str, Any]], int]:
    """The dive's link events on its clock, in time order, and how many could not be placed
    (no time): ``{t_s, kind, text, command_id}``. Per command: its first copy sent, its last
    copy (when later), its acknowledgement or rejection (at the vehicle's ``t_s`` when the
    acknowledgement has one), or how it ended otherwise; the log's events (an echo
    mismatch, a datum set)."""
    out: list[dict[str, Any]] = []
    unplaced = 0

    def add(t: float | None, kind: str, text: str, command_id: int | None) -> None:
        nonlocal unplaced
        if t is None:
            unplaced += 1
        else:
            out.append({"t_s": t, "kind": kind, "text": text, "command_id": command_id})

    for r in commands:
        cid, name = int(r["id"]), _command_text(r)
        if r.get("first_sent_at"):
            copies = r.get("copies") or 1
            add(clock(r["first_sent_at"]), "sent", f"{name} sent (copy 1 of {copies})", cid)
            if r.get("sent_at") and r["sent_at"] != r["first_sent_at"]:
                add(clock(r["sent_at"]), "sent", f"command {cid}: last copy sent", cid)
        ack = r.get("ack") if isinstance(r.get("ack"), Mapping) else None
        if ack is not None:
            vehicle_t = ack.get("t_s")
            t = (
                float(vehicle_t) - start_t_s
                if isinstance(vehicle_t, int | float) and start_t_s is not None
                else clock(r.get("acked_at") or r.get("updated_at"))
            )
            if ack.get("outcome") == "accepted":
                bits = ack.get("corrected_bits")
                add(t, "acknowledged", f"command {cid} acknowledged (corrected {bits} bits)", cid)
            else:
                why = ack.get("detail") or ack.get("reason") or "rejected"
                add(t, "rejected", f"command {cid} rejected: {why}", cid)
        elif r.get("state") in ("timed_out", "failed", "superseded", "interrupted"):
            state = str(r["state"]).replace("_", " ")
            add(clock(r.get("updated_at")), str(r["state"]), f"command {cid} {state}", cid)
    for e in events:
        add(clock(e.get("at")), str(e["kind"]), str(e["detail"]), None)
    out.sort(key=lambda e: e["t_s"])
    return out, unplaced


def vehicle_events(events: Sequence[Row], vehicle: str | None) -> list[Row]:
    """The log's ``events`` a fleet's ``vehicle``'s replay shows: its own and those naming no
    vehicle (a datum set, the console's own); None (no fleet): every one."""
    if vehicle is None:
        return list(events)
    return [e for e in events if e.get("vehicle") in (None, vehicle)]


def position_at(samples: Sequence[Row], t_s: float) -> dict[str, Any]:
    """The vehicle at ``t_s`` on the dive's clock (``samples``: the timeline's, ``t_s`` since
    the start, time order, at least one): position linear between the samples around it,
    heading the shorter way round, what it ran the sample at or before."""
    ts = [float(s["t_s"]) for s in samples]
    k = max(0, bisect.bisect_right(ts, t_s) - 1)
    a = samples[k]
    b = samples[min(k + 1, len(samples) - 1)]
    span = float(b["t_s"]) - float(a["t_s"])
    f = 0.0 if span <= 0 else min(1.0, max(0.0, (t_s - float(a["t_s"])) / span))
    turn = (float(b["heading_deg"]) - float(a["heading_deg"]) + 180.0) % 360.0 - 180.0
    return {
        "t_s": t_s,
        "x_m": a["x_m"] + (b["x_m"] - a["x_m"]) * f,
        "y_m": a["y_m"] + (b["y_m"] - a["y_m"]) * f,
        "z_m": a["z_m"] + (b["z_m"] - a["z_m"]) * f,
        "heading_deg": (float(a["heading_deg"]) + turn * f) % 360.0,
        **{k: a.get(k) for k in ("mode", "pattern", "command_id")},
        "sample": k,
    }


def samples_of(
    rows: Sequence[Row], commands: Sequence[Row], only: int | None = None
) -> list[dict[str, Any]]:
    """The track ``rows`` as the timeline's samples (``t_s`` from the first row); which logged
    command each was running is matched for every sample, or for sample ``only`` alone (the
    others' ``command_id`` None)."""
    start = float(rows[0]["t_s"]) if rows else 0.0
    sent = sorted((c for c in commands if c.get("first_sent_at")), key=lambda c: c["first_sent_at"])
    sent_at = [epoch_s(c["first_sent_at"]) or 0.0 for c in sent]
    samples = []
    for k, r in enumerate(rows):
        active = r.get("active")
        command_id = None
        if only is None or k == only:
            at = epoch_s(r.get("at"))
            by_then = sent if at is None else sent[: bisect.bisect_right(sent_at, at)]
            command_id = running_command(active, by_then)
        samples.append(
            {
                "t_s": float(r["t_s"]) - start,
                **{key: r[key] for key in ("x_m", "y_m", "z_m", "heading_deg", "mode")},
                "pattern": active.get("pattern") if isinstance(active, Mapping) else None,
                "command_id": command_id,
            }
        )
    return samples


def dive_timeline(
    rows: Sequence[Row], commands: Sequence[Row], events: Sequence[Row], started_at: str
) -> dict[str, Any]:
    """The dive's samples (``t_s`` since its start; position, mode, the pattern the vehicle
    reported running and the logged command it is), its commands and link events."""
    clock = dive_clock(rows, started_at)
    start = float(rows[0]["t_s"]) if rows else None
    samples = samples_of(rows, commands)
    placed, unplaced = link_events(commands, events, clock, start)
    ends = [s["t_s"] for s in samples] + [e["t_s"] for e in placed]
    return {
        "start_t_s": start,
        "from_t_s": min([0.0, *ends]),
        "duration_s": max([0.0, *ends]),
        "samples": samples,
        "commands": [
            {
                "id": c["id"],
                "pattern": c["pattern"],
                "kind": c.get("kind"),
                "params": c.get("params") or {},
                "state": c["state"],
                "text": _command_text(c),
                "sent_t_s": clock(c.get("first_sent_at")),
            }
            for c in commands
        ],
        "events": placed,
        "unplaced_events": unplaced,
    }


def vehicle_at(
    rows: Sequence[Row], commands: Sequence[Row], events: Sequence[Row], started_at: str, t_s: float
) -> tuple[tuple[float, float], dict[str, Any] | None]:
    """For the replay's slider: the timeline's range ``(from_t_s, duration_s)``, and the
    vehicle at ``t_s`` (:func:`position_at`, the command it ran matched for that sample alone;
    None without a track)."""
    samples = samples_of(rows, commands, only=-1)
    placed, _ = link_events(commands, events, dive_clock(rows, started_at), _start(rows))
    ends = [s["t_s"] for s in samples] + [e["t_s"] for e in placed]
    span = (min([0.0, *ends]), max([0.0, *ends]))
    if not samples:
        return span, None
    pos = position_at(samples, t_s)
    pos["command_id"] = samples_of(rows, commands, only=pos["sample"])[pos["sample"]]["command_id"]
    return span, pos


def _start(rows: Sequence[Row]) -> float | None:
    return float(rows[0]["t_s"]) if rows else None
