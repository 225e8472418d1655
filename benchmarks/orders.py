"""Convergence orders and work–precision look-ups from (step, error, cost) samples."""
import math

import numpy as np

# Errors outside this band are not in the asymptotic regime: above, the method
# has lost the solution (errors saturate near 1); below, round-off dominates.
ASYMPTOTIC_MAX = 0.3
ASYMPTOTIC_MIN = 1e-11


FIT_POINTS = 4          # the finest runs in the band: the order is a small-h limit


def fit_order(h, err):
    """Least-squares slope of log(error) against log(h) over the finest asymptotic points.

    Returns (order, number of points used); order is NaN with fewer than 2 points."""
    pts = sorted((math.log(a), math.log(e)) for a, e in zip(h, err)
                 if ASYMPTOTIC_MIN < e < ASYMPTOTIC_MAX and math.isfinite(e))[:FIT_POINTS]
    if len(pts) < 2:
        return float("nan"), len(pts)
    x, y = np.array(pts).T
    slope = np.polyfit(x, y, 1)[0]
    return float(slope), len(pts)


def cost_for_error(costs, errs, target):
    """Smallest cost at which the error falls to `target`, by log–log interpolation
    between neighbouring runs (sorted by cost).

    Returns (cost, at_most): at_most is True when the cheapest run already meets
    the target, so the true cost may be lower; None if no run reaches it."""
    pts = sorted((c, e) for c, e in zip(costs, errs) if math.isfinite(e) and e > 0)
    best = None
    for i, (c, e) in enumerate(pts):
        if e > target:
            continue
        at_most = i == 0
        if i > 0 and pts[i - 1][1] > target:
            (c0, e0), (c1, e1) = pts[i - 1], (c, e)
            f = (math.log(target) - math.log(e0)) / (math.log(e1) - math.log(e0))
            c = math.exp(math.log(c0) + f * (math.log(c1) - math.log(c0)))
        if best is None or c < best[0]:
            best = (c, at_most)
    return best
