"""Small typed readers for scene dicts: each names the key path on failure."""
import math
import re

import numpy as np

from .errors import SceneError

NAME_RE = re.compile(r"^[A-Za-z][A-Za-z0-9_]*$")


def _finite(v) -> bool:
    """math.isfinite that also says False for an integer beyond float64 (10**400)."""
    try:
        return math.isfinite(v)
    except OverflowError:
        return False


def _floats(values) -> np.ndarray:
    """A float array of `values`, an integer beyond float64 becoming inf."""
    return np.array([x if _finite(x) else math.inf for x in values], dtype=float)


class Reader:
    """Reads one mapping of the scene, remembering the file and key path."""

    def __init__(self, source: str, data, path: str = ""):
        self.source = source
        self.path = path
        if not isinstance(data, dict):
            raise SceneError(source, path or "<top level>", "a mapping", type(data).__name__)
        self.data = data

    def at(self, key) -> str:
        if isinstance(key, int) and not isinstance(key, bool):
            return f"{self.path}[{key}]"
        key = str(key) if len(str(key)) <= 60 else str(key)[:59] + "…"   # a key can be any length
        return f"{self.path}.{key}" if self.path else key

    def fail(self, key, expected, got=None):
        raise SceneError(self.source, self.at(key), expected, got)

    def only(self, allowed):
        for k in self.data:
            if k not in allowed:
                raise SceneError(self.source, self.at(k), "one of: " + ", ".join(sorted(allowed)),
                                 "unknown key")

    def has(self, key) -> bool:
        return key in self.data

    def sub(self, key, default=None) -> "Reader":
        v = self.data.get(key, default if default is not None else {})
        if v is None:
            v = {}
        return Reader(self.source, v, self.at(key))

    def number(self, key, default=None, *, min=None, max=None, positive=False, integer=False):
        if key not in self.data:
            if default is None:
                self.fail(key, "a number (required)", "missing")
            return default
        v = self.data[key]
        kind = "an integer" if integer else "a number"
        if isinstance(v, bool) or not isinstance(v, (int, float)) or (integer and not isinstance(v, int)):
            self.fail(key, kind, v)
        if not _finite(v):
            self.fail(key, "a finite number", v)
        self._check_range(key, v, kind, min, max, positive)
        return int(v) if integer else float(v)

    def _check_range(self, key, v, kind, min, max, positive):
        if positive and not v > 0:
            self.fail(key, f"{kind} > 0", v)
        if min is not None and v < min:
            self.fail(key, f"{kind} >= {min}", v)
        if max is not None and v > max:
            self.fail(key, f"{kind} <= {max}", v)

    def boolean(self, key, default):
        v = self.data.get(key, default)
        if not isinstance(v, bool):
            self.fail(key, "true or false", v)
        return v

    def string(self, key, default=None, choices=None):
        if key not in self.data:
            if default is None:
                self.fail(key, "a string (required)", "missing")
            return default
        v = self.data[key]
        if not isinstance(v, str):
            self.fail(key, "a string", v)
        if choices is not None and v not in choices:
            self.fail(key, "one of: " + ", ".join(choices), v)
        return v

    def vector(self, key, size, default=None):
        if key not in self.data:
            if default is None:
                self.fail(key, f"a list of {size} numbers (required)", "missing")
            return np.array(default, dtype=float)
        v = self.data[key]
        if (not isinstance(v, (list, tuple)) or len(v) != size
                or any(isinstance(x, bool) or not isinstance(x, (int, float)) for x in v)):
            self.fail(key, f"a list of {size} numbers", v)
        arr = _floats(v)
        if not np.all(np.isfinite(arr)):
            self.fail(key, f"a list of {size} finite numbers", v)
        return arr

    def items(self, key):
        """Readers for each mapping in a list under `key` (empty if absent)."""
        v = self.data.get(key, [])
        if v is None:
            v = []
        if not isinstance(v, list):
            self.fail(key, "a list", type(v).__name__)
        return [Reader(self.source, item, f"{self.at(key)}[{i}]") for i, item in enumerate(v)]
