"""Where results go, and their raw data as JSON so the summary can be rebuilt from files."""
import json
import os
import platform

import numpy as np

DEFAULT_OUT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "results")


def ensure(out):
    os.makedirs(out, exist_ok=True)
    return out


def write_text(out, name, text):
    path = os.path.join(ensure(out), name)
    with open(path, "w", encoding="utf-8") as f:
        f.write(text)
    return path


def write_json(out, name, data):
    path = os.path.join(ensure(out), name)
    with open(path, "w", encoding="utf-8") as f:
        json.dump(data, f, indent=1, default=_plain, sort_keys=False)
        f.write("\n")
    return path


def read_json(out, name):
    path = os.path.join(out, name)
    if not os.path.exists(path):
        return None
    with open(path, encoding="utf-8") as f:
        return json.load(f)


def machine():
    """One line naming the machine the numbers were taken on."""
    return (f"{platform.machine()}, {os.cpu_count()} CPU, Python {platform.python_version()}, "
            f"numpy {np.__version__}")


def _plain(x):
    if isinstance(x, np.generic):
        return x.item()
    if isinstance(x, np.ndarray):
        return x.tolist()
    raise TypeError(type(x))
