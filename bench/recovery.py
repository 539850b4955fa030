"""``nemesys bench recovery``: records a SIGKILLed console left on their way are recovered.

A loopback TCP listener stands for an ME modem's TCP gateway: it decodes the frames it gets
(``codec.FrameReceiver``) and counts them. Then ``--kills`` cycles, all on one log (a SQLite
file in a temporary directory, or the PostgreSQL database ``NEMESYS_DATABASE_URL`` names when
it is set): ``nemesys console`` starts with ``--target tcp://127.0.0.1:<listener>`` (one-way
link, copies 0.05 s apart), two threads POST a random burst of commands (5-20 copies each) and
Surface presses with the operator token, and once the first is accepted the console is
SIGKILLed after a seeded random delay. The log is then read directly (its own connection):
records left ``queued``/``transmitted`` by the kill; records the console answered 202 for that
are not in the log as answered (lost, target 0); records with a required field missing or
unreadable (half-written, target 0). The next start runs the recovery before it prints its
URL; once it answers, the log is read again: records still ``queued``/``transmitted`` (stuck,
target 0) and records made ``interrupted`` (should equal those left on their way, and the
count the console printed). Everything binds to and talks to 127.0.0.1 only.
"""

from __future__ import annotations

import json
import os
import random
import re
import sqlite3
import tempfile
import threading
import time
from collections.abc import Sequence
from dataclasses import astuple, dataclass
from pathlib import Path
from typing import Any, TextIO

import httpx

from backend.commands.lifecycle import State
from backend.mission_log.database import is_postgres_url, masked, pg_sql
from bench._gateway import FrameGateway
from bench._server import ConsoleProcess, start_console
from bench._timing import table, verdict

LOOPBACK = "127.0.0.1"
TOKEN = "recovery-bench-token-0123456789"
AUTH = {"Authorization": f"Bearer {TOKEN}"}
ENV = {
    "NEMESYS_COPY_INTERVAL_S": "0.05",
    "NEMESYS_SURFACE_REPEAT_S": "0.05",
    "NEMESYS_MAX_SENDS_PER_MINUTE": "600",
    "NO_PROXY": "127.0.0.1,localhost",
}
SENDERS = 2
SENDS_PER_THREAD = 40
MAX_KILL_DELAY_S = 0.6
PRINTED = re.compile(r"^(\d+) commands? an earlier run left queued or transmitted", re.M)


#: A record's columns that are never null (a null one: half-written).
REQUIRED = (
    "id", "dive", "created_at", "updated_at", "operator", "target", "kind", "pattern",
    "pattern_id", "params", "requested", "bits", "hex", "state", "attempts",
)  # fmt: skip


@dataclass
class Cycle:
    delay_ms: float
    records: int  # written in this cycle, before the kill
    left: int  # queued/transmitted in the log right after the kill
    interrupted: int  # made interrupted by the next start
    printed: int  # what that start printed
    non_terminal: int  # queued/transmitted once it answered (target 0)
    frames: int  # frames the listener decoded in this cycle
    accepted: int = 0  # sends the console answered 202 in this cycle
    lost: int = 0  # of those, not in the log as answered (target 0)
    half_written: int = 0  # records with a required field missing or unreadable (target 0)


def read(where: Path | str, sql: str) -> list[tuple[Any, ...]]:
    """Rows of ``sql`` read straight from the log (a connection of its own; the SQLite
    file read-only)."""
    if is_postgres_url(where):
        import psycopg

        with psycopg.connect(str(where), connect_timeout=10) as pg:
            return list(pg.execute(pg_sql(sql)).fetchall())
    with sqlite3.connect(f"file:{where}?mode=ro", uri=True) as raw:
        rows = raw.execute(sql).fetchall()
    raw.close()
    return rows


def counts(where: Path | str) -> tuple[int, int, int]:
    """(records, records queued or transmitted, records interrupted), read-only."""
    ((total, on_way, interrupted),) = read(
        where,
        "SELECT COUNT(*), "
        "COALESCE(SUM(CASE WHEN state IN ('queued', 'transmitted') THEN 1 ELSE 0 END), 0), "
        "COALESCE(SUM(CASE WHEN state = 'interrupted' THEN 1 ELSE 0 END), 0) FROM commands",
    )
    return int(total), int(on_way), int(interrupted)


