"""The BER estimate in the console: fed by every acknowledgement (the command manager), shown
in the link's health, reset with the dive; ``PUT /api/link``'s ``copies_from`` (its refusals,
its event in the mission log, the copies it gives); and, in training, the estimate beside the
emulated channel's BER end to end (the coverage study over many runs is
tests/bench/test_channel_estimate.py)."""

from __future__ import annotations

from typing import Any

import pytest
from fastapi.testclient import TestClient

from backend.mission_log.store import LogWriteError
from codec import FRAME_BITS, SYNC_BITS, copies_for, encode_frame
from onboard.agent import OnboardAgent
from onboard.guidance import Guidance
from planner import VehicleState
from station.channel_estimate import MIN_FRAMES, ChannelEstimator, estimate_ber
from station.link import Capability
from tests.agent_link import AgentLink
from tests.backend.conftest import (
    AUTH,
    CIRCLE,
    FINAL,
    MakeClient,
    MakeLightClient,
    console_of,
    loc_of,
    send,
    wait_state,
    wait_until,
)

DEFAULT_BER = 1e-3  # the link_ber setting's default


def link(client: TestClient) -> dict[str, Any]:
    body: dict[str, Any] = client.get("/api/vehicle").json()["link"]
    return body


def damaged_acks(count: int, codeword_errors: int) -> list[dict[str, Any]]:
    """The onboard agent's acknowledgements of ``count`` circle frames, each with
    ``codeword_errors`` codeword bits flipped (3 or more: refused by the decoder)."""
    frame = encode_frame("circle", **CIRCLE).frame
    agent = OnboardAgent(Guidance())
    acks = []
    for i in range(count):
        flips = [SYNC_BITS + (i + 7 * j) % 72 for j in range(codeword_errors)]
        value = frame.value
        for bit in flips:
            value ^= 1 << (FRAME_BITS - 1 - bit)
        acks.append(agent.receive(value, FRAME_BITS, VehicleState(0.0, 0.0, 2.0))[0])
    return acks


def feed(client: TestClient, acks: list[dict[str, Any]]) -> None:
    """Acknowledgements as the link delivers them: to the command manager, on the app's loop."""
    cm = console_of(client).commands
    assert cm is not None
    for ack in acks:
        client.portal.call(cm.on_mission, ack)  # type: ignore[union-attr]


def events(client: TestClient, kind: str) -> list[dict[str, Any]]:
    console = console_of(client)
    assert console.log is not None
    return [e for e in console.log.events(console.dive) if e["kind"] == kind]


# --- the estimate in the link's health -------------------------------------------------------


def test_every_acknowledgement_feeds_the_estimate_shown_in_the_link_health(
    client: TestClient,
) -> None:
    fresh = link(client)["channel"]
    assert fresh == {
        "frames": 0,
        "min_frames": MIN_FRAMES,
        "ber": None,
        "low": None,
        "high": None,
        "confidence": 0.95,
        "not_decoded": 0,
        "ignored": 0,
    }
    for _ in range(2):  # through the in-memory vehicle: clean frames, acknowledged
        wait_state(client, send(client)["id"], FINAL)
    channel = wait_until(lambda: (c := link(client)["channel"])["frames"] == 2 and c)
    assert channel["ber"] is None  # fewer than MIN_FRAMES: no estimate yet
    acks = damaged_acks(MIN_FRAMES, 1) + damaged_acks(2, 3)
    feed(client, acks)
    channel = link(client)["channel"]
    assert channel["frames"] == 2 + MIN_FRAMES + 2 and channel["not_decoded"] == 2
    expected = ChannelEstimator()
    for ack in [{"outcome": "accepted", "corrected_bits": 0, "sync_errors": 0}] * 2 + acks:
        expected.observe(ack)
    est = expected.estimate()
    assert est is not None
    assert (channel["ber"], channel["low"], channel["high"]) == (est.ber, est.low, est.high)
    assert channel["low"] < channel["ber"] < channel["high"]


# --- PUT /api/link copies_from ---------------------------------------------------------------


@pytest.mark.parametrize("value", ["upper", "ESTIMATE_UPPER", 1, True, ["assumed"]])
def test_copies_from_refuses_anything_else_naming_what_is_allowed(
    client: TestClient, value: object
) -> None:
    r = client.put("/api/link", json={"copies_from": value}, headers=AUTH)
    assert r.status_code == 422, r.text
    assert loc_of(r.json()) == ["body", "copies_from"]
    msg = r.json()["detail"][0]["msg"]
    assert 'copies_from must be "assumed" or "estimate_upper"' in msg
    assert link(client)["copies_from"] == "assumed" and events(client, "copies_from") == []


