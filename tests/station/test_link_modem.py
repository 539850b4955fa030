"""The console's modem link and hybrid link (issue 21, items 6 and 7), on loopback gateway
doubles (tests/station/gateways.py) and the rosbridge stand-in (tests/fake_vehicle.py).

* The modem link's health follows the gateway without a command: it goes away (red, naming
  why) and comes back (connected again), and the gateway gets not one byte; "test link" sends
  nothing either.
* A frame that did not leave is named among the problems until one leaves.
* The hybrid link: frames over the modem only, its capability the rosbridge's while that is
  up, one-way (naming why) when it is down.
"""

from __future__ import annotations

import asyncio
import json
import time
from collections.abc import Callable, Iterator

import pytest

from codec import FRAME_BYTES, encode_frame
from station.link import Capability
from station.link_modem import HybridLink, ModemLink, open_link, parse_telemetry
from tests.fake_vehicle import AGENT, STRING_TYPE, WITH_AGENT, GraphNode, Rosbridge
from tests.station.gateways import Gateway

FRAME = encode_frame("circle", speed=0.5, depth=2, radius=5, direction="cw").frame
QUICK = {"probe_s": 0.05, "backoff_s": 0.02, "max_backoff_s": 0.1}


@pytest.fixture
def gateway() -> Iterator[Gateway]:
    g = Gateway("read")
    yield g
    g.close()


async def until(what: str, check: Callable[[], object], timeout_s: float = 10.0) -> None:
    """Wait on the event loop until ``check()`` is true."""
    deadline = time.monotonic() + timeout_s
    while not check():
        if time.monotonic() > deadline:
            raise AssertionError(f"timed out after {timeout_s} s waiting for {what}")
        await asyncio.sleep(0.01)


def test_the_health_follows_a_gateway_away_and_back_without_a_frame(gateway: Gateway) -> None:
    async def scenario() -> None:
        link = ModemLink(gateway.target, 36_000, **QUICK)
        assert not link.connected and "connecting" in (link.connection_problem or "")
        await link.start()
        try:
            assert link.connected  # start checked it
            assert link.connection_problem is None and link.capability is Capability.NONE
            await asyncio.to_thread(gateway.wait_for, "accepted", lambda: gateway.connections == 1)
            await asyncio.to_thread(gateway.stop)
            await until("the gateway seen gone", lambda: not link.connected)
            await until("refused", lambda: "connection refused" in (link.connection_problem or ""))
            assert gateway.target in (link.connection_problem or "")
            await asyncio.to_thread(gateway.restart)
            await until("connected again", lambda: link.connected)
            assert link.connection_problem is None
            (check,) = await link.test()
            assert check.ok and check.what == "modem" and check.target == gateway.target
        finally:
            await link.stop()

    asyncio.run(scenario())
    gateway.wait_for("the second connection accepted", lambda: gateway.connections == 2)
    assert gateway.total() == 0  # not one byte: the watch and the test send nothing


def test_test_link_names_why_when_the_gateway_is_not_there(gateway: Gateway) -> None:
    gateway.stop()

    async def scenario() -> None:
        link = ModemLink(gateway.target, 36_000)
        (check,) = await link.test()  # not started: the test opens the modem itself
        assert not check.ok and check.reason == "connection refused"
        assert not link.connected and "connection refused" in (link.connection_problem or "")

    asyncio.run(scenario())


def test_a_frame_that_did_not_leave_is_named_until_one_leaves() -> None:
    g = Gateway("close", one_connection=True)

    async def scenario() -> None:
        link = ModemLink(g.target, 36_000, **QUICK)
        assert await link.transmit(FRAME) is None
        await asyncio.to_thread(g.wait_for, "the close", lambda: g.closed_by_gateway == 1)
        reason = await link.transmit(FRAME)
        assert reason == "connection refused"
        assert not link.connected
        failed = [p for p in link.capability_problems if "the last frame did not reach" in p]
        assert failed and "closed the connection (end of file)" in failed[0]
        g.restart()  # listening again (each connection still closed after one frame)
        await link.start()
        await until("connected again", lambda: link.connected)
        assert failed[0] in link.capability_problems  # the watch does not clear it
        assert await link.transmit(FRAME) is None
        assert link.last_failure is None and link.capability_problems == [
            link.capability_problems[0]
        ]
        await link.stop()

    try:
        asyncio.run(scenario())
        g.wait_for("two frames", lambda: g.total() == 2 * FRAME_BYTES)
    finally:
        g.close()


