"""The one rosbridge client (:mod:`rosbridge.transport`) against a scripted websocket server on
127.0.0.1: the dispatch table (publish to the topic's handler, service_response to the call
with its id, status to the log), junk and failing handlers that leave the connection up,
timeouts, and what a close does to waiting calls. The link, the transmitter and vehicle-check
are tested through it in tests/station."""

from __future__ import annotations

import asyncio
import json
import logging
from collections.abc import AsyncIterator, Awaitable, Callable
from contextlib import asynccontextmanager
from typing import Any

import pytest
from websockets.asyncio.server import ServerConnection, serve
from websockets.exceptions import ConnectionClosed

from rosbridge.client import ClientProtocol
from rosbridge.transport import RosbridgeClient
from tests.rosbridge.helpers import free_port
from vehicle_contract.contract import FRAME_TOPIC, MISSION_TOPIC, POSE_TOPIC, STATUS_TOPIC

#: What the scripted server does with one connection.
Script = Callable[[ServerConnection, list[dict[str, Any]]], Awaitable[None]]


@asynccontextmanager
async def scripted(script: Script) -> AsyncIterator[tuple[str, list[dict[str, Any]]]]:
    """A websocket server running ``script`` per connection: (its URL, what it received)."""
    received: list[dict[str, Any]] = []

    async def handler(ws: ServerConnection) -> None:
        await script(ws, received)

    async with serve(handler, "127.0.0.1", 0) as server:
        port = server.sockets[0].getsockname()[1]
        yield f"ws://127.0.0.1:{port}", received


async def read(ws: ServerConnection, received: list[dict[str, Any]], n: int) -> None:
    """Take ``n`` messages from the client into ``received``."""
    for _ in range(n):
        received.append(json.loads(await ws.recv()))


def publish(topic: str, msg: object) -> str:
    return json.dumps({"op": "publish", "topic": topic, "msg": msg})


async def until(condition: Callable[[], bool], timeout_s: float = 2.0) -> None:
    async with asyncio.timeout(timeout_s):
        while not condition():
            await asyncio.sleep(0.005)


def protocol() -> ClientProtocol:
    return ClientProtocol(advertise=[FRAME_TOPIC], subscribe=[POSE_TOPIC, MISSION_TOPIC])


def test_publications_go_to_their_topics_handler_through_junk_and_failures(
    caplog: pytest.LogCaptureFixture,
) -> None:
    async def script(ws: ServerConnection, received: list[dict[str, Any]]) -> None:
        await read(ws, received, 3)  # advertise, subscribe, subscribe
        await ws.send(publish(POSE_TOPIC, {"n": 1}))
        await ws.send("not json at all")
        await ws.send(b"\x00\x01")
        await ws.send('["a", "list"]')
        await ws.send(json.dumps({"op": "status", "level": "error", "msg": "unknown topic"}))
        await ws.send(json.dumps({"op": "set_level", "level": "info"}))
        await ws.send(publish(STATUS_TOPIC, {"data": "{}"}))  # no handler: dropped
        await ws.send(publish(MISSION_TOPIC, {"data": "boom"}))  # its handler fails
        await ws.send(publish(POSE_TOPIC, {"n": 2}))
        await ws.wait_closed()

    poses: list[object] = []

    def failing(msg: object) -> None:
        raise RuntimeError("a bug in a handler")

    async def go() -> list[dict[str, Any]]:
        async with scripted(script) as (url, received):
            handlers = {POSE_TOPIC: poses.append, MISSION_TOPIC: failing}
            client = await RosbridgeClient.connect(url, protocol(), handlers)
            await client.open()
            await until(lambda: len(poses) == 2)
            assert not client.closed
            await client.close()
            return received

    with caplog.at_level(logging.DEBUG, logger="rosbridge.transport"):
        received = asyncio.run(go())
    assert poses == [{"n": 1}, {"n": 2}]  # in order, past everything else
    assert [m["op"] for m in received] == ["advertise", "subscribe", "subscribe"]
    assert "not JSON" in caplog.text and "not a JSON object" in caplog.text
    assert "binary message of 2 bytes" in caplog.text
    assert "rosbridge status: unknown topic" in caplog.text
    assert "ignoring a 'set_level' message" in caplog.text
    assert f"ignoring a message on {STATUS_TOPIC}" in caplog.text
    assert f"the handler of {MISSION_TOPIC} failed" in caplog.text
    assert "RuntimeError: a bug in a handler" in caplog.text


