"""What the standard's read-only queries answer: entity filters, info and
bounds, from the World's model and state."""

import re

import numpy as np
from geometry_msgs.msg import Vector3
from simulation_interfaces.msg import Bounds, EntityCategory, EntityInfo, Result, TagsFilter

from physics_core import shapes

from .entities import EntityError

_SHAPE_TAG = {shapes.SPHERE: "sphere", shapes.BOX: "box", shapes.PLANE: "plane"}


def category(model, i):
    static = bool(model.is_static[i])
    return EntityCategory.CATEGORY_STATIC_OBJECT if static else EntityCategory.CATEGORY_OBJECT


def tags(model, i, spawned):
    """Tags every entity carries: static|dynamic, its shape, spawned|scene, its material."""
    name = model.names[i]
    return [
        "static" if model.is_static[i] else "dynamic",
        _SHAPE_TAG[int(model.shape_type[i])],
        "spawned" if name in spawned else "scene",
        model.material_names[int(model.material[i])],
    ]


def info(model, i, spawned):
    shape = int(model.shape_type[i])
    if shape == shapes.SPHERE:
        size = f"radius {float(model.radius[i]):g} m"
    elif shape == shapes.BOX:
        size = "half extents " + " x ".join(f"{float(h):g}" for h in model.half_extents[i]) + " m"
    else:
        size = f"normal {np.round(model.plane_normal[i], 6).tolist()}, offset {float(model.plane_offset[i]):g} m"
    mass = "static" if model.is_static[i] else f"{float(model.mass[i]):g} kg"
    return EntityInfo(
        category=EntityCategory(category=category(model, i)),
        description=f"{_SHAPE_TAG[shape]}, {size}, {mass}",
        tags=tags(model, i, spawned),
    )


def bounds(model, i):
    """Bounds in the body's own frame: a box's corners, a sphere's centre and
    radius, none (unbounded) for a plane."""
    shape = int(model.shape_type[i])
    if shape == shapes.SPHERE:
        return Bounds(type=Bounds.TYPE_SPHERE, points=[Vector3(), Vector3(x=float(model.radius[i]))])
    if shape == shapes.BOX:
        h = [float(v) for v in model.half_extents[i]]
        upper, lower = Vector3(x=h[0], y=h[1], z=h[2]), Vector3(x=-h[0], y=-h[1], z=-h[2])
        return Bounds(type=Bounds.TYPE_BOX, points=[upper, lower])
    return Bounds(type=Bounds.TYPE_EMPTY)


def matching(world, filters, spawned):
    """Indices of the bodies that pass an EntityFilters, in world order."""
    model = world.model
    keep = np.ones(len(model.names), dtype=bool)
    if filters.filter:
        try:
            pattern = re.compile(filters.filter)
        except re.error as exc:
            why = f"filter {filters.filter!r} is not a regular expression: {exc}"
            raise EntityError(Result.RESULT_OPERATION_FAILED, why) from None
        keep &= np.array([pattern.search(n) is not None for n in model.names], dtype=bool)
    if filters.categories:
        wanted = {c.category for c in filters.categories}
        keep &= np.array([category(model, i) in wanted for i in range(len(model.names))], dtype=bool)
    if filters.tags.tags:
        keep &= _tag_mask(model, filters.tags, spawned)
    if filters.bounds.type != Bounds.TYPE_EMPTY:
        keep &= _overlap_mask(world, filters.bounds)
    return [int(i) for i in np.flatnonzero(keep)]


def _tag_mask(model, tags_filter, spawned):
    wanted = set(tags_filter.tags)
    every = tags_filter.filter_mode == TagsFilter.FILTER_MODE_ALL
    test = wanted.issubset if every else (lambda have: bool(wanted & have))
    return np.array([test(set(tags(model, i, spawned))) for i in range(len(model.names))], dtype=bool)


def _overlap_mask(world, b):
    """Bodies whose bounding box overlaps a sphere or box region (world frame)."""
    pts = np.array([[p.x, p.y, p.z] for p in b.points], dtype=float)
    if b.type == Bounds.TYPE_SPHERE and len(pts) == 2:
        lo = hi = pts[0]
        radius = float(pts[1][0])
    elif b.type == Bounds.TYPE_BOX and len(pts) == 2:
        lo, hi, radius = pts.min(axis=0), pts.max(axis=0), 0.0
    elif b.type == Bounds.TYPE_CONVEX_HULL:
        why = "bounds filter: TYPE_CONVEX_HULL is not supported (TYPE_SPHERE and TYPE_BOX are)"
        raise EntityError(Result.RESULT_FEATURE_UNSUPPORTED, why)
    else:
        why = f"bounds filter: type {b.type} with {len(pts)} points is not a valid sphere or box"
        raise EntityError(Result.RESULT_OPERATION_FAILED, why)
    if not np.all(np.isfinite(pts)) or radius < 0:
        raise EntityError(Result.RESULT_OPERATION_FAILED, "bounds filter: points must be finite and a radius >= 0")
    model, s = world.model, world.state
    out = np.zeros(len(model.names), dtype=bool)
    for i in range(len(model.names)):
        out[i] = _body_overlaps(model, s, i, lo, hi, radius)
    return out


def _body_overlaps(model, s, i, lo, hi, radius):
    shape = int(model.shape_type[i])
    if shape == shapes.PLANE:
        # the half-space n·x <= offset: does the region reach into it?
        n, offset = model.plane_normal[i], float(model.plane_offset[i])
        nearest = np.where(n > 0, lo, hi)  # the region's corner deepest along -n
        return float(n @ nearest) - radius <= offset
    if shape == shapes.SPHERE:
        extent = np.full(3, float(model.radius[i]))
    else:
        from msg_adapters.frames import rotate_to_world

        axes = np.abs(np.array([rotate_to_world(s.quat[i], e) for e in np.eye(3)]))
        extent = axes.T @ model.half_extents[i]
    # distance from the body's box to the region's box, against the region's radius
    gap = np.maximum(0.0, np.maximum(lo - (s.pos[i] + extent), (s.pos[i] - extent) - hi))
    return float(np.sqrt(gap @ gap)) <= radius
