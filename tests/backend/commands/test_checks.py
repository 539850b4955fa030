"""The checks of a plan before a send (backend/commands/checks.py): each check ok, violated or
skipped with its reason, the kinds (hard: the depth rating; soft: the rest), endurance against the
battery now, the ME link's reach, and the preview document carrying the same report."""

from __future__ import annotations

import math
from typing import Any

import pytest
from fastapi.testclient import TestClient

from backend.authoring.durations import flown
from backend.authoring.preview import plan_doc
from backend.authoring.profile import (
    UNKNOWN,
    VehicleProfile,
    cruise_thrust_power_w,
    endurance_left_s,
    twin_profile,
)
from backend.chart.gps import Station
from backend.commands import checks
from backend.commands.checks import CheckReport, check_plan
from codec import decode_frame, encode_frame
from planner import (
    CircleFence,
    Limits,
    Plan,
    VehicleState,
    Violation,
    plan,
    turn_radius_m,
)
from sim.environment import SOC_FAST_PCT, SOC_FAST_TAU_H, SOC_LINEAR_PCT_PER_H, BatteryConfig
from sim.model import VehicleParams
from tests.backend.conftest import AUTH, MakeClient

TWIN = twin_profile(100.0)
#: The transmitter at the datum, and 35 m west of it (the issue's 775 m for a 740 m circle).
AT_ORIGIN = Station(None, None, 0.0, 0.0, "datum")
WEST = Station(None, None, 0.0, -35.0, "settings")
RANGE_M = 730.0
#: The issue's circle: 740 m around where the vehicle is, at a speed the vehicle can fly.
WIDE_CIRCLE: dict[str, Any] = {"speed": 0.18, "depth": 5, "radius": 740, "direction": "cw"}
SMALL_CIRCLE: dict[str, Any] = {"speed": 0.18, "depth": 3, "radius": 5, "direction": "cw"}
ORDER = [
    "depth_rating",
    "depth_limit",
    "speed_limit",
    "top_speed",
    "endurance",
    "geofence",
    "reach",
]


def planned(pattern: str, params: dict[str, Any], x_m: float = 0.0) -> Plan:
    """The command as the vehicle decodes it, planned from (``x_m``, 0) at 2 m."""
    cmd = decode_frame(encode_frame(pattern, params).frame.bits).command
    return plan(cmd, VehicleState(x_m=x_m, y_m=0.0, z_m=2.0, heading_deg=0.0, speed_mps=0.0))


def run(
    p: Plan,
    *,
    limits: Limits | None = None,
    profile: VehicleProfile | None = TWIN,
    soc_pct: float | None = 100.0,
    station: Station | None = AT_ORIGIN,
    range_m: float | None = RANGE_M,
) -> CheckReport:
    return check_plan(
        p,
        limits=limits or Limits(),
        profile=profile,
        soc_pct=soc_pct,
        station=station,
        range_m=range_m,
    )


def status(report: CheckReport) -> dict[str, str]:
    return {line.check: line.status for line in report.lines}


def detail(report: CheckReport, check: str) -> str:
    (line,) = [line for line in report.lines if line.check == check]
    return line.detail


def test_a_plan_within_every_limit_has_every_line_ok_but_the_unset_geofence() -> None:
    report = run(planned("straight", {"speed": 0.18, "depth": 4, "duration": 60, "heading": 0}))
    assert report.violations == () and report.hard == () and report.soft == ()
    assert [line.check for line in report.lines] == ORDER
    assert status(report) == {**dict.fromkeys(ORDER, "ok"), "geofence": "skipped"}
    assert detail(report, "geofence") == "no geofence set"
    assert detail(report, "depth_rating") == "deepest 4 m, within the vehicle's 100 m rating"
    assert detail(report, "speed_limit") == "speed 0.18 m/s, within the maximum speed 1 m/s"
    assert detail(report, "top_speed") == "speed 0.18 m/s, within the vehicle's 0.19 m/s top speed"
    assert detail(report, "endurance").startswith("the path takes ")
    assert detail(report, "endurance").endswith(
        ", within the 26,110 s the battery has left at 100 %"
    )
    assert detail(report, "reach").startswith("the path stays within ")
    assert detail(report, "reach").endswith(" m of the transmitter (range 730 m)")