def test_each_answer_goes_to_the_call_with_its_id() -> None:
    async def script(ws: ServerConnection, received: list[dict[str, Any]]) -> None:
        await read(ws, received, 2)
        # answered in the other order, with a stray answer first
        stray = {"op": "service_response", "id": "nobody", "values": {}, "result": True}
        await ws.send(json.dumps(stray))
        for request, n in ((received[1], 2), (received[0], 1)):
            answer = {"op": "service_response", "id": request["id"], "result": True}
            await ws.send(json.dumps({**answer, "values": {"n": n}}))
        await ws.wait_closed()

    async def go() -> tuple[list[Any], list[dict[str, Any]]]:
        async with scripted(script) as (url, received):
            client = await RosbridgeClient.connect(url, protocol())
            answers = await asyncio.gather(
                client.call_service("/rosapi/topics", timeout_s=2.0),
                client.call_service("/rosapi/subscribers", {"topic": "/x"}, timeout_s=2.0),
            )
            await client.close()
            return list(answers), received

    answers, received = asyncio.run(go())
    assert [a["values"] for a in answers] == [{"n": 1}, {"n": 2}]
    assert [a["id"] for a in answers] == [r["id"] for r in received]
    assert received[1] == {
        "op": "call_service",
        "id": received[1]["id"],
        "service": "/rosapi/subscribers",
        "args": {"topic": "/x"},
    }


def test_an_unanswered_call_gives_none_after_its_timeout() -> None:
    async def script(ws: ServerConnection, received: list[dict[str, Any]]) -> None:
        await read(ws, received, 1)
        await ws.wait_closed()

    async def go() -> tuple[object, float, bool]:
        async with scripted(script) as (url, _):
            client = await RosbridgeClient.connect(url, protocol())
            start = asyncio.get_running_loop().time()
            answer = await client.call_service("/rosapi/topics", timeout_s=0.2)
            took = asyncio.get_running_loop().time() - start
            closed = client.closed
            await client.close()
            return answer, took, closed

    answer, took, closed = asyncio.run(go())
    assert answer is None and 0.19 <= took < 1.0 and not closed


def test_a_close_by_the_server_ends_waiting_calls_and_tells_the_owner() -> None:
    async def script(ws: ServerConnection, received: list[dict[str, Any]]) -> None:
        await read(ws, received, 1)
        await ws.close()

    async def go() -> tuple[object, float, int]:
        async with scripted(script) as (url, _):
            client = await RosbridgeClient.connect(url, protocol())
            told: list[bool] = []
            client.on_close = lambda: told.append(True)
            start = asyncio.get_running_loop().time()
            answer = await client.call_service("/rosapi/topics", timeout_s=5.0)
            took = asyncio.get_running_loop().time() - start
            await client.wait_closed()
            assert client.closed
            assert await client.call_service("/rosapi/topics", timeout_s=5.0) is None
            with pytest.raises(ConnectionClosed):
                await client.publish(FRAME_TOPIC, {"data": [1]})
            await client.close("never sent")
            return answer, took, len(told)

    answer, took, told = asyncio.run(go())
    assert answer is None and took < 1.0  # not the 5 s timeout
    assert told == 1


def test_close_says_farewell_and_publish_uses_the_protocol() -> None:
    async def script(ws: ServerConnection, received: list[dict[str, Any]]) -> None:
        async for text in ws:
            received.append(json.loads(text))

    async def go() -> list[dict[str, Any]]:
        async with scripted(script) as (url, received):
            proto = protocol()
            client = await RosbridgeClient.connect(url, proto)
            await client.open()
            await client.publish(FRAME_TOPIC, {"data": [1, 2]})
            await client.close(*proto.close_messages())
            await until(lambda: len(received) == 7)
            return received

    received = asyncio.run(go())
    assert [m["op"] for m in received] == [
        "advertise", "subscribe", "subscribe", "publish", "unsubscribe", "unsubscribe",
        "unadvertise",
    ]  # fmt: skip
    assert received[3] == {
        "op": "publish",
        "id": "publish:/nemesys/frame:4",
        "topic": FRAME_TOPIC,
        "msg": {"data": [1, 2]},
        "latch": False,
    }


def test_connecting_to_nothing_raises_for_the_caller_to_name() -> None:
    async def go() -> None:
        await RosbridgeClient.connect(f"ws://127.0.0.1:{free_port()}", protocol())

    with pytest.raises(OSError):
        asyncio.run(go())
