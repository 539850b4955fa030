"""The telemetry fan-out: one serialisation of a telemetry message for every page (a fleet's:
one per vehicle, and one per event), and an age that stays true for a page that joins later."""

from __future__ import annotations

import asyncio
import json
from typing import Any

import pytest

from backend.messages import (
    ActivePathMessage,
    FleetTelemetryMessage,
    TelemetryMessage,
    for_vehicle,
    message_json,
)
from backend.telemetry import TelemetryHub, _Client
from vehicle_contract.messages import POSE_KEYS

#: A whole pose: every number the contract names, known.
POSE: dict[str, float | None] = {
    **{key: float(i) for i, key in enumerate(POSE_KEYS)},
    "lat_deg": None,
    "lon_deg": None,
}


class Page:
    """A page's websocket: what it was sent."""

    def __init__(self) -> None:
        self.texts: list[str] = []

    async def send_text(self, data: str) -> None:
        self.texts.append(data)

    def telemetry_models(self) -> list[TelemetryMessage]:
        """Each vehicle's telemetry it got, out of its ``fleet_telemetry`` messages (each
        checked against the message's model)."""
        return [
            t
            for text in self.texts
            if json.loads(text)["type"] == "fleet_telemetry"
            for t in FleetTelemetryMessage.model_validate_json(text).telemetry
        ]

    def telemetry(self) -> list[dict[str, Any]]:
        """:meth:`telemetry_models` as the page reads them."""
        return [json.loads(message_json(t)) for t in self.telemetry_models()]


@pytest.fixture
def encoded(monkeypatch: pytest.MonkeyPatch) -> list[Any]:
    """Every message the hub serialises, in turn."""
    calls: list[Any] = []
    real = message_json

    def counting(message: Any) -> str:
        calls.append(message)
        return real(message)

    monkeypatch.setattr("backend.telemetry.message_json", counting)
    return calls


def test_one_serialisation_for_every_page(encoded: list[Any]) -> None:
    calls = encoded
    # every page waits one period (0.5 s) for events, then they all want the telemetry at once
    hub = TelemetryHub(rate_hz=2.0)
    hub.set_pose(POSE)
    pages = [Page() for _ in range(20)]

    async def run() -> None:
        tasks = [asyncio.create_task(hub.serve(p)) for p in pages]
        async with asyncio.timeout(30):  # a page that never gets one fails, not hangs
            while not all(p.texts for p in pages):
                assert not any(t.done() for t in tasks), [t.exception() for t in tasks]
                await asyncio.sleep(0.001)
        for t in tasks:
            t.cancel()
        await asyncio.gather(*tasks, return_exceptions=True)

    asyncio.run(run())
    assert all(
        json.loads(p.texts[0])["pose"] == json.loads(pages[0].texts[0])["pose"] for p in pages
    )
    # 20 pages, one change of the pose: serialised once, or again only when a period went by
    # between two pages (a loaded machine), never once a page.
    assert 1 <= len(calls) < len(pages) // 2


