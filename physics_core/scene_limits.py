"""Bounds on a scene file, checked before (and while) it is parsed.

A scene comes from a file anyone can hand the node, so what it can cost is
bounded: the file's size (read at most that many bytes, so /dev/zero or a
growing file cannot fill the memory), its encoding (UTF-8 text, no NUL),
YAML aliases (refused: 532 bytes of nested aliases expand to gigabytes; an
anchor alone is harmless and allowed) and the number of bodies (each body
costs two command subscriptions and an odometry publisher in the node).
Every failure is a SceneError naming the file and what was wrong.
"""
import os

import yaml

from .errors import SceneError

MAX_BODIES = 10_000             # overridable: load_scene(..., max_bodies=N), physics-node --max-bodies N
MIN_FILE_BYTES = 1 << 20        # the size limit is this plus BYTES_PER_BODY per allowed body
BYTES_PER_BODY = 1 << 10        # a typed-in body takes 100-300 bytes; 1 KiB leaves room for comments


def max_file_bytes(max_bodies=MAX_BODIES):
    """Largest scene file accepted when up to `max_bodies` bodies are: 11 MiB at 10,000."""
    return MIN_FILE_BYTES + BYTES_PER_BODY * int(max_bodies)


def read_scene_text(path, max_bytes):
    """The text of scene file `path`, or SceneError (missing, a folder, too
    large, not UTF-8, binary)."""
    if os.path.isdir(path):
        raise SceneError(path, "", "a scene file", "a folder")
    try:
        with open(path, "rb") as f:
            data = f.read(max_bytes + 1)
    except OSError as e:
        raise SceneError(path, "", "a readable scene file", e.strerror or str(e)) from None
    if len(data) > max_bytes:
        raise SceneError(path, "", f"a scene file of at most {max_bytes} bytes "
                         "(raise --max-bodies for larger scenes)", "a larger file")
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as e:
        raise SceneError(path, "", "UTF-8 text",
                         f"byte 0x{data[e.start]:02x} at offset {e.start} (a binary file?)") from None
    if "\0" in text:
        raise SceneError(path, "", "text", f"a NUL character at offset {text.index(chr(0))} (a binary file?)")
    return text


def refuse_aliases(text, source, loader):
    """SceneError at the first YAML alias (`*name`, also in `<<: *name`)."""
    if "*" not in text:   # no alias can be written without one
        return
    try:
        for event in yaml.parse(text, Loader=loader):
            if isinstance(event, yaml.AliasEvent):
                line = event.start_mark.line + 1 if event.start_mark else "?"
                raise SceneError(source, f"line {line}", "a scene without YAML aliases (*name); write the "
                                 "value out where it is used", f"*{str(event.anchor)[:40]}")
    except yaml.YAMLError as e:
        raise SceneError(source, "", "valid YAML", _one_line(e)) from None


def check_body_count(source, bodies, max_bodies):
    if isinstance(bodies, list) and len(bodies) > max_bodies:
        raise SceneError(source, "bodies", f"at most {max_bodies} bodies (raise it with --max-bodies or "
                         "load_scene(..., max_bodies=N))", f"{len(bodies)} bodies")


def _one_line(error, limit=300):
    text = " ".join(str(error).split())
    return text if len(text) <= limit else text[:limit] + "…"
