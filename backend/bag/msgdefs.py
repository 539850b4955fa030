"""The ROS 2 message definitions of the dive exports: the standard ones from rosbags' type
store (ROS 2 Humble's, unchanged since), the NemeSys ones read from the ``.msg`` files of the
interface package ``ros2/nemesys_msgs`` (one source: what ``colcon build`` generates code from
is what the exports declare).

:func:`typestore` is the store both writers use (rosbags serialises the rosbag2 form with it);
:func:`definition` is a type's full text as MCAP's ``ros2msg`` schema and rosbag2's metadata
carry it (the type, then each type it uses after a line of ``=``).
"""

from __future__ import annotations

import functools
from pathlib import Path
from typing import Final

from rosbags.typesys import Stores, get_types_from_msg, get_typestore
from rosbags.typesys.store import Typestore

#: The interface package's folder of ``.msg`` files.
MSG_DIR: Final = Path(__file__).resolve().parents[2] / "ros2" / "nemesys_msgs" / "msg"
#: The interface package's name.
PACKAGE: Final = "nemesys_msgs"
#: Its messages, each after the ones it uses (the order ``CMakeLists.txt`` lists them in).
NEMESYS_MESSAGES: Final = ("Param", "Command", "Ack", "Status", "CommandRecord")


def type_name(message: str) -> str:
    """The ROS 2 name of a NemeSys message: ``Status`` -> ``nemesys_msgs/msg/Status``."""
    return f"{PACKAGE}/msg/{message}"


def msg_text(message: str, folder: Path = MSG_DIR) -> str:
    """The ``.msg`` file of a NemeSys message, as written.

    Raises:
        FileNotFoundError: naming the file (a checkout without ``ros2/nemesys_msgs``).
    """
    return (folder / f"{message}.msg").read_text(encoding="utf-8")


@functools.cache
def typestore() -> Typestore:
    """ROS 2 Humble's standard types with the NemeSys messages registered from their files."""
    store = get_typestore(Stores.ROS2_HUMBLE)
    for message in NEMESYS_MESSAGES:
        store.register(get_types_from_msg(msg_text(message), type_name(message)))
    return store


@functools.cache
def definition(ros_type: str) -> str:
    """``ros_type``'s full definition (``pkg/msg/Name``), its dependencies after it."""
    text, _ = typestore().generate_msgdef(ros_type, ros_version=2)
    return text
