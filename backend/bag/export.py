"""A dive of the mission log exported: as an MCAP file, a rosbag2 directory, or MCAP bytes
streamed (``GET /api/dives/{dive}/export.mcap``); the pieces are :mod:`backend.bag.dive` (the
messages) and :mod:`backend.bag.write` (the writers).

The datum that places ``/nemesys/fix``: the one given (``nemesys export --datum``), else the
log's own (the ``datum`` events up to the dive, each from when it was set), starting from
``fallback`` (the console's current datum, for the API); without any, the export has no fix.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

from backend.bag import messages as m
from backend.bag.dive import DatumWalk, Message, dive_messages
from backend.bag.write import Progress, Written, mcap_bytes, write_mcap_file, write_rosbag2_dir
from backend.chart.geo import Datum
from backend.mission_log.dive_reader import DiveReader, snapshot
from backend.mission_log.read_only import ReadOnlyDatabase

#: What an export says about its time base (MCAP metadata, rosbag2 custom data).
TIME_BASE = (
    "log time: the console's monotonic-anchored UTC when each row was written; header stamps: "
    "the vehicle's ROS time for what the vehicle said, the console's UTC for what it did"
)


@dataclass(frozen=True)
class DivePlan:
    """One dive's export, ready to stream: its messages (in log-time order), the metadata it
    carries and how many messages to expect (the progress' total; an upper bound)."""

    dive: int
    messages: Iterator[Message]
    metadata: dict[str, str]
    expected: int


def plan(
    reader: DiveReader, dive: int, datum: Datum | None = None, fallback: Datum | None = None
) -> DivePlan:
    """The export of ``dive`` (see the module's docstring for ``datum`` and ``fallback``).

    Raises:
        NoSuchDive: the log has no such dive (nothing read beyond).
    """
    row = reader.dive(dive)
    datums = DatumWalk(reader.datums(dive), fixed=datum, fallback=fallback)
    n = reader.counts(dive)
    fixes = n["positioned"] if datums.any else 0
    expected = n["positioned"] + fixes + n["track"] + n["commands"] + n["frames"]
    expected += 2 * n["acks"] + n["events"]
    metadata = {
        "dive": str(dive),
        "started_at": str(row["started_at"]),
        "target": str(row["target"]),
        "time_base": TIME_BASE,
        "pose_frame": f"{m.MAP_FRAME} (ENU, REP-103), body {m.BODY_FRAME} (FLU)",
        "datum": "given" if datum is not None else "the log's" if datums.any else "none",
    }
    vehicles = reader.vehicles(dive)
    if vehicles:  # a fleet's: each vehicle's topics under /<name>
        metadata["vehicles"] = ",".join(vehicles)
    messages = dive_messages(reader, dive, datums, str(row["started_at"]))
    return DivePlan(dive, messages, metadata, expected)


def export_files(
    db: ReadOnlyDatabase,
    dive: int,
    *,
    mcap: Path | None = None,
    rosbag2: Path | None = None,
    force: bool = False,
    datum: Datum | None = None,
    progress: Progress | None = None,
) -> list[Written]:
    """``dive`` of the log ``db`` (a read-only connection to a SQLite file or a PostgreSQL
    database) as an MCAP file and/or a rosbag2 directory (one pass of the log each, in one read
    snapshot).

    Raises:
        NoSuchDive: the log has no such dive (nothing written).
        ExportExists, FileNotFoundError: an output that may not be written (nothing written).
    """
    out: list[Written] = []
    with snapshot(db) as reader:
        for path, write in ((mcap, write_mcap_file), (rosbag2, write_rosbag2_dir)):
            if path is None:
                continue
            p = plan(reader, dive, datum)
            out.append(
                write(
                    path,
                    p.messages,
                    p.metadata,
                    force=force,
                    expected=p.expected,
                    progress=progress,
                )
            )
    return out


def stream_mcap(db: ReadOnlyDatabase, dive: int, fallback: Datum | None) -> Iterator[bytes]:
    """``dive`` as MCAP bytes, a piece at a time, in one read snapshot of ``db`` (held until
    the last piece, or until the consumer closes the iterator)."""
    with snapshot(db) as reader:
        p = plan(reader, dive, fallback=fallback)
        yield from mcap_bytes(p.messages, p.metadata)
