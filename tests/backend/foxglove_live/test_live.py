"""The live Foxglove view in the app (backend/foxglove_live/, ``NEMESYS_FOXGLOVE_PORT``): off by
default, on the host setting, started and stopped with the app, read-only, one context per
console; the news a page gets, as Foxglove messages on the dive's clock (the light app: a
vehicle held still, moved by the test; the training console's moving vehicle through
Foxglove's own client is ``test_interop.py``)."""

from __future__ import annotations

import asyncio
import logging
import socket
import time
from collections.abc import Awaitable
from pathlib import Path
from typing import TypeVar

import pytest
from fastapi.testclient import TestClient
from foxglove.messages import Pose, PoseInFrame, Vector3
from pydantic import ValidationError

from backend.app import create_app
from backend.foxglove_live.channels import CHANNELS
from backend.foxglove_live.clock import to_ns
from backend.foxglove_live.frames import attitude, stamp
from backend.foxglove_live.server import LOGGERS, FoxgloveLive, LiveViewError
from backend.settings import Settings
from planner import VehicleState
from tests.agent_link import AgentLink
from tests.backend.conftest import (
    CIRCLE,
    TOKEN,
    MakeLightClient,
    clear_nemesys_env,
    console_of,
    settings_for,
)
from tests.backend.foxglove_live.foxglove_client import Session, open_session

T = TypeVar("T")


def run(coro: Awaitable[T]) -> T:
    async def main() -> T:
        return await coro

    return asyncio.run(main())


async def subscribed(live: FoxgloveLive, *topics: str, timeout_s: float = 10.0) -> None:
    """Wait until the server has taken the subscriptions to ``topics`` (a message logged
    before that reaches no one)."""
    channels = {**live.channels.typed, **live.channels.json}
    deadline = time.monotonic() + timeout_s
    while not all(channels[t].has_sinks() for t in topics):
        assert time.monotonic() < deadline, f"no subscription to {topics} after {timeout_s} s"
        await asyncio.sleep(0.01)


def live_of(client: TestClient) -> FoxgloveLive:
    live = console_of(client).foxglove
    assert live is not None, "the live view is not on"
    return live


def test_off_unless_its_port_is_set(
    make_light_client: MakeLightClient, monkeypatch: pytest.MonkeyPatch
) -> None:
    clear_nemesys_env(monkeypatch)
    assert Settings().foxglove_port is None
    client = make_light_client()
    assert console_of(client).foxglove is None
    monkeypatch.setenv("NEMESYS_FOXGLOVE_PORT", "8765")
    assert Settings.load().foxglove_port == 8765
    monkeypatch.setenv("NEMESYS_FOXGLOVE_PORT", "70000")
    with pytest.raises(ValidationError, match="foxglove_port"):
        Settings.load()


def test_serves_the_listed_channels_read_only_on_the_host_setting(
    make_light_client: MakeLightClient,
) -> None:
    client = make_light_client(foxglove_port=0)
    live = live_of(client)

    async def look() -> Session:
        session = await open_session(live.port)
        await session.ws.close()
        return session

    session = run(look())
    assert session.ws.subprotocol == "foxglove.sdk.v1"
    info = session.server_info
    assert info["name"] == "NemeSys Console"
    assert info["capabilities"] == ["time"]  # no clientPublish, services or parameters
    assert {t: c["schemaName"] for t, c in session.channels.items()} == {
        c.topic: c.schema for c in CHANNELS
    }
    with pytest.raises(OSError):  # bound to 127.0.0.1 only (the host setting)
        socket.create_connection((_other_address(), live.port), timeout=1.0).close()


def _other_address() -> str:
    """An address of this machine that is not loopback (skip the check without one)."""
    probe = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    try:
        probe.connect(("192.0.2.1", 9))  # TEST-NET-1: nothing is sent (UDP connect)
        address = str(probe.getsockname()[0])
    except OSError:
        address = "127.0.0.1"
    finally:
        probe.close()
    if address.startswith("127."):
        pytest.skip("no non-loopback address to check the binding against")
    return address


def test_two_consoles_in_one_process_keep_their_channels_apart(
    make_light_client: MakeLightClient,
) -> None:
    first = live_of(make_light_client(foxglove_port=0))
    second = live_of(make_light_client(foxglove_port=0))
    assert first.port != second.port and first.context is not second.context

    async def count(port: int) -> int:
        session = await open_session(port)
        await session.ws.close()
        return len(session.channels)

    assert run(count(first.port)) == run(count(second.port)) == len(CHANNELS)


class CountedLink(AgentLink):
    """An in-memory link that counts its starts and stops."""

    starts = stops = 0

    async def start(self) -> None:
        self.starts += 1
        await super().start()

    async def stop(self) -> None:
        self.stops += 1
        await super().stop()


