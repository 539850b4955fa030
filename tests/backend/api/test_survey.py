"""``POST /api/survey/preview`` on the light console: each vehicle's command is exactly what
the encode (and so the send) API makes of its pattern and params, the figures are the
survey's, and bad input is a 422 naming the field."""

from __future__ import annotations

from typing import Any

from fastapi.testclient import TestClient

from codec import decode_frame
from tests.backend.conftest import console_of

AREA: dict[str, Any] = {
    "origin_x_m": 20.0,
    "origin_y_m": -40.0,
    "heading_deg": 30.0,
    "width_m": 120.0,
    "length_m": 200.0,
    "lane_spacing_m": 10.0,
    "depth_m": 5.0,
    "speed_mps": 0.18,
}
VEHICLES: list[dict[str, Any]] = [
    {"vehicle": "auv1", "x_m": 0.0, "y_m": 0.0, "heading_deg": 0.0},
    {"vehicle": "auv2", "x_m": -30.0, "y_m": 60.0, "heading_deg": 90.0},
    {"vehicle": "auv3", "x_m": 250.0, "y_m": 150.0, "heading_deg": 200.0, "z_m": 2.0},
]
SURVEY: dict[str, Any] = {"area": AREA, "vehicles": VEHICLES}


def test_a_survey_preview(client: TestClient) -> None:
    r = client.post("/api/survey/preview", json=SURVEY)
    assert r.status_code == 200, r.text
    doc = r.json()
    assert doc["lanes"] == 12 and len(doc["lanes_across_m"]) == 12
    assert [v["vehicle"] for v in doc["vehicles"]] == ["auv1", "auv2", "auv3"]
    assert doc["coverage"]["covered_fraction"] >= 0.95
    assert doc["coverage"]["overlap_fraction"] <= 0.02
    assert doc["exact"] is True
    durations = {v["vehicle"]: v["duration_s"] for v in doc["vehicles"]}
    assert doc["time_to_finish_s"] == max(durations.values())
    assert doc["slowest"] == max(durations, key=lambda name: durations[name])
    lanes = sorted(
        i
        for v in doc["vehicles"]
        for i in range(v["block"]["first_lane"], v["block"]["last_lane"] + 1)
    )
    assert lanes == list(range(12))
    for v in doc["vehicles"]:
        cmd = v["command"]
        assert cmd["pattern"] == "lawnmower"
        # the frame decodes to the params returned
        decoded = decode_frame(cmd["hex"]).command
        assert decoded.params == cmd["params"]
        assert decode_frame(cmd["bits"]).command.params == cmd["params"]
        # and its params are what the send takes: the encode API makes the same frame
        again = client.post("/api/encode", json={"pattern": "lawnmower", "params": cmd["params"]})
        assert again.json()["hex"] == cmd["hex"]
        # the path: the transit from the vehicle, then the lanes from the entry
        path = v["path"]
        assert (path["x_m"][0], path["y_m"][0]) == (v["from"]["x_m"], v["from"]["y_m"])
        start = path["body_start"]
        assert path["x_m"][start] == v["entry"]["x_m"] and path["y_m"][start] == v["entry"]["y_m"]
        assert path["t_s"] == sorted(path["t_s"])
        assert v["duration_s"] == v["transit_duration_s"] + v["survey_duration_s"]
        assert [c["check"] for c in v["checks"]][:3] == [
            "depth_rating",
            "depth_limit",
            "speed_limit",
        ]
    assert any(
        "send each command once its vehicle is at its entry" in a for a in doc["assumptions"]
    )


def test_nothing_is_sent(client: TestClient) -> None:
    log = console_of(client).log
    assert log is not None
    before = log.commands(limit=10)
    assert client.post("/api/survey/preview", json=SURVEY).status_code == 200
    assert log.commands(limit=10) == before


def test_a_quantised_block_says_so(client: TestClient) -> None:
    area = {**AREA, "length_m": 123.0, "lane_spacing_m": 7.3, "width_m": 116.8}
    doc = client.post("/api/survey/preview", json={**SURVEY, "area": area}).json()
    assert doc["exact"] is False
    for v in doc["vehicles"]:
        assert v["exact"] is False
        assert v["footprint"]["lane_spacing_m"] == 7.25 and v["footprint"]["sweep_length_m"] == 125
        assert v["footprint"]["max_lane_shift_m"] > 0
        snaps = {s["field"]: s for s in v["command"]["snaps"]}
        assert snaps["lane_spacing"]["changed"] and snaps["lane_spacing"]["sent"] == 7.25
        assert any(n.startswith("lane_spacing: requested 7.3 m, sent 7.25 m") for n in v["notes"])


def test_bad_input_is_a_422_naming_the_field(client: TestClient) -> None:
    cases: list[tuple[dict[str, Any], list[Any], str]] = [
        ({**SURVEY, "vehicles": []}, ["body", "vehicles"], "no vehicles"),
        (
            {**SURVEY, "area": {**AREA, "length_m": 900}},
            ["body", "area", "length_m"],
            "allows 0 to 750 m",
        ),
        (
            {**SURVEY, "area": {**AREA, "width_m": 50}},
            ["body", "vehicles"],
            "3 vehicles need at least 6",
        ),
        (
            {**SURVEY, "vehicles": [*VEHICLES[:2], {**VEHICLES[2], "x_m": 5000.0}]},
            ["body", "vehicles", 2, "x_m"],
            "beyond the link's 730 m range",
        ),
    ]
    for body, loc, words in cases:
        r = client.post("/api/survey/preview", json=body)
        assert r.status_code == 422, r.text
        (item,) = r.json()["detail"]
        assert item["loc"] == loc and item["type"] == "survey_error"
        assert words in item["msg"]
    # the request's own shape: pydantic's 422
    r = client.post("/api/survey/preview", json={**SURVEY, "area": {**AREA, "width_m": True}})
    assert r.status_code == 422
    assert r.json()["detail"][0]["loc"] == ["body", "area", "width_m"]
    r = client.post(
        "/api/survey/preview",
        json={**SURVEY, "vehicles": [{**VEHICLES[0], "heading_deg": 400}]},
    )
    assert r.status_code == 422
    assert r.json()["detail"][0]["loc"] == ["body", "vehicles", 0, "heading_deg"]