def test_a_fleet_of_ten_serialised_once_for_twenty_pages(encoded: list[Any]) -> None:
    """Ten vehicles' hubs fed to the console's hub (as :class:`backend.fleet.state.Fleet`
    wires them), 20 pages: each vehicle's telemetry and each event is encoded once and the
    same text fanned out, not once a page (the fleet's cost must not grow with the pages)."""
    calls = encoded
    names = [f"auv{i}" for i in range(1, 11)]
    hub = TelemetryHub(rate_hz=2.0)
    hub.feeds = [TelemetryHub(rate_hz=2.0, vehicle=name) for name in names]
    for i, feed in enumerate(hub.feeds):
        feed.set_pose({**POSE, "x_m": float(i)})
    pages = [Page() for _ in range(20)]

    def got(page: Page) -> tuple[set[str], int]:
        docs = [json.loads(t) for t in page.texts]
        assert not [d for d in docs if d["type"] == "telemetry"], "a fleet's come batched"
        telemetry = {d["vehicle"] for d in page.telemetry()}
        return telemetry, sum(d["type"] == "active_path" for d in docs)

    async def run() -> None:
        tasks = [asyncio.create_task(hub.serve(p)) for p in pages]
        async with asyncio.timeout(30):  # every page connected before the event
            while hub.client_count < len(pages):
                await asyncio.sleep(0.001)
        hub.publish(for_vehicle(ActivePathMessage(active_path=None), "auv3"))
        async with asyncio.timeout(30):  # a page that never gets them fails, not hangs
            while not all(got(p) == (set(names), 1) for p in pages):
                assert not any(t.done() for t in tasks), [t.exception() for t in tasks]
                await asyncio.sleep(0.001)
        for t in tasks:
            t.cancel()
        await asyncio.gather(*tasks, return_exceptions=True)

    asyncio.run(run())
    # every page got each vehicle's own telemetry (its pose, not another's)
    for i, name in enumerate(names):
        mine = [d for p in pages for d in p.telemetry() if d["vehicle"] == name]
        assert {d["pose"]["x_m"] for d in mine} == {float(i)}
    events = [c for c in calls if isinstance(c, ActivePathMessage)]
    assert len(events) == 1  # the event: once, for 20 pages
    for name in names:
        encoded = [c for c in calls if getattr(c, "vehicle", None) == name and c not in events]
        # once per vehicle, or again only when a period went by between two pages (a loaded
        # machine), never once a page
        assert 1 <= len(encoded) < len(pages) // 2, (name, len(encoded))
    assert not [c for c in calls if c not in events and getattr(c, "vehicle", None) is None]


def test_a_page_joining_later_gets_a_fresh_age(monkeypatch: pytest.MonkeyPatch) -> None:
    clock = [100.0]
    monkeypatch.setattr("backend.telemetry.time.monotonic", lambda: clock[0])
    hub = TelemetryHub(rate_hz=10.0)
    hub.set_pose(POSE)
    first = json.loads(hub.telemetry_json())
    clock[0] += 60.0  # the vehicle is silent for a minute; the pose is unchanged
    later = json.loads(hub.telemetry_json())
    assert first["age_s"] == pytest.approx(0.0)
    assert later["age_s"] == pytest.approx(60.0)


def test_a_fleets_telemetry_is_one_message_a_period_of_what_changed(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """A page gets its fleet's telemetry in one ``fleet_telemetry`` message a period: at
    first every vehicle's, then only the vehicles whose pose or status changed since (latest
    value wins), and nothing while none did."""
    monkeypatch.setattr("backend.telemetry.time.monotonic", lambda: 100.0)  # one period
    names = [f"auv{i}" for i in range(1, 6)]
    hub = TelemetryHub(rate_hz=20.0)
    hub.feeds = [TelemetryHub(rate_hz=20.0, vehicle=name) for name in names]
    for i, feed in enumerate(hub.feeds):
        feed.set_pose({**POSE, "x_m": float(i)})
    page = Page()
    client = _Client(page, max_events=10)

    def period() -> list[dict[str, Any]]:
        """What one period's turn sends the page (its texts, parsed)."""
        before = len(page.texts)
        asyncio.run(hub._send_feeds(client))
        return [json.loads(t) for t in page.texts[before:]]

    (first,) = period()
    assert first["type"] == "fleet_telemetry"
    assert [t["vehicle"] for t in first["telemetry"]] == names
    assert [t["pose"]["x_m"] for t in first["telemetry"]] == [0.0, 1.0, 2.0, 3.0, 4.0]
    assert period() == []  # nothing changed: nothing sent
    hub.feeds[3].set_pose({**POSE, "x_m": 30.0})
    hub.feeds[3].set_pose({**POSE, "x_m": 31.0})  # the newer one wins
    hub.feeds[1].set_status({"mode": "hover"})
    (second,) = period()
    assert [t["vehicle"] for t in second["telemetry"]] == ["auv2", "auv4"]
    assert second["telemetry"][1]["pose"]["x_m"] == 31.0
    assert second["telemetry"][0]["status"]["mode"] == "hover"
    assert period() == []
    # the pages that want every vehicle share one text, joined once
    other = Page()
    asyncio.run(hub._send_feeds(_Client(other, max_events=10)))
    again = Page()
    asyncio.run(hub._send_feeds(_Client(again, max_events=10)))
    assert other.texts[0] is again.texts[0]
    assert [t.vehicle for t in other.telemetry_models()] == names
