"""``nemesys bench export``: a 5-hour dive exported as MCAP and as a rosbag2 directory: the
export's time, its peak memory and the file's size per hour of dive, each beside its target,
and the same at 1 hour to show the memory is flat (it does not grow with the dive).

The dive is synthetic (:mod:`bench._dive_log`): filled through the mission log's own store API
with the log's clock moved by hand, so 18 000 track points at 1 Hz, 30 commands with their
frames and acknowledgements and the events carry the stamps of a real 5-hour dive. Running the
training simulator at time scale 50 would make the same rows in 6 minutes of this 2-core
machine; the export reads rows, not how they were made. The log is a file in a temporary
directory; the export reads it read-only, as ``nemesys export`` does.

Memory, two ways: the peak RSS growth over the export in a fresh process (Linux: ``VmHWM``
reset through ``/proc/self/clear_refs`` before it; C allocations included: zstd, SQLite), and
tracemalloc's peak of Python allocations (a separate run: tracing slows the export). Flat
means the long dive's peak is within :data:`TARGET_FLAT_MIB` of the short one's.
"""

from __future__ import annotations

import json
import math
import os
import subprocess
import sys
import tempfile
import time
import tracemalloc
from pathlib import Path
from typing import Final, TextIO

from backend.bag.export import export_files
from backend.bag.messages import TOPICS
from backend.bag.msgdefs import definition
from backend.bag.write import Written
from backend.mission_log.dive_reader import open_read_only
from backend.mission_log.store import MissionLog
from bench._dive_log import ManualUtc, fill_dive
from bench._timing import ROOT, machine, table, verdict

#: The dive lengths measured (h): the short one shows the memory does not grow with the dive.
HOURS: Final = (1.0, 5.0)
QUICK_HOURS: Final = (0.5, 1.0)
#: Targets: a 5-hour dive exports within this (s)...
TARGET_TIME_S: Final = 60.0
#: ... its peak memory stays under this (MiB, RSS growth and Python allocations alike)...
TARGET_PEAK_MIB: Final = 64.0
#: ... and an hour of dive costs at most this much file (MB per hour).
TARGET_MB_PER_HOUR: Final = 5.0

#: The long dive's peak may exceed the short one's by at most this (MiB): a cost that grew
#: with the dive (a row kept per row) would add megabytes per hour.
TARGET_FLAT_MIB: Final = 2.0
#: The export forms, by name: how each is written into a folder.
FORMS: Final = ("MCAP", "rosbag2")


def _rss_kib(field: str) -> int | None:
    try:
        with open("/proc/self/status", encoding="ascii") as f:
            line = next((ln for ln in f if ln.startswith(field + ":")), None)
    except OSError:
        return None
    return None if line is None else int(line.split()[1])


def _reset_peak_rss() -> bool:
    """Reset the kernel's peak RSS of this process (Linux 4.0 and later); False: cannot."""
    try:
        with open("/proc/self/clear_refs", "w", encoding="ascii") as f:
            f.write("5")
    except OSError:
        return False
    return True


def export(form: str, log: Path, folder: Path) -> Written:
    """Dive 1 of ``log`` written in ``form`` into ``folder`` (replacing the last one)."""
    db = open_read_only(log)
    try:
        if form == "MCAP":
            return export_files(db, 1, mcap=folder / "dive.mcap", force=True)[0]
        return export_files(db, 1, rosbag2=folder / "dive_bag", force=True)[0]
    finally:
        db.close()


def _warm_up() -> None:
    """What any first export loads once (the type store, the definitions): not its cost."""
    for topic in TOPICS:
        definition(topic.type)


def child(form: str, log: Path, folder: Path) -> dict[str, float]:
    """One export in this (fresh) process: its time, messages, size and peak RSS growth (MiB;
    NaN where the kernel cannot reset the peak)."""
    _warm_up()
    before = _rss_kib("VmRSS") if _reset_peak_rss() else None
    written = export(form, log, folder)
    peak = _rss_kib("VmHWM")
    growth = math.nan if before is None or peak is None else (peak - before) / 1024
    return {
        "seconds": written.seconds,
        "messages": written.messages,
        "size_bytes": written.size_bytes,
        "rss_growth_mib": growth,
    }