def test_the_wide_circle_breaks_the_reach_and_the_endurance_softly() -> None:
    p = planned("circle", WIDE_CIRCLE)
    report = run(p, station=WEST)
    assert [(v.check, v.kind, v.param) for v in report.violations] == [
        ("endurance", "soft", "radius"),
        ("reach", "soft", "radius"),
    ]
    assert report.hard == () and report.soft == report.violations
    assert all(v.overridable for v in report.violations)
    assert status(report)["endurance"] == status(report)["reach"] == "violated"
    assert status(report)["turn_radius"] == "ok"  # a round pattern: its turn is checked too

    endurance, reach = report.violations
    est = flown(p, TWIN)[0]  # the estimate as the vehicle flies it
    assert est.repeats and est.lap_duration_s is not None
    # the first lap ends after the join: one lap alone is within the battery, join and lap not
    assert est.lap_duration_s < 26_110 < est.duration_s
    assert endurance.message == (
        f"the join and one lap take {est.duration_s:,.0f} s, beyond the 26,110 s the battery "
        "has left at 100 %"
    )
    assert (endurance.value, endurance.limit, endurance.unit) == (
        est.duration_s,
        TWIN.endurance_s,
        "s",
    )
    assert endurance.allowed == "up to 26,110 s"

    far = max(
        math.sqrt(x * x + (y + 35.0) ** 2 + z * z)
        for x, y, z in zip(p.path.xs, p.path.ys, p.path.zs, strict=True)
    )
    assert 770 < far < 780
    assert reach.message == (
        f"the path goes {far:.0f} m from the transmitter, beyond the ME link's 730 m range: the "
        "next retask could not reach the vehicle there"
    )
    assert reach.value == pytest.approx(far) and reach.limit == RANGE_M and reach.unit == "m"
    assert reach.allowed == "within 730 m of the transmitter"


def test_depth_beyond_the_rating_is_hard_and_stands_for_the_maximum_too() -> None:
    report = run(planned("circle", {**SMALL_CIRCLE, "depth": 105}), limits=Limits(20.0))
    (v,) = report.violations
    assert report.hard == (v,) and report.soft == ()
    assert (v.check, v.param, v.kind, v.overridable) == ("depth_rating", "depth", "hard", False)
    assert (v.value, v.limit, v.unit, v.allowed) == (105.0, 100.0, "m", "0 to 100 m")
    assert "cannot be overridden" in v.message
    assert status(report)["depth_rating"] == status(report)["depth_limit"] == "violated"
    assert detail(report, "depth_limit") == (
        "depth 105 m is deeper than the maximum depth 20 m (and the rating)"
    )


def test_depth_beyond_the_maximum_is_soft() -> None:
    report = run(planned("circle", {**SMALL_CIRCLE, "depth": 30}), limits=Limits(20.0))
    (v,) = report.violations
    assert (v.check, v.param, v.kind, v.value, v.limit) == ("depth_limit", "depth", "soft", 30, 20)
    assert v.allowed == "0 to 20 m"
    assert status(report)["depth_rating"] == "ok"


def test_the_maximum_speed_is_soft_and_the_top_speed_then_says_why_it_is_skipped() -> None:
    report = run(planned("circle", {**SMALL_CIRCLE, "speed": 1.5}))
    (v,) = report.violations
    assert (v.check, v.param, v.kind, v.allowed) == ("speed_limit", "speed", "soft", "0 to 1 m/s")
    assert status(report)["top_speed"] == "skipped"
    assert "refuses onboard" in detail(report, "top_speed")


def test_the_top_speed_is_soft() -> None:
    report = run(planned("circle", {**SMALL_CIRCLE, "speed": 0.8}))
    (v,) = report.violations
    assert (v.check, v.param, v.kind, v.value) == ("top_speed", "speed", "soft", 0.8)
    assert v.limit == TWIN.top_speed_mps and v.allowed == "0 to 0.19 m/s"
    assert v.message.startswith("speed 0.8 m/s exceeds the vehicle's 0.19 m/s top speed")


def test_a_circle_tighter_than_the_vehicle_turns_is_soft() -> None:
    assert turn_radius_m(1.0) > 1.0
    report = run(planned("circle", {**SMALL_CIRCLE, "speed": 1.0, "radius": 1}))
    checks = {v.check: v for v in report.violations}
    v = checks["turn_radius"]
    assert (v.param, v.kind, v.value) == ("radius", "soft", 1.0)
    assert v.allowed == f"at least {turn_radius_m(1.0):.2f} m at 1 m/s"
    # no line for a pattern without a radius to turn
    assert "turn_radius" not in status(
        run(planned("straight", {"speed": 0.18, "depth": 2, "duration": 60, "heading": 0}))
    )


