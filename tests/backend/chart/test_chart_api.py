"""The geo reference through the API: the session's datum, the chart document, PUT
/api/datum (operator), lat/lon beside x/y in the pose, the track and previews (each as
backend.chart.geo converts it), and the preview's link reach with its warning."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest
from fastapi.testclient import TestClient

from backend.chart.geo import TRAINING_DATUM, Datum, geodetic_to_ned, ned_to_geodetic
from backend.chart.gps import Station
from backend.chart.reach import MARGINAL_FRACTION, lat_lon, link_reach, point_lat_lon
from tests.backend.chart.test_tiles import tile_dir
from tests.backend.conftest import (
    AUTH,
    CIRCLE,
    WRONG_AUTH,
    MakeClient,
    MakeLightClient,
    console_of,
    loc_of,
    wait_until,
)
from tests.backend.test_openapi import Contract

#: 200 s north at 0.18 m/s (the training vehicle's pace): about 36 m from its start.
STRAIGHT: dict[str, Any] = {"speed": 0.18, "depth": 2, "duration": 200, "heading": 0}
SITE = {"lat_deg": TRAINING_DATUM.lat_deg, "lon_deg": TRAINING_DATUM.lon_deg}


def preview(client: TestClient, pattern: str, params: dict[str, Any]) -> dict[str, Any]:
    r = client.post("/api/preview", json={"pattern": pattern, "params": params})
    assert r.status_code == 200, r.text
    doc: dict[str, Any] = r.json()
    return doc


def point(datum: Datum, x_m: float, y_m: float) -> tuple[float, float]:
    lat, lon = ned_to_geodetic(datum, x_m, y_m)
    return float(lat), float(lon)


def expected_lat_lon(datum: Datum, xs: list[float], ys: list[float]) -> tuple[Any, Any]:
    return ned_to_geodetic(datum, np.array(xs), np.array(ys))


# --- session and chart -----------------------------------------------------------------------


@pytest.mark.training
def test_training_has_the_documented_site_and_the_transmitter_at_the_datum(
    client: TestClient,
) -> None:
    assert client.get("/api/session").json()["datum"] == SITE
    chart = client.get("/api/chart").json()
    assert chart == {
        "datum": SITE,
        "station": {**SITE, "x_m": 0.0, "y_m": 0.0, "source": "datum", "age_s": None},
        "me_range_m": 730.0,
        "marginal_fraction": 0.75,
        "tiles": None,
        "gps": None,
    }


def test_a_vehicle_without_a_datum_has_metres_only(make_client: MakeClient) -> None:
    client = make_client(target="loop://", station_lat_deg=29.5, station_lon_deg=-82.3)
    assert client.get("/api/session").json()["datum"] is None
    station = client.get("/api/chart").json()["station"]
    # the station's lat/lon is known, but not where it is from the (unknown) NED origin
    assert station == {
        "lat_deg": 29.5,
        "lon_deg": -82.3,
        "x_m": None,
        "y_m": None,
        "source": "settings",
        "age_s": None,
    }
    doc = preview(client, "circle", CIRCLE)
    assert doc["path"]["lat_deg"] is None and doc["path"]["lon_deg"] is None
    assert doc["link_reach"] is None


def test_a_configured_datum_and_station(make_client: MakeClient) -> None:
    client = make_client(
        datum_lat_deg=-33.8568,
        datum_lon_deg=151.2153,
        station_lat_deg=-33.8578,
        station_lon_deg=151.2163,
    )
    datum = Datum(-33.8568, 151.2153)
    assert client.get("/api/session").json()["datum"] == {
        "lat_deg": -33.8568,
        "lon_deg": 151.2153,
    }
    station = client.get("/api/chart").json()["station"]
    assert station["source"] == "settings"
    x, y = geodetic_to_ned(datum, -33.8578, 151.2163)
    assert (station["x_m"], station["y_m"]) == pytest.approx((x, y), abs=1e-6)
    assert x == pytest.approx(-110.9, abs=0.5) and y == pytest.approx(92.6, abs=0.5)
    reach = preview(client, "circle", CIRCLE)["link_reach"]
    assert (reach["station_x_m"], reach["station_y_m"]) == pytest.approx((x, y), abs=1e-6)


# --- PUT /api/datum ----------------------------------------------------------------------------


def test_setting_the_datum_needs_the_operator(make_light_client: MakeLightClient) -> None:
    client = make_light_client(datum_lat_deg=SITE["lat_deg"], datum_lon_deg=SITE["lon_deg"])
    body = {"lat_deg": 10.0, "lon_deg": 20.0}
    assert client.put("/api/datum", json=body).status_code == 401
    assert client.put("/api/datum", json=body, headers=WRONG_AUTH).status_code == 403
    assert client.get("/api/session").json()["datum"] == SITE


@pytest.mark.parametrize(
    ("body", "field", "words"),
    [
        ({}, "lat_deg", "lat_deg is required"),
        ({"lat_deg": 10}, "lon_deg", "lon_deg is required"),
        ({"lat_deg": 90.5, "lon_deg": 0}, "lat_deg", "less than or equal to 90"),
        ({"lat_deg": 0, "lon_deg": -181}, "lon_deg", "greater than or equal to -180"),
        ({"lat_deg": "north", "lon_deg": 0}, "lat_deg", "valid number"),
        ({"source": "glonass"}, "source", "'gps'"),
        ({"source": "gps", "lat_deg": 1}, "lat_deg", "not both"),
        ({"lat_deg": 1, "lon_deg": 2, "height_m": 3}, "height_m", "Extra inputs"),
    ],
)
def test_a_bad_datum_is_422_naming_the_field(
    make_light_client: MakeLightClient, body: dict[str, Any], field: str, words: str
) -> None:
    client = make_light_client(datum_lat_deg=SITE["lat_deg"], datum_lon_deg=SITE["lon_deg"])
    assert client.get("/api/session").json()["datum"] == SITE
    r = client.put("/api/datum", json=body, headers=AUTH)
    assert r.status_code == 422, r.text
    assert loc_of(r.json()) == ["body", field]
    assert words in r.json()["detail"][0]["msg"]
    assert client.get("/api/session").json()["datum"] == SITE  # unchanged


def test_the_datum_from_gps_without_a_gps_is_409(client: TestClient) -> None:
    r = client.put("/api/datum", json={"source": "gps"}, headers=AUTH)
    assert r.status_code == 409
    assert r.json()["detail"] == (
        "cannot take the datum from the GPS: no surface GPS is configured (the gps setting)"
    )


@pytest.mark.training
def test_a_new_datum_moves_every_lat_lon_and_is_logged(client: TestClient) -> None:
    wait_until(lambda: client.get("/api/vehicle").json()["pose"], what="a pose")
    r = client.put("/api/datum", json={"lat_deg": 59.9, "lon_deg": 10.7}, headers=AUTH)
    assert r.status_code == 200, r.text
    assert r.json()["datum"] == {"lat_deg": 59.9, "lon_deg": 10.7}
    assert r.json()["station"]["lat_deg"] == 59.9
    assert client.get("/api/session").json()["datum"] == {"lat_deg": 59.9, "lon_deg": 10.7}
    new = Datum(59.9, 10.7)
    # the next pose is converted from the new datum
    pose = wait_until(
        lambda: (p := client.get("/api/vehicle").json()["pose"])["lat_deg"] > 59 and p,
        what="a pose from the new datum",
    )
    lat, lon = point(new, pose["x_m"], pose["y_m"])
    assert (pose["lat_deg"], pose["lon_deg"]) == pytest.approx((lat, lon), abs=1e-12)
    doc = preview(client, "circle", CIRCLE)
    lats, _ = expected_lat_lon(new, doc["path"]["x_m"], doc["path"]["y_m"])
    assert doc["path"]["lat_deg"] == pytest.approx(lats.tolist(), abs=1e-12)
    console = console_of(client)
    assert console.log is not None
    event = [e for e in console.log.events(console.dive) if e["kind"] == "datum"][-1]
    assert event["data"] == {
        "lat_deg": 59.9,
        "lon_deg": 10.7,
        "source": "operator",
        "previous": SITE,
    }


# --- lat/lon beside x/y ----------------------------------------------------------------------


@pytest.mark.training
def test_pose_track_and_preview_carry_lat_lon_from_the_datum(client: TestClient) -> None:
    pose = wait_until(lambda: client.get("/api/vehicle").json()["pose"], what="a pose")
    lat, lon = point(TRAINING_DATUM, pose["x_m"], pose["y_m"])
    assert (pose["lat_deg"], pose["lon_deg"]) == pytest.approx((lat, lon), abs=1e-12)
    with client.websocket_connect("/ws") as ws:
        while (msg := ws.receive_json())["type"] != "telemetry" or msg["pose"] is None:
            pass
    live = msg["pose"]
    lat, lon = point(TRAINING_DATUM, live["x_m"], live["y_m"])
    assert (live["lat_deg"], live["lon_deg"]) == pytest.approx((lat, lon), abs=1e-12)

    doc = preview(client, "circle", {**CIRCLE, "radius": 40})
    path = doc["path"]
    lats, lons = expected_lat_lon(TRAINING_DATUM, path["x_m"], path["y_m"])
    assert len(path["lat_deg"]) == len(path["x_m"]) > 10
    assert path["lat_deg"] == pytest.approx(lats.tolist(), abs=1e-12)
    assert path["lon_deg"] == pytest.approx(lons.tolist(), abs=1e-12)
    # and back: each waypoint's lat/lon is its x/y from the datum
    for i in range(0, len(path["x_m"]), 7):
        x, y = geodetic_to_ned(TRAINING_DATUM, path["lat_deg"][i], path["lon_deg"][i])
        assert (x, y) == pytest.approx((path["x_m"][i], path["y_m"][i]), abs=0.001)

    console = console_of(client)
    track = wait_until(
        lambda: (t := client.get(f"/api/dives/{console.dive}").json()["track"]) and t,
        what="track points in the log",
    )
    for p in track:
        lat, lon = point(TRAINING_DATUM, p["x_m"], p["y_m"])
        assert (p["lat_deg"], p["lon_deg"]) == pytest.approx((lat, lon), abs=1e-12)


# --- link reach ------------------------------------------------------------------------------


def check_reach(doc: dict[str, Any], range_m: float) -> dict[str, Any]:
    """The document's reach against the distances computed here, waypoint by waypoint."""
    reach: dict[str, Any] = doc["link_reach"]
    path = doc["path"]
    d = np.sqrt(
        (np.array(path["x_m"]) - reach["station_x_m"]) ** 2
        + (np.array(path["y_m"]) - reach["station_y_m"]) ** 2
        + np.array(path["z_m"]) ** 2
    )
    assert reach["range_m"] == range_m
    assert reach["marginal_m"] == pytest.approx(0.75 * range_m)
    assert reach["max_distance_m"] == pytest.approx(d.max())
    states = [
        "out_of_range" if v > range_m else "marginal" if v > 0.75 * range_m else "in_range"
        for v in d
    ]
    covered: list[str] = []
    for i, seg in enumerate(reach["segments"]):
        assert seg["start"] == len(covered) and seg["end"] >= seg["start"]
        covered += [seg["state"]] * (seg["end"] - seg["start"] + 1)
        if i:
            assert seg["state"] != reach["segments"][i - 1]["state"]  # runs are maximal
    assert covered == states
    order = ["in_range", "marginal", "out_of_range"]
    assert reach["state"] == max(states, key=order.index)
    return reach


