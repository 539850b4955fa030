"""A stand-in for the slice of rclpy and the message packages node.py touches.

ROS 2 cannot be installed here, so the node's wiring is exercised against these fakes: they
record publishers, subscriptions, timers and QoS, and build messages as plain attribute
objects. This checks that node.py calls what it means to call with what it means to pass; it
says nothing about real rclpy behaviour (see the package README).
"""

from __future__ import annotations

import sys
import types
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from types import SimpleNamespace
from typing import Any

from pytest import MonkeyPatch

MODULES = (
    "rclpy",
    "rclpy.node",
    "rclpy.qos",
    "rclpy.executors",
    "std_msgs",
    "std_msgs.msg",
    "geometry_msgs",
    "geometry_msgs.msg",
    "nav_msgs",
    "nav_msgs.msg",
    "sensor_msgs",
    "sensor_msgs.msg",
)


class Message(SimpleNamespace):
    """A message built from keyword fields."""


class String(Message):
    def __init__(self, data: str = "") -> None:
        super().__init__(data=data)


class UInt8MultiArray(Message):
    def __init__(self, data: Any = ()) -> None:
        super().__init__(layout=SimpleNamespace(dim=[], data_offset=0), data=data)


class PoseStamped(Message):
    def __init__(self) -> None:
        super().__init__(
            header=SimpleNamespace(stamp=SimpleNamespace(sec=0, nanosec=0), frame_id=""),
            pose=SimpleNamespace(
                position=SimpleNamespace(x=0.0, y=0.0, z=0.0),
                orientation=SimpleNamespace(x=0.0, y=0.0, z=0.0, w=1.0),
            ),
        )


class OdometryMsg(Message):
    def __init__(self) -> None:
        super().__init__(
            header=SimpleNamespace(stamp=SimpleNamespace(sec=0, nanosec=0), frame_id="odom"),
            child_frame_id="base_link",
            pose=SimpleNamespace(pose=PoseStamped().pose),
            twist=SimpleNamespace(
                twist=SimpleNamespace(
                    linear=SimpleNamespace(x=0.0, y=0.0, z=0.0),
                    angular=SimpleNamespace(x=0.0, y=0.0, z=0.0),
                )
            ),
        )


class NavSatFix(Message):
    def __init__(self, latitude: float = 0.0, longitude: float = 0.0, status: int = -1) -> None:
        super().__init__(
            header=SimpleNamespace(stamp=SimpleNamespace(sec=0, nanosec=0), frame_id="gps"),
            status=SimpleNamespace(status=status, service=1),
            latitude=latitude,
            longitude=longitude,
            altitude=0.0,
        )


class BatteryState(Message):
    def __init__(self, percentage: float = float("nan")) -> None:
        super().__init__(voltage=float("nan"), percentage=percentage)


class Publisher:
    def __init__(self, msg_type: type, topic: str, qos: Any) -> None:
        self.msg_type = msg_type
        self.topic = topic
        self.qos = qos
        self.sent: list[Any] = []

    def publish(self, msg: Any) -> None:
        assert isinstance(msg, self.msg_type)
        self.sent.append(msg)


class Logger:
    def __init__(self) -> None:
        self.lines: list[tuple[str, str]] = []

    def info(self, text: str) -> None:
        self.lines.append(("info", text))

    def warning(self, text: str) -> None:
        self.lines.append(("warning", text))


class Node:
    """Records what a node creates. ``overrides``: parameter values as from a params file."""

    overrides: dict[str, Any] = {}  # noqa: RUF012  (set per test, read at declaration)
    clock_ns = 1_700_000_000_250_000_000
    created: list[Node] = []  # noqa: RUF012

    def __init__(self, name: str) -> None:
        self.name = name
        self.params: dict[str, Any] = {}
        self.publishers: dict[str, Publisher] = {}
        self.subscriptions: dict[str, tuple[type, Callable[[Any], None], Any]] = {}
        self.timers: list[tuple[float, Callable[[], None]]] = []
        self.logger = Logger()
        self.destroyed = False
        Node.created.append(self)

    def declare_parameters(self, namespace: str, parameters: list[tuple[str, Any]]) -> None:
        assert namespace == ""
        for name, default in parameters:
            value = self.overrides.get(name, default)
            assert type(value) is type(default), (name, value, default)  # rclpy's typing
            self.params[name] = value

    def get_parameters(self, names: list[str]) -> list[SimpleNamespace]:
        return [SimpleNamespace(name=n, value=self.params[n]) for n in names]

    def create_publisher(self, msg_type: type, topic: str, qos: Any) -> Publisher:
        assert topic not in self.publishers
        pub = self.publishers[topic] = Publisher(msg_type, topic, qos)
        return pub

    def create_subscription(
        self, msg_type: type, topic: str, callback: Callable[[Any], None], qos: Any
    ) -> None:
        assert topic not in self.subscriptions
        self.subscriptions[topic] = (msg_type, callback, qos)

    def create_timer(self, period_s: float, callback: Callable[[], None]) -> None:
        self.timers.append((period_s, callback))

    def get_logger(self) -> Logger:
        return self.logger

    def get_clock(self) -> SimpleNamespace:
        return SimpleNamespace(now=lambda: SimpleNamespace(nanoseconds=self.clock_ns))

    def destroy_node(self) -> None:
        self.destroyed = True


class ExternalShutdownException(Exception):
    pass


def _policy(*names: str) -> SimpleNamespace:
    return SimpleNamespace(**{n: n.lower() for n in names})


@contextmanager
def installed(monkeypatch: MonkeyPatch) -> Iterator[SimpleNamespace]:
    """Install the fakes in ``sys.modules`` and import ``nemesys_vehicle.node`` against them;
    yields ``SimpleNamespace(node=<the module>, calls=<rclpy calls>)``."""
    mods = {name: types.ModuleType(name) for name in MODULES}
    calls: list[str] = []
    rclpy: Any = mods["rclpy"]
    rclpy.init = lambda args=None: calls.append("init")
    rclpy.spin = lambda node: calls.append("spin")
    rclpy.try_shutdown = lambda: calls.append("shutdown")
    node_mod: Any = mods["rclpy.node"]
    node_mod.Node = Node
    qos: Any = mods["rclpy.qos"]
    qos.QoSProfile = SimpleNamespace
    qos.HistoryPolicy = _policy("KEEP_LAST", "KEEP_ALL")
    qos.ReliabilityPolicy = _policy("RELIABLE", "BEST_EFFORT")
    qos.DurabilityPolicy = _policy("VOLATILE", "TRANSIENT_LOCAL")
    executors: Any = mods["rclpy.executors"]
    executors.ExternalShutdownException = ExternalShutdownException
    std: Any = mods["std_msgs.msg"]
    std.String, std.UInt8MultiArray = String, UInt8MultiArray
    geometry: Any = mods["geometry_msgs.msg"]
    geometry.PoseStamped = PoseStamped
    nav: Any = mods["nav_msgs.msg"]
    nav.Odometry = OdometryMsg
    sensor: Any = mods["sensor_msgs.msg"]
    sensor.NavSatFix, sensor.BatteryState = NavSatFix, BatteryState
    for name, mod in mods.items():
        monkeypatch.setitem(sys.modules, name, mod)
    monkeypatch.delitem(sys.modules, "nemesys_vehicle.node", raising=False)
    monkeypatch.setattr(Node, "created", [])
    from nemesys_vehicle import node

    try:
        yield SimpleNamespace(node=node, calls=calls)
    finally:
        sys.modules.pop("nemesys_vehicle.node", None)
        vars(sys.modules["nemesys_vehicle"]).pop("node", None)
