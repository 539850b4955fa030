"""A dive as one stream of ROS 2 messages on one clock, read row by row from the mission log.

Time: every message's log time (MCAP's ``log_time``, rosbag2's timestamp) is the console's
UTC when the row was written (:data:`backend.clock.CONSOLE_UTC`, monotonic-anchored): a track
point when it arrived, a command when it was written, a frame when its first copy left, an
acknowledgement when it arrived, an event when it was logged. So everything in a dive is on one
time base, in the order it happened at the console. The header stamps keep each source's own
clock: the vehicle's ROS time (``t_s``) for what the vehicle said (odometry, fix, status, an
acknowledgement that carries ``t_s``), the console's UTC for what the console did. A track
point of an older log without its arrival time is placed at the dive's start plus its
vehicle seconds since the first point.

A fleet's dive (rows naming their ``vehicle``) is every vehicle's in one export: what is a
vehicle's (its pose, fix and status, its commands' records, frames and acknowledgements, its
events) on its own topics under ``/<name>`` (:func:`backend.bag.messages.vehicle_topic`, the
live Foxglove view's naming), its odometry's child frame ``<name>/base_link``; the events
naming no vehicle on the plain topic. A row naming no vehicle (every row of a single
vehicle's dive) is on the topics as they always were.

The tables' rows are merged by log time (one row of each table in memory at a time), and a
stamp older than the one before it (a log whose clock was stepped, before the monotonic
anchor) is written at the one before: the log times never go back.
"""

from __future__ import annotations

import heapq
from collections.abc import Iterator
from datetime import datetime
from typing import Any, NamedTuple

from backend.bag import messages as m
from backend.chart.geo import Datum, ned_to_geodetic
from backend.mission_log.dive_reader import DiveReader


class Message(NamedTuple):
    """One message of the export: its log time (ns since the epoch, UTC), topic and fields."""

    log_time_ns: int
    topic: m.Topic
    msg: m.Msg


def ns_of(iso: str | None) -> int | None:
    """An ISO 8601 time of the log as ns since the epoch; None if absent or unreadable."""
    if not iso:
        return None
    try:
        moment = datetime.fromisoformat(iso)
    except ValueError:
        return None
    return round(moment.timestamp() * 1_000_000) * 1000  # the log keeps milliseconds


class DatumWalk:
    """The datum in force at each moment of the dive: ``fixed`` when given (it is used
    throughout), else the log's datum events as they were set (``changes``: ``(at, lat, lon)``,
    oldest first), starting from ``fallback`` before the first."""

    def __init__(
        self,
        changes: list[tuple[str, float, float]],
        fixed: Datum | None = None,
        fallback: Datum | None = None,
    ) -> None:
        self._changes = (
            [] if fixed is not None else [(ns_of(a), lat, lon) for a, lat, lon in changes]
        )
        self._next = 0
        self.current = fixed if fixed is not None else fallback

    def at(self, log_time_ns: int) -> Datum | None:
        """The datum at ``log_time_ns`` (called with non-decreasing times)."""
        while self._next < len(self._changes):
            when, lat, lon = self._changes[self._next]
            if when is not None and when > log_time_ns:
                break
            self.current = Datum(lat, lon)
            self._next += 1
        return self.current

    @property
    def any(self) -> bool:
        """Whether a datum is known at some moment of the dive."""
        return self.current is not None or bool(self._changes)


def _track(reader: DiveReader, dive: int, started_ns: int, datums: DatumWalk) -> Iterator[Message]:
    first_t_s: float | None = None
    for row in reader.track(dive):
        t_s = float(row["t_s"])
        first_t_s = t_s if first_t_s is None else first_t_s
        at = ns_of(row["at"])
        log_ns = at if at is not None else started_ns + round((t_s - first_t_s) * 1e9)
        vehicle = row.get("vehicle")
        if row["x_m"] is not None:
            yield Message(log_ns, m.vehicle_topic(m.ODOM, vehicle), m.odometry(row))
            datum = datums.at(log_ns)
            if datum is not None:
                lat, lon = ned_to_geodetic(datum, row["x_m"], row["y_m"])
                fix = m.nav_sat_fix(row, float(lat), float(lon))
                yield Message(log_ns, m.vehicle_topic(m.FIX, vehicle), fix)
        yield Message(log_ns, m.vehicle_topic(m.STATUS, vehicle), m.status(row))


def _console(ns: int) -> float:
    """A log time as the header stamp of what the console did (s)."""
    return ns / 1e9


def _commands(reader: DiveReader, dive: int) -> Iterator[Message]:
    for record in reader.commands(dive):
        ns = ns_of(record["created_at"])
        if ns is not None:
            topic = m.vehicle_topic(m.COMMANDS, record.get("vehicle"))
            yield Message(ns, topic, m.command_record(record, _console(ns)))


def _frames(reader: DiveReader, dive: int) -> Iterator[Message]:
    for left_at, record in reader.sent(dive):
        ns = ns_of(left_at)
        if ns is not None and record.get("hex"):
            topic = m.vehicle_topic(m.FRAME, record.get("vehicle"))
            yield Message(ns, topic, m.frame(record["hex"]))


def _acks(reader: DiveReader, dive: int) -> Iterator[Message]:
    for acked_at, record in reader.acks(dive):
        ns = ns_of(acked_at)
        ack: Any = record["ack"]
        if ns is None or not isinstance(ack, dict):
            continue
        vehicle_t = ack.get("t_s")
        t_s = float(vehicle_t) if isinstance(vehicle_t, int | float) else _console(ns)
        vehicle = record.get("vehicle")
        yield Message(ns, m.vehicle_topic(m.ACK, vehicle), m.ack(ack, t_s))
        yield Message(ns, m.vehicle_topic(m.MISSION, vehicle), m.json_string(ack))


def _events(reader: DiveReader, dive: int) -> Iterator[Message]:
    for event in reader.events(dive):
        ns = ns_of(event["at"])
        if ns is not None:
            doc = {k: event[k] for k in ("kind", "detail", "data")}
            topic = m.vehicle_topic(m.EVENTS, event.get("vehicle"))
            yield Message(ns, topic, m.json_string(doc))


def _keyed(k: int, stream: Iterator[Message]) -> Iterator[tuple[tuple[int, int, int], Message]]:
    for n, msg in enumerate(stream):
        yield (msg.log_time_ns, k, n), msg


def dive_messages(
    reader: DiveReader, dive: int, datums: DatumWalk, started_at: str
) -> Iterator[Message]:
    """Every message of ``dive`` in log-time order (see the module's docstring); ``datums``
    places the fixes (none without a datum)."""
    started_ns = ns_of(started_at) or 0
    streams = (
        _track(reader, dive, started_ns, datums),
        _commands(reader, dive),
        _frames(reader, dive),
        _acks(reader, dive),
        _events(reader, dive),
    )
    # ties: the stream's index, then the order within it (a point's odometry, fix, status)
    merged = heapq.merge(*(_keyed(k, stream) for k, stream in enumerate(streams)))
    last = 0
    for _, msg in merged:
        last = max(last, msg.log_time_ns)
        yield msg if msg.log_time_ns == last else msg._replace(log_time_ns=last)
