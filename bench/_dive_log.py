"""A synthetic dive filled into a mission log through its own store API (``MissionLog``), with
the log's clock moved by hand: a dive of hours is written in seconds, its stamps those of the
real thing (``nemesys bench export``, and the export tests).

Each second of the dive: a track point with the vehicle's status (a lawnmower at 3 m, the
battery running down), or during the navigation fault a point without position. Every
:data:`COMMAND_EVERY_S`: a command written, its first copy sent a second later and its
acknowledgement two seconds after that (every fourth rejected), with a frame decoded from the
real codec. A datum event at the start, an echo-mismatch event in the middle.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from datetime import UTC, datetime
from typing import Any, Final

from backend.mission_log.store import MissionLog
from codec import encode_frame
from onboard.agent import command_json

#: The console's clock at the dive's first second (POSIX s).
EPOCH_S: Final = 1_750_000_000.0
#: The vehicle's ROS time at the dive's first second (s).
VEHICLE_T0_S: Final = 1000.0
#: A command every this many seconds of the dive.
COMMAND_EVERY_S: Final = 600
#: The navigation fault: its start (s into the dive, scaled to short dives) and length (s).
NAV_FAULT_FRACTION: Final = 0.4
NAV_FAULT_S: Final = 120
#: The datum the dive's event sets (deg).
DATUM: Final = (43.1, 5.9)

LAWNMOWER: Final[dict[str, Any]] = {
    "speed": 0.3,
    "depth": 3,
    "sweep_length": 40,
    "lane_spacing": 4,
    "laps": 10,
}
CIRCLE: Final[dict[str, Any]] = {"speed": 0.18, "depth": 5, "radius": 8, "direction": "cw"}


class ManualUtc:
    """The log's clock, moved by hand: ISO UTC of :data:`EPOCH_S` plus ``elapsed_s``."""

    def __init__(self) -> None:
        self.elapsed_s = 0.0

    def __call__(self) -> str:
        moment = datetime.fromtimestamp(EPOCH_S + self.elapsed_s, UTC)
        return moment.isoformat(timespec="milliseconds")


@dataclass(frozen=True)
class Filled:
    """What was written: the dive, and the rows of each kind."""

    dive: int
    track: int
    positioned: int
    commands: int
    sent: int
    acks: int
    events: int


def _record(pattern: str, params: dict[str, Any]) -> dict[str, Any]:
    enc = encode_frame(pattern, params)
    return {
        "operator": "bench",
        "target": "sim",
        "kind": "command",
        "pattern": enc.command.pattern.name,
        "pattern_id": enc.command.pattern.id,
        "params": dict(enc.command.params),
        "requested": dict(params),
        "bits": enc.frame.bits,
        "hex": enc.frame.hex,
        "origin": "api",
    }


def fill_dive(
    log: MissionLog, seconds: int, clock: ManualUtc, command_every_s: int = COMMAND_EVERY_S
) -> Filled:
    """Write a dive of ``seconds`` (1 Hz) into ``log``, whose stamps come from ``clock``, a
    command every ``command_every_s``."""
    dive = log.new_dive("sim")
    log.add_event(
        dive,
        "datum",
        "datum set from the operator",
        {"lat_deg": DATUM[0], "lon_deg": DATUM[1], "source": "operator", "previous": None},
    )
    fault_from = int(seconds * NAV_FAULT_FRACTION)
    active: dict[str, Any] | None = None
    pending: list[tuple[int, str, int, dict[str, Any]]] = []  # (due s, what, id, command)
    n_cmd = n_sent = n_ack = 0
    n_events = 1
    positioned = 0
    for k in range(seconds):
        clock.elapsed_s = float(k)
        t_s = VEHICLE_T0_S + k
        if k % command_every_s == 0:
            pattern, params = (
                ("lawnmower", LAWNMOWER) if (k // command_every_s) % 2 == 0 else ("circle", CIRCLE)
            )
            rec = log.insert_command(dive, _record(pattern, params))
            n_cmd += 1
            command = command_json(encode_frame(pattern, params).command)
            pending.append((k + 1, "sent", rec["id"], command))
        for due, what, cid, cmd in [p for p in pending if p[0] == k]:
            pending.remove((due, what, cid, cmd))
            if what == "sent":
                stamp = clock()
                log.update_command(
                    cid,
                    state="transmitted",
                    attempts=1,
                    copies=2,
                    copies_sent=1,
                    first_sent_at=stamp,
                    sent_at=stamp,
                    p_delivered=0.9,
                )
                n_sent += 1
                pending.append((k + 2, "acked", cid, cmd))
            elif what == "acked":
                rejected = cid % 4 == 0
                sent = log.command(cid)
                assert sent is not None
                ack = {
                    "seq": cid,
                    "t_s": t_s - 0.4,
                    "outcome": "rejected" if rejected else "accepted",
                    "frame_hex": sent["hex"],
                    "corrected_bits": 1 if not rejected else None,
                    "sync_errors": 0,
                    "reason": "out_of_range" if rejected else None,
                    "detail": "rejected: out of range" if rejected else "accepted",
                    "command": None if rejected else cmd,
                    "duplicate": False,
                    "decode_latency_ms": 0.4,
                    "replan_latency_ms": 2.5,
                    "waypoints": 120,
                    "active": active if rejected else cmd,
                    "from": None,
                }
                log.update_command(
                    cid, state="rejected" if rejected else "acknowledged", acked_at=clock(), ack=ack
                )
                n_ack += 1
                if not rejected:
                    active = cmd
        if k == seconds // 2:
            n_events += 1
            log.add_event(
                dive,
                "echo_mismatch",
                "the vehicle runs a command this console did not send",
                {"vehicle": active},
            )
        depth_m = 3.0 + 0.2 * math.sin(k / 60.0)
        heading_deg = (k * 0.5) % 360.0
        status = {
            "t_s": t_s,
            "depth_m": depth_m,
            "speed_mps": 0.3,
            "battery_pct": 100.0 - 80.0 * k / max(seconds, 1),
            "mode": "running" if active else "idle",
            "active": active,
            "nav_valid": True,
            "nav_age_s": 0.1,
            "heading_deg": heading_deg,
        }
        if fault_from <= k < fault_from + NAV_FAULT_S:
            log.add_status_point(
                dive,
                t_s,
                {
                    **status,
                    "nav_valid": False,
                    "nav_age_s": 5.0 + k - fault_from,
                    "mode": "nav_fault",
                    "heading_deg": None,
                    "depth_m": None,
                },
            )
        else:
            lane = (k // 120) % 20
            along = (k % 120) * 0.3 * (1 if lane % 2 == 0 else -1)
            log.add_track(dive, t_s, 4.0 * lane, along, depth_m, heading_deg, status)
            positioned += 1
    log.flush_track()
    return Filled(dive, seconds, positioned, n_cmd, n_sent, n_ack, n_events)
