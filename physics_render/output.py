"""Frames to files: an animated GIF (Pillow), an MP4 (imageio's ffmpeg), one
PNG, or a folder of numbered PNGs."""

import os

import numpy as np
from PIL import Image

GIF, MP4, PNG, FOLDER, MCAP = "gif", "mp4", "png", "folder", "mcap"


class OutputError(ValueError):
    pass


def output_kind(path):
    """What `path` asks for: a .gif, a .mp4, a .png, or else a folder of PNG frames."""
    ext = os.path.splitext(str(path))[1].lower()
    if ext in (".gif", ".mp4", ".png", ".mcap"):
        return ext[1:]
    if ext and not os.path.isdir(path):
        raise OutputError(f"--out {path}: unknown picture type {ext!r}; use .gif, .mp4, .png, a folder, "
                          "or .mcap (a recording's copy for Foxglove)")
    return FOLDER


def check_output(path, kind, size):
    """Refuse what cannot be written before anything is rendered."""
    width, height = size
    if kind == MP4 and (width % 2 or height % 2):
        raise OutputError(f"--size {width}x{height}: an MP4 (H.264, yuv420p) needs an even width and height")
    parent = os.path.dirname(os.path.abspath(str(path))) if kind != FOLDER else os.path.abspath(str(path))
    if kind != FOLDER and not os.path.isdir(parent):
        raise OutputError(f"--out {path}: folder {parent} does not exist")


def write(path, kind, pictures, fps):
    """Write the (h, w, 3) uint8 pictures; returns how many were written."""
    if kind == GIF:
        return _write_gif(path, pictures, fps)
    if kind == MP4:
        return _write_mp4(path, pictures, fps)
    if kind == PNG:
        count = 0
        for picture in pictures:
            Image.fromarray(picture).save(path, optimize=True)
            count += 1
        return count
    os.makedirs(path, exist_ok=True)
    count = 0
    for count, picture in enumerate(pictures, start=1):
        Image.fromarray(picture).save(os.path.join(path, f"frame_{count - 1:05d}.png"))
    return count


def _write_gif(path, pictures, fps):
    """GIF frame delays are whole centiseconds: 25 fps (4 cs) and 50 fps (2 cs)
    play exactly, 30 fps plays at 1/0.03 = 33.3 fps. Each frame gets its own
    palette of at most 128 colours."""
    frames = [Image.fromarray(p).quantize(colors=128, method=Image.Quantize.MEDIANCUT, dither=Image.Dither.NONE)
              for p in pictures]
    if not frames:
        return 0
    delay = max(20, int(round(1000.0 / fps / 10.0)) * 10)
    frames[0].save(path, save_all=True, append_images=frames[1:], duration=delay, loop=0, optimize=True,
                   disposal=1)
    return len(frames)


def _write_mp4(path, pictures, fps):
    try:
        import imageio.v2 as imageio
    except ImportError as exc:  # the `render` extra
        raise OutputError("MP4 output needs imageio and imageio-ffmpeg: pip install 'physics_node[render]'") from exc
    count = 0
    writer = imageio.get_writer(path, fps=fps, codec="libx264", quality=7, pixelformat="yuv420p",
                                macro_block_size=1, ffmpeg_log_level="error")
    try:
        for picture in pictures:
            writer.append_data(np.ascontiguousarray(picture))
            count += 1
    finally:
        writer.close()
    return count
