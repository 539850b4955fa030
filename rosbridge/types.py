"""ROS message types for the rosbridge server: type names and field layouts.

:func:`resolve_type` turns ``pkg/Name`` or ``pkg/msg/Name`` into the ROS 2 spelling the real
server reports, or raises :class:`InvalidType` as its ``ros_loader`` would. Only the types
the NemeSys topics, the server's own topics and rosapi use are laid out in
:data:`MESSAGE_FIELDS`; any other well-formed type of a standard package is accepted and
passed through unchecked (the simulator cannot know every package a robot has installed).
The JSON conversion is :mod:`rosbridge.convert`.
"""

from __future__ import annotations

from collections.abc import Mapping
from types import MappingProxyType
from typing import Final

from rosbridge.errors import InvalidType

#: Field layouts: ROS 2 type -> ``(name, field type)`` in rosidl's spelling.
MESSAGE_FIELDS: Final[Mapping[str, tuple[tuple[str, str], ...]]] = MappingProxyType(
    {
        "builtin_interfaces/msg/Time": (("sec", "int32"), ("nanosec", "uint32")),
        "builtin_interfaces/msg/Duration": (("sec", "int32"), ("nanosec", "uint32")),
        "std_msgs/msg/Header": (("stamp", "builtin_interfaces/Time"), ("frame_id", "string")),
        "std_msgs/msg/String": (("data", "string"),),
        "std_msgs/msg/Bool": (("data", "boolean"),),
        "std_msgs/msg/Int32": (("data", "int32"),),
        "std_msgs/msg/Int64": (("data", "int64"),),
        "std_msgs/msg/UInt8": (("data", "uint8"),),
        "std_msgs/msg/Float32": (("data", "float"),),
        "std_msgs/msg/Float64": (("data", "double"),),
        "std_msgs/msg/Empty": (),
        "std_msgs/msg/MultiArrayDimension": (
            ("label", "string"),
            ("size", "uint32"),
            ("stride", "uint32"),
        ),
        "std_msgs/msg/MultiArrayLayout": (
            ("dim", "sequence<std_msgs/MultiArrayDimension>"),
            ("data_offset", "uint32"),
        ),
        "std_msgs/msg/UInt8MultiArray": (
            ("layout", "std_msgs/MultiArrayLayout"),
            ("data", "sequence<uint8>"),
        ),
        "geometry_msgs/msg/Point": (("x", "double"), ("y", "double"), ("z", "double")),
        "geometry_msgs/msg/Vector3": (("x", "double"), ("y", "double"), ("z", "double")),
        "geometry_msgs/msg/Quaternion": (
            ("x", "double"),
            ("y", "double"),
            ("z", "double"),
            ("w", "double"),
        ),
        "geometry_msgs/msg/Pose": (
            ("position", "geometry_msgs/Point"),
            ("orientation", "geometry_msgs/Quaternion"),
        ),
        "geometry_msgs/msg/PoseStamped": (
            ("header", "std_msgs/Header"),
            ("pose", "geometry_msgs/Pose"),
        ),
        "rcl_interfaces/msg/Log": (
            ("stamp", "builtin_interfaces/Time"),
            ("level", "uint8"),
            ("name", "string"),
            ("msg", "string"),
            ("file", "string"),
            ("function", "string"),
            ("line", "uint32"),
        ),
        "rosbridge_msgs/msg/ConnectedClient": (
            ("ip_address", "string"),
            ("connection_time", "builtin_interfaces/Time"),
        ),
        "rosbridge_msgs/msg/ConnectedClients": (
            ("clients", "sequence<rosbridge_msgs/ConnectedClient>"),
        ),
    }
)

#: Defaults that are not zero (rosidl: ``geometry_msgs/Quaternion.w`` is 1).
FIELD_DEFAULTS: Final = {("geometry_msgs/msg/Quaternion", "w"): 1.0}

