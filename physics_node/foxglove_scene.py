"""The world as Foxglove's own messages: a SceneUpdate (one entity per body,
its shape at its pose, and one entity of contact arrows) and FrameTransforms
(world -> each moving body). Poses are float64 end to end, so a scene
update's poses are the engine's state bit for bit, like `~/poses`.
"""

import numpy as np
from foxglove.messages import (
    ArrowPrimitive,
    Color,
    CubePrimitive,
    FrameTransform,
    FrameTransforms,
    Pose,
    Quaternion,
    SceneEntity,
    SceneEntityDeletion,
    SceneEntityDeletionType,
    SceneUpdate,
    SpherePrimitive,
    Timestamp,
    Vector3,
)

from msg_adapters import WORLD_FRAME
from msg_adapters.frames import quat_between_z_and
from physics_core.shapes import BOX, PLANE, SPHERE
from physics_render.draw import EVENT_RGB, NORMAL_LENGTH
from physics_render.shapes import Shapes

PLANE_DRAW_SIZE = 20.0  # m: an infinite plane is drawn as a square slab this wide, as in ~/bodies
PLANE_DRAW_THICKNESS = 0.002
CONTACTS_ENTITY = "contacts"


def timestamp(time_ns):
    return Timestamp(int(time_ns) // 1_000_000_000, int(time_ns) % 1_000_000_000)


def _pose(p, q):
    """Foxglove pose from a position and an engine quaternion (w, x, y, z)."""
    return Pose(position=Vector3(x=p[0], y=p[1], z=p[2]), orientation=Quaternion(x=q[1], y=q[2], z=q[3], w=q[0]))


def _quat_from_x_to(v):
    """(w, x, y, z) turning +x onto the unit vector v (an arrow primitive points along its +x)."""
    x = np.array([1.0, 0.0, 0.0])
    c = float(x @ v)
    if c < -0.999999:
        return (0.0, 0.0, 0.0, 1.0)  # half a turn about z
    axis = np.cross(x, v)
    q = np.array([1.0 + c, *axis])
    return tuple((q / np.linalg.norm(q)).tolist())


class SceneMessages:
    """Builds the scene update and transforms of one step for one set of
    shapes (physics_render.Shapes, or a scene Model)."""

    def __init__(self, shapes):
        self.shapes = shapes if isinstance(shapes, Shapes) else Shapes.from_model(shapes)
        s = self.shapes
        self._color = [Color(r=c[0], g=c[1], b=c[2], a=1.0) for c in (s.color(i) for i in range(len(s)))]
        self._event_color = {e: Color(r=c[0], g=c[1], b=c[2], a=1.0) for e, c in EVENT_RGB.items()}

    def _entity(self, i, pos, quat, stamp):
        s = self.shapes
        kind = int(s.kind[i])
        shape = {"pose": _pose(pos[i], quat[i]), "color": self._color[i]}
        if kind == SPHERE:
            d = 2.0 * float(s.radius[i])
            prims = {"spheres": [SpherePrimitive(size=Vector3(x=d, y=d, z=d), **shape)]}
        elif kind == BOX:
            h = s.half_extents[i]
            prims = {"cubes": [CubePrimitive(size=Vector3(x=2 * h[0], y=2 * h[1], z=2 * h[2]), **shape)]}
        else:
            n = s.plane_normal[i]
            centre = n * (float(s.plane_offset[i]) - 0.5 * PLANE_DRAW_THICKNESS)  # top face on n·x = offset
            size = Vector3(x=PLANE_DRAW_SIZE, y=PLANE_DRAW_SIZE, z=PLANE_DRAW_THICKNESS)
            prims = {"cubes": [CubePrimitive(pose=_pose(centre, quat_between_z_and(n)), size=size,
                                             color=self._color[i])]}
        return SceneEntity(timestamp=stamp, frame_id=WORLD_FRAME, id=s.names[i], **prims)

    def _contacts(self, contacts, stamp):
        arrows = []
        for point, normal, event in zip(np.asarray(contacts.point).tolist(), np.asarray(contacts.normal),
                                        np.asarray(contacts.event).tolist()):
            arrows.append(ArrowPrimitive(
                pose=_pose(point, _quat_from_x_to(normal)), shaft_length=0.7 * NORMAL_LENGTH, shaft_diameter=0.01,
                head_length=0.3 * NORMAL_LENGTH, head_diameter=0.025,
                color=self._event_color.get(int(event), self._event_color[1]),
            ))
        return SceneEntity(timestamp=stamp, frame_id=WORLD_FRAME, id=CONTACTS_ENTITY, arrows=arrows)

    def scene_update(self, pos, quat, contacts, time_ns):
        """Everything drawn anew: a delete-all first (bodies may have been removed), then every entity."""
        stamp = timestamp(time_ns)
        entities = [self._entity(i, pos, quat, stamp) for i in range(len(self.shapes))]
        entities.append(self._contacts(contacts, stamp))
        return SceneUpdate(deletions=[SceneEntityDeletion(timestamp=stamp, type=SceneEntityDeletionType.All)],
                           entities=entities)

    def transforms(self, pos, quat, time_ns):
        stamp = timestamp(time_ns)
        s = self.shapes
        return FrameTransforms(transforms=[
            FrameTransform(timestamp=stamp, parent_frame_id=WORLD_FRAME, child_frame_id=s.names[i],
                           translation=Vector3(x=pos[i][0], y=pos[i][1], z=pos[i][2]),
                           rotation=Quaternion(x=quat[i][1], y=quat[i][2], z=quat[i][3], w=quat[i][0]))
            for i in range(len(s)) if s.kind[i] != PLANE
        ])
