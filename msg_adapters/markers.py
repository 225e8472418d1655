"""Bodies and contacts as visualization_msgs/MarkerArray for RViz and Foxglove."""

import numpy as np
from geometry_msgs.msg import Point
from visualization_msgs.msg import Marker, MarkerArray

from .frames import WORLD_FRAME, quat_between_z_and
from .stamps import time_msg

SPHERE_SHAPE, BOX_SHAPE, PLANE_SHAPE = 0, 1, 2

# An infinite plane is drawn as a thin square slab this wide (m).
PLANE_DRAW_SIZE = 20.0
PLANE_DRAW_THICKNESS = 0.002
CONTACT_ARROW_LENGTH = 0.15  # m

_STATIC_RGBA = (0.55, 0.55, 0.55, 1.0)
_PALETTE = (
    (0.90, 0.30, 0.25),
    (0.25, 0.55, 0.90),
    (0.30, 0.75, 0.35),
    (0.95, 0.70, 0.20),
    (0.60, 0.40, 0.80),
    (0.20, 0.75, 0.75),
)
_EVENT_RGBA = {0: (0.1, 0.9, 0.1, 1.0), 1: (0.95, 0.85, 0.1, 1.0), 2: (0.9, 0.1, 0.1, 1.0)}


def _set_pose(marker, p, q):
    marker.pose.position.x, marker.pose.position.y, marker.pose.position.z = (float(x) for x in p)
    o = marker.pose.orientation
    o.w, o.x, o.y, o.z = (float(x) for x in q)


def _set_rgba(marker, rgba):
    marker.color.r, marker.color.g, marker.color.b, marker.color.a = (float(x) for x in rgba)


def body_marker(model, index, pos, quat, stamp_ns, frame_id=WORLD_FRAME):
    """One marker for body `index`: id = scene index, ns and text = its name."""
    m = Marker()
    m.header.stamp = time_msg(stamp_ns)
    m.header.frame_id = frame_id
    return fill_body_marker(m, model, index, pos, quat)


def fill_body_marker(m, model, index, pos, quat):
    """`m` made body `index`'s marker, its header left as it is: every field
    that differs between bodies is set."""
    m.ns = model.names[index]
    m.text = model.names[index]
    m.id = int(index)
    m.action = Marker.ADD
    m.type, scale, p, q = body_marker_shape(model, index, pos, quat)
    m.scale.x, m.scale.y, m.scale.z = scale
    _set_pose(m, p, q)
    _set_rgba(m, body_marker_rgba(model, index))
    return m


def body_marker_shape(model, index, pos, quat):
    """(Marker type, scale (x, y, z), position, orientation w, x, y, z) of body `index`."""
    shape = int(model.shape_type[index])
    if shape == SPHERE_SHAPE:
        d = 2.0 * float(model.radius[index])
        return Marker.SPHERE, (d, d, d), pos[index], quat[index]
    if shape == BOX_SHAPE:
        return Marker.CUBE, tuple(2.0 * float(h) for h in model.half_extents[index]), pos[index], quat[index]
    normal = np.asarray(model.plane_normal[index], dtype=np.float64)
    normal = normal / np.linalg.norm(normal)
    # The slab's top face lies on the plane n·x = offset.
    centre = normal * (float(model.plane_offset[index]) - 0.5 * PLANE_DRAW_THICKNESS)
    return Marker.CUBE, (PLANE_DRAW_SIZE, PLANE_DRAW_SIZE, PLANE_DRAW_THICKNESS), centre, quat_between_z_and(normal)


def body_marker_rgba(model, index):
    if bool(model.is_static[index]):
        return _STATIC_RGBA
    return _PALETTE[index % len(_PALETTE)] + (1.0,)


def body_markers(model, pos, quat, stamp_ns, frame_id=WORLD_FRAME):
    """MarkerArray with one marker per body, in scene order."""
    return MarkerArray(markers=[body_marker(model, i, pos, quat, stamp_ns, frame_id) for i in range(len(model.names))])


def contact_arrow(j, point, normal, event, stamp_ns, frame_id=WORLD_FRAME):
    m = Marker()
    m.header.stamp = time_msg(stamp_ns)
    m.header.frame_id = frame_id
    m.ns = "contacts"
    m.id = int(j)
    m.type = Marker.ARROW
    m.action = Marker.ADD
    m.pose.orientation.w = 1.0
    start = np.asarray(point, dtype=np.float64)
    end = start + CONTACT_ARROW_LENGTH * np.asarray(normal, dtype=np.float64)
    m.points = [_point(start), _point(end)]
    m.scale.x, m.scale.y, m.scale.z = 0.01, 0.02, 0.03  # shaft, head diameters, head length
    _set_rgba(m, _EVENT_RGBA.get(int(event), _EVENT_RGBA[1]))
    return m


def _point(v):
    return Point(x=float(v[0]), y=float(v[1]), z=float(v[2]))


class SceneMarkers:
    """Builds `scene_markers` step after step for one model, reusing the body
    markers and changing only their stamps and poses (building a Marker from
    scratch costs more than the rest of a small step)."""

    def __init__(self, model, frame_id=WORLD_FRAME):
        n = len(model.names)
        self.frame_id = frame_id
        self._clear = Marker(action=Marker.DELETEALL)
        self._clear.header.frame_id = frame_id
        self._bodies = body_markers(model, np.zeros((n, 3)), np.tile([1.0, 0, 0, 0], (n, 1)), 0, frame_id).markers
        self._moving = [i for i in range(n) if int(model.shape_type[i]) != PLANE_SHAPE]

    def build(self, pos, quat, contacts, stamp_ns):
        stamp = time_msg(stamp_ns)
        self._clear.header.stamp = stamp
        pos_rows, quat_rows = pos.tolist(), quat.tolist()
        for i in self._moving:
            _set_pose(self._bodies[i], pos_rows[i], quat_rows[i])
        for m in self._bodies:
            m.header.stamp = stamp
        arrows = [
            contact_arrow(j, contacts.point[j], contacts.normal[j], contacts.event[j], stamp_ns, self.frame_id)
            for j in range(len(contacts))
        ]
        return MarkerArray(markers=[self._clear, *self._bodies, *arrows])


def scene_markers(model, pos, quat, contacts, stamp_ns, frame_id=WORLD_FRAME):
    """The world at one step: clear the previous frame, then bodies at their
    poses and one arrow per contact event along its normal."""
    clear = Marker()
    clear.header.stamp = time_msg(stamp_ns)
    clear.header.frame_id = frame_id
    clear.action = Marker.DELETEALL
    markers = [clear]
    markers += body_markers(model, pos, quat, stamp_ns, frame_id).markers
    for j in range(len(contacts)):
        markers.append(contact_arrow(j, contacts.point[j], contacts.normal[j], contacts.event[j], stamp_ns, frame_id))
    return MarkerArray(markers=markers)
