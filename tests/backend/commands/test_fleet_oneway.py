"""A fleet of three on a one-way ME modem (issue 23): the console against a loopback TCP gateway
(as the modem's own tests: ``tests/station/gateways.py``), every frame it received decoded with
the codec to read its address and command.

On the wire: the copies of the three vehicles' commands interleave (a frame at a time, each
command's copies spaced); no frame of an older command for a vehicle leaves after the first
frame of a newer one for it (address 0, Surface to all, is every vehicle's); and the records'
copies are the frames the gateway got."""

from __future__ import annotations

import threading
from collections.abc import Iterator
from typing import Any

import pytest
from fastapi.testclient import TestClient

from codec import ADDRESSED_FRAME_BYTES, decode_addressed_frame
from station.link_fleet import open_fleet_link
from tests.backend.conftest import (
    AUTH,
    CIRCLE,
    SQUARE,
    MakeLightClient,
    wait_state,
    wait_until,
)
from tests.station.gateways import Gateway
from vehicle_contract.fleet import parse_vehicles

FLEET = parse_vehicles("3")
HOVER: dict[str, Any] = {"duration": 60, "depth": 3, "heading": 90}


class Wire:
    """What the gateway received, decoded: ``(address, pattern, params)`` per frame."""

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._frames: list[tuple[int, str, dict[str, Any]]] = []
        self.undecoded: list[str] = []

    def take(self, data: bytes) -> None:
        try:
            d = decode_addressed_frame(data)
        except ValueError as err:  # a DecodeError: the wire carried something else
            with self._lock:
                self.undecoded.append(f"{data.hex()}: {err}")
            return
        with self._lock:
            self._frames.append((d.address, d.command.pattern.name, dict(d.command.params)))

    def frames(self) -> list[tuple[int, str, dict[str, Any]]]:
        with self._lock:
            return list(self._frames)


@pytest.fixture
def wire() -> Iterator[tuple[Gateway, Wire]]:
    got = Wire()
    gateway = Gateway("read", on_frame=got.take, frame_bytes=ADDRESSED_FRAME_BYTES)
    try:
        yield gateway, got
    finally:
        gateway.close()
        assert not got.undecoded, f"bytes the gateway could not decode: {got.undecoded}"


def post(client: TestClient, body: dict[str, Any], path: str = "/api/commands") -> dict[str, Any]:
    r = client.post(path, json=body, headers=AUTH)
    assert r.status_code == 202, r.text
    out: dict[str, Any] = r.json()
    return out


def command(vehicle: str, pattern: str, params: dict[str, Any], copies: int) -> dict[str, Any]:
    return {"pattern": pattern, "params": params, "vehicle": vehicle, "copies": copies}


def key(record: dict[str, Any]) -> tuple[int, str, dict[str, Any]]:
    """A record's frame as the wire carries it: (address, pattern, params)."""
    d = decode_addressed_frame(record["hex"])
    return d.address, d.command.pattern.name, dict(d.command.params)


def test_one_way_modem_with_three_addresses_interleaves_and_never_sends_an_older_command_late(
    make_light_client: MakeLightClient, wire: tuple[Gateway, Wire]
) -> None:
    gateway, got = wire
    # the modem's watch quick, as the modem link's own tests have it
    link = open_fleet_link(
        gateway.target, 36_000, FLEET, probe_s=0.05, backoff_s=0.02, max_backoff_s=0.1
    )
    client = make_light_client(
        link,  # type: ignore[arg-type]  # a fleet's link (the fixture's type names the single one)
        vehicles="3",
        target=gateway.target,
        copy_interval_s=0.05,
        surface_repeat_s=0.05,
        link_ber=1e-2,
    )
    assert all(not v["link"]["acknowledges"] for v in client.get("/api/vehicles").json())
    sent = [  # in the order sent: each a vehicle's newer command than the one before it
        post(client, command("auv1", "circle", CIRCLE, 6)),
        post(client, command("auv2", "hover", HOVER, 6)),
        post(client, command("auv3", "square", SQUARE, 6)),
    ]
    wait_until(lambda: len(got.frames()) >= 4, what="the copies under way")
    sent.append(post(client, command("auv1", "square", SQUARE, 4)))  # supersedes auv1's circle
    wait_until(lambda: len(got.frames()) >= 8, what="more copies")
    surface = post(client, {"vehicle": "all"}, "/api/surface")["commands"]
    sent.append(surface[0])  # one frame for all three
    wait_until(lambda: len(got.frames()) >= 10, what="the Surface under way")
    sent.append(post(client, command("auv3", "hover", HOVER, 3)))  # splits the Surface
    records = [*sent[:-2], *surface, sent[-1]]
    ended = [wait_state(client, r["id"], timeout_s=30) for r in records]
    wait_until(lambda: not client.get("/api/transmitter").json()["queued"], what="all out")
    frames = got.frames()

    # the three vehicles' copies interleave: their first copies leave before any second
    firsts = [frames.index(key(r)) for r in sent[:3]]
    seconds = [frames.index(key(r), f + 1) for r, f in zip(sent[:3], firsts, strict=True)]
    assert max(firsts) < min(seconds), frames

    # no frame of an older command for a vehicle after the first of a newer one for it
    for address in (1, 2, 3):
        mine = [key(r) for r in sent if key(r)[0] in (0, address)]
        for i, older in enumerate(mine):
            for newer in mine[i + 1 :]:
                first_newer = frames.index(newer)
                late = [k for k, f in enumerate(frames) if f == older and k > first_newer]
                assert not late, f"vehicle {address}: {older} at {late} after {newer}"

    # the Surface to all went on addressed to auv1 and auv2 alone once auv3 had a newer one
    after = frames.index(key(sent[-1]))
    assert not [f for f in frames[after:] if f[0] == 0]
    assert {f[0] for f in frames[after:] if f[1] == "surface"} <= {1, 2}
    states = {r["id"]: e["state"] for r, e in zip(records, ended, strict=True)}
    assert states[sent[0]["id"]] == "superseded" and states[surface[2]["id"]] == "superseded"
    assert states[surface[0]["id"]] == states[surface[1]["id"]] == "sent"

    # every copy the log counts reached the gateway: a command's, its own frames; a vehicle's
    # Surface record, the address-0 frames and those addressed to it alone
    counted = {r["id"]: e["copies_sent"] for r, e in zip(records, ended, strict=True)}
    for r in records:
        address, pattern, _ = key(r)
        if pattern == "surface":
            vehicle = next(v.address for v in FLEET if v.name == r["vehicle"])
            on_wire = sum(f[1] == "surface" and f[0] in (0, vehicle) for f in frames)
        else:
            on_wire = frames.count(key(r))
        assert counted[r["id"]] == on_wire, (r["vehicle"], pattern)
    print("\n".join(f"{i:2d} to {a} {p}" for i, (a, p, _) in enumerate(frames)))
