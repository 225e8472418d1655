"""`physics-render`: frame count and size as asked, and bodies drawn where the
engine (or the recording) put them, checked through the camera's own formula."""

import base64
import json
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from foxglove_client import protobuf_class
from mcap.reader import make_reader
from mcap.writer import Writer
from PIL import Image
from test_node_support import NodeProcess

from geometry_msgs.msg import PoseArray
from rclpy.serialization import deserialize_message
from sensor_msgs.msg import PointCloud2

from msg_adapters import arrays_from_pose_array, contacts_from_cloud
from physics_core import default_scene_path, load_scene
from physics_node.recording_reader import Recording
from physics_render import Camera, frame_scene
from physics_render.cli import main as render_main
from physics_render.draw import Renderer, sphere_fill
from physics_render.recording_frames import open_recording, recording_frames
from physics_render.timeline import NS_PER_S, frame_times, scene_frames, step_at

BALL = 1  # the default scene's ball: radius 0.1 m, dropped from 1.5 m


def ball_pixels(picture, shapes, index=BALL, tolerance=3):
    """(u, v) centroid of the pixels painted in the sphere's own two fill
    colours (disc and highlight), pixel i spanning [i, i + 1)."""
    fills = [np.array(c) * 255.0 for c in sphere_fill(shapes.color(index))]
    mask = np.zeros(picture.shape[:2], dtype=bool)
    for c in fills:
        mask |= np.all(np.abs(picture.astype(float) - c) <= tolerance, axis=-1)
    v, u = np.nonzero(mask)
    assert len(u) > 50, "the ball is not on the picture"
    return np.array([u.mean() + 0.5, v.mean() + 0.5]), len(u)


def test_camera_formula_puts_the_target_in_the_middle_and_x_to_the_right():
    cam = Camera(target=(1.0, 2.0, 0.5), distance=4.0, elevation=30.0, azimuth=-90.0, width=400, height=300)
    assert np.allclose(cam.project(cam.target), (200.0, 150.0))
    # Looking along +y: world +x is to the right, world +z is up (smaller v).
    right, up = cam.project([2.0, 2.0, 0.5]), cam.project([1.0, 2.0, 1.5])
    assert right[0] > 200.0 and abs(right[1] - 150.0) < 1e-9
    assert up[1] < 150.0
    # A point 1 m right of the target at the target's depth lands f/d pixels right: f = (h/2)/tan(fov/2).
    f = 150.0 / np.tan(np.radians(20.0))
    assert right[0] - 200.0 == pytest.approx(f / 4.0, rel=1e-12)
    assert np.all(np.isnan(cam.project(cam.eye - 0.1 * (np.asarray(cam.target) - cam.eye))))


@settings(max_examples=60, deadline=None)
@given(
    lo=st.tuples(*[st.floats(-5, 5)] * 3),
    size=st.tuples(*[st.floats(0.01, 4)] * 3),
    elevation=st.floats(-85, 85),
    azimuth=st.floats(-180, 180),
    fov=st.floats(10, 120),
    shape=st.sampled_from([(320, 200), (200, 320), (64, 64)]),
)
def test_framing_fits_every_corner_of_the_box_on_the_picture(lo, size, elevation, azimuth, fov, shape):
    lo = np.array(lo)
    hi = lo + np.array(size)
    cam = frame_scene(lo, hi, elevation=elevation, azimuth=azimuth, fov=fov, width=shape[0], height=shape[1])
    corners = np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])])
    px = cam.project(corners)
    assert np.all((px >= 0) & (px <= shape)), px
    # And the picture's middle is the box's middle.
    assert np.allclose(cam.project(0.5 * (lo + hi)), np.array(shape) / 2.0)


@pytest.mark.parametrize("azimuth, elevation", [(-70.0, 20.0), (-90.0, 5.0), (30.0, 60.0)])
def test_ball_drawn_where_the_engine_put_it(azimuth, elevation):
    """At t = 0.3 s the ball is falling; an engine of its own stepped to the
    same step says where it is, and the camera's formula where that lands."""
    t_ns = int(0.3 * NS_PER_S)
    frame = next(scene_frames(load_scene(default_scene_path()), [t_ns]))
    reference = load_scene(default_scene_path())
    reference.step(step_at(t_ns, reference.dt))
    expected_pos = reference.body("ball").position
    assert np.array_equal(frame.pos[BALL], expected_pos)
    assert 1.0 < expected_pos[2] < 1.1  # about 1.5 - g t^2 / 2 = 1.06 m: in flight, not resting
    cam = Camera(target=(0.0, 0.0, 0.7), distance=3.5, azimuth=azimuth, elevation=elevation, width=480, height=360)
    picture = Renderer(cam).render(frame)
    assert picture.shape == (360, 480, 3)
    centre, area = ball_pixels(picture, frame.shapes)
    assert np.linalg.norm(centre - cam.project(expected_pos)) < 1.5
    # Its size too: a 0.1 m sphere at distance d has a radius of about f r / d
    # pixels; the mask leaves out the outline stroke and the antialiased rim
    # (up to 1.5 px of the radius) and nothing outside it.
    d = np.linalg.norm(cam.eye - expected_pos)
    radius = cam.focal * 0.1 / d
    assert radius - 1.5 < np.sqrt(area / np.pi) < radius + 0.25