def test_the_estimates_upper_bound_is_an_explicit_logged_choice(
    make_light_client: MakeLightClient,
) -> None:
    vehicle = AgentLink()
    client = make_light_client(vehicle)
    assert client.put("/api/link", json={"copies_from": "estimate_upper"}).status_code == 401
    r = client.put("/api/link", json={"copies_from": "estimate_upper"}, headers=AUTH)
    assert r.status_code == 200, r.text
    # no estimate yet: the assumed BER, and the health says which it is
    body = r.json()
    assert body["copies_from"] == "estimate_upper" and body["ber_source"] == "assumed"
    assert body["ber"] == DEFAULT_BER
    (event,) = events(client, "copies_from")
    assert event["data"] == {
        "operator": "operator",
        "copies_from": "estimate_upper",
        "was": "assumed",
    }
    assert event["detail"].startswith("operator chose") and "upper end" in event["detail"]

    feed(client, damaged_acks(4 * MIN_FRAMES, 2) + damaged_acks(5, 3))
    health = link(client)
    high = health["channel"]["high"]
    assert health["ber_source"] == "estimate_upper" and health["ber"] == high > DEFAULT_BER
    # the copies follow it as soon as they depend on the BER: the acknowledgements stop
    vehicle.capability = Capability.NONE
    target = health["delivery_target"]
    assert link(client)["copies"] == copies_for(high, target) > copies_for(DEFAULT_BER, target)
    record = send(client)
    assert record["ber"] == high and record["copies"] == copies_for(high, target)

    # the same choice again changes nothing and logs nothing; back to the assumed BER logs
    client.put("/api/link", json={"copies_from": "estimate_upper"}, headers=AUTH)
    assert len(events(client, "copies_from")) == 1
    back = client.put("/api/link", json={"copies_from": "assumed"}, headers=AUTH).json()
    assert back["ber_source"] == "assumed" and back["ber"] == DEFAULT_BER
    assert [e["data"]["copies_from"] for e in events(client, "copies_from")] == [
        "estimate_upper",
        "assumed",
    ]


def test_a_choice_the_log_cannot_keep_is_not_applied(
    client: TestClient, monkeypatch: pytest.MonkeyPatch
) -> None:
    log = console_of(client).log
    assert log is not None

    def refuse(*_args: object) -> dict[str, Any]:
        raise LogWriteError("disk I/O error")

    monkeypatch.setattr(log, "add_event", refuse)
    body = {"copies_from": "estimate_upper", "link_ber": 0.01}
    r = client.put("/api/link", json=body, headers=AUTH)
    assert r.status_code == 503 and "nothing was changed" in r.json()["detail"]
    after = link(client)
    assert after["copies_from"] == "assumed" and after["ber"] == DEFAULT_BER


# --- training: the estimate beside the emulated channel --------------------------------------


def test_in_training_the_estimate_stands_beside_the_emulated_ber(make_client: MakeClient) -> None:
    """Frames through the simulator's emulated channel at BER 0.02 (its seed is the settings',
    so the run is the same every time): the console's estimate rests on every acknowledgement
    the simulated vehicle sent, equals the estimate recomputed from them, and its interval
    holds the emulated BER; the copies keep following the emulated BER; a reset starts the
    estimate again."""
    client = make_client(max_sends_per_minute=600)
    r = client.put("/api/training/channel", json={"ber": 0.02}, headers=AUTH)
    assert r.status_code == 200, r.text
    r = client.put("/api/link", json={"copies_from": "estimate_upper"}, headers=AUTH)
    assert r.status_code == 409 and "/api/training/channel" in r.json()["detail"]
    frames = 25
    for _ in range(frames):
        wait_state(client, send(client)["id"], FINAL)
    channel = wait_until(lambda: (c := link(client)["channel"])["frames"] == frames and c)
    sim = console_of(client).sim
    assert sim is not None
    acks = list(sim.acks)
    assert len(acks) == frames
    expected = ChannelEstimator()
    for ack in acks:
        expected.observe(ack)
    est = estimate_ber(expected.counts)
    assert est is not None and channel["ber"] == est.ber
    assert channel["low"] <= 0.02 <= channel["high"]
    health = link(client)
    assert health["ber"] == 0.02 and health["ber_source"] == "emulated"
    assert health["copies_from"] == "assumed"

    assert client.post("/api/training/reset", headers=AUTH).status_code == 200
    assert link(client)["channel"]["frames"] == 0
