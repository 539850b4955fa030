"""The contract's topic names under a vehicle namespace: the one place they are built.

Several vehicles share one ROS graph by namespace: every contract topic of a vehicle under
``auv1`` is ``/auv1/nemesys/...`` (the reference node's ``vehicle_namespace`` parameter, the
console's ``NEMESYS_VEHICLE_NAMESPACE``); without one the names are the contract's
(:data:`vehicle_contract.contract.TOPICS`). The console, the transmitter, ``vehicle-check``
and the node all take their names from :func:`topic_names`.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from typing import Final

from vehicle_contract.contract import (
    DATUM_TOPIC,
    FRAME_TOPIC,
    MISSION_TOPIC,
    POSE_TOPIC,
    STATUS_TOPIC,
    TOPICS,
    topic,
)

#: One token of a ROS 2 namespace: a letter or an underscore, then letters, digits, underscores.
_NAMESPACE_TOKEN: Final = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")


def check_namespace(namespace: str) -> str:
    """A vehicle namespace as topic names take it: ``""`` (none) or ``"/a"``, ``"/a/b"``.

    ``"auv1"``, ``"/auv1"`` and ``"/auv1/"`` are the same namespace; ``"/"`` is none.

    Raises:
        ValueError: naming what is allowed, for a token that is not a ROS 2 name token.
    """
    inner = namespace.strip("/")
    tokens = inner.split("/") if inner else []
    for token in tokens:
        if not _NAMESPACE_TOKEN.fullmatch(token):
            raise ValueError(
                f"vehicle namespace {namespace!r}: each part must be a letter or an underscore "
                "followed by letters, digits or underscores (e.g. auv1 or fleet/auv1); empty "
                "for none"
            )
    return "".join(f"/{t}" for t in tokens)


def topic_name(base: str, namespace: str = "") -> str:
    """The name of contract topic ``base`` on a vehicle under ``namespace``: the one place
    topic names are built (the console, the transmitter and the node all call it).
    ``/nemesys/pose`` under ``auv1`` is ``/auv1/nemesys/pose``; without a namespace it is
    ``base``.

    Raises:
        KeyError: ``base`` is not a contract topic.
        ValueError: a namespace :func:`check_namespace` refuses.
    """
    return check_namespace(namespace) + topic(base).name


def contract_topic_of(name: str) -> str:
    """The contract topic a vehicle's topic ``name`` is, without its namespace:
    ``/auv1/nemesys/pose`` -> ``/nemesys/pose``.

    Raises:
        KeyError: ``name`` is no contract topic under any valid namespace.
    """
    for t in TOPICS:
        if name == t.name:
            return t.name
        prefix = name.removesuffix(t.name)
        if prefix != name and prefix.startswith("/"):
            try:
                if check_namespace(prefix) == prefix:
                    return t.name
            except ValueError:
                pass
    raise KeyError(name)


@dataclass(frozen=True)
class TopicNames:
    """The contract's topic names on one vehicle (:func:`topic_names`)."""

    namespace: str
    frame: str
    pose: str
    mission: str
    status: str
    datum: str

    def by_topic(self) -> dict[str, str]:
        """Each contract topic -> its name on this vehicle."""
        return {
            FRAME_TOPIC: self.frame,
            POSE_TOPIC: self.pose,
            MISSION_TOPIC: self.mission,
            STATUS_TOPIC: self.status,
            DATUM_TOPIC: self.datum,
        }


def topic_names(namespace: str = "") -> TopicNames:
    """Every contract topic's name under ``namespace`` (:func:`topic_name`).

    Raises:
        ValueError: a namespace :func:`check_namespace` refuses.
    """
    ns = check_namespace(namespace)
    return TopicNames(
        ns,
        topic_name(FRAME_TOPIC, ns),
        topic_name(POSE_TOPIC, ns),
        topic_name(MISSION_TOPIC, ns),
        topic_name(STATUS_TOPIC, ns),
        topic_name(DATUM_TOPIC, ns),
    )
