"""``GET /api/series``: the current dive's telemetry from the mission log (backend/api/dives.py)."""

from __future__ import annotations

import pytest
from fastapi.testclient import TestClient

from station.link import Capability
from tests.agent_link import HOLDING, AgentLink
from tests.backend.conftest import MakeLightClient, console_of


def test_before_any_dive_the_series_is_empty(make_light_client: MakeLightClient) -> None:
    client = make_light_client(AgentLink(Capability.NONE))
    assert client.get("/api/series").json() == {
        "dive": None,
        "started_at": None,
        "start_t_s": None,
        "interval_s": None,
        "t_s": [],
        "depth_m": [],
        "commanded_depth_m": [],
        "battery_pct": [],
        "speed_mps": [],
    }


def test_the_series_is_the_dives_track_from_its_start(client: TestClient) -> None:
    console = console_of(client)
    assert console.log is not None and console.dive == 1  # the first pose started it
    circle = {"pattern": "circle", "params": {"depth": 3.0}}
    for k in range(1, 10):
        status = {
            "depth_m": 2.0 + k / 10,
            "battery_pct": 100 - k,
            "speed_mps": 0.3,
            "active": circle,
        }
        console.log.add_track(1, HOLDING.t_s + k, 0.0, 0.0, 2.0, 0.0, status)
    s = client.get("/api/series").json()
    assert s["dive"] == 1 and s["started_at"] == client.get("/api/dives").json()[0]["started_at"]
    assert s["start_t_s"] == HOLDING.t_s  # the first pose heard
    assert s["t_s"] == [float(k) for k in range(10)]
    assert s["depth_m"][0] == 2.0 and s["depth_m"][-1] == pytest.approx(2.9)
    assert s["commanded_depth_m"] == [None] + [3.0] * 9
    assert s["battery_pct"][1:] == [100 - k for k in range(1, 10)]
    # the same dive named, thinned evenly to three samples (first and last kept)
    thin = client.get("/api/series", params={"dive": 1, "limit": 3}).json()
    assert thin["t_s"] == [0.0, 4.0, 9.0] and thin["interval_s"] == 4.5


@pytest.mark.parametrize(
    ("params", "where", "allowed"),
    [
        ({"dive": 0}, "dive", "greater than or equal to 1"),
        ({"dive": "current"}, "dive", "valid integer"),
        ({"limit": 1}, "limit", "greater than or equal to 2"),
        ({"limit": 100_000}, "limit", "less than or equal to 86400"),
        ({"limit": "all"}, "limit", "valid integer"),
    ],
)
def test_bad_input_is_422_naming_what_is_allowed(
    client: TestClient, params: dict[str, object], where: str, allowed: str
) -> None:
    r = client.get("/api/series", params=params)
    assert r.status_code == 422, r.text
    (item,) = r.json()["detail"]
    assert item["loc"] == ["query", where]
    assert allowed in item["msg"], item


def test_a_dive_that_does_not_exist_is_404(client: TestClient) -> None:
    r = client.get("/api/series", params={"dive": 99})
    assert r.status_code == 404 and r.json() == {"detail": "no dive 99"}
