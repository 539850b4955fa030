"""Topic names under a vehicle namespace (one function builds them), and what the contract
states beyond the topics: the conventions, the acknowledgement deadline, the datum and the
fields 2.0 added (vehicle side: no console package needed)."""

from __future__ import annotations

from typing import Any

import pytest

from vehicle_contract import codes, contract, payloads
from vehicle_contract.contract import (
    DATUM_TOPIC,
    FRAME_TOPIC,
    MISSION_TOPIC,
    POSE_TOPIC,
    STATUS_TOPIC,
)
from vehicle_contract.names import check_namespace, contract_topic_of, topic_name, topic_names


@pytest.mark.parametrize(
    ("given", "normal"),
    [("", ""), ("/", ""), ("auv1", "/auv1"), ("/auv1", "/auv1"), ("/auv1/", "/auv1"),
     ("fleet/auv_2", "/fleet/auv_2"), ("_x", "/_x")],
)  # fmt: skip
def test_namespaces_are_normalised(given: str, normal: str) -> None:
    assert check_namespace(given) == normal


@pytest.mark.parametrize("bad", ["auv-1", "1auv", "a//b", "a b", "ä"])
def test_a_namespace_that_is_no_ros_name_is_refused_saying_what_is_allowed(bad: str) -> None:
    with pytest.raises(ValueError, match="letter or an underscore"):
        check_namespace(bad)


def test_every_contract_topic_goes_under_the_namespace() -> None:
    assert topic_name(POSE_TOPIC) == POSE_TOPIC
    assert topic_name(POSE_TOPIC, "") == "/nemesys/pose"
    assert topic_name(MISSION_TOPIC, "auv1") == "/auv1/nemesys/mission"
    names = topic_names("/fleet/auv1/")
    assert names.namespace == "/fleet/auv1"
    assert (names.frame, names.pose, names.mission, names.status, names.datum) == tuple(
        f"/fleet/auv1{t}"
        for t in (FRAME_TOPIC, POSE_TOPIC, MISSION_TOPIC, STATUS_TOPIC, DATUM_TOPIC)
    )
    assert topic_names() == topic_names("")
    assert topic_names().frame == FRAME_TOPIC
    with pytest.raises(KeyError):
        topic_name("/nemesys/other", "auv1")


def test_a_namespaced_name_is_traced_back_to_its_contract_topic() -> None:
    for t in contract.TOPICS:
        assert contract_topic_of(t.name) == t.name
        assert contract_topic_of(topic_name(t.name, "fleet/auv1")) == t.name
    for bad in ("/nemesys/other", "/auv-1/nemesys/pose", "auv1/nemesys/pose", "/x/nemesys"):
        with pytest.raises(KeyError):
            contract_topic_of(bad)


# --- what 2.0 states -------------------------------------------------------------------------


def test_the_contract_states_its_conventions_and_deadline() -> None:
    doc = contract.contract_json()
    assert doc["version"] == contract.CONTRACT_VERSION == "2.1.0"  # 2.1: addresses (optional)
    assert doc["ack_deadline_s"] == contract.ACK_DEADLINE_S == codes.ACK_DEADLINE_S == 1.0
    conventions = doc["conventions"]
    assert "true (geographic) north" in conventions["heading"]
    assert "below the water surface, positive down" in conventions["depth"]
    assert "FRD" in conventions["body frame"]
    assert DATUM_TOPIC in conventions["datum"]
    assert "navigation solution" in doc["time_base"]["pose stamp"]
    obligations = " ".join(doc["obligations"])
    for words in (
        "no_navigation",
        "late: true",
        "recent_acks",
        "frame_input receiver",
        "nav_fault",
    ):
        assert words in obligations, words
    datum = contract.topic(DATUM_TOPIC)
    assert (datum.qos.durability, datum.qos.depth, datum.required) == (
        contract.Durability.TRANSIENT_LOCAL,
        1,
        False,
    )
    assert set(payloads.SCHEMAS) == {"ack", "status", "datum"}
    assert codes.NO_NAVIGATION in codes.REJECT_REASONS
    assert codes.Mode.NAV_FAULT.value in codes.MODES


ACK: dict[str, Any] = {
    "seq": 3,
    "t_s": 12.0,
    "outcome": "rejected",
    "frame_hex": "aaaa7c3141c46000000d50840",
    "reason": "no_navigation",
    "detail": "navigation stale",
    "command": {"pattern": "circle", "pattern_id": 3, "params": {"speed": 0.2, "depth": 2.0,
                "radius": 3.0, "direction": "cw"}},
    "duplicate": False,
    "active": None,
    "from": None,
    "late": False,
}  # fmt: skip


def test_the_new_fields_validate_and_are_checked() -> None:
    assert payloads.validate_ack(ACK) == []
    assert payloads.validate_ack({**ACK, "late": "no"}) != []
    status = {
        "t_s": 13.0,
        "depth_m": None,
        "heading_deg": None,
        "speed_mps": None,
        "battery_pct": 50.0,
        "mode": "nav_fault",
        "pattern": "circle",
        "nav_valid": False,
        "nav_age_s": 3.5,
        "frame_input": "receiver",
        "recent_acks": [ACK],
    }
    assert payloads.validate_status(status) == []
    problems = payloads.validate_status({**status, "recent_acks": [{**ACK, "outcome": "maybe"}]})
    assert problems and "recent_acks" in problems[0]
    assert payloads.validate_status({**status, "recent_acks": [ACK] * 11}) != []
    assert payloads.validate_status({**status, "frame_input": "serial"}) != []
    datum = {"t_s": 1.0, "lat_deg": 29.5, "lon_deg": -82.3, "source": "parameters"}
    assert payloads.validate_datum(datum) == []
    assert payloads.validate_datum({**datum, "odometry_origin": None}) == []
    for bad in ({"lat_deg": 91.0}, {"source": "gps"}, {"lon_deg": None}):
        assert payloads.validate_datum({**datum, **bad}) != [], bad
    assert any("source" in p for p in payloads.validate_datum({**datum, "source": "gps"}))
