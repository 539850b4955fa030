"""Launch the NemeSys vehicle node with its parameter file.

``ros2 launch nemesys_vehicle vehicle.launch.py [params_file:=/path/to/params.yaml]``
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
            Node(
                package="nemesys_vehicle",
                executable="vehicle_node",
                name="nemesys_vehicle",
                parameters=[LaunchConfiguration("params_file")],
                output="screen",
                emulate_tty=True,
            ),
        ]
    )
