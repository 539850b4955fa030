"""Which node in rosapi's answers is rosbridge itself (:mod:`rosbridge.bridge_node`), and the
one-shot sender's wait for the frame topic's subscriber, which is not rosbridge's."""

from __future__ import annotations

from rosbridge.bridge_node import bridge_topics, is_bridge, node_names, others
from rosbridge.subscriber_wait import SubscriberWait


def test_the_bridge_by_name_in_any_namespace_or_known() -> None:
    assert is_bridge("/rosbridge_websocket")
    assert is_bridge("/boat1/rosbridge_websocket")
    assert not is_bridge("/rosbridge_websocket_relay")
    assert not is_bridge("/nemesys_vehicle")
    assert is_bridge("/boat1/bridge", ["/boat1/bridge"])
    assert others(["/a", "/rosbridge_websocket", "/b", "/x"], ["/x"]) == ["/a", "/b"]


def test_the_bridges_own_topic_in_a_listing() -> None:
    listing = {
        "/client_count": "std_msgs/msg/Int32",
        "/connected_clients": "rosbridge_msgs/msg/ConnectedClients",
        "/boat1/connected_clients": "rosbridge_msgs/ConnectedClients",
        "/nemesys/pose": "geometry_msgs/msg/PoseStamped",
    }
    assert bridge_topics(listing) == ["/connected_clients", "/boat1/connected_clients"]


def test_node_names_reads_a_list_of_strings_only() -> None:
    assert node_names({"publishers": ["/a"]}, "publishers") == ["/a"]
    assert node_names({"publishers": ["/a", 3]}, "publishers") is None
    assert node_names({"subscribers": []}, "publishers") is None
    assert node_names("nope", "publishers") is None


def answer(*nodes: str) -> dict[str, object]:
    return {"result": True, "values": {"subscribers": list(nodes)}}


def test_rosbridge_subscribing_for_its_clients_is_not_a_subscriber() -> None:
    wait = SubscriberWait("/nemesys/frame", 1.0, now_s=0.0)
    assert wait.ask(0.0)
    wait.answer(answer("/rosbridge_websocket"), 0.01)
    assert not wait.present and not wait.done(0.01)
    assert wait.ask(0.11)  # asked again after the poll period
    wait.answer(answer("/rosbridge_websocket", "/nemesys_vehicle"), 0.12)
    assert wait.present and wait.done(0.12)


def test_only_rosbridge_until_the_bound_warns() -> None:
    wait = SubscriberWait("/nemesys/frame", 0.5, now_s=0.0)
    wait.answer(answer("/rosbridge_websocket"), 0.0)
    assert wait.done(0.5) and not wait.present
    assert wait.warning == "no subscriber to /nemesys/frame after 0.5 s: the frame may be lost"
