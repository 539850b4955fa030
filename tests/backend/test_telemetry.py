"""The telemetry fan-out: one serialisation of a telemetry message for every page, and an age
that stays true for a page that joins later."""

from __future__ import annotations

import asyncio
import json
from typing import Any

import pytest

from backend.messages import message_json
from backend.telemetry import TelemetryHub
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


def test_one_serialisation_for_every_page(monkeypatch: pytest.MonkeyPatch) -> None:
    calls: list[object] = []
    real = message_json

    def counting(message: Any) -> str:
        calls.append(message)
        return real(message)

    monkeypatch.setattr("backend.telemetry.message_json", counting)
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