def test_a_path_in_range(client: TestClient) -> None:
    reach = check_reach(preview(client, "circle", CIRCLE), 730.0)
    assert reach["state"] == "in_range" and reach["warning"] is None
    assert len(reach["segments"]) == 1


def test_a_path_that_leaves_range_warns_and_is_an_overridable_violation(
    make_client: MakeClient,
) -> None:
    client = make_client(me_range_m=20)
    doc = preview(client, "straight", STRAIGHT)
    reach = check_reach(doc, 20.0)
    assert reach["state"] == "out_of_range"
    assert [s["state"] for s in reach["segments"]][-1] == "out_of_range"
    far = reach["max_distance_m"]
    assert 25 < far < 40
    sentence = (
        f"the path goes {far:.0f} m from the transmitter, beyond the ME link's 20 m range: the "
        "next retask could not reach the vehicle there"
    )
    assert reach["warning"] == sentence
    # the send checks name it from the same distances (backend/commands/checks.py): soft,
    # overridable
    (v,) = [v for v in doc["violations"] if v["check"] == "reach"]
    assert (v["param"], v["kind"], v["overridable"]) == ("duration", "soft", True)
    assert (v["value"], v["limit"], v["message"]) == (far, 20.0, sentence)
    assert client.get("/api/chart").json()["me_range_m"] == 20.0