#: Message packages of a ROS 2 desktop install: their types resolve even when not laid out.
KNOWN_PACKAGES: Final = frozenset(
    {
        "action_msgs",
        "builtin_interfaces",
        "diagnostic_msgs",
        "example_interfaces",
        "geometry_msgs",
        "lifecycle_msgs",
        "nav_msgs",
        "rcl_interfaces",
        "rosapi_msgs",
        "rosbridge_msgs",
        "sensor_msgs",
        "service_msgs",
        "shape_msgs",
        "statistics_msgs",
        "std_msgs",
        "stereo_msgs",
        "tf2_msgs",
        "trajectory_msgs",
        "type_description_interfaces",
        "unique_identifier_msgs",
        "visualization_msgs",
    }
)
#: Every message of ``std_msgs`` (a misspelt one is refused, as the real loader does).
_STD_MSGS: Final = frozenset(
    {"Bool", "Byte", "Char", "ColorRGBA", "Empty", "Header", "String"}
    | {f"{kind}{bits}" for kind in ("Int", "UInt") for bits in (8, 16, 32, 64)}
    | {"Float32", "Float64", "MultiArrayDimension", "MultiArrayLayout"}
    | {f"{kind}MultiArray" for kind in ("Byte", "Float32", "Float64")}
    | {f"{kind}{bits}MultiArray" for kind in ("Int", "UInt") for bits in (8, 16, 32, 64)}
)

INT_RANGES: Final = MappingProxyType(
    {
        "int8": (-(2**7), 2**7 - 1),
        "uint8": (0, 2**8 - 1),
        "char": (0, 2**8 - 1),
        "int16": (-(2**15), 2**15 - 1),
        "uint16": (0, 2**16 - 1),
        "int32": (-(2**31), 2**31 - 1),
        "uint32": (0, 2**32 - 1),
        "int64": (-(2**63), 2**63 - 1),
        "uint64": (0, 2**64 - 1),
    }
)
FLOATS: Final = frozenset({"float", "double", "float32", "float64"})
BOOLS: Final = frozenset({"bool", "boolean"})
BINARY: Final = frozenset({"sequence<uint8>", "uint8[]", "sequence<char>", "char[]"})
TIMES: Final = frozenset({"builtin_interfaces/Time", "builtin_interfaces/Duration"})


# ---------------------------------------------------------------------------------------------
# Type names
# ---------------------------------------------------------------------------------------------


def canonical_type(type_name: str) -> str:
    """The ROS 1 spelling of a message type: ``std_msgs/msg/String`` -> ``std_msgs/String``.

    Names already in ROS 1 form, and names of any other shape, are returned unchanged.
    """
    parts = type_name.strip().split("/")
    if len(parts) == 3 and parts[1] == "msg" and parts[0] and parts[2]:
        return f"{parts[0]}/{parts[2]}"
    return type_name.strip()


def ros2_type(type_name: str) -> str:
    """The ROS 2 spelling ``pkg/msg/Name`` of ``pkg/Name`` (other names unchanged)."""
    parts = type_name.strip().split("/")
    if len(parts) == 2 and all(parts):
        return f"{parts[0]}/msg/{parts[1]}"
    return type_name.strip()


def same_type(a: str, b: str) -> bool:
    """True when two type names denote the same message type in either ROS spelling."""
    return canonical_type(a) == canonical_type(b)


def resolve_type(type_name: str) -> str:
    """The ROS 2 spelling of a message type a ROS 2 rosbridge accepts, as it resolves it.

    ``pkg/Name`` and ``pkg/<anything>/Name`` both name ``pkg/msg/Name`` (the real loader falls
    back to ``msg``). Raises :class:`InvalidType` with the real loader's words for a malformed
    name, a package that is not installed, or a ``std_msgs`` type that does not exist.
    """
    parts = [part for part in type_name.split("/") if part]
    if len(parts) not in (2, 3):
        raise InvalidType(f"{type_name} is not a valid type string")
    package, name = parts[0], parts[-1]
    full = f"{package}/msg/{name}"
    if full in MESSAGE_FIELDS:
        return full
    if package not in KNOWN_PACKAGES:
        raise InvalidType(
            f"Unable to import {package}.msg from package {package}. "
            f"Caused by: No module named '{package}'"
        )
    if package == "std_msgs" and name not in _STD_MSGS:
        raise InvalidType(
            f"Unable to import msg class {name} from package {package}. "
            f"Caused by module '{package}.msg' has no attribute '{name}'"
        )
    return full


def short_type(type_name: str) -> str:
    """``pkg/Name``, the way the real server names a message type in its errors."""
    return canonical_type(type_name)


def python_type(value: object) -> str:
    return f"<class '{type(value).__name__}'>"