def test_default_scene_gif_has_the_frames_and_size_asked(tmp_path):
    out = tmp_path / "pile.gif"
    assert render_main(["--duration", "0.6", "--fps", "25", "--size", "240x160", "--out", str(out)]) == 0
    with Image.open(out) as gif:
        assert gif.size == (240, 160)
        assert gif.n_frames == 16  # 0.6 s at 25 fps, both ends: 0, 0.04, ..., 0.6
        assert gif.info["duration"] == 40


def test_still_and_png_folder(tmp_path):
    still = tmp_path / "still.png"
    assert render_main(["--at", "0.25", "--size", "200x150", "--out", str(still)]) == 0
    assert Image.open(still).size == (200, 150)
    folder = tmp_path / "frames"
    assert render_main(["--duration", "0.2", "--fps", "10", "--size", "64x48", "--out", str(folder)]) == 0
    names = sorted(p.name for p in folder.iterdir())
    assert names == [f"frame_{k:05d}.png" for k in range(3)]


def test_bad_options_are_refused_with_what_was_wrong(tmp_path, capsys):
    assert render_main(["--out", str(tmp_path / "x.png")]) == 2
    assert "--at T" in capsys.readouterr().err
    assert render_main(["--size", "big", "--out", str(tmp_path / "x.gif")]) == 2
    assert "WIDTHxHEIGHT" in capsys.readouterr().err
    assert render_main(["--size", "101x80", "--out", str(tmp_path / "x.mp4")]) == 2
    assert "even" in capsys.readouterr().err
    assert render_main([str(tmp_path / "missing.mcap"), "--out", str(tmp_path / "x.gif")]) == 2
    assert "missing.mcap" in capsys.readouterr().err


@pytest.fixture(scope="module")
def recording(tmp_path_factory):
    """The built-in scene run by the node for 1.2 s of sim time, recorded."""
    workdir = tmp_path_factory.mktemp("render")
    path = workdir / "run.mcap"
    with NodeProcess(["--record", path, "--rtf", "0", "--duration", "1.2"], workdir, isolated=True) as node:
        assert node.wait(60.0) == 0, node.log()
    return path


def test_recording_mp4_has_the_frames_and_size_asked(recording, tmp_path):
    import imageio.v3 as imageio  # the render extra, installed by make install
    out = tmp_path / "run.mp4"
    assert render_main([str(recording), "--fps", "10", "--size", "160x120", "--out", str(out)]) == 0
    frames = imageio.imread(out)
    assert frames.shape == (13, 120, 160, 3)  # all 1.2 s at 10 fps, both ends


def test_recording_ball_drawn_at_its_recorded_pose(recording):
    rec, node = open_recording(recording)
    t_ns = int(0.35 * NS_PER_S)
    (frame,) = recording_frames(rec, node, [t_ns])
    recorded = [m for m in Recording(recording).messages() if m.topic == f"{node}/poses" and m.log_time <= t_ns]
    assert frame.step == recorded[-1].sequence  # the last state at or before the time asked
    cam = Camera(target=(0.0, 0.0, 0.7), distance=3.0, azimuth=-80.0, elevation=15.0, width=400, height=300)
    centre, _ = ball_pixels(Renderer(cam).render(frame), frame.shapes)
    assert np.linalg.norm(centre - cam.project(frame.pos[BALL])) < 1.5
    # The same moment as the engine computes it from the scene (the node ran it unpushed).
    reference = load_scene(default_scene_path())
    reference.step(frame.step)
    assert np.array_equal(frame.pos, reference.state.pos)


def _cut_copy(src, dst, keep=0.6):
    """`src` rewritten in small chunks and then cut at `keep` of its length,
    as a crash leaves it: no summary, no footer, a torn last chunk."""
    rec = Recording(src)
    with open(dst, "wb") as f:
        writer = Writer(f, chunk_size=16 << 10)
        writer.start(profile=rec.profile, library=rec.library or "")
        for a in rec.attachments:
            writer.add_attachment(a.create_time, a.log_time, a.name, a.media_type, a.data)
        for name, values in rec.metadata.items():
            writer.add_metadata(name, values)
        ids = {}
        for r in rec.raw_records():
            kind = type(r).__name__
            if kind == "Schema":
                ids[("s", r.id)] = writer.register_schema(r.name, r.encoding, r.data)
            elif kind == "Channel":
                ids[("c", r.id)] = writer.register_channel(r.topic, r.message_encoding, ids[("s", r.schema_id)],
                                                           r.metadata)
            else:
                writer.add_message(ids[("c", r.channel_id)], r.log_time, r.data, r.publish_time, r.sequence)
        writer.finish()
    size = dst.stat().st_size
    with open(dst, "r+b") as f:
        f.truncate(int(size * keep))


