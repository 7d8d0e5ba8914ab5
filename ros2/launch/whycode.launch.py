"""whycode_node on one camera, or on several (one node each).

whycode_node must be on PATH (e.g. `cargo install --path ros2`, or copy
target/release/whycode_node to /usr/local/bin); it is not a colcon
package, so the Node action has no package.

    ros2 launch ros2/launch/whycode.launch.py camera:=/camera diameter:=0.05
    ros2 launch ros2/launch/whycode.launch.py cameras:=/left,/right

Without arguments the node runs on its own defaults (whycode.params.yaml
holds them): no diameter, so markers without poses. params_file:=FILE loads
a setup's own parameters instead (example.params.yaml names markers and
sizes them).
"""

import os

from launch import LaunchDescription
from launch.actions import DeclareLaunchArgument, OpaqueFunction
from launch.substitutions import LaunchConfiguration
from launch_ros.actions import Node

HERE = os.path.dirname(os.path.abspath(__file__))


def nodes(context):
    cameras = LaunchConfiguration("cameras").perform(context) or LaunchConfiguration(
        "camera"
    ).perform(context)
    diameter = float(LaunchConfiguration("diameter").perform(context))
    params_file = LaunchConfiguration("params_file").perform(context)
    made = []
    for camera in [c.strip().rstrip("/") for c in cameras.split(",") if c.strip()]:
        # /left -> whycode_left; one node per camera, its own ~/markers.
        suffix = camera.strip("/").replace("/", "_")
        made.append(
            Node(
                executable="whycode_node",
                name=f"whycode_{suffix}" if suffix else "whycode",
                output="screen",
                parameters=[
                    params_file,
                    {"diameter": diameter},
                ],
                remappings=[
                    ("image", f"{camera}/image_raw"),
                    ("camera_info", f"{camera}/camera_info"),
                ],
            )
        )
    return made


def generate_launch_description():
    return LaunchDescription(
        [
            DeclareLaunchArgument("camera", default_value="/camera"),
            DeclareLaunchArgument(
                "cameras", default_value="", description="comma-separated cameras, one node each"
            ),
            DeclareLaunchArgument(
                "diameter",
                default_value="0.0",
                description="marker diameter, metres; 0: no poses (the node's default)",
            ),
            DeclareLaunchArgument(
                "params_file",
                default_value=os.path.join(HERE, "whycode.params.yaml"),
                description="the node's parameters",
            ),
            OpaqueFunction(function=nodes),
        ]
    )
