"""What a vehicle's ROS graph says about it, asked through rosapi, and THE rule that reads it.

The console's link (:mod:`station.link`) and ``nemesys vehicle-check``
(:mod:`station.vehicle_check`) both decide from :func:`verdict_of` what a vehicle can do.

In ROS 2 a topic exists while anything publishes or subscribes to it, and rosbridge's own node
publishes and subscribes for its clients (:mod:`rosbridge.bridge_node`): once the console (or
any observer) subscribes to ``/nemesys/mission``, ``/rosapi/topics`` lists it whether or not the
vehicle publishes it. So the listing says only the types; who is at the other end comes from
``/rosapi/publishers`` and ``/rosapi/subscribers``, leaving the bridge out:

* the onboard agent runs when ``/nemesys/mission`` and ``/nemesys/status`` have a publisher
  other than the bridge (with the contract's types);
* frames reach it over rosbridge when ``/nemesys/frame`` has a subscriber other than the bridge
  (a vehicle without one takes frames over its own ME receiver: "receiver-only");
* its telemetry is the pose and status that a node other than the bridge publishes;
* an optional contract topic (the datum) counts only when a node other than the bridge
  publishes it: the console subscribes to it, so on a vehicle without it the bridge's own
  subscription lists it.

:func:`read_graph` asks (five calls at once, plus one per connection to learn the bridge's
name); :func:`verdict_of` is the rule, with a finding per contract topic that names the nodes.
"""

from __future__ import annotations

import asyncio
from collections.abc import Awaitable, Callable, Mapping
from dataclasses import dataclass, field
from typing import Any, Final

from rosbridge.bridge_node import PUBLISHERS_SERVICE, bridge_topics, is_bridge, node_names
from rosbridge.client import topics_listing
from rosbridge.errors import InvalidData
from rosbridge.protocol import TOPICS_SERVICE, canonical_type, same_type
from rosbridge.subscriber_wait import SUBSCRIBERS_SERVICE
from rosbridge.transport import RosbridgeClient
from vehicle_contract.contract import (
    FRAME_TOPIC,
    MISSION_TOPIC,
    POSE_TOPIC,
    STATUS_TOPIC,
    TOPICS,
    Direction,
)

#: The contract topics the vehicle publishes (their publishers are asked), and those it
#: subscribes to (their subscribers are asked).
PUBLISHED: Final = tuple(t.name for t in TOPICS if t.direction is Direction.TO_CONSOLE)
SUBSCRIBED: Final = tuple(t.name for t in TOPICS if t.direction is Direction.TO_VEHICLE)


@dataclass(frozen=True)
class VehicleGraph:
    """rosapi's answers: the listing (``{topic: type}``, the names as the graph has them), the
    node names publishing each of :data:`PUBLISHED` and subscribing to each of
    :data:`SUBSCRIBED` (bridge included, as rosapi gives them; keyed by contract topic), the
    bridge's node names learnt on this connection, and ``names``: each contract topic's name
    on this vehicle (under its namespace, if any; absent: the contract's name)."""

    topics: Mapping[str, str]
    publishers: Mapping[str, tuple[str, ...]]
    subscribers: Mapping[str, tuple[str, ...]]
    bridges: frozenset[str] = frozenset()
    names: Mapping[str, str] = field(default_factory=dict)

    def name(self, topic: str) -> str:
        """Contract topic ``topic``'s name on this vehicle."""
        return self.names.get(topic, topic)

    def endpoints(self, topic: str) -> tuple[str, ...]:
        """Who is at the vehicle's end of a contract topic: its publishers for a topic the
        vehicle sends, its subscribers for the frame topic (bridge included)."""
        table = self.subscribers if topic in SUBSCRIBED else self.publishers
        return table.get(topic, ())

    def vehicle_nodes(self, topic: str) -> list[str]:
        """:meth:`endpoints` without rosbridge's own node."""
        return [n for n in self.endpoints(topic) if not is_bridge(n, self.bridges)]

    def bridge_nodes(self, topic: str) -> list[str]:
        return [n for n in self.endpoints(topic) if is_bridge(n, self.bridges)]


