"""Message definitions as the real ``rosapi`` gives them, and the ROS 2 type store behind them.

``/rosapi/topics_and_raw_types`` answers, for each topic, ``typedefs_full_text``: the topic's
message definition followed by the definition of every message type it uses, the form
``gendeps --cat`` and rosbag2 use and Foxglove's rosbridge player parses. The real ``rosapi``
(``stringify_field_types``) builds it so: the root type's text first; then its field types
are visited last-found-first (a stack), each once, each preceded by a line of 80 ``=`` and
``MSG: pkg/Type``; a type that cannot be loaded gives the single line ``# failed to get full
definition text for <type>: <reason>``. :func:`full_text` follows the same rule.

The real server reads each type's ``.msg`` file from the ROS install; the simulator has no
install, so a type's text is written from the type store (:func:`msg_text`: constants and
fields in ``.msg`` syntax, without the files' comments). The store is rosbags' ROS 2 Jazzy
store (:data:`rosbridge.graph.ROS_DISTRO`) plus ``rosbridge_msgs``, which the simulator
publishes on ``/connected_clients`` and rosbags does not ship (:data:`EXTRA_DEFINITIONS`, as
rosbridge_suite defines them). The same store serializes ``cbor-raw`` messages to CDR
(:mod:`rosbridge.compression`).
"""

from __future__ import annotations

import functools
from collections.abc import Mapping
from types import MappingProxyType
from typing import Final

from rosbags.interfaces import Nodetype
from rosbags.interfaces.typing import FieldDesc
from rosbags.typesys import Stores, get_types_from_msg, get_typestore
from rosbags.typesys.store import Typestore

#: The line between two definitions in a full text (rosapi's and rosbag2's).
SEPARATOR: Final = "=" * 80
#: Message types the simulator publishes that are not in rosbags' store: name -> ``.msg``.
EXTRA_DEFINITIONS: Final[Mapping[str, str]] = MappingProxyType(
    {
        "rosbridge_msgs/msg/ConnectedClient": (
            "string ip_address\nbuiltin_interfaces/Time connection_time\n"
        ),
        "rosbridge_msgs/msg/ConnectedClients": "ConnectedClient[] clients\n",
    }
)


#: The member rosidl gives an empty message (``std_msgs/Empty``) in its serialized form; no
#: ``.msg`` file and no rclpy message has it.
PLACEHOLDER_FIELD: Final = "structure_needs_at_least_one_member"


class UnknownDefinition(LookupError):
    """A message type the type store does not define."""


@functools.cache
def typestore() -> Typestore:
    """rosbags' ROS 2 Jazzy type store with :data:`EXTRA_DEFINITIONS` registered (built once,
    on first use: about 0.1 s)."""
    store = get_typestore(Stores.ROS2_JAZZY)
    for name, text in EXTRA_DEFINITIONS.items():
        store.register(get_types_from_msg(text, name))
    return store


def ros2_name(type_name: str) -> str:
    """``pkg/msg/Name`` for ``pkg/Name`` or ``pkg/msg/Name`` (the store's spelling)."""
    parts = type_name.split("/")
    return f"{parts[0]}/msg/{parts[-1]}" if len(parts) in (2, 3) else type_name


def short_name(type_name: str) -> str:
    """``pkg/Name``: how a ``.msg`` file and a ``MSG:`` line name a message type."""
    parts = type_name.split("/")
    return f"{parts[0]}/{parts[-1]}" if len(parts) in (2, 3) else type_name


def fields_of(type_name: str) -> list[tuple[str, FieldDesc]]:
    """``(name, descriptor)`` of each field of a message type, in definition order.

    Raises :class:`UnknownDefinition` for a type the store does not define.
    """
    try:
        return typestore().fielddefs[ros2_name(type_name)][1]
    except KeyError:
        raise UnknownDefinition(
            f"no definition of {type_name} is known to the NemeSys simulator"
        ) from None


def message_fields(type_name: str) -> list[tuple[str, FieldDesc]]:
    """:func:`fields_of` as a ``.msg`` file and ``rclpy`` know them: an empty message has no
    field (the store's placeholder member is only in its CDR)."""
    fields = fields_of(type_name)
    return [] if [name for name, _ in fields] == [PLACEHOLDER_FIELD] else fields


def _spelling(desc: FieldDesc) -> str:
    """A field's type as a ``.msg`` file writes it: ``float64``, ``string<=10``,
    ``std_msgs/Header``, ``uint8[]``, ``float64[36]``, ``int32[<=5]``."""
    if desc[0] == Nodetype.BASE:
        base, bound = desc[1]
        return f"{base}<={bound}" if bound else base
    if desc[0] == Nodetype.NAME:
        return short_name(desc[1])
    inner, size = desc[1]
    element = _spelling(inner)
    if desc[0] == Nodetype.ARRAY:
        return f"{element}[{size}]"
    return f"{element}[<={size}]" if size else f"{element}[]"


def msg_text(type_name: str) -> str:
    """One type's definition in ``.msg`` syntax (constants, then fields), ending in a newline
    as a file does. Raises :class:`UnknownDefinition`."""
    fields = message_fields(type_name)
    constants = typestore().fielddefs[ros2_name(type_name)][0]
    lines = [
        f"{kind} {name}={str(value).lower() if isinstance(value, bool) else value}"
        for name, kind, value in constants
    ]
    lines += [f"{_spelling(desc)} {name}" for name, desc in fields]
    return "".join(f"{line}\n" for line in lines)


def _used_types(type_name: str) -> list[str]:
    """The message types of a type's fields (``pkg/Name``), in field order, once each."""
    out: list[str] = []
    for _, desc in fields_of(type_name):
        inner = desc[1][0] if desc[0] in (Nodetype.ARRAY, Nodetype.SEQUENCE) else desc
        if inner[0] == Nodetype.NAME and short_name(inner[1]) not in out:
            out.append(short_name(inner[1]))
    return out


@functools.lru_cache(maxsize=256)  # bounded: clients name the types of the topics they make
def full_text(type_name: str) -> str:
    """``typedefs_full_text`` of a topic's type, built by the real ``rosapi``'s rule (see the
    module's docstring); the failure line for a type the store does not define."""
    try:
        text = msg_text(type_name)
        stack = _used_types(type_name)
        seen = set(stack)
        while stack:
            dep = stack.pop()
            text += f"\n{SEPARATOR}\nMSG: {dep}\n{msg_text(dep)}"
            for more in _used_types(dep):
                if more not in seen:
                    seen.add(more)
                    stack.append(more)
    except UnknownDefinition as exc:
        return f"# failed to get full definition text for {type_name}: {exc}"
    return text