def test_cut_recording_renders_up_to_its_last_complete_chunk(recording, tmp_path):
    cut = tmp_path / "cut.mcap"
    _cut_copy(recording, cut)
    rec, node = open_recording(cut)
    assert not rec.complete
    last_pose = max(m.log_time for m in rec.messages() if m.topic == f"{node}/poses")
    assert 0.2 * NS_PER_S < last_pose < 1.0 * NS_PER_S
    folder = tmp_path / "frames"
    assert render_main([str(cut), "--fps", "20", "--size", "64x48", "--out", str(folder)]) == 0
    expected = sum(1 for _, t in zip(range(100), frame_times(20.0)) if t <= last_pose)  # frames at 0, 0.05, ...
    assert len(list(folder.iterdir())) == expected


def test_foxglove_copy_of_a_recording_draws_every_step_at_its_recorded_pose(recording, tmp_path):
    """The .mcap for Foxglove: every recorded message, plus a scene update per
    recorded step whose body poses are that step's ~/poses, bit for bit, and
    whose contact arrows are that step's contact events."""
    out = tmp_path / "run.foxglove.mcap"
    assert render_main([str(recording), "--out", str(out)]) == 0
    with open(out, "rb") as f:
        reader = make_reader(f)
        summary = reader.get_summary()
        scene_channel = next(c for c in summary.channels.values() if c.topic == "/physics/scene")
        schema = summary.schemas[scene_channel.schema_id]
        SceneUpdate = protobuf_class({"schemaEncoding": schema.encoding, "schemaName": schema.name,
                                      "schema": base64.b64encode(schema.data).decode()})
        poses, contacts, scenes = {}, {}, {}
        for _schema, channel, message in reader.iter_messages():
            if channel.topic == "/physics/poses":
                poses[message.log_time] = arrays_from_pose_array(deserialize_message(message.data, PoseArray))
            elif channel.topic == "/physics/contacts":
                contacts[message.log_time] = contacts_from_cloud(deserialize_message(message.data, PointCloud2))
            elif channel.topic == "/physics/scene":
                scenes[message.log_time] = SceneUpdate.FromString(message.data)
    original = sum(1 for m in Recording(recording).messages() if m.topic == "/physics/poses")
    assert len(scenes) == len(poses) == original
    for t, update in scenes.items():
        by_id = {e.id: e for e in update.entities}
        pos, quat = poses[t]
        for name, i in (("ball", 1), ("crate", 2), ("bob", 3)):
            prim = (list(by_id[name].spheres) + list(by_id[name].cubes))[0]
            p, q = prim.pose.position, prim.pose.orientation
            assert (p.x, p.y, p.z) == tuple(pos[i]) and (q.w, q.x, q.y, q.z) == tuple(quat[i]), (t, name)
        assert len(by_id["contacts"].arrows) == len(contacts[t])
    assert any(len(c) for c in contacts.values()), "the bodies should touch the ground within 1.2 s"
    # The layout shipped in the repo shows these topics.
    layout = json.loads((Path(__file__).parents[1] / "layouts" / "foxglove_physics.json").read_text())
    three_d = layout["configById"]["3D!physics"]["topics"]
    assert three_d["/physics/scene"]["visible"] and three_d["/physics/contacts"]["colorField"] == "event"
    plotted = layout["configById"]["Plot!bodyheight"]["paths"][0]["value"]
    assert plotted == "/physics/poses.poses[1].position.z"  # the ball's height


def test_still_shows_only_its_own_steps_contact_events():
    """A still once showed every `begin` since t = 0 (the whole pyramid green
    at 1 s). A still shows the events of its own step; a clip frame also the
    begins and ends of the steps since the frame before, each once."""
    pyramid = str(Path(__file__).parents[1] / "scenes" / "pyramid_10.yaml")
    reference = load_scene(pyramid)
    per_step = [np.zeros(0, dtype=np.uint8)]  # events of step k (step 0: none yet)
    for _ in range(19):
        reference.step()
        per_step.append(np.asarray(reference.contacts.event).copy())
    t = int(0.04 * NS_PER_S)
    k1, k2 = step_at(t, reference.dt), step_at(2 * t, reference.dt)  # 9 and 19

    def expected(first_step, last_step):
        transient = [e[e != 1] for e in per_step[first_step:last_step]]
        return np.sort(np.concatenate(transient + [per_step[last_step]]))

    (still,) = scene_frames(load_scene(pyramid), [t], span_ns=0)
    assert np.array_equal(np.sort(still.contact_event), np.sort(per_step[k1]))
    first, second, third = scene_frames(load_scene(pyramid), [0, t, 2 * t], span_ns=t)
    assert len(first.contact_event) == 0  # before the first step
    assert np.array_equal(np.sort(second.contact_event), expected(1, k1))
    assert np.count_nonzero(second.contact_event == 0) >= 300  # the boxes' first touches, from step 1
    assert np.array_equal(np.sort(third.contact_event), expected(k1 + 1, k2))