@dataclass(frozen=True)
class GraphUnknown:
    """Why the graph could not be read: the service, and what went wrong in words (naming
    it)."""

    service: str
    why: str

    def __str__(self) -> str:
        return self.why


@dataclass(frozen=True)
class Finding:
    """One contract topic as the graph shows it: ``ok`` when it has the contract's type and a
    node other than the bridge at the vehicle's end; ``reason`` says which, naming nodes."""

    ok: bool
    reason: str
    #: What is wrong in a few words (empty when ``ok``).
    short: str = ""


@dataclass(frozen=True)
class Verdict:
    """What the rule makes of a graph (see the module doc)."""

    findings: Mapping[str, Finding]
    #: The onboard agent publishes the acknowledgements and the status.
    agent: bool
    #: A node other than the bridge takes frames from the frame topic.
    frames: bool
    pose: bool
    status: bool
    #: For the operator, most important first (the console shows them, amber).
    problems: tuple[str, ...]

    @property
    def receiver_only(self) -> bool:
        """The agent answers over rosbridge but takes its frames elsewhere (its ME receiver)."""
        return self.agent and not self.frames


def _finding(graph: VehicleGraph, base: str, kind: str, sends: bool) -> Finding:
    role, verb, by, other = (
        ("publisher", "publishes", "published", "subscribes to")
        if sends
        else ("subscriber", "subscribes to", "subscribed", "publishes")
    )
    topic = graph.name(base)
    listed = graph.topics.get(topic)
    if listed is None:
        return Finding(False, f"no {topic} topic: no node {verb} it", f"no {topic} topic")
    if not same_type(listed, kind):
        wrong = f"{topic} is a {listed}, not a {canonical_type(kind)}: it is ignored"
        return Finding(False, wrong, wrong)
    nodes = graph.vehicle_nodes(base)
    if nodes:
        return Finding(True, f"{listed}, {by} by {', '.join(nodes)}")
    bridge = graph.bridge_nodes(base)
    if bridge:
        return Finding(
            False,
            f"{topic} has no {role} but rosbridge's own node ({', '.join(bridge)}), there for "
            "its clients: the topic exists only because a client uses it",
            f"only rosbridge {verb} {topic}",
        )
    return Finding(
        False,
        f"no node {verb} {topic} (it exists because something {other} it, such as rosbridge "
        "for its clients)",
        f"no node {verb} {topic}",
    )


def verdict_of(graph: VehicleGraph, *, frames_over_rosbridge: bool = True) -> Verdict:
    """THE rule (module doc). ``frames_over_rosbridge`` False: the console sends its frames
    another way (an ME modem), so a missing frame subscriber is no problem. ``findings`` has
    every required contract topic, and an optional one a node other than the bridge is at the
    vehicle's end of; keyed by contract topic."""
    findings = {
        t.name: _finding(graph, t.name, t.type, t.direction is Direction.TO_CONSOLE)
        for t in TOPICS
        if t.required or graph.vehicle_nodes(t.name)  # an optional one only if the vehicle's
    }
    ok = {name: f.ok for name, f in findings.items()}
    agent = ok[MISSION_TOPIC] and ok[STATUS_TOPIC]
    problems: list[str] = []
    if not agent:
        missing = [findings[t].short for t in (MISSION_TOPIC, STATUS_TOPIC) if not ok[t]]
        problems.append(
            f"no onboard agent ({'; '.join(missing)}): commands are sent as repeated copies "
            "without acknowledgement"
        )
    if frames_over_rosbridge and not ok[FRAME_TOPIC]:
        why = findings[FRAME_TOPIC].reason
        if agent:
            problems.append(
                f"receiver-only: {why}: the vehicle takes frames over its own ME receiver, so "
                "frames sent over rosbridge reach nothing; send through the ME modem"
            )
        else:
            problems.append(f"{why}: frames sent over rosbridge reach nothing")
    if not ok[POSE_TOPIC]:
        problems.append(f"{findings[POSE_TOPIC].reason}: the vehicle's position is not known")
    return Verdict(
        findings=findings,
        agent=agent,
        frames=ok[FRAME_TOPIC],
        pose=ok[POSE_TOPIC],
        status=ok[STATUS_TOPIC],
        problems=tuple(problems),
    )


