"""`physics-render run.mcap --out run.foxglove.mcap`: a copy of a recording
that Foxglove draws as it is: every recorded message, plus at every recorded
step a foxglove.SceneUpdate on `<node>/scene` (each body as its shape at its
pose, the step's contact events as arrows) and foxglove.FrameTransforms on
`<node>/transforms`, at the step's sim time. The recording itself keeps only
ROS types (rosbag2 readers decode all of it); this copy is for viewing.
"""

import os

from msg_adapters import arrays_from_pose_array, contacts_from_cloud

from .recording_frames import RecordingError, open_recording, scene_shapes


class _Pending:
    """A step's poses, held until its contacts (written just after them) arrive."""

    def __init__(self):
        self.pose = None  # (time ns, pos, quat)

    def take(self):
        pose, self.pose = self.pose, None
        return pose


def export(src, dst):
    """Write the Foxglove copy; returns the number of scene updates written."""
    import foxglove
    from foxglove.channels import FrameTransformsChannel, SceneUpdateChannel
    from geometry_msgs.msg import PoseArray
    from rclpy.serialization import deserialize_message
    from sensor_msgs.msg import PointCloud2

    from physics_core.contact_events import ContactEvents
    from physics_node.foxglove_scene import SceneMessages

    recording, node = open_recording(src)
    shapes = scene_shapes(recording)
    if shapes is None:
        raise RecordingError(f"{src}: no scene attachment, so the bodies' shapes are unknown")
    scene = SceneMessages(shapes)
    if os.path.abspath(src) == os.path.abspath(dst):
        raise RecordingError(f"--out {dst}: would overwrite the recording it is made from")
    context = foxglove.Context()
    writer = foxglove.open_mcap(dst, allow_overwrite=True, context=context)
    scene_channel = SceneUpdateChannel(f"{node}/scene", context=context)
    transforms_channel = FrameTransformsChannel(f"{node}/transforms", context=context)
    for a in recording.attachments:  # the scene and the session's parameters travel along
        writer.attach(log_time=a.log_time, create_time=a.create_time, name=a.name, media_type=a.media_type,
                      data=bytes(a.data))
    for name, values in recording.metadata.items():
        writer.write_metadata(name, dict(values))
    schemas, channels, pending, count = {}, {}, _Pending(), 0
    empty = ContactEvents.empty()

    def emit(pose, contacts):
        t, pos, quat = pose
        scene_channel.log(scene.scene_update(pos, quat, contacts, t), log_time=t)
        transforms_channel.log(scene.transforms(pos, quat, t), log_time=t)

    try:
        for r in recording.raw_records():
            kind = type(r).__name__
            if kind == "Schema":
                schemas[r.id] = foxglove.Schema(name=r.name, encoding=r.encoding, data=bytes(r.data))
                continue
            if kind == "Channel":
                if r.id not in channels:
                    channels[r.id] = foxglove.Channel(r.topic, schema=schemas.get(r.schema_id),
                                                      message_encoding=r.message_encoding, metadata=dict(r.metadata),
                                                      context=context)
                continue
            channel = channels[r.channel_id]
            channel.log(bytes(r.data), log_time=r.log_time)
            topic = channel.topic()
            if topic == f"{node}/poses":
                held = pending.take()
                if held is not None:
                    emit(held, empty)
                    count += 1
                pos, quat = arrays_from_pose_array(deserialize_message(r.data, PoseArray))
                pending.pose = (r.log_time, pos.tolist(), quat.tolist())
            elif topic == f"{node}/contacts" and pending.pose is not None and pending.pose[0] == r.log_time:
                emit(pending.take(), contacts_from_cloud(deserialize_message(r.data, PointCloud2)))
                count += 1
        held = pending.take()
        if held is not None:
            emit(held, empty)
            count += 1
    finally:
        writer.close()
    return count