def test_link_reach_classes_and_segments() -> None:
    station = Station(0.0, 0.0, 100.0, 0.0, "settings")
    xs = [100, 150, 180, 190, 220, 175, 100, 100]  # north of the datum
    zs = [0, 0, 0, 0, 0, 0, 0, 99]  # the last one deep under the transmitter
    reach = link_reach(xs, [0.0] * len(xs), zs, station, 100.0)
    assert reach is not None
    assert MARGINAL_FRACTION == 0.75
    assert reach["segments"] == [
        {"state": "in_range", "start": 0, "end": 1},
        {"state": "marginal", "start": 2, "end": 3},
        {"state": "out_of_range", "start": 4, "end": 4},
        {"state": "in_range", "start": 5, "end": 6},
        {"state": "marginal", "start": 7, "end": 7},  # slant range: 99 m down
    ]
    assert reach["state"] == "out_of_range" and reach["max_distance_m"] == 120.0
    assert "120 m from the transmitter, beyond the ME link's 100 m range" in reach["warning"]
    # exactly at the range is still in range (marginal), as the simulator's channel has it
    edge = link_reach([175.0, 200.0], [0.0, 0.0], [0.0, 0.0], station, 100.0)
    assert edge is not None
    assert edge["state"] == "marginal" and edge["warning"] is None
    assert edge["segments"] == [
        {"state": "in_range", "start": 0, "end": 0},
        {"state": "marginal", "start": 1, "end": 1},
    ]
    assert link_reach([], [], [], station, 100.0) == {
        **link_reach([], [], [], station, 100.0),  # type: ignore[dict-item]
        "segments": [],
        "state": "in_range",
        "max_distance_m": 0.0,
    }
    unplaced = Station(1.0, 2.0, None, None, "settings")
    assert link_reach([1.0], [1.0], [1.0], unplaced, 100.0) is None


