"""Launch the NemeSys vehicle node with its parameter file.

``ros2 launch nemesys_vehicle vehicle.launch.py [params_file:=/path/to/params.yaml]
[vehicle_namespace:=auv1]``

``vehicle_namespace`` puts the node in that namespace (its name is then
``/auv1/nemesys_vehicle``) and its contract topics under ``/auv1/nemesys/...``: several
vehicles in one graph. The argument sets the parameter (over the params file's); empty, the
default: no namespace.
"""

from launch.actions import DeclareLaunchArgument
from launch.substitutions import LaunchConfiguration, PathJoinSubstitution
from launch_ros.actions import Node
from launch_ros.substitutions import FindPackageShare

from launch import LaunchDescription


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
            Node(
                package="nemesys_vehicle",
                executable="vehicle_node",
                name="nemesys_vehicle",
                namespace=LaunchConfiguration("vehicle_namespace"),
                parameters=[
                    LaunchConfiguration("params_file"),
                    {"vehicle_namespace": LaunchConfiguration("vehicle_namespace")},
                ],
                output="screen",
                emulate_tty=True,
            ),
        ]
    )