def test_the_hybrid_link_takes_its_capability_from_the_rosbridge(gateway: Gateway) -> None:
    bridge = Rosbridge(WITH_AGENT).start()
    stopped = False

    def stop_bridge() -> None:
        nonlocal stopped
        if not stopped:
            stopped = True
            bridge.stop()

    try:

        async def scenario() -> None:
            link = open_link(gateway.target, 36_000, bridge.url)
            assert isinstance(link, HybridLink) and link.telemetry_target == bridge.url
            poses: list[object] = []
            link.on_pose = poses.append
            await link.start()
            try:
                await until("two-way", lambda: link.capability is Capability.ACKS_AND_TELEMETRY)
                assert link.acknowledges and link.telemetry and link.connected
                await until("a pose through the hybrid link", lambda: poses)
                assert await link.transmit(FRAME) is None
                checks = await link.test()
                assert [(c.what, c.ok) for c in checks] == [("modem", True), ("telemetry", True)]
                await asyncio.to_thread(stop_bridge)
                await until("one-way", lambda: link.capability is Capability.NONE)
                assert not link.acknowledges and link.connected  # the modem is still there
                (problem,) = link.capability_problems
                assert problem.startswith("no telemetry: ") and "one-way copies" in problem
                assert bridge.url in problem
                checks = await link.test()
                assert [(c.what, c.ok) for c in checks] == [("modem", True), ("telemetry", False)]
            finally:
                await link.stop()

        asyncio.run(scenario())
    finally:
        stop_bridge()
    gateway.wait_for("the frame", lambda: gateway.total() == FRAME_BYTES)
    assert bridge.frame_count() == 0 and "advertise" not in bridge.ops()  # frames: modem only


def test_the_hybrid_link_reads_a_receiver_only_vehicle_under_its_namespace(
    gateway: Gateway,
) -> None:
    """The vehicle of the hybrid link takes its frames by its own ME receiver (no frame
    subscriber) under /auv1: acknowledgements expected, no problem named, every topic read
    under the namespace, the datum passed on to the console."""
    node = GraphNode(
        "/auv1/nemesys_vehicle",
        {
            **{f"/auv1{name}": kind for name, kind in AGENT.publishes.items()},
            "/auv1/nemesys/datum": STRING_TYPE,
        },
        best_effort=frozenset({"/auv1/nemesys/pose"}),
    )
    bridge = Rosbridge((node,)).start()
    datum = {"lat_deg": 43.1, "lon_deg": 5.9, "source": "settings"}
    try:

        async def scenario() -> None:
            link = open_link(gateway.target, 36_000, bridge.url, namespace="auv1")
            heard: list[dict[str, object]] = []
            link.on_datum = heard.append
            await link.start()
            try:
                await until("two-way", lambda: link.capability is Capability.ACKS_AND_TELEMETRY)
                assert link.capability_problems == []
                # the capability comes from the graph, read before the subscriptions: publish
                # once the datum's subscription is in (the vehicle's node re-sends it anyway)
                await until(
                    "the datum's subscription",
                    lambda: any(
                        m.get("op") == "subscribe" and m.get("topic") == "/auv1/nemesys/datum"
                        for m in list(bridge.received)
                    ),
                )
                message = {"data": json.dumps(datum)}
                await asyncio.to_thread(bridge.publish, "/auv1/nemesys/datum", message)
                await until("the datum", lambda: heard)
                assert heard == [datum]
            finally:
                await link.stop()

        asyncio.run(scenario())
    finally:
        bridge.stop()
    subscribed = {m["topic"] for m in bridge.received if m.get("op") == "subscribe"}
    assert subscribed == {f"/auv1/nemesys/{t}" for t in ("pose", "status", "mission", "datum")}


@pytest.mark.parametrize(
    ("url", "problem"),
    [
        ("vehicle:9090", "no scheme"),
        ("tcp://vehicle:9090", "the scheme must be ws:// or wss://"),
        ("ws://:9090", "no host"),
        ("ws://vehicle:99999", "the port must be a number"),
    ],
)
def test_a_bad_telemetry_url_names_the_problem_and_the_forms(url: str, problem: str) -> None:
    with pytest.raises(ValueError, match="bad telemetry url") as caught:
        parse_telemetry(url)
    assert problem in str(caught.value) and "ws://host:port[/path]" in str(caught.value)


def test_telemetry_is_only_for_a_modem_target() -> None:
    with pytest.raises(ValueError, match="telemetry is for an ME modem target"):
        open_link("ws://vehicle:9090", 36_000, "ws://vehicle:9090")
    assert type(open_link("loop://", 36_000)) is ModemLink