def test_positions_no_frame_can_hold_get_no_lat_lon() -> None:
    """A vehicle reporting nonsense (1e30 m) must not put NaN or infinity in a document
    (the JSON would be invalid): no lat/lon, no reach, rather than a wrong one."""
    assert point_lat_lon(TRAINING_DATUM, 1e30, 0.0) == (None, None)
    assert point_lat_lon(TRAINING_DATUM, 10.0, None) == (None, None)
    assert point_lat_lon(None, 10.0, 10.0) == (None, None)
    assert lat_lon(TRAINING_DATUM, [0.0, 1e308], [0.0, -1e308]) == (None, None)
    lats, lons = lat_lon(TRAINING_DATUM, [], [])
    assert lats == [] and lons == []
    station = Station(0.0, 0.0, 0.0, 0.0, "datum")
    assert link_reach([1e200], [1e200], [0.0], station, 730.0) is None


def test_the_answers_match_the_openapi(make_client: MakeClient, tmp_path: Path) -> None:
    """Every answer of the chart's operations (and a preview out of range), checked against
    the OpenAPI document by test_openapi's contract: statuses documented, bodies valid."""
    client = make_client(tiles=tile_dir(tmp_path), me_range_m=20)
    c = Contract(client)
    c.call("GET", "/api/chart")
    c.call("GET", "/api/session")
    assert c.call("GET", "/api/tiles/3/2/5").status_code == 200
    assert c.call("GET", "/api/tiles/3/2/6").status_code == 404
    assert c.call("GET", "/api/tiles/3/9/6").status_code == 422
    body = {"lat_deg": 29.5, "lon_deg": -82.3}
    assert c.call("PUT", "/api/datum", json=body).status_code == 401
    assert c.call("PUT", "/api/datum", json=body, headers=WRONG_AUTH).status_code == 403
    assert c.call("PUT", "/api/datum", json={"lat_deg": 1}, headers=AUTH).status_code == 422
    assert c.call("PUT", "/api/datum", json={"source": "gps"}, headers=AUTH).status_code == 409
    assert c.call("PUT", "/api/datum", json=body, headers=AUTH).status_code == 200
    doc = c.call("POST", "/api/preview", json={"pattern": "straight", "params": STRAIGHT})
    assert doc.json()["link_reach"]["state"] == "out_of_range"
    wait_until(lambda: c.call("GET", "/api/vehicle").json()["pose"], what="a pose")
    c.call("GET", f"/api/dives/{console_of(client).dive}")
    ops = {(m, p) for m, p, _ in c.operations()}
    assert {("GET", "/api/chart"), ("PUT", "/api/datum"), ("GET", "/api/tiles/{z}/{x}/{y}")} <= ops
    secured = {(m, p) for m, p, op in c.operations() if "security" in op}
    assert ("PUT", "/api/datum") in secured and ("GET", "/api/chart") not in secured


@pytest.mark.training
def test_the_active_path_is_given_for_every_pages_chart(client: TestClient) -> None:
    """The path the vehicle flies (the station's mirror) comes with /api/vehicle in NED and
    lat/lon, so a page that did not preview it can still draw it; a reset clears it."""
    assert client.get("/api/vehicle").json()["active_path"] is None
    r = client.post("/api/commands", json={"pattern": "straight", "params": STRAIGHT}, headers=AUTH)
    assert r.status_code == 202, r.text
    active = wait_until(
        lambda: client.get("/api/vehicle").json()["active_path"], what="the active path"
    )
    assert active["pattern"] == "straight"
    assert len(active["x_m"]) == len(active["lat_deg"]) >= 2
    lat, lon = expected_lat_lon(TRAINING_DATUM, active["x_m"], active["y_m"])
    assert np.allclose(active["lat_deg"], lat, atol=1e-9)
    assert np.allclose(active["lon_deg"], lon, atol=1e-9)
    assert max(active["x_m"]) > 30  # 200 s north at 0.18 m/s
    assert client.post("/api/training/reset", headers=AUTH).status_code == 200
    assert client.get("/api/vehicle").json()["active_path"] is None
