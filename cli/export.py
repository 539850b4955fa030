"""``nemesys export``: a dive of the mission log for the robotics tools, as an MCAP file
(``--mcap FILE``) and/or a rosbag2 directory (``--rosbag2 DIR``): docs/foxglove.md.

Registered by :mod:`cli.main` (:func:`add_parser`). The log (a SQLite file, or a
``postgresql://`` URL as the console's ``NEMESYS_DATABASE_URL``) is opened read-only (a console
may be running on it; an older log is read as it is, never migrated) and read in one snapshot.
Progress goes to standard error, the result to standard output. Bad input (no such log, dive or
directory; an output that exists without ``--force``) is one line and exit status 2, with
nothing written.
"""

from __future__ import annotations

import argparse
import os
import sys
from collections.abc import Callable
from pathlib import Path
from typing import TextIO

from cli.common import EXIT_OK, UsageError
from codec import int_from_text, number_from_text

#: The console's default mission log (``backend.settings.Settings.db_path``), and its variable.
DEFAULT_DB = Path(".nemesys/missions.sqlite3")
DB_VARIABLE = "NEMESYS_DB_PATH"
#: The console's log on PostgreSQL (``Settings.database_url``): when set, before the file.
URL_VARIABLE = "NEMESYS_DATABASE_URL"


def _datum(text: str) -> tuple[float, float]:
    lat_text, sep, lon_text = text.partition(",")
    try:
        if not sep:
            raise ValueError("two numbers are needed")
        lat, lon = number_from_text(lat_text.strip()), number_from_text(lon_text.strip())
    except ValueError as err:
        raise argparse.ArgumentTypeError(
            f"LAT,LON in degrees is needed (e.g. 43.1,5.9), got {text!r}: {err}"
        ) from None
    if not (-90 <= lat <= 90 and -180 <= lon <= 180):
        raise argparse.ArgumentTypeError(
            f"the latitude must be in [-90, 90] and the longitude in [-180, 180], got {text}"
        )
    return lat, lon


def add_parser(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    p = sub.add_parser(
        "export",
        help="export a dive as MCAP or rosbag2 (Foxglove, ros2 bag, PlotJuggler)",
        description="Write a dive of the mission log in ROS 2 message types: the vehicle's "
        "odometry (ENU) and fix, its status, the frames sent, the command records, the "
        "acknowledgements (typed nemesys_msgs, and the contract's JSON) and the log's events, "
        "on the console's clock. See docs/foxglove.md.",
    )
    p.add_argument("dive", type=int_from_text, metavar="DIVE", help="the dive's number")
    p.add_argument("--mcap", type=Path, metavar="FILE", help="write an MCAP file")
    p.add_argument(
        "--rosbag2", type=Path, metavar="DIR", help="write a rosbag2 directory (metadata.yaml)"
    )
    p.add_argument(
        "--db",
        metavar="FILE|URL",
        help="the mission log: a SQLite file or a postgresql:// URL (default, as the console: "
        f"${URL_VARIABLE}, else ${DB_VARIABLE}, else {DEFAULT_DB})",
    )
    p.add_argument(
        "--datum",
        type=_datum,
        metavar="LAT,LON",
        help="the datum that places /nemesys/fix (default: the log's own datum events)",
    )
    p.add_argument("--force", action="store_true", help="replace an existing output")
    p.add_argument("--quiet", action="store_true", help="no progress on standard error")


def _progress(stream: TextIO) -> Callable[[int, int], None]:
    def report(done: int, total: int) -> None:
        pct = 100.0 * done / total if total else 100.0
        stream.write(f"\r  {done} of {total} messages ({pct:.0f} %)")
        if done >= total:
            stream.write("\n")
        stream.flush()

    return report


def cmd_export(args: argparse.Namespace, out: TextIO) -> int:
    from backend.bag.export import export_files
    from backend.bag.write import ExportExists
    from backend.chart.geo import Datum
    from backend.mission_log.dive_reader import NoSuchDive, open_read_only
    from backend.mission_log.opening import LogError

    if args.mcap is None and args.rosbag2 is None:
        raise UsageError("give --mcap FILE, --rosbag2 DIR, or both")
    if args.dive < 1:
        raise UsageError(f"DIVE is a dive's number, 1 and up, got {args.dive}")
    where: str = (
        args.db
        or os.environ.get(URL_VARIABLE, "").strip()
        or os.environ.get(DB_VARIABLE)
        or str(DEFAULT_DB)
    )
    datum = None if args.datum is None else Datum(*args.datum)
    try:
        db = open_read_only(where)
    except LogError as err:
        raise UsageError(str(err)) from None
    try:
        written = export_files(
            db,
            args.dive,
            mcap=args.mcap,
            rosbag2=args.rosbag2,
            force=args.force,
            datum=datum,
            progress=None if args.quiet else _progress(sys.stderr),
        )
    except (NoSuchDive, ExportExists, FileNotFoundError) as err:
        raise UsageError(str(err)) from None
    finally:
        db.close()
    for w in written:
        topics = ", ".join(f"{name} {n}" for name, n in sorted(w.topics.items()))
        out.write(
            f"{w.path}: dive {args.dive}, {w.messages} messages ({topics}), "
            f"{w.size_bytes / 1e6:.2f} MB in {w.seconds:.1f} s\n"
        )
    return EXIT_OK
