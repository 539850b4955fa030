"""A dive in a mission log file, filled through the store API (bench/_dive_log.py): ten
minutes at 1 Hz with five commands (the fourth rejected), two minutes of navigation fault, a
datum and an echo-mismatch event."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import pytest

from backend.mission_log.store import MissionLog
from bench._dive_log import Filled, ManualUtc, fill_dive

#: The dive's length (s), and a command every so many seconds.
DIVE_S = 600
COMMAND_EVERY_S = 120


@dataclass(frozen=True)
class DiveLog:
    """The log file and what was written into it."""

    path: Path
    filled: Filled


@pytest.fixture(scope="module")
def dive_log(tmp_path_factory: pytest.TempPathFactory) -> DiveLog:
    path = tmp_path_factory.mktemp("dive") / "missions.sqlite3"
    clock = ManualUtc()
    log = MissionLog(path, now=clock)
    try:
        filled = fill_dive(log, DIVE_S, clock, COMMAND_EVERY_S)
    finally:
        log.close()
    return DiveLog(path, filled)