def records(where: Path | str) -> dict[int, dict[str, Any]]:
    """Every command record by id, the required columns only."""
    rows = read(where, f"SELECT {', '.join(REQUIRED)} FROM commands")
    return {int(row[0]): dict(zip(REQUIRED, row, strict=True)) for row in rows}


def half_written(record: dict[str, Any]) -> bool:
    """A required field null, JSON that does not parse, a state that does not exist, or
    bits that are not the frame's hex."""
    if any(record[column] is None for column in REQUIRED):
        return True
    try:
        json.loads(record["params"])
        json.loads(record["requested"])
        bits_hex = format(int(record["bits"], 2), f"0{len(record['hex'])}x")
    except ValueError:
        return True
    return record["state"] not in tuple(State) or bits_hex != record["hex"]


def lost(accepted: Sequence[dict[str, Any]], logged: dict[int, dict[str, Any]]) -> int:
    """Records answered 202 that the log does not hold as answered (same id, frame,
    creation time and parameters)."""
    missing = 0
    for answer in accepted:
        row = logged.get(int(answer["id"]))
        if (
            row is None
            or any(row[key] != answer[key] for key in ("hex", "created_at", "pattern", "dive"))
            or json.loads(row["params"]) != answer["params"]
        ):
            missing += 1
    return missing


def start(workdir: Path, where: Path | str, port: int, n: int) -> ConsoleProcess:
    env = dict(ENV)
    log_args: tuple[str, ...] = ("--db", str(workdir / "missions.sqlite3"))
    if is_postgres_url(where):
        env["NEMESYS_DATABASE_URL"] = str(where)  # the token stays beside --db
    else:
        log_args = ("--db", str(where))
    console = start_console(
        workdir / f"console-{n}.log",
        TOKEN,
        *log_args,
        *("--target", f"tcp://{LOOPBACK}:{port}"),
        env=env,
    )
    if console.host != LOOPBACK:
        console.stop()
        raise RuntimeError(f"the console is not on loopback: {console.base_url}")
    return console


def printed_count(console: ConsoleProcess) -> int:
    match = PRINTED.search(console.log_path.read_text(errors="replace"))
    return int(match.group(1)) if match else 0


def sender(
    console: ConsoleProcess,
    seed: int,
    started: threading.Event,
    errors: list[str],
    accepted: list[dict[str, Any]],
) -> None:
    """POST commands and Surface presses until the console dies or the burst is done; the
    records answered 202 are added to ``accepted``."""
    rng = random.Random(seed)
    with console.client(timeout_s=5.0) as http:
        for _ in range(SENDS_PER_THREAD):
            try:
                if rng.random() < 0.15:
                    r = http.post("/api/surface", headers=AUTH)
                else:
                    params = {
                        "speed": 0.18,
                        "depth": rng.choice([2, 3]),
                        "radius": rng.choice([3, 4, 5, 6]),
                        "direction": rng.choice(["cw", "ccw"]),
                    }
                    body = {"pattern": "circle", "params": params, "copies": rng.randint(5, 20)}
                    r = http.post("/api/commands", json=body, headers=AUTH)
            except httpx.TransportError:
                return  # killed
            started.set()
            if r.status_code != 202:
                errors.append(f"{r.request.url.path} answered {r.status_code}: {r.text[:200]}")
                return
            accepted.append(r.json())
            time.sleep(rng.uniform(0.0, 0.05))  # an operator's pace, not a condition


def kill_during_sends(
    console: ConsoleProcess, rng: random.Random
) -> tuple[float, list[dict[str, Any]]]:
    """Fire the burst, SIGKILL a random time after the first send is accepted; returns the
    delay (s) and the records answered 202."""
    started = threading.Event()
    errors: list[str] = []
    accepted: list[dict[str, Any]] = []
    threads = [
        threading.Thread(
            target=sender, args=(console, rng.randrange(2**32), started, errors, accepted)
        )
        for _ in range(SENDERS)
    ]
    for t in threads:
        t.start()
    if not started.wait(30.0):
        console.kill()
        raise RuntimeError(f"no send was accepted:\n{console.log_tail()}")
    delay = rng.uniform(0.0, MAX_KILL_DELAY_S)
    time.sleep(delay)  # the deliberate random kill moment
    console.kill()
    for t in threads:
        t.join()
    if errors:
        raise RuntimeError(f"a send failed: {errors[0]}")
    return delay, accepted


