"""A snippet run in a fresh Python process, and the value it printed last."""
import ast
import subprocess
import sys

ROOT = __file__.rsplit("/tests/", 1)[0]


def printed_value(code, timeout=300, env=None):
    """The Python literal `code` prints last, run from the project root in a
    fresh process; a failing run's stderr is the assertion's message."""
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          timeout=timeout, env=env, cwd=ROOT)
    assert done.returncode == 0, done.stderr[-3000:]
    return ast.literal_eval(done.stdout.strip().splitlines()[-1])