def test_a_taken_port_stops_the_start_with_the_setting_named(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    clear_nemesys_env(monkeypatch)
    link = CountedLink()
    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen()
        port = taken.getsockname()[1]
        settings = settings_for(
            tmp_path / "m.sqlite3", target="ws://127.0.0.1:9", foxglove_port=port
        )
        app = create_app(settings, viewer=False, link=link)
        with (
            pytest.raises(LiveViewError, match=f"NEMESYS_FOXGLOVE_PORT={port}"),
            TestClient(app),
        ):
            pass
    assert (link.starts, link.stops) == (1, 1)  # the console started, then was stopped


def test_poses_on_the_dives_clock_in_the_scene_frame(
    make_light_client: MakeLightClient,
) -> None:
    link = AgentLink()
    client = make_light_client(link, foxglove_port=0, datum_lat_deg=29.5, datum_lon_deg=-82.3)
    live = live_of(client)
    moved = VehicleState(10.0, 3.0, 2.5, heading_deg=90.0, speed_mps=0.0, t_s=101.5)

    async def watch() -> Session:
        session = await open_session(live.port)
        await session.subscribe("/vehicle/pose", "/vehicle/fix", "/vehicle/track")
        await subscribed(live, "/vehicle/pose", "/vehicle/fix", "/vehicle/track")
        link.state = moved
        await asyncio.to_thread(client.portal.call, link.report)  # type: ignore[union-attr]
        # (the first pose, at the dive's start, may come too if the view heard it late)
        await session.until(
            lambda s: any(r.log_time > 0 for r in s.on("/vehicle/pose")), what="the moved pose"
        )
        await session.until(
            lambda s: any(r.log_time > 0 for r in s.on("/vehicle/fix")), what="the moved fix"
        )
        await session.until(lambda s: bool(s.on("/vehicle/track")), what="the track")
        # the server's time: the same clock
        await session.until(lambda s: to_ns(1.5) in s.times, what="the server's time")
        await session.ws.close()
        return session

    session = run(watch())
    pose = session.on("/vehicle/pose")[-1]
    # the dive began at the first pose (t_s 100: its first track point); this one is 1.5 s on
    assert pose.log_time == to_ns(1.5)
    heard = console_of(client).hub.pose  # as the pages got it (through the contract's quaternion)
    heading = None if heard is None else heard["heading_deg"]
    assert heading is not None and heading == pytest.approx(90.0)
    expected = PoseInFrame(
        timestamp=stamp(to_ns(1.5)),
        frame_id="map",
        pose=Pose(
            position=Vector3(x=3.0, y=10.0, z=-2.5),  # east, north, up
            orientation=attitude(heading, 0.0),  # east: about no ENU yaw
        ),
    )
    assert pose.data == expected.encode()
    assert session.on("/vehicle/fix")[-1].log_time == to_ns(1.5)


def test_previews_and_the_active_path_stay_drawn_for_a_late_subscriber(
    make_light_client: MakeLightClient,
) -> None:
    client = make_light_client(foxglove_port=0)
    live = live_of(client)
    r = client.post(
        "/api/preview",
        json={"pattern": "circle", "params": CIRCLE},
        headers={"X-Nemesys-View": "page-one-view"},
    )
    assert r.status_code == 200, r.text
    r = client.post(
        "/api/commands",
        json={"pattern": "circle", "params": CIRCLE},
        headers={"Authorization": f"Bearer {TOKEN}"},
    )
    assert r.status_code == 202, r.text

    async def late() -> Session:
        session = await open_session(live.port)
        await session.subscribe("/paths/preview", "/paths/active", "/station")
        await session.until(
            lambda s: all(s.on(t) for t in ("/paths/preview", "/paths/active", "/station")),
            what="what stays drawn",
        )
        await session.ws.close()
        return session

    session = run(late())
    assert b"preview: circle" in session.on("/paths/preview")[-1].data
    assert b"active: circle" in session.on("/paths/active")[-1].data
    assert b"ME transmitter (730 m)" in session.on("/station")[-1].data


def test_log_lines_with_the_token_scrubbed(make_light_client: MakeLightClient) -> None:
    client = make_light_client(foxglove_port=0)
    live = live_of(client)

    async def watch() -> Session:
        session = await open_session(live.port)
        await session.subscribe("/log")
        await subscribed(live, "/log")
        logging.getLogger("backend.test").error("the operator token is %s", TOKEN)
        await session.until(
            lambda s: any(b"operator token" in r.data for r in s.on("/log")), what="the line"
        )
        await session.ws.close()
        return session

    line = next(r for r in run(watch()).on("/log") if b"operator token" in r.data)
    assert b"the operator token is ***" in line.data and TOKEN.encode() not in line.data
    assert b"backend.test" in line.data


def test_stopped_with_the_app(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    clear_nemesys_env(monkeypatch)
    settings = settings_for(tmp_path / "m.sqlite3", target="ws://127.0.0.1:9", foxglove_port=0)
    app = create_app(settings, viewer=False, link=AgentLink())
    with TestClient(app) as client:
        live = live_of(client)
        port = live.port
        assert all(live._lines in logging.getLogger(name).handlers for name in LOGGERS)
    assert console_of(client).foxglove is None
    with pytest.raises(OSError):
        socket.create_connection(("127.0.0.1", port), timeout=1.0).close()
    assert all(live._lines not in logging.getLogger(name).handlers for name in LOGGERS)