def measure(
    kills: int, seed: int, workdir: Path, database_url: str = ""
) -> tuple[list[Cycle], FrameGateway, float]:
    """``kills`` cycles on the SQLite file in ``workdir``, or on ``database_url``."""
    rng = random.Random(seed)
    db: Path | str = database_url or workdir / "missions.sqlite3"
    listener = FrameGateway()
    t0 = time.monotonic()
    cycles: list[Cycle] = []
    console: ConsoleProcess | None = None
    try:
        console = start(workdir, db, listener.port, 0)
        for n in range(1, kills + 1):
            frames_before, total_before = listener.count(), counts(db)[0]
            delay, accepted = kill_during_sends(console, rng)
            total, left, interrupted_before = counts(db)
            logged = records(db)
            frames = listener.count() - frames_before
            console = None
            console = start(workdir, db, listener.port, n)  # runs the recovery
            _total, non_terminal, interrupted = counts(db)
            cycles.append(
                Cycle(
                    delay * 1e3,
                    total - total_before,
                    left,
                    interrupted - interrupted_before,
                    printed_count(console),
                    non_terminal,
                    frames,
                    len(accepted),
                    lost(accepted, logged),
                    sum(half_written(r) for r in logged.values()),
                )
            )
    finally:
        if console is not None:
            console.stop()
        listener.close()
    return cycles, listener, time.monotonic() - t0


def format_report(cycles: list[Cycle], listener: FrameGateway, db_total: int, wall_s: float) -> str:
    headers = ["kill", "delay ms", "records", "on their way at kill", "interrupted", "printed"]
    headers += ["left non-terminal", "frames received", "accepted", "lost", "half-written"]
    rows = [
        [str(i), f"{c.delay_ms:.0f}", *(str(v) for v in astuple(c)[1:])]
        for i, c in enumerate(cycles, 1)
    ]
    non_terminal = sum(c.non_terminal for c in cycles)
    consistent = all(c.interrupted == c.left == c.printed for c in cycles)
    lost_total = sum(c.lost for c in cycles)
    half_total = sum(c.half_written for c in cycles)
    summary = [
        ["kills", str(len(cycles)), ""],
        ["records total", str(db_total), ""],
        [
            "records left non-terminal after restart",
            str(non_terminal),
            "target 0: " + verdict(non_terminal == 0),
        ],
        ["records interrupted", str(sum(c.interrupted for c in cycles)), ""],
        [
            "records answered 202 not in the log",
            str(lost_total),
            "target 0: " + verdict(lost_total == 0),
        ],
        ["records half-written", str(half_total), "target 0: " + verdict(half_total == 0)],
        [
            "on their way at kill = interrupted = printed",
            "every kill" if consistent else "NO",
            verdict(consistent),
        ],
        ["frames decoded / rejected", f"{listener.count()} / {len(listener.rejected)}", ""],
        ["wall time", f"{wall_s:.1f} s", ""],
    ]
    return "\n".join([table(headers, rows), "", table(["", "measured", ""], summary)])


def met(cycles: Sequence[Cycle]) -> bool:
    """Nothing stuck, lost or half-written, and every kill's records on their way recovered
    and reported."""
    return all(
        c.non_terminal == c.lost == c.half_written == 0 and c.interrupted == c.left == c.printed
        for c in cycles
    )


def run(out: TextIO, quick: bool = False, kills: int | None = None, seed: int = 0) -> int:
    """On the SQLite file of a temporary directory, or on the PostgreSQL database
    ``NEMESYS_DATABASE_URL`` names (its records of earlier runs are left as they are)."""
    kills = kills if kills is not None else 3 if quick else 20
    database_url = os.environ.get("NEMESYS_DATABASE_URL", "")
    with tempfile.TemporaryDirectory(prefix="nemesys-recovery-") as tmp:
        workdir = Path(tmp)
        cycles, listener, wall_s = measure(kills, seed, workdir, database_url)
        db_total = counts(database_url or workdir / "missions.sqlite3")[0]
    where = f"PostgreSQL {masked(database_url)}" if database_url else "SQLite"
    out.write(f"Recovery after SIGKILL: {kills} kills, seed {seed}, on {where}\n\n")
    out.write(format_report(cycles, listener, db_total, wall_s) + "\n")
    return 0 if met(cycles) else 1
