"""`nemesys sim` in a subprocess on a free loopback port, for the third-party client tests
(roslibpy, roslibjs)."""

from __future__ import annotations

import contextlib
import re
import subprocess
import sys
import threading
from collections.abc import Iterator

#: ``nemesys`` as a subprocess: this interpreter running ``cli.main``.
NEMESYS = [sys.executable, "-m", "cli.main"]


@contextlib.contextmanager
def nemesys_sim(*options: str) -> Iterator[int]:
    """Run ``nemesys sim --port 0 ...`` and yield its port; stop it with SIGTERM after."""
    proc = subprocess.Popen(
        [*NEMESYS, "sim", "--port", "0", "--quiet", *options],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    stdout, stderr = proc.stdout, proc.stderr
    assert stdout is not None and stderr is not None
    lines: list[str] = []
    reader = threading.Thread(target=lambda: lines.append(stdout.readline()), daemon=True)
    reader.start()
    reader.join(15)
    match = re.search(r"ws://127\.0\.0\.1:(\d+)", lines[0] if lines else "")
    if match is None:
        proc.kill()
        raise AssertionError(f"nemesys sim did not start: {lines} {stderr.read()}")
    try:
        yield int(match.group(1))
    finally:
        proc.terminate()
        assert proc.wait(10) == 0, "nemesys sim must stop cleanly on SIGTERM"