# --- asking ---------------------------------------------------------------------------------


def _failed(service: str, answer: Mapping[str, Any] | None, timeout_s: float) -> str | None:
    """Why a service's answer is no answer (None when it is one)."""
    if answer is None:
        return f"no answer from {service} in {timeout_s:g} s (is rosapi running?)"
    if answer.get("result") is False:
        return f"{service} failed: {str(answer.get('values'))[:120]}"
    return None


async def read_graph(
    client: RosbridgeClient,
    timeout_s: float,
    bridges: frozenset[str] | None = None,
    names: Mapping[str, str] | None = None,
) -> VehicleGraph | GraphUnknown:
    """Ask rosapi for the listing and the contract topics' publishers and subscribers, each
    within ``timeout_s`` (all at once). ``bridges``: the bridge's node names learnt earlier on
    this connection; None asks who publishes its ``connected_clients``. ``names``: contract
    topic -> its name on this vehicle (a namespaced vehicle; default the contract's names).

    Raises:
        websockets.exceptions.ConnectionClosed: a request could not be sent.
    """
    named = dict(names or {})

    async def call(service: str, topic: str | None = None) -> dict[str, Any] | None:
        args = None if topic is None else {"topic": topic}
        return await client.call_service(service, args, timeout_s=timeout_s)

    listing_answer, *answers = await asyncio.gather(
        call(TOPICS_SERVICE),
        *(call(PUBLISHERS_SERVICE, named.get(t, t)) for t in PUBLISHED),
        *(call(SUBSCRIBERS_SERVICE, named.get(t, t)) for t in SUBSCRIBED),
    )
    why = _failed(TOPICS_SERVICE, listing_answer, timeout_s)
    if why is not None:
        return GraphUnknown(TOPICS_SERVICE, why)
    assert listing_answer is not None
    try:
        listing = topics_listing(listing_answer.get("values"))
    except InvalidData as error:
        return GraphUnknown(TOPICS_SERVICE, f"{TOPICS_SERVICE}: {error.reason}")
    asked = [(PUBLISHERS_SERVICE, "publishers", t) for t in PUBLISHED]
    asked += [(SUBSCRIBERS_SERVICE, "subscribers", t) for t in SUBSCRIBED]
    tables: dict[str, dict[str, tuple[str, ...]]] = {"publishers": {}, "subscribers": {}}
    for (service, key, topic), answer in zip(asked, answers, strict=True):
        why = _failed(service, answer, timeout_s)
        nodes = None if answer is None else node_names(answer.get("values"), key)
        if why is None and nodes is None:
            why = f"{service} answered without a list of {key}"
        if why is not None:
            return GraphUnknown(service, f"{why} (asked about {named.get(topic, topic)})")
        assert nodes is not None
        tables[key][topic] = tuple(nodes)
    if bridges is None:
        bridges = await _bridges(call, listing)
    return VehicleGraph(listing, tables["publishers"], tables["subscribers"], bridges, named)


_Call = Callable[[str, str | None], Awaitable[dict[str, Any] | None]]


async def _bridges(call: _Call, listing: Mapping[str, str]) -> frozenset[str]:
    """The nodes publishing a ``connected_clients`` topic: rosbridge servers, whatever their
    name (an unanswered question leaves the name rule alone)."""
    topics = bridge_topics(listing)
    answers = await asyncio.gather(*(call(PUBLISHERS_SERVICE, t) for t in topics))
    found: set[str] = set()
    for answer in answers:
        if answer is not None and answer.get("result") is not False:
            found.update(node_names(answer.get("values"), "publishers") or ())
    return frozenset(found)
