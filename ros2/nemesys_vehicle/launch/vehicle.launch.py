"""Launch the NemeSys vehicle node with its parameter file.

``ros2 launch nemesys_vehicle vehicle.launch.py [params_file:=/path/to/params.yaml]
[vehicle_namespace:=auv1] [vehicle_address:=1]``

``vehicle_namespace`` puts the node in that namespace (its name is then
``/auv1/nemesys_vehicle``) and its contract topics under ``/auv1/nemesys/...``: several
vehicles in one graph. The argument sets the parameter (over the params file's); empty, the
default: no namespace. ``vehicle_address`` (1-15) makes it one of a fleet sharing one ME link
(docs/protocol.md, "Addressing"); without it, the params file's (0: none).
"""

from launch.actions import DeclareLaunchArgument, OpaqueFunction
from launch.launch_context import LaunchContext
from launch.substitutions import LaunchConfiguration, PathJoinSubstitution
from launch_ros.actions import Node
from launch_ros.substitutions import FindPackageShare

from launch import LaunchDescription


def _node(context: LaunchContext) -> list[Node]:
    """The node, its namespace from the argument, its address from the argument when given
    (else the params file's): read at launch, so an empty address overrides nothing."""
    namespace = LaunchConfiguration("vehicle_namespace").perform(context)
    overrides: dict[str, object] = {"vehicle_namespace": namespace}
    address = LaunchConfiguration("vehicle_address").perform(context).strip()
    if address:
        overrides["vehicle_address"] = int(address)  # the node checks the range (1-15, or 0)
    return [
        Node(
            package="nemesys_vehicle",
            executable="vehicle_node",
            name="nemesys_vehicle",
            namespace=namespace,
            parameters=[LaunchConfiguration("params_file"), overrides],
            output="screen",
            emulate_tty=True,
        )
    ]


def generate_launch_description() -> LaunchDescription:
    default_params = PathJoinSubstitution(
        [FindPackageShare("nemesys_vehicle"), "config", "params.yaml"]
    )
    return LaunchDescription(
        [
            DeclareLaunchArgument(
                "params_file",
                default_value=default_params,
                description="the node's parameters (see config/params.yaml)",
            ),
            DeclareLaunchArgument(
                "vehicle_namespace",
                default_value="",
                description="the vehicle's namespace (topics /<it>/nemesys/...); empty: none",
            ),
            DeclareLaunchArgument(
                "vehicle_address",
                default_value="",
                description="the vehicle's address in a fleet, 1-15 (0: none); empty: the "
                "params file's",
            ),
            OpaqueFunction(function=_node),
        ]
    )
