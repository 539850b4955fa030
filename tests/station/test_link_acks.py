"""The console's link and the vehicle's acknowledgements across a short reconnect: what the
vehicle contract gives for it is the status's ``recent_acks`` (the last acknowledgements, as
published); the link hands the console each acknowledgement once, whether it came on
``/nemesys/mission``, again on it (a transient-local replay), or from a status."""

from __future__ import annotations

import asyncio
import json
import time
from typing import Any

import pytest

from station.link import RosbridgeLink
from tests.fake_vehicle import MISSION, STATUS, WITH_AGENT, Rosbridge


def ack(seq: int, t_s: float) -> dict[str, Any]:
    return {"seq": seq, "t_s": t_s, "outcome": "accepted", "frame_hex": "aaaa7c" + "0" * 19}


def text(body: dict[str, Any]) -> dict[str, str]:
    """A std_msgs/String carrying ``body``, as rosbridge sends it."""
    return {"data": json.dumps(body)}


async def until(probe: Any, what: str, timeout_s: float = 10.0) -> None:
    deadline = time.monotonic() + timeout_s
    while not probe():
        assert time.monotonic() < deadline, f"timed out waiting for {what}"
        await asyncio.sleep(0.02)


@pytest.mark.slow  # a real reconnect
def test_acknowledgements_missed_while_reconnecting_come_from_the_status() -> None:
    first = Rosbridge(WITH_AGENT).start()
    port = first.port
    delivered: list[int] = []
    statuses: list[dict[str, Any]] = []
    bridges = [first]

    async def run() -> None:
        link = RosbridgeLink(first.url, graph_poll_s=0.2)
        link.on_mission = lambda a: delivered.append(a["seq"])
        link.on_status = statuses.append
        await link.start()
        try:
            assert await link.wait_connected(5.0)
            vehicle = first
            await until(lambda: vehicle.subscriptions(STATUS) == 1, "the subscriptions")
            # the first status: its acknowledgements predate this console
            await asyncio.to_thread(vehicle.publish, STATUS, text({"recent_acks": [ack(1, 5.0)]}))
            await until(lambda: len(statuses) == 1, "the first status")
            assert delivered == []
            await asyncio.to_thread(vehicle.publish, MISSION, text(ack(2, 6.0)))
            await until(lambda: delivered == [2], "acknowledgement 2")

            # the console's connection drops; acknowledgement 3 is published meanwhile
            await asyncio.to_thread(vehicle.stop)
            bridges.remove(vehicle)
            await until(lambda: not link.connected, "the link noticing")
            vehicle = await asyncio.to_thread(Rosbridge(WITH_AGENT, port=port).start)
            bridges.append(vehicle)
            await until(lambda: vehicle.subscriptions(STATUS) == 1, "the new subscriptions")
            # a transient-local replay of 2, then the status that carries 1, 2 and the missed 3
            await asyncio.to_thread(vehicle.publish, MISSION, text(ack(2, 6.0)))
            recent = [ack(1, 5.0), ack(2, 6.0), ack(3, 7.0)]
            await asyncio.to_thread(vehicle.publish, STATUS, text({"recent_acks": recent}))
            await until(lambda: len(statuses) == 2, "the status after the reconnect")
            assert delivered == [2, 3]
            # the same status again delivers nothing more; a new acknowledgement does
            await asyncio.to_thread(vehicle.publish, STATUS, text({"recent_acks": recent}))
            await asyncio.to_thread(vehicle.publish, MISSION, text(ack(4, 8.0)))
            await until(lambda: len(statuses) == 3 and 4 in delivered, "acknowledgement 4")
            assert delivered == [2, 3, 4]
        finally:
            await link.stop()

    try:
        asyncio.run(run())
    finally:
        for bridge in bridges:
            bridge.stop()


def test_an_acknowledgement_without_seq_is_never_taken_for_a_repeat() -> None:
    vehicle = Rosbridge(WITH_AGENT).start()
    delivered: list[dict[str, Any]] = []

    async def run() -> None:
        link = RosbridgeLink(vehicle.url)
        link.on_mission = delivered.append
        await link.start()
        try:
            assert await link.wait_connected(5.0)
            await until(lambda: vehicle.subscriptions(MISSION) == 1, "the subscription")
            bare = {"t_s": 1.0, "outcome": "rejected", "frame_hex": None}
            for _ in range(2):
                await asyncio.to_thread(vehicle.publish, MISSION, text(bare))
            await until(lambda: len(delivered) == 2, "both acknowledgements")
        finally:
            await link.stop()

    try:
        asyncio.run(run())
    finally:
        vehicle.stop()