def test_a_limit_no_check_names_is_never_dropped(monkeypatch: pytest.MonkeyPatch) -> None:
    """A violation the planner's validate adds later (here ``laps``) still stops the send."""
    p = planned(
        "lawnmower", {"speed": 0.18, "depth": 2, "sweep_length": 10, "lane_spacing": 2, "laps": 2}
    )
    assert "onboard_limit" not in status(run(p))
    extra = Violation("laps", 2.0, 1.0, "", "laps 2 is more than 1")
    monkeypatch.setattr(checks, "validate", lambda plan, limits: (extra,))
    report = run(p)
    (v,) = report.violations
    assert (v.check, v.param, v.kind, v.message) == ("onboard_limit", "laps", "soft", extra.message)
    assert status(report)["onboard_limit"] == "violated"


def test_geofence_is_soft_and_named() -> None:
    fence = CircleFence(10.0)
    report = run(planned("circle", {**SMALL_CIRCLE, "radius": 20}), limits=Limits(geofence=fence))
    (v,) = report.violations
    assert (v.check, v.param, v.kind) == ("geofence", "radius", "soft")
    assert v.allowed == "inside the geofence circle of 10 m around (0 N, 0 E)"
    inside = run(planned("circle", SMALL_CIRCLE), limits=Limits(geofence=fence))
    assert status(inside)["geofence"] == "ok" and inside.violations == ()
    assert (
        detail(inside, "geofence")
        == "the path stays inside the geofence circle of 10 m around (0 N, 0 E)"
    )


def test_checks_that_cannot_run_are_skipped_with_the_reason() -> None:
    p = planned("circle", WIDE_CIRCLE)
    unknown = VehicleProfile(None, None, None, 100.0, None, "settings")
    report = run(p, profile=unknown, station=Station(1.0, 2.0, None, None, "settings"))
    assert report.violations == ()  # nothing it could check is broken: the depth, the speed
    assert status(report)["top_speed"] == status(report)["endurance"] == "skipped"
    assert detail(report, "top_speed") == UNKNOWN["top_speed_mps"]
    assert detail(report, "endurance") == UNKNOWN["endurance_s"]
    assert unknown.skipped_checks() == [
        UNKNOWN["top_speed_mps"],
        UNKNOWN["heave_rate_mps"],
        UNKNOWN["endurance_s"],
    ]
    assert status(report)["reach"] == "skipped"
    assert "no datum" in detail(report, "reach")
    none = run(p, profile=None, station=None)
    assert detail(none, "top_speed") == detail(none, "endurance") == "no vehicle profile"
    assert detail(none, "reach") == "the transmitter or its range is unknown"
    assert status(run(p, range_m=None))["reach"] == "skipped"


def test_endurance_is_against_the_battery_now() -> None:
    # 3210 s of straight: within a battery at 20 %, beyond one at 5 %
    p = planned("straight", {"speed": 0.18, "depth": 2, "duration": 3210, "heading": 0})
    assert run(p, soc_pct=20.0).violations == ()
    (v,) = run(p, soc_pct=5.0).violations
    assert TWIN.endurance_s is not None
    left = endurance_left_s(TWIN.endurance_s, 5.0)
    assert 1_000 < left < 3_000 and v.limit == pytest.approx(left)
    assert v.check == "endurance" and v.param == "duration" and v.kind == "soft"
    assert v.message.endswith(f", beyond the {left:,.0f} s the battery has left at 5 %")
    # the charge unknown: against a full battery, saying so
    assert detail(run(p, soc_pct=None), "endurance").endswith(
        "within the 26,110 s a full battery lasts (the charge now is unknown)"
    )


