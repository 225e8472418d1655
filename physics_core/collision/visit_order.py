"""The order a manifold's points take their friction in, in the collision pass.

Rows come in key order, and a face's keys go round it (box_pair._QUAD, a
box's vertex numbers): in key order the first two corners of a face stand
on one side of it. Friction applied point by point, each on the velocities
the one before left, then turns a body that slides along the face: the
first corner's impulse turns it about the normal, and the next corners
meet a slip turned sideways. Three boxes in a plane (one landing at 2.3
m/s across two) left the pass moving out of their plane at 4.8 mm/s,
turning at 0.14 rad/s about the vertical; a pyramid of 10,000 boxes leaned
out of its plane and fell down. Visited from opposite corners first, the
first two impulses turn the body about no axis of the face.
"""
from numba import njit

from .contact_layout import ARM_A


@njit(cache=True, inline="always")
def farthest(R, first, count):
    """The offset (1..count − 1) of the point of rows first..first + count − 1
    farthest from the first one along the face (the lowest on a tie):
    |(r_j − r_0) × n| from the rows' lever-arm products r × n; 1 for one
    point."""
    far, best = 1, -1.0
    for j in range(1, count):
        d = 0.0
        for i in range(3):
            d += (R[first + j, ARM_A + i] - R[first, ARM_A + i]) ** 2
        if d > best:
            far, best = j, d
    return far


@njit(cache=True, inline="always")
def visit(j, far):
    """The offset of the j-th point visited: the first, the one farthest from
    it, then the others in key order."""
    if j == 0:
        return 0
    if j == 1:
        return far
    return j - 1 if j - 1 < far else j
