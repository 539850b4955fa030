"""``nemesys bench console`` starts a real console, prints its rows with their targets and
stops the server afterwards (figures are not asserted: timings belong to the benchmark, not
the tests)."""

from __future__ import annotations

import io
import os
import re
import socket
from pathlib import Path
from urllib.parse import urlsplit

import pytest

from bench import console as bench_console

#: The console benchmark against a `nemesys console` subprocess: make test, not make test-fast.
pytestmark = pytest.mark.slow

NUMBER = r"-?\d+(?:\.\d+)?"
#: Every table with a few samples each (the quick run's loads take 36 s; the figures are
#: the benchmark's business, the tables and the server's end the test's).
SIZES = bench_console.Sizes(api_s=0.6, sends=4, telemetry_s=3.0, predictions=1)


def _gone(pid: int, base_url: str) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        pass
    else:
        return False
    url = urlsplit(base_url)
    with socket.socket() as sock:
        sock.settimeout(1.0)
        return sock.connect_ex((url.hostname or "127.0.0.1", url.port or 80)) != 0


def _row(lines: list[str], prefix: str) -> str:
    return next(ln for ln in lines if ln.startswith(prefix))


def test_a_run_prints_every_table_and_stops_the_server() -> None:
    out = io.StringIO()
    assert bench_console.run(out, sizes=SIZES) == 0
    text = out.getvalue()
    lines = text.splitlines()
    header = re.search(r"pid (\d+), (http://\S+);", text)
    assert header is not None
    assert _gone(int(header.group(1)), header.group(2))

    # 1. preview / encode: three loads, each with preview, encode and both rows
    for load in ("1 client, back to back", "20 clients, back to back", "20 clients, 1 pair"):
        at = next(i for i, ln in enumerate(lines) if ln.startswith(load))
        for offset, kind in enumerate(("preview", "encode", "both")):
            row = lines[at + offset]
            assert re.search(rf"\b{kind}\s+\d+\s+\d+\s+{NUMBER}\s+{NUMBER}\s", row), row
            if load.startswith("20 clients, 1 pair"):  # graded at the page's pace
                assert "<= 5 / <= 25" in row and ("met" in row or "MISSED" in row)
            else:  # unloaded and saturation rows are references
                assert "(reference)" in row
        both = lines[at + 2]
        assert re.search(r"\bboth\b.*\s0\s+[\d-]+ / \d+ / [\d-]+ %", both), both  # errors, CPU

    # 2. send -> acknowledgement, without and with the channel delay
    for channel in (
        "delay 0 s (default), before the clients",
        "delay 0 s (default), after the clients",
        "delay 0.5 s",
    ):
        row = _row(lines, channel)
        match = re.search(rf"(\d+)/(\d+)(?:\s+{NUMBER}){{5}}\s+<= 50", row)
        assert match is not None, row
        assert int(match.group(2)) == SIZES.sends and int(match.group(1)) > 0
        assert "met" in row or "MISSED" in row

    # 3. 50 telemetry clients
    rate = _row(lines, "telemetry per client, min")
    assert re.search(rf"{NUMBER} Hz\s+>= 9 Hz", rate) and ("met" in rate or "MISSED" in rate)
    assert re.search(rf"{NUMBER} Hz", _row(lines, "telemetry per client, median"))
    without = _row(lines, "send->ack excess median, without")
    assert re.search(rf"{NUMBER} ms \(before \+ after, \d+ sends\)", without), without
    errors = _row(lines, "errors and closes, all clients")
    assert re.search(r"\s\d+\s+0\s+(met|MISSED)", errors), errors
    with_clients = _row(lines, "send->ack excess median, with")
    assert re.search(rf"{NUMBER} ms \(\d+/{SIZES.sends} acked\)", with_clients), with_clients
    effect = _row(lines, "with - without (medians)")
    assert re.search(rf"[+-]{NUMBER} ms \(ratio {NUMBER}\)\s+<= \+10 ms", effect), effect
    assert "met" in effect or "MISSED" in effect


def test_the_server_is_stopped_when_a_measurement_fails(tmp_path: Path) -> None:
    with pytest.raises(RuntimeError, match="boom"), bench_console.console_server(tmp_path) as s:
        server = s
        raise RuntimeError("boom")
    assert server.proc.returncode is not None
    assert _gone(server.pid, server.base_url)
