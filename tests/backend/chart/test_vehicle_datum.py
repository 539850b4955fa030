"""The vehicle's datum against the console's: the vehicle's own latitude/longitude conversion
agrees with PROJ (the console's), a datum that differs is named (link health, one mission log
event each time it begins), the console without a datum takes the vehicle's, and the setting
that moves the link's topics under the vehicle's namespace."""

from __future__ import annotations

import math
from typing import Any

import pytest
from pydantic import ValidationError

from backend.chart.geo import TRAINING_DATUM, Datum, geodetic_to_ned
from backend.chart.vehicle_datum import DATUM_TOLERANCE_M, DatumWatch, datum_of, offset_m
from backend.settings import Settings
from nemesys_vehicle import geo as vehicle_geo
from tests.agent_link import AgentLink
from tests.backend.conftest import MakeLightClient, console_of, wait_until

SITE = TRAINING_DATUM


def _msg(lat_deg: float, lon_deg: float, source: str = "navsatfix") -> dict[str, Any]:
    return {"t_s": 5.0, "lat_deg": lat_deg, "lon_deg": lon_deg, "source": source}


# --- the vehicle's conversion is the console's ------------------------------------------------


@pytest.mark.parametrize("datum", [SITE, Datum(-45.0, 170.0), Datum(60.1, -3.2), Datum(0.0, 0.0)])
@pytest.mark.parametrize(
    ("d_lat", "d_lon"), [(0.0, 0.0), (1e-4, 0.0), (-0.003, 0.007), (0.05, -0.1)]
)
def test_the_vehicles_conversion_agrees_with_proj(datum: Datum, d_lat: float, d_lon: float) -> None:
    """The node's standard-library pipeline (a vehicle has no PROJ) and the console's PROJ
    pipeline give the same metres, to the millimetre, out to ~10 km."""
    lat, lon = datum.lat_deg + d_lat, datum.lon_deg + d_lon
    north, east = vehicle_geo.geodetic_to_ned(datum.lat_deg, datum.lon_deg, lat, lon)
    want_north, want_east = geodetic_to_ned(datum, lat, lon)
    assert north == pytest.approx(want_north, abs=1e-3)
    assert east == pytest.approx(want_east, abs=1e-3)


# --- the watch -----------------------------------------------------------------------------------


def test_a_console_without_a_datum_takes_the_vehicles() -> None:
    watch = DatumWatch()
    event = watch.on_message(_msg(29.5, -82.3), None)
    assert watch.vehicle == Datum(29.5, -82.3)
    assert event is not None
    kind, detail, data = event
    assert kind == "datum"
    assert "from the vehicle" in detail
    assert (data["lat_deg"], data["source"], data["vehicle_source"]) == (
        29.5,
        "vehicle",
        "navsatfix",
    )
    assert watch.problem(None) is None


def test_a_datum_that_differs_is_named_once_each_time_it_begins() -> None:
    watch = DatumWatch()
    assert watch.on_message(_msg(SITE.lat_deg, SITE.lon_deg), SITE) is None
    assert watch.problem(SITE) is None
    # about 1.1 km north of the console's
    far = _msg(SITE.lat_deg + 0.01, SITE.lon_deg, "parameters")
    event = watch.on_message(far, SITE)
    assert event is not None
    kind, detail, data = event
    assert kind == "datum_mismatch"
    problem = watch.problem(SITE)
    assert problem == detail
    assert "1108 m from the console's" in problem and "from its parameters" in problem
    assert data["offset_m"] == pytest.approx(1108.0, abs=1.0)
    assert data["console"] == {"lat_deg": SITE.lat_deg, "lon_deg": SITE.lon_deg}
    assert watch.on_message(far, SITE) is None  # the same mismatch: not logged again
    assert watch.on_message(_msg(SITE.lat_deg, SITE.lon_deg), SITE) is None  # it ended
    assert watch.problem(SITE) is None
    again = watch.on_message(far, SITE)
    assert again is not None and again[0] == "datum_mismatch"


