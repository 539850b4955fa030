"""When a dive starts (backend/dives.py): when the vehicle is first heard, at the first command
or event before that, or at a training reset; never at a console start alone."""

from __future__ import annotations

import logging
from pathlib import Path

import pytest
from fastapi.testclient import TestClient

from backend.app import create_app
from backend.dives import Dives
from backend.mission_log.store import LogWriteError, MissionLog
from planner import VehicleState
from station.link import Capability
from tests.agent_link import HOLDING, TARGET, AgentLink
from tests.backend.conftest import (
    AUTH,
    MakeClient,
    MakeLightClient,
    clear_nemesys_env,
    console_of,
    send,
    settings_for,
    wait_until,
)


def dive_ids(client: TestClient) -> list[int]:
    return [d["id"] for d in client.get("/api/dives").json()]


# --- the console ----------------------------------------------------------------------------


def test_a_console_start_then_stop_adds_no_dive(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    clear_nemesys_env(monkeypatch)
    db = tmp_path / "log.sqlite3"
    for _ in range(2):  # twice: the second start finds the log as the first left it
        app = create_app(
            settings_for(db, target=TARGET), viewer=False, link=AgentLink(Capability.NONE)
        )
        with TestClient(app) as client:
            assert client.get("/api/session").json()["dive"] is None
            assert dive_ids(client) == []
            series = client.get("/api/series").json()
            assert series["dive"] is None and series["t_s"] == []
    log = MissionLog(db)
    try:
        assert log.dives() == []
    finally:
        log.close()


def test_the_first_pose_starts_the_dive_and_its_track(make_light_client: MakeLightClient) -> None:
    link = AgentLink()  # two-way: it reports the vehicle's pose and status when it starts
    client = make_light_client(link)
    assert client.get("/api/session").json()["dive"] == 1
    assert dive_ids(client) == [1]
    link.state = VehicleState(0.0, 0.0, 2.0, heading_deg=0.0, t_s=HOLDING.t_s + 1.0)
    client.portal.call(link.report)  # type: ignore[union-attr]
    track = client.get("/api/dives/1").json()["track"]
    assert [p["t_s"] for p in track] == [HOLDING.t_s, HOLDING.t_s + 1.0]
    assert dive_ids(client) == [1]  # heard again: the same dive


def test_a_command_before_the_vehicle_is_heard_starts_the_dive(
    make_light_client: MakeLightClient, tmp_path: Path
) -> None:
    db = tmp_path / "one-way.sqlite3"
    client = make_light_client(AgentLink(Capability.NONE), db_path=db)
    assert client.get("/api/session").json()["dive"] is None
    record = send(client)
    assert record["dive"] == 1
    assert client.get("/api/session").json()["dive"] == 1
    assert send(client)["dive"] == 1  # the next command: the same dive
    assert dive_ids(client) == [1]


def test_a_datum_set_before_the_vehicle_is_heard_is_logged_in_a_new_dive(
    make_light_client: MakeLightClient,
) -> None:
    client = make_light_client(AgentLink(Capability.NONE))
    r = client.put("/api/datum", json={"lat_deg": 59.9, "lon_deg": 10.7}, headers=AUTH)
    assert r.status_code == 200, r.text
    assert dive_ids(client) == [1]
    log = console_of(client).log
    assert log is not None and [e["kind"] for e in log.events(1)] == ["datum"]


@pytest.mark.training
def test_a_training_reset_starts_a_new_dive_each_time(make_client: MakeClient) -> None:
    client = make_client()
    wait_until(lambda: dive_ids(client) == [1], what="the dive the first pose starts")
    for expected in (2, 3):  # a reset always starts one, even right after another
        r = client.post("/api/training/reset", headers=AUTH)
        assert r.status_code == 200 and r.json() == {"dive": expected}, r.text
    assert dive_ids(client) == [3, 2, 1]
    assert send(client)["dive"] == 3
    series = wait_until(
        lambda: (s := client.get("/api/series").json())["t_s"] and s, what="the new dive's track"
    )
    assert series["dive"] == 3 and series["t_s"][0] == 0.0
    # the simulator's clock restarted: the new dive starts near its zero
    assert series["start_t_s"] is not None and series["start_t_s"] < 5.0


# --- Dives on its own -----------------------------------------------------------------------


@pytest.fixture
def log() -> MissionLog:
    return MissionLog(":memory:")


def test_ensure_starts_one_dive_and_start_new_another(log: MissionLog) -> None:
    dives = Dives(log, "sim")
    assert dives.current is None and log.dives() == []
    assert dives.ensure() == dives.ensure() == 1
    assert dives.start_new() == 2 and dives.ensure() == 2
    assert [d["id"] for d in log.dives()] == [2, 1]


def test_the_track_is_kept_at_1_hz_of_the_vehicle_clock_with_the_status(log: MissionLog) -> None:
    dives = Dives(log, "sim")
    circle = {"pattern": "circle", "params": {"depth": 3.0}}
    status = {"depth_m": 2.5, "speed_mps": 0.2, "battery_pct": 99.0, "mode": "running"}
    for t in (10.0, 10.4, 10.9, 11.0, 11.5, 12.2):
        dives.track((t, 1.0, 2.0, 2.4, 90.0), {**status, "active": circle})
    dives.track((0.5, 0.0, 0.0, 0.0, 0.0), {"depth_m": None, "mode": 3, "active": "circle"})
    rows = log.track_rows(1)
    assert [r["t_s"] for r in rows] == [0.5, 10.0, 11.0, 12.2]  # the clock went back: kept
    assert rows[1]["depth_m"] == 2.5 and rows[1]["battery_pct"] == 99.0
    assert rows[1]["mode"] == "running" and rows[1]["active"] == circle
    assert rows[1]["at"]  # the station's clock, to place link events on the vehicle's
    first = rows[0]
    assert (first["depth_m"], first["mode"], first["active"]) == (None, None, None)


def test_heard_with_a_log_that_cannot_be_written_logs_and_goes_on(
    log: MissionLog, monkeypatch: pytest.MonkeyPatch, caplog: pytest.LogCaptureFixture
) -> None:
    dives = Dives(log, "sim")

    def full(target: str) -> int:
        raise LogWriteError("database or disk is full")

    monkeypatch.setattr(log, "new_dive", full)
    with caplog.at_level(logging.ERROR, logger="backend.console"):
        assert dives.heard() is None
        dives.track((1.0, 0.0, 0.0, 1.0, 0.0), {})  # nothing raised into the telemetry path
    assert "could not start a dive" in caplog.text
    with pytest.raises(LogWriteError):
        dives.event("datum", "datum set")  # a caller that can answer 503 gets the error
