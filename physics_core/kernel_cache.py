"""Where the compiled kernels are cached: a folder named by the engine's source.

Numba's own cache (cache=True) is keyed by each function's file, so a
kernel compiled together with one it calls from another file keeps the old
code when only that other file changes. Keying the whole cache folder by a
hash of every source file of physics_core means any edit starts a fresh
folder and a stale kernel is never loaded; the folder of the previous
source is removed. A user's own NUMBA_CACHE_DIR is left alone.
"""
import hashlib
import os
import shutil

import numba

PACKAGE_DIR = os.path.dirname(os.path.abspath(__file__))
PREFIX = "kernels-"


def source_hash(root=PACKAGE_DIR) -> str:
    h = hashlib.sha1(numba.__version__.encode())
    for folder, dirs, files in sorted(os.walk(root)):
        dirs[:] = sorted(d for d in dirs if d != "__pycache__")
        for name in sorted(f for f in files if f.endswith(".py")):
            path = os.path.join(folder, name)
            h.update(os.path.relpath(path, root).encode())
            with open(path, "rb") as f:
                h.update(f.read())
    return h.hexdigest()[:16]


def _writable_base():
    for base in (os.path.join(PACKAGE_DIR, "__pycache__"),
                 os.path.join(os.path.expanduser("~"), ".cache", "physics_core")):
        try:
            os.makedirs(base, exist_ok=True)
            if os.access(base, os.W_OK):
                return base
        except OSError:
            continue
    return None


def use_source_keyed_cache():
    """Point numba's cache at this source's folder (before any kernel is defined)."""
    if os.environ.get("NUMBA_CACHE_DIR"):
        return numba.config.CACHE_DIR
    base = _writable_base()
    if base is None:
        return None
    folder = os.path.join(base, PREFIX + source_hash())
    for old in os.listdir(base):
        if old.startswith(PREFIX) and os.path.join(base, old) != folder:
            shutil.rmtree(os.path.join(base, old), ignore_errors=True)
    numba.config.CACHE_DIR = folder
    return folder
