"""The honest TCP modem (issue 21, item 7): a copy counts as sent only when the gateway took its
bytes and had not closed. Against loopback gateways that misbehave as real ones do
(tests/station/gateways.py): one that closes (or half-closes) after one frame, one that never
reads, one that goes away and comes back. Copies counted equal frames that reached the gateway;
a check sends no byte."""

from __future__ import annotations

from collections.abc import Callable, Iterator

import pytest

from codec import FRAME_BYTES, encode_frame
from station import transmit_tcp
from station.transmit import SendResult, TcpTransmitter, open_transmitter
from tests.station.gateways import Behaviour, Gateway

FRAME = encode_frame("circle", speed=0.5, depth=2, radius=5, direction="cw").frame


@pytest.fixture
def gateways() -> Iterator[list[Gateway]]:
    made: list[Gateway] = []
    yield made
    for g in made:
        g.close()


def gateway(made: list[Gateway], behaviour: Behaviour, *, one_connection: bool = False) -> Gateway:
    g = Gateway(behaviour, one_connection=one_connection)
    made.append(g)
    return g


def transmitter(g: Gateway, drain_timeout_s: float = 2.0) -> TcpTransmitter:
    tx = open_transmitter(g.target)
    assert isinstance(tx, TcpTransmitter)
    tx.drain_timeout_s = drain_timeout_s
    return tx


def closed(g: Gateway, n: int) -> Callable[[], bool]:
    """The condition: the gateway has closed ``n`` connections itself."""
    return lambda: g.closed_by_gateway == n


def sent(results: list[SendResult]) -> int:
    return sum(r.sent for r in results)


def test_a_working_gateway_gets_every_frame_on_one_connection(gateways: list[Gateway]) -> None:
    g = gateway(gateways, "read")
    with transmitter(g) as tx:
        results = [tx.send(FRAME) for _ in range(3)]
        g.wait_for("3 frames", lambda: sum(g.received) == 3 * FRAME_BYTES)
    assert all(r.ok and r.transport == "tcp" and r.target == g.target for r in results)
    assert g.frames() == sent(results) == tx.frames_sent == 3 and g.connections == 1


@pytest.mark.parametrize("behaviour", ["close", "half_close"])
def test_a_gateway_that_closes_after_each_frame_gets_each_copy_on_a_new_connection(
    gateways: list[Gateway], behaviour: Behaviour
) -> None:
    """Today's 4 counted, 1 received: the end of file is seen before the next write, the copy
    goes out on a new connection."""
    g = gateway(gateways, behaviour)
    results = []
    with transmitter(g) as tx:
        for _ in range(4):
            results.append(tx.send(FRAME))
            g.wait_for(f"the gateway closed {len(results)}", closed(g, len(results)))
    assert [r.ok for r in results] == [True] * 4, [r.detail for r in results]
    assert g.frames() == sent(results) == 4 and g.connections == 4


@pytest.mark.parametrize("behaviour", ["close", "half_close"])
def test_a_gateway_that_closes_and_stops_listening_counts_one(
    gateways: list[Gateway], behaviour: Behaviour
) -> None:
    g = gateway(gateways, behaviour, one_connection=True)
    with transmitter(g) as tx:
        first = tx.send(FRAME)
        g.wait_for("the gateway closed", lambda: g.closed_by_gateway == 1)
        rest = [tx.send(FRAME) for _ in range(3)]
    assert first.ok
    for r in rest:
        assert not r.sent and r.reason == "connection refused", r
        assert "closed the connection (end of file)" in r.detail or "refused" in r.detail
    assert "closed the connection (end of file)" in rest[0].detail
    assert g.frames() == sent([first, *rest]) == 1


def test_a_reset_while_the_frame_is_on_its_way_fails_the_copy(
    gateways: list[Gateway], monkeypatch: pytest.MonkeyPatch
) -> None:
    """The gateway's close crossing the write (the check before it saw nothing): its reset is
    seen while waiting for the acknowledgement."""
    g = gateway(gateways, "close", one_connection=True)
    with transmitter(g) as tx:
        assert tx.send(FRAME).ok
        g.wait_for("the gateway closed", lambda: g.closed_by_gateway == 1)
        monkeypatch.setattr(transmit_tcp, "_peer_gone", lambda _sock: None)
        crossed = tx.send(FRAME)
    assert not crossed.sent and crossed.reason in ("connection reset", "connection closed")
    assert "on its way" in crossed.detail
    assert g.frames() == 1


@pytest.mark.slow  # some 90 frames, each acknowledged after the gateway's delayed ACK (40 ms)
def test_a_gateway_that_never_reads_is_found_when_its_buffer_is_full(
    gateways: list[Gateway],
) -> None:
    """Copies count while the gateway's kernel takes them; the first one it does not take
    whole within the bound fails, and the connection is reset so the rest never arrives."""
    g = gateway(gateways, "never_read")
    results: list[SendResult] = []
    with transmitter(g, drain_timeout_s=0.3) as tx:
        while len(results) < 2000 and (not results or results[-1].ok):
            results.append(tx.send(FRAME))
        last = results[-1]
        assert not last.sent and last.reason == "gateway not reading", last
        assert "not acknowledged by the gateway within 0.3 s" in last.detail
        assert not tx.connected
    assert sent(results) == len(results) - 1 > 0
    # what it holds is what was counted, and at most a part of the copy that failed
    assert g.frames() == sent(results)
    partial = g.total() - FRAME_BYTES * sent(results)
    if partial:
        assert f"it took {partial} of the frame's 13: a partial frame" in last.detail


def test_a_check_sends_nothing_and_follows_the_gateway_away_and_back(
    gateways: list[Gateway],
) -> None:
    g = gateway(gateways, "read")
    with transmitter(g) as tx:
        ok = tx.check()
        assert ok.ok and ok.what == "modem" and ok.target == g.target and ok.reason is None
        g.wait_for("the connection", lambda: g.connections == 1)
        assert tx.connected
        assert tx.check().ok and g.connections == 1  # the kept connection is checked
        g.stop()
        away = tx.check()
        assert not away.ok and away.reason == "connection refused", away
        assert "closed the connection" in away.detail and not tx.connected
        assert not tx.check().ok
        g.restart()
        back = tx.check()
        assert back.ok and tx.connected
        assert tx.send(FRAME).ok
        g.wait_for("the frame", lambda: g.total() == FRAME_BYTES)
    assert g.connections == 2 and tx.frames_sent == 1  # the only byte: the frame's


def test_a_check_of_a_gateway_that_never_reads_passes_until_its_buffer_is_full(
    gateways: list[Gateway],
) -> None:
    """A check writes nothing: a gateway that never reads passes it (TCP cannot tell)."""
    g = gateway(gateways, "never_read")
    with transmitter(g) as tx:
        assert tx.check().ok
    assert g.total() == 0


def test_a_refused_gateway_is_connection_refused(gateways: list[Gateway]) -> None:
    g = gateway(gateways, "read")
    g.stop()
    with transmitter(g) as tx:
        result = tx.send(FRAME)
        check = tx.check()
    assert not result.sent and result.reason == "connection refused"
    assert f"connecting to 127.0.0.1:{g.port}" in result.detail
    assert not check.ok and check.reason == "connection refused"
