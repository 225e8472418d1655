"""A box pyramid (one vertical wall of boxes, each row half a box in from the one below)
with about n boxes, as an engines.py body list."""
import math

HALF = 0.1          # m, half size of each cube
GAP = 0.002         # m left between neighbours, so the pyramid starts awake and settles


def rows_for(n):
    """Base row b with b (b + 1) / 2 ≥ n."""
    return max(1, math.ceil((math.sqrt(8 * n + 1) - 1) / 2))


def boxes(n):
    b = rows_for(n)
    out = []
    pitch = 2 * HALF + GAP
    for row in range(b):
        count = b - row
        z = HALF + GAP + row * (2 * HALF + GAP)
        x0 = -0.5 * (count - 1) * pitch
        for k in range(count):
            out.append(("box", (HALF, HALF, HALF), (x0 + k * pitch, 0.0, z)))
    return out[:max(n, 1)] if n < len(out) else out