def test_within_the_tolerance_is_the_same_datum() -> None:
    near = Datum(SITE.lat_deg + 1e-5, SITE.lon_deg)  # about 1.1 m
    assert 0.5 < offset_m(SITE, near) < DATUM_TOLERANCE_M
    watch = DatumWatch()
    assert watch.on_message(_msg(near.lat_deg, near.lon_deg), SITE) is None
    assert watch.problem(SITE) is None


@pytest.mark.parametrize(
    "bad",
    [{}, {"lat_deg": 95.0, "lon_deg": 0.0}, {"lat_deg": None, "lon_deg": 1.0},
     {"lat_deg": "29.5", "lon_deg": 1.0}, {"lat_deg": math.nan, "lon_deg": 1.0}],
)  # fmt: skip
def test_a_message_without_a_usable_datum_changes_nothing(bad: dict[str, Any]) -> None:
    assert datum_of(bad) is None
    watch = DatumWatch()
    assert watch.on_message(bad, SITE) is None
    assert watch.vehicle is None


# --- through the console -----------------------------------------------------------------------


def _link_problems(client: Any) -> list[str]:
    r = client.get("/api/vehicle")
    assert r.status_code == 200, r.text
    problems: list[str] = r.json()["link"]["problems"]
    return problems


def test_the_console_names_a_vehicle_datum_that_differs(
    make_light_client: MakeLightClient,
) -> None:
    link = AgentLink()
    client = make_light_client(link, datum_lat_deg=SITE.lat_deg, datum_lon_deg=SITE.lon_deg)
    console = console_of(client)
    assert not any("datum" in p for p in _link_problems(client))
    far = _msg(SITE.lat_deg, SITE.lon_deg + 0.01)  # about 970 m east
    client.portal.call(link.on_datum, far)  # type: ignore[union-attr]
    problems = _link_problems(client)
    mismatch = [p for p in problems if "the vehicle's datum" in p]
    assert len(mismatch) == 1 and "m from the console's" in mismatch[0]
    assert client.get("/api/vehicle").json()["link"]["level"] != "green"
    log = console.log
    assert log is not None
    events = wait_until(
        lambda: [e for e in log.events(console.dive) if e["kind"] == "datum_mismatch"],
        what="the datum_mismatch event",
    )
    assert len(events) == 1 and events[0]["detail"] == mismatch[0]
    client.portal.call(link.on_datum, far)  # type: ignore[union-attr]
    kinds = [e["kind"] for e in log.events(console.dive)]
    assert kinds.count("datum_mismatch") == 1
    # the operator takes the vehicle's datum: the problem is gone
    assert console.datum is not None
    client.portal.call(link.on_datum, _msg(SITE.lat_deg, SITE.lon_deg))  # type: ignore[union-attr]
    assert not any("the vehicle's datum" in p for p in _link_problems(client))


def test_a_console_without_a_datum_takes_the_vehicles_through_the_link(
    make_light_client: MakeLightClient,
) -> None:
    link = AgentLink()
    client = make_light_client(link)
    console = console_of(client)
    assert console.datum is None
    client.portal.call(link.on_datum, _msg(10.5, 20.25, "parameters"))  # type: ignore[union-attr]
    assert console.datum == Datum(10.5, 20.25)
    assert client.get("/api/chart").json()["datum"] == {"lat_deg": 10.5, "lon_deg": 20.25}
    assert console.log is not None
    kinds = [e["kind"] for e in console.log.events(console.dive)]
    assert kinds == ["datum"]
    assert not any("datum" in p for p in _link_problems(client))


# --- the namespace setting ---------------------------------------------------------------------


def test_the_vehicle_namespace_setting_is_checked_and_normalised() -> None:
    assert Settings(vehicle_namespace="").vehicle_namespace == ""
    assert Settings(vehicle_namespace="auv1/").vehicle_namespace == "/auv1"
    with pytest.raises(ValidationError, match="letter or an underscore"):
        Settings(vehicle_namespace="auv-1")
