"""``nemesys bench recovery``: records a SIGKILLed console left on their way are recovered.

A loopback TCP listener stands for an ME modem's TCP gateway: it decodes the frames it gets
(``codec.FrameReceiver``) and counts them. Then ``--kills`` cycles, all on one SQLite log:
``nemesys console`` starts with ``--target tcp://127.0.0.1:<listener>`` (one-way link, copies
0.05 s apart), two threads POST a random burst of commands (5-20 copies each) and Surface
presses with the operator token, and once the first is accepted the console is SIGKILLed after
a seeded random delay. The log file is then read directly (sqlite3, read-only): records left
``queued``/``transmitted`` by the kill. The next start runs the recovery before it prints its
URL; once it answers, the file is read again: records still ``queued``/``transmitted`` (target
0) and records made ``interrupted`` (should equal those left on their way, and the count the
console printed). Everything binds to and talks to 127.0.0.1 only.
"""

from __future__ import annotations

import random
import re
import sqlite3
import tempfile
import threading
import time
from dataclasses import astuple, dataclass
from pathlib import Path
from typing import TextIO

import httpx

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


@dataclass
class Cycle:
    delay_ms: float
    records: int  # written in this cycle, before the kill
    left: int  # queued/transmitted in the file right after the kill
    interrupted: int  # made interrupted by the next start
    printed: int  # what that start printed
    non_terminal: int  # queued/transmitted once it answered (target 0)
    frames: int  # frames the listener decoded in this cycle


def counts(db: Path) -> tuple[int, int, int]:
    """(records, records queued or transmitted, records interrupted), read-only."""
    with sqlite3.connect(f"file:{db}?mode=ro", uri=True) as raw:
        total, on_way, interrupted = raw.execute(
            "SELECT COUNT(*), "
            "COALESCE(SUM(state IN ('queued', 'transmitted')), 0), "
            "COALESCE(SUM(state = 'interrupted'), 0) FROM commands"
        ).fetchone()
    return int(total), int(on_way), int(interrupted)


def start(workdir: Path, db: Path, port: int, n: int) -> ConsoleProcess:
    console = start_console(
        workdir / f"console-{n}.log",
        TOKEN,
        *("--db", str(db), "--target", f"tcp://{LOOPBACK}:{port}"),
        env=ENV,
    )
    if console.host != LOOPBACK:
        console.stop()
        raise RuntimeError(f"the console is not on loopback: {console.base_url}")
    return console


def printed_count(console: ConsoleProcess) -> int:
    match = PRINTED.search(console.log_path.read_text(errors="replace"))
    return int(match.group(1)) if match else 0


def sender(console: ConsoleProcess, seed: int, started: threading.Event, errors: list[str]) -> None:
    """POST commands and Surface presses until the console dies or the burst is done."""
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
            time.sleep(rng.uniform(0.0, 0.05))  # an operator's pace, not a condition


def kill_during_sends(console: ConsoleProcess, rng: random.Random) -> float:
    """Fire the burst, SIGKILL a random time after the first send is accepted; returns the
    delay (s)."""
    started = threading.Event()
    errors: list[str] = []
    threads = [
        threading.Thread(target=sender, args=(console, rng.randrange(2**32), started, errors))
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
    return delay


def measure(kills: int, seed: int, workdir: Path) -> tuple[list[Cycle], FrameGateway, float]:
    rng = random.Random(seed)
    db = workdir / "missions.sqlite3"
    listener = FrameGateway()
    t0 = time.monotonic()
    cycles: list[Cycle] = []
    console: ConsoleProcess | None = None
    try:
        console = start(workdir, db, listener.port, 0)
        for n in range(1, kills + 1):
            frames_before, total_before = listener.count(), counts(db)[0]
            delay = kill_during_sends(console, rng)
            total, left, interrupted_before = counts(db)
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
                )
            )
    finally:
        if console is not None:
            console.stop()
        listener.close()
    return cycles, listener, time.monotonic() - t0


def format_report(cycles: list[Cycle], listener: FrameGateway, db_total: int, wall_s: float) -> str:
    headers = ["kill", "delay ms", "records", "on their way at kill", "interrupted", "printed"]
    headers += ["left non-terminal", "frames received"]
    rows = [
        [str(i), f"{c.delay_ms:.0f}", *(str(v) for v in astuple(c)[1:])]
        for i, c in enumerate(cycles, 1)
    ]
    non_terminal = sum(c.non_terminal for c in cycles)
    consistent = all(c.interrupted == c.left == c.printed for c in cycles)
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
            "on their way at kill = interrupted = printed",
            "every kill" if consistent else "NO",
            verdict(consistent),
        ],
        ["frames decoded / rejected", f"{listener.count()} / {len(listener.rejected)}", ""],
        ["wall time", f"{wall_s:.1f} s", ""],
    ]
    return "\n".join([table(headers, rows), "", table(["", "measured", ""], summary)])


def run(out: TextIO, quick: bool = False, kills: int | None = None, seed: int = 0) -> int:
    kills = kills if kills is not None else 3 if quick else 20
    with tempfile.TemporaryDirectory(prefix="nemesys-recovery-") as tmp:
        workdir = Path(tmp)
        cycles, listener, wall_s = measure(kills, seed, workdir)
        db_total = counts(workdir / "missions.sqlite3")[0]
    out.write(f"Recovery after SIGKILL: {kills} kills, seed {seed}\n\n")
    out.write(format_report(cycles, listener, db_total, wall_s) + "\n")
    met = sum(c.non_terminal for c in cycles) == 0 and all(
        c.interrupted == c.left == c.printed for c in cycles
    )
    return 0 if met else 1
