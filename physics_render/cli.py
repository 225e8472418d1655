"""`physics-render [SCENE.yaml | FILE.mcap] --out FILE.gif|FILE.mp4|FILE.png|DIR`."""

import argparse
import os
import sys
import time
import warnings

import numpy as np

from physics_core.shapes import PLANE

from .camera import Camera, frame_scene
from .draw import Renderer
from .output import MCAP, OutputError, check_output, output_kind, write
from .timeline import NS_PER_S, frame_times, scene_frames

DEFAULT_SCENE_DURATION = 3.0  # s


def build_parser():
    p = argparse.ArgumentParser(
        prog="physics-render",
        description="Pictures and video of a scene (stepped by the engine) or of a recording (read back): "
        "every body as its shape, the ground, contact points and normals coloured by event, sim time in a corner.",
    )
    p.add_argument("input", nargs="?", help="scene .yaml or recording .mcap (default: the built-in scene)")
    p.add_argument("--out", help="FILE.gif, FILE.mp4, FILE.png (with --at) or a folder of PNG frames "
                   "(default: the input's name with .gif, or .png with --at); from a recording, FILE.mcap writes "
                   "a copy with Foxglove scene updates at every step")
    p.add_argument("--duration", type=float, metavar="S",
                   help=f"seconds shown (scene default {DEFAULT_SCENE_DURATION:g}; recording default: all of it)")
    p.add_argument("--start", type=float, default=0.0, metavar="S", help="first frame's time (default 0)")
    p.add_argument("--at", type=float, metavar="T", help="one still picture at time T")
    p.add_argument("--fps", type=float, default=25.0, help="frames per second (default 25)")
    p.add_argument("--size", default="640x480", metavar="WxH", help="picture size in pixels (default 640x480)")
    p.add_argument("--elevation", type=float, default=20.0, metavar="DEG", help="camera above the xy plane (20)")
    p.add_argument("--azimuth", type=float, default=-70.0, metavar="DEG",
                   help="camera direction from +x towards +y (-70; -90 looks along +y)")
    p.add_argument("--distance", type=float, metavar="M", help="camera to target (default: frames every body)")
    p.add_argument("--target", type=float, nargs=3, metavar=("X", "Y", "Z"),
                   help="point looked at (default: the middle of the bodies' range)")
    p.add_argument("--fov", type=float, default=40.0, metavar="DEG", help="vertical field of view (40)")
    p.add_argument("--no-shadows", action="store_true", help="no shadow blobs on the planes")
    return p


def parse_size(text):
    try:
        w, h = (int(v) for v in text.lower().split("x"))
    except ValueError:
        raise OutputError(f"--size {text!r}: expected WIDTHxHEIGHT in pixels, e.g. 640x480") from None
    if w < 16 or h < 16 or w > 8192 or h > 8192:
        raise OutputError(f"--size {text!r}: width and height must be within 16..8192 pixels")
    return w, h


def load_frames(source, times_ns, span_ns=0):
    """(frames, title) from a scene path (None = built-in) or a recording."""
    if source is not None and source.lower().endswith(".mcap"):
        from .recording_frames import open_recording, recording_frames

        recording, node = open_recording(source)
        frames = list(recording_frames(recording, node, times_ns, span_ns))
        if not frames:
            raise OutputError(f"{source}: no recorded poses at the times asked for (the recording is shorter)")
        return frames, os.path.basename(source)
    from physics_core import default_scene_path, load_scene

    path = source or default_scene_path()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # a render need not repeat the loader's notes
        world = load_scene(path)
    return list(scene_frames(world, times_ns, span_ns)), os.path.basename(path)


def bounds(frames):
    """Corners of the box holding every non-plane body in every frame."""
    lo, hi = np.full(3, np.inf), np.full(3, -np.inf)
    for f in frames:
        solid = np.flatnonzero(f.shapes.kind != PLANE)
        if len(solid) == 0:
            continue
        r = np.array([f.shapes.bounding_radius(i) for i in solid])[:, None]
        lo = np.minimum(lo, (f.pos[solid] - r).min(axis=0))
        hi = np.maximum(hi, (f.pos[solid] + r).max(axis=0))
        for a, b, point_a, point_b in f.shapes.springs:
            for body, point in ((a, point_a), (b, point_b)):
                if body < 0:  # a spring's anchor in the world is in the picture too
                    lo, hi = np.minimum(lo, point), np.maximum(hi, point)
    if not np.all(np.isfinite(lo)):
        return np.full(3, -1.0), np.full(3, 1.0)
    return lo, hi


def camera_for(args, frames, size):
    options = {"elevation": args.elevation, "azimuth": args.azimuth, "fov": args.fov, "width": size[0],
               "height": size[1]}
    if args.distance is not None:
        options["distance"] = args.distance
    if args.target is not None:
        options["target"] = tuple(args.target)
    if args.distance is not None and args.target is not None:
        return Camera(**options)
    return frame_scene(*bounds(frames), **options)


def default_out(source, still):
    stem = os.path.splitext(os.path.basename(source))[0] if source else "default"
    return stem + (".png" if still else ".gif")


def render(args):
    size = parse_size(args.size)
    still = args.at is not None
    out = args.out or default_out(args.input, still)
    kind = output_kind(out)
    if kind == MCAP:
        return _export(args, out)
    if kind == "png" and not still:
        raise OutputError(f"--out {out}: a .png holds one picture; give --at T for a still, or a folder for frames")
    duration = args.duration
    if duration is None and not (args.input or "").lower().endswith(".mcap"):
        duration = DEFAULT_SCENE_DURATION
    check_output(out, kind, size)
    span_ns = 0 if still else int(round(NS_PER_S / args.fps)) if args.fps > 0 else 0
    frames, title = load_frames(args.input, frame_times(args.fps, duration, args.at, args.start), span_ns)
    camera = camera_for(args, frames, size)
    renderer = Renderer(camera, shadows=not args.no_shadows, title=title)
    count = write(out, kind, (renderer.render(f) for f in frames), args.fps)
    return out, count, frames, size


def _export(args, out):
    if not (args.input or "").lower().endswith(".mcap"):
        raise OutputError(f"--out {out}: a Foxglove copy is made from a recording (.mcap), not from a scene")
    from .foxglove_export import export

    count = export(args.input, out)
    return out, count, None, None


def main(argv=None):
    args = build_parser().parse_args(argv)
    started = time.monotonic()
    try:
        out, count, frames, size = render(args)
    except (OutputError, ValueError, OSError) as exc:
        print(f"physics-render: {exc}", file=sys.stderr, flush=True)
        return 2
    kb = _size_kb(out)
    if frames is None:
        print(f"wrote {out}{kb}: the recording and {count} scene updates for Foxglove", flush=True)
        return 0
    span = f"t = {frames[0].time:.3f} s" if count == 1 else f"{frames[0].time:.3f}-{frames[-1].time:.3f} s"
    print(f"wrote {count} frame{'s' * (count != 1)} ({size[0]}x{size[1]}, {span}) to {out}{kb} "
          f"in {time.monotonic() - started:.1f} s", flush=True)
    return 0


def _size_kb(path):
    if os.path.isfile(path):
        return f" ({os.path.getsize(path) / 1024:.0f} kB)"
    return ""


if __name__ == "__main__":
    sys.exit(main())