def test_the_endurance_left_follows_the_twins_battery_at_cruise() -> None:
    """The twin's endurance is its battery fit at cruise load down to the cut-off: after t
    hours of cruise the charge the fit gives leaves exactly the rest of it."""
    battery = BatteryConfig()
    endurance = TWIN.endurance_s
    assert endurance is not None
    load = (battery.hotel_power_w + cruise_thrust_power_w(VehicleParams())) / (
        battery.hotel_power_w + battery.nominal_thrust_power_w
    )
    for t_h in (0.5, 2.0, 5.0):
        soc = (
            100
            - SOC_LINEAR_PCT_PER_H * load * t_h
            - SOC_FAST_PCT * -math.expm1(-t_h / SOC_FAST_TAU_H)
        )
        assert endurance_left_s(endurance, soc) == pytest.approx(endurance - t_h * 3600, abs=1.0)
    assert endurance_left_s(endurance, 100.0) == endurance_left_s(endurance, None) == endurance
    assert endurance_left_s(endurance, 0.0) == 0.0
    # the fast initial term is spent first: half the charge is less than half the time
    assert endurance_left_s(endurance, 50.0) < endurance / 2 + 5_000
    assert endurance_left_s(endurance, 50.0) > endurance_left_s(endurance, 49.0)


def test_surface_is_never_held_back_for_the_battery_or_the_reach() -> None:
    p = planned("surface", {}, x_m=800.0)  # out of range, on an almost empty battery
    report = run(p, soc_pct=0.5)
    assert report.violations == ()
    assert status(report)["endurance"] == status(report)["reach"] == "skipped"
    # the same vehicle sent a circle there: both named
    there = run(planned("circle", SMALL_CIRCLE, x_m=800.0), soc_pct=0.01)
    assert {v.check for v in there.violations} == {"endurance", "reach"}


def test_the_preview_document_carries_the_same_report() -> None:
    p = planned("circle", WIDE_CIRCLE)
    doc = plan_doc(p, None, Limits(), TWIN, 100.0, station=WEST, range_m=RANGE_M)
    report = run(p, station=WEST)
    assert doc["checks"] == [
        {"check": line.check, "status": line.status, "detail": line.detail} for line in report.lines
    ]
    assert [(v["check"], v["kind"], v["allowed"], v["message"]) for v in doc["violations"]] == [
        (v.check, v.kind, v.allowed, v.message) for v in report.violations
    ]
    assert all(v["overridable"] for v in doc["violations"])
    est = doc["estimate"]
    assert est["repeats"] is True and est["lap_duration_s"] < est["duration_s"]
    finite = plan_doc(
        planned("straight", {"speed": 0.18, "depth": 2, "duration": 60, "heading": 0}),
        None,
        Limits(),
    )
    assert finite["estimate"]["repeats"] is False and finite["estimate"]["lap_duration_s"] is None


# --- through the API ---------------------------------------------------------------------------


def test_the_preview_api_shows_every_check(make_client: MakeClient) -> None:
    client: TestClient = make_client()
    r = client.post("/api/preview", json={"pattern": "circle", "params": WIDE_CIRCLE})
    assert r.status_code == 200, r.text
    doc = r.json()
    lines = {c["check"]: c for c in doc["checks"]}
    assert [c["check"] for c in doc["checks"]] == [*ORDER[:3], "turn_radius", *ORDER[3:]]
    assert lines["reach"]["status"] == lines["endurance"]["status"] == "violated"
    assert lines["geofence"] == {
        "check": "geofence",
        "status": "skipped",
        "detail": "no geofence set",
    }
    by_check = {v["check"]: v for v in doc["violations"]}
    assert set(by_check) == {"reach", "endurance"}
    assert by_check["reach"]["message"] == doc["link_reach"]["warning"]  # one sentence
    assert by_check["endurance"]["kind"] == "soft" and by_check["endurance"]["param"] == "radius"
    assert doc["estimate"]["repeats"] is True
    # a soft violation: the send needs the override, and says which
    refused = client.post(
        "/api/commands", json={"pattern": "circle", "params": WIDE_CIRCLE}, headers=AUTH
    )
    assert refused.status_code == 409, refused.text
    named = {v["check"] for v in refused.json()["detail"]["violations"]}
    assert named == {"reach", "endurance"}


def test_the_preview_api_refuses_the_rating_as_hard(make_client: MakeClient) -> None:
    client: TestClient = make_client()
    body = {"pattern": "circle", "params": {**SMALL_CIRCLE, "depth": 105}}
    doc = client.post("/api/preview", json=body).json()
    (v,) = doc["violations"]
    assert (v["check"], v["kind"], v["overridable"], v["allowed"]) == (
        "depth_rating",
        "hard",
        False,
        "0 to 100 m",
    )
    r = client.post("/api/commands", json={**body, "override": True}, headers=AUTH)
    assert r.status_code == 422 and r.json()["detail"]["violations"][0]["kind"] == "hard"
