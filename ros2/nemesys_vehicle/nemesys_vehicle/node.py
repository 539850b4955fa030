"""The rclpy node: wires topics, timers and parameters to :class:`VehicleCore`. No logic here.

Every callback is one line handing a converted message (``nemesys_vehicle.convert``) and the
node's ROS time to the core, or publishing what the core produced. Imports only where ROS 2 is
installed; the tests check the core, and check statically that this file stays logic-free.
"""

from __future__ import annotations

from typing import Any

import rclpy
from geometry_msgs.msg import PoseStamped
from nav_msgs.msg import Odometry as OdometryMsg
from rclpy.executors import ExternalShutdownException
from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy
from sensor_msgs.msg import BatteryState, NavSatFix
from std_msgs.msg import String, UInt8MultiArray

from nemesys_vehicle.config import VehicleConfig
from nemesys_vehicle.convert import (
    ODOMETRY_QOS,
    SENSOR_QOS,
    SETPOINT_QOS,
    battery_fraction,
    config_from_parameters,
    contract_qos,
    fill_pose_stamped,
    frame_data,
    json_text,
    navsatfix_from_msg,
    odometry_from_msg,
    ros_time_s,
)
from nemesys_vehicle.core import VehicleCore
from nemesys_vehicle.messages import Sinks
from nemesys_vehicle.serial_input import SerialByteSource
from vehicle_contract.contract import (
    DATUM_TOPIC,
    FRAME_TOPIC,
    MISSION_TOPIC,
    POSE_TOPIC,
    STATUS_TOPIC,
    VEHICLE_NODE,
    Durability,
    QoS,
    Reliability,
)
from vehicle_contract.names import topic_names

_RELIABILITY = {
    Reliability.RELIABLE: ReliabilityPolicy.RELIABLE,
    Reliability.BEST_EFFORT: ReliabilityPolicy.BEST_EFFORT,
}
_DURABILITY = {
    Durability.VOLATILE: DurabilityPolicy.VOLATILE,
    Durability.TRANSIENT_LOCAL: DurabilityPolicy.TRANSIENT_LOCAL,
}


def qos_profile(qos: QoS) -> Any:
    """An rclpy QoSProfile of a contract QoS (history KEEP_LAST of its depth)."""
    return QoSProfile(
        history=HistoryPolicy.KEEP_LAST,
        depth=qos.depth,
        reliability=_RELIABILITY[qos.reliability],
        durability=_DURABILITY[qos.durability],
    )


class VehicleNode(Node):  # type: ignore[misc]  # rclpy is untyped here (not installed)
    """The NemeSys vehicle node (parameters: ``config/params.yaml``)."""

    def __init__(self) -> None:
        super().__init__(VEHICLE_NODE.lstrip("/"))  # the contract's node name
        self.declare_parameters("", VehicleConfig.parameter_defaults())
        config = config_from_parameters(self.get_parameters(VehicleConfig.parameter_names()))
        names = topic_names(config.vehicle_namespace)  # the contract's, under the namespace
        self._mission_pub = self.create_publisher(
            String, names.mission, qos_profile(contract_qos(MISSION_TOPIC))
        )
        self._status_pub = self.create_publisher(
            String, names.status, qos_profile(contract_qos(STATUS_TOPIC))
        )
        self._pose_pub = self.create_publisher(
            PoseStamped, names.pose, qos_profile(contract_qos(POSE_TOPIC))
        )
        self._datum_pub = self.create_publisher(
            String, names.datum, qos_profile(contract_qos(DATUM_TOPIC))
        )
        self._setpoint_pub = self.create_publisher(
            PoseStamped, config.resolve(config.setpoint_topic), qos_profile(SETPOINT_QOS)
        )
        self.core = VehicleCore(
            config,
            Sinks(
                ack=self._publish_ack,
                status=self._publish_status,
                pose=self._publish_pose,
                setpoint=self._publish_setpoint,
                datum=self._publish_datum,
            ),
        )
        # opened on the first poll: never in topic mode
        self._serial = SerialByteSource(
            config.serial_url,
            config.serial_baud,
            log=self.get_logger().warning,
            info=self.get_logger().info,
        )
        self.create_subscription(
            OdometryMsg,
            config.resolve(config.odometry_topic),
            self._on_odometry,
            qos_profile(ODOMETRY_QOS),
        )
        self.create_subscription(
            NavSatFix,
            config.resolve(config.navsatfix_topic),
            self._on_navsatfix,
            qos_profile(SENSOR_QOS),
        )
        self.create_subscription(
            BatteryState,
            config.resolve(config.battery_topic),
            self._on_battery,
            qos_profile(SENSOR_QOS),
        )
        if config.frame_input == "serial":
            self.create_timer(config.serial_poll_period_s, self._on_serial_poll)
        else:
            self.create_subscription(
                UInt8MultiArray, names.frame, self._on_frame, qos_profile(contract_qos(FRAME_TOPIC))
            )
        self.create_timer(config.status_period_s, self._on_status_timer)
        self.create_timer(config.pose_period_s, self._on_pose_timer)
        self.create_timer(config.guidance_period_s, self._on_guidance_timer)
        self.get_logger().info(f"nemesys_vehicle: {config}")

    def _now_s(self) -> float:
        return ros_time_s(self.get_clock().now().nanoseconds)

    # --- inputs --------------------------------------------------------------------------

    def _on_frame(self, msg: Any) -> None:
        self.core.on_frame(frame_data(msg), self._now_s())

    def _on_serial_poll(self) -> None:
        self.core.on_serial_bytes(self._serial.read_available(), self._now_s())

    def _on_odometry(self, msg: Any) -> None:
        self.core.on_odometry(odometry_from_msg(msg, self._now_s()))

    def _on_navsatfix(self, msg: Any) -> None:
        self.core.on_navsatfix(self._now_s(), *navsatfix_from_msg(msg))

    def _on_battery(self, msg: Any) -> None:
        self.core.on_battery_state(battery_fraction(msg))

    def _on_status_timer(self) -> None:
        self.core.tick_status(self._now_s())

    def _on_pose_timer(self) -> None:
        self.core.tick_pose(self._now_s())

    def _on_guidance_timer(self) -> None:
        self.core.tick_guidance(self._now_s())

    # --- outputs -------------------------------------------------------------------------

    def _publish_ack(self, ack: dict[str, Any]) -> None:
        self._mission_pub.publish(String(data=json_text(ack)))

    def _publish_status(self, status: dict[str, Any]) -> None:
        self._status_pub.publish(String(data=json_text(status)))

    def _publish_pose(self, pose: dict[str, Any]) -> None:
        self._pose_pub.publish(fill_pose_stamped(PoseStamped(), pose))

    def _publish_setpoint(self, setpoint: dict[str, Any]) -> None:
        self._setpoint_pub.publish(fill_pose_stamped(PoseStamped(), setpoint))

    def _publish_datum(self, datum: dict[str, Any]) -> None:
        self._datum_pub.publish(String(data=json_text(datum)))

    def destroy_node(self) -> None:
        self._serial.close()
        super().destroy_node()


def main(args: list[str] | None = None) -> None:
    """``ros2 run nemesys_vehicle vehicle_node`` (console script ``vehicle_node``)."""
    rclpy.init(args=args)
    node = VehicleNode()
    try:
        rclpy.spin(node)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    finally:
        node.destroy_node()
        rclpy.try_shutdown()