def in_child(form: str, log: Path, folder: Path) -> dict[str, float]:
    """:func:`child` in a fresh interpreter (this one's, this checkout first on its path), so
    no earlier export's freed memory hides this one's."""
    done = subprocess.run(
        [sys.executable, "-m", "bench.export", "--child", form, str(log), str(folder)],
        capture_output=True,
        text=True,
        check=True,
        cwd=ROOT,
        env={**os.environ, "PYTHONPATH": os.pathsep.join([ROOT, os.environ.get("PYTHONPATH", "")])},
    )
    got: dict[str, float] = json.loads(done.stdout.strip().splitlines()[-1])
    return got


def python_peak_mib(form: str, log: Path, folder: Path) -> float:
    """tracemalloc's peak over one export in this process (MiB), after the warm-up."""
    _warm_up()
    tracemalloc.start()
    try:
        export(form, log, folder)
        return tracemalloc.get_traced_memory()[1] / 2**20
    finally:
        tracemalloc.stop()


def fill(path: Path, hours: float) -> tuple[float, int]:
    """A synthetic dive of ``hours`` into a new log at ``path``: (seconds taken, track rows)."""
    clock = ManualUtc()
    log = MissionLog(path, now=clock)
    started = time.perf_counter()
    try:
        filled = fill_dive(log, round(hours * 3600), clock)
    finally:
        log.close()
    return time.perf_counter() - started, filled.track


def run(out: TextIO, quick: bool = False) -> int:
    hours = QUICK_HOURS if quick else HOURS
    short, long = hours
    got: dict[tuple[str, float], dict[str, float]] = {}
    print(f"export of a synthetic dive (bench/_dive_log.py) on {machine()}", file=out)
    with tempfile.TemporaryDirectory(prefix="nemesys-bench-export-") as tmp:
        work = Path(tmp)
        for h in hours:
            log = work / f"dive-{h:.2f}h.sqlite3"
            fill_s, track = fill(log, h)
            print(
                f"{h:.2f} h dive: {track} track rows filled through the store in {fill_s:.1f} s",
                file=out,
            )
            for form in FORMS:
                got[(form, h)] = {
                    **in_child(form, log, work),
                    "py_peak_mib": python_peak_mib(form, log, work),
                }
    rows = [
        [
            form,
            f"{h:.2f}",
            f"{g['messages']:.0f}",
            f"{g['seconds']:.1f}",
            f"{g['rss_growth_mib']:.1f}",
            f"{g['py_peak_mib']:.1f}",
            f"{g['size_bytes'] / 1e6:.2f}",
            f"{g['size_bytes'] / 1e6 / h:.2f}",
        ]
        for (form, h), g in got.items()
    ]
    headers = [
        "form",
        "dive h",
        "messages",
        "export s",
        "peak RSS+ MiB",
        "peak py MiB",
        "MB",
        "MB/h",
    ]
    print(table(headers, rows), file=out)
    time_target = TARGET_TIME_S * long / 5.0  # the target scaled to the dive measured
    print(f"\ntargets for the {long:.2f} h dive (measured; target):", file=out)
    ok = True
    for form in FORMS:
        g, s = got[(form, long)], got[(form, short)]
        peak = max(g["rss_growth_mib"], g["py_peak_mib"])  # NaN-safe: max keeps a number first
        growth = max(g["rss_growth_mib"] - s["rss_growth_mib"], g["py_peak_mib"] - s["py_peak_mib"])
        per_hour = g["size_bytes"] / 1e6 / long
        checks = (
            (f"export {g['seconds']:.1f} s", g["seconds"] <= time_target, f"<= {time_target:g} s"),
            (f"peak {peak:.1f} MiB", peak <= TARGET_PEAK_MIB, f"<= {TARGET_PEAK_MIB:g} MiB"),
            (
                f"peak growth from {short:.2f} h {growth:+.1f} MiB",
                growth <= TARGET_FLAT_MIB,
                f"<= {TARGET_FLAT_MIB:g} MiB (flat)",
            ),
            (
                f"{per_hour:.2f} MB per hour",
                per_hour <= TARGET_MB_PER_HOUR,
                f"<= {TARGET_MB_PER_HOUR:g}",
            ),
        )
        for what, met, target in checks:
            print(f"  {form}: {what} (target {target}: {verdict(met)})", file=out)
            ok = ok and met
    return 0 if ok else 1


if __name__ == "__main__":
    if sys.argv[1:2] == ["--child"]:
        form, log, folder = sys.argv[2:5]
        print(json.dumps(child(form, Path(log), Path(folder))))
        raise SystemExit(0)
    raise SystemExit(run(sys.stdout, quick="--quick" in sys.argv))
