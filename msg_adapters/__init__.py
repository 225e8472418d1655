"""Conversions between the engine's numpy arrays and ROS 2 messages.

Nothing here steps a world or talks to a ROS graph: each function takes arrays
(or a model) and returns a message, or the reverse.
"""

from .contacts import ContactArrays, cloud_to_structured, contact_cloud, contacts_from_cloud
from .diagnostics import diagnostic_array, diagnostic_values
from .frames import WORLD_FRAME, rotate_to_body, rotate_to_world
from .markers import SceneMarkers, body_markers, scene_markers
from .poses import BodyOdometry, arrays_from_pose_array, odometries, odometry, pose_array, state_from_odometry
from .schema import message_class, ros2msg_schema, type_name
from .stamps import sim_time_ns, time_msg, time_ns
from .wrenches import is_world_frame, to_world_axes, wrench_arrays, wrench_stamped

__all__ = [
    "BodyOdometry",
    "ContactArrays",
    "SceneMarkers",
    "WORLD_FRAME",
    "arrays_from_pose_array",
    "body_markers",
    "cloud_to_structured",
    "contact_cloud",
    "contacts_from_cloud",
    "diagnostic_array",
    "diagnostic_values",
    "is_world_frame",
    "message_class",
    "odometries",
    "odometry",
    "pose_array",
    "ros2msg_schema",
    "rotate_to_body",
    "rotate_to_world",
    "scene_markers",
    "sim_time_ns",
    "state_from_odometry",
    "time_msg",
    "time_ns",
    "to_world_axes",
    "type_name",
    "wrench_arrays",
    "wrench_stamped",
]
