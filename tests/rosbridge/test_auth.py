"""The training bridge's ``auth`` op: the MAC, its validity, and a session that refuses
publishes until a client authenticates (subscribing stays open)."""

from __future__ import annotations

import json

from codec import encode_frame
from rosbridge.auth import AUTH_VALID_S, AuthGate, auth_message, check_auth
from rosbridge.session import ClientSession
from vehicle_contract.contract import FRAME_TOPIC, POSE_TOPIC

SECRET = "s" * 32
NOW_S = 1_800_000_000.0


def frame_publish() -> str:
    data = list(encode_frame("surface", {}).frame.to_bytes())
    return json.dumps({"op": "publish", "topic": FRAME_TOPIC, "msg": {"data": data}})


def test_a_message_from_the_secret_authenticates_within_its_validity() -> None:
    message = auth_message(SECRET, "nemesys-console", "ws://127.0.0.1:1", NOW_S)
    assert message["op"] == "auth" and message["end"] == NOW_S + AUTH_VALID_S
    assert check_auth(SECRET, message, NOW_S) is None
    assert check_auth(SECRET, message, NOW_S + AUTH_VALID_S) is None
    assert "validity" in (check_auth(SECRET, message, NOW_S + AUTH_VALID_S + 1) or "")
    assert "validity" in (check_auth(SECRET, message, NOW_S - 60) or "")


def test_a_wrong_secret_or_a_changed_field_is_refused() -> None:
    message = auth_message(SECRET, "nemesys-console", "ws://127.0.0.1:1", NOW_S)
    assert check_auth("t" * 32, message, NOW_S) == "auth refused: wrong mac"
    forged = {**message, "end": NOW_S + 10_000}
    assert check_auth(SECRET, forged, NOW_S) == "auth refused: wrong mac"
    missing = {k: v for k, v in message.items() if k != "rand"}
    assert "needs" in (check_auth(SECRET, missing, NOW_S) or "")
    assert check_auth(SECRET, {**message, "mac": 5}, NOW_S) == "auth refused: wrong mac"


def test_a_gated_session_refuses_publishes_until_auth() -> None:
    session = ClientSession(auth=AuthGate(SECRET, clock=lambda: NOW_S))
    refused = session.receive(frame_publish())
    assert len(refused) == 1 and refused[0].dropped and refused[0].frame is None
    assert "refused" in refused[0].logs[0].text and "auth first" in refused[0].logs[0].text
    # subscribing needs no auth
    sub = session.receive(json.dumps({"op": "subscribe", "topic": POSE_TOPIC}))
    assert not sub[0].dropped and session.is_subscribed(POSE_TOPIC)
    wrong = auth_message("t" * 32, "intruder", "ws://127.0.0.1:1", NOW_S)
    assert session.receive(json.dumps(wrong))[0].dropped
    assert session.receive(frame_publish())[0].frame is None
    good = auth_message(SECRET, "nemesys-console", "ws://127.0.0.1:1", NOW_S)
    assert session.receive(json.dumps(good)) == []  # accepted: nothing to log or send
    accepted = session.receive(frame_publish())
    assert accepted[0].frame == encode_frame("surface", {}).frame.to_bytes()


def test_without_a_secret_auth_is_an_unknown_op_as_on_the_real_server() -> None:
    session = ClientSession()
    out = session.receive(json.dumps({"op": "auth", "mac": "x"}))
    assert out[0].dropped and "auth" in out[0].logs[0].text
    assert session.receive(frame_publish())[0].frame is not None
