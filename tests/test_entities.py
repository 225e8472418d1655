"""The simulator standard's entity operations on a World, in-process
(physics_node.entities, entity_frames, entity_queries): frames, reset
scopes, filters, bounds. The node's services are thin wrappers over these
(tests/test_sim_interfaces.py drives those)."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from geometry_msgs.msg import Vector3
from simulation_interfaces.msg import Bounds, EntityCategory, EntityFilters, EntityState, Result, TagsFilter
from simulation_interfaces.srv import ResetSimulation, SpawnEntity

from physics_core import load_scene
from physics_node.entities import Entities, EntityError
from physics_node.entity_frames import Motion, to_frame, to_world
from physics_node.entity_queries import bounds, info, matching
from physics_node.stepping import Stepper

SCENE = {
    "dt": 0.01,
    "gravity": "earth",
    "bodies": [
        {"name": "ground", "shape": {"type": "plane", "normal": [0, 0, 1], "offset": 0.0}, "static": True},
        {"name": "ball", "shape": {"type": "sphere", "radius": 0.1}, "mass": 1.0, "position": [0, 0, 1],
         "velocity": [1.0, 0, 0]},
        {"name": "slab", "shape": {"type": "box", "half_extents": [0.5, 0.2, 0.1]}, "mass": 2.0,
         "position": [3, 0, 1], "orientation": [0.7071067811865476, 0, 0, 0.7071067811865476]},
    ],
}  # fmt: skip
R = ResetSimulation.Request


def make():
    world = load_scene(SCENE)
    return world, Entities(Stepper(world))


def spawn_request(text, name="", z=2.0, **fields):
    r = SpawnEntity.Request(name=name, resource_string=text, **fields)
    r.initial_pose.pose.position.z = z
    return r


CUBE = "shape: {type: box, half_extents: [0.1, 0.1, 0.1]}\nmass: 1.0\n"

unit = st.floats(-1.0, 1.0, allow_nan=False)
coordinate = st.floats(-100.0, 100.0, allow_nan=False)


def quaternions():
    return st.tuples(unit, unit, unit, unit).filter(lambda q: np.linalg.norm(q) > 0.1).map(
        lambda q: np.array(q) / np.linalg.norm(q)
    )


def motions():
    v3 = st.tuples(coordinate, coordinate, coordinate).map(np.array)
    return st.builds(Motion, v3, quaternions(), v3, v3)


@settings(max_examples=200, deadline=None)
@given(motions(), motions())
def test_a_motion_seen_from_a_frame_maps_back_to_the_world(body, frame):
    back = to_world(to_frame(body, frame), frame)
    n = np.linalg.norm
    size = 1.0 + n(body.pos) + n(frame.pos)
    speed = 1.0 + n(body.vel) + n(frame.vel) + n(frame.omega) * n(body.pos - frame.pos)
    assert np.allclose(back.pos, body.pos, rtol=0, atol=1e-13 * size)
    assert abs(abs(back.quat @ body.quat) - 1.0) < 1e-13  # the same rotation (q or -q)
    assert np.allclose(back.vel, body.vel, rtol=0, atol=1e-13 * speed)
    assert np.allclose(back.omega, body.omega, rtol=0, atol=1e-13 * (1.0 + n(body.omega) + n(frame.omega)))


def test_a_body_at_rest_on_a_spinning_frame_is_seen_to_move_against_the_spin():
    # frame turning at ω about z; a body still in the world at r = (1, 0, 0) from it
    frame = Motion(np.zeros(3), np.array([1.0, 0, 0, 0]), np.zeros(3), np.array([0, 0, 2.0]))
    body = Motion(np.array([1.0, 0, 0]), np.array([1.0, 0, 0, 0]), np.zeros(3), np.zeros(3))
    seen = to_frame(body, frame)
    assert seen.vel == pytest.approx([0.0, -2.0, 0.0])  # v = −ω × r
    assert seen.omega == pytest.approx([0.0, 0.0, -2.0])


def test_reset_time_keeps_the_bodies_where_they_are():
    world, e = make()
    world.step(10)
    before = world.state.pos.copy()
    e.reset(R.SCOPE_TIME)
    assert world.step_index == 0 and world.time == 0.0
    assert np.array_equal(world.state.pos, before)


def test_reset_state_returns_scene_and_spawned_bodies_to_their_start_and_keeps_time():
    world, e = make()
    e.spawn(spawn_request(CUBE, name="cube", z=5.0))
    world.apply_force("ball", [3.0, 0, 0])
    world.step(20)
    e.reset(R.SCOPE_STATE)
    assert world.step_index == 20
    assert world.model.names == ("ground", "ball", "slab", "cube")
    assert world.body("ball").position.tolist() == [0.0, 0.0, 1.0]
    assert world.body("ball").velocity.tolist() == [1.0, 0.0, 0.0]
    assert world.body("cube").position.tolist() == [0.0, 0.0, 5.0]
    assert not world.state.user_force.any()  # loads let go


def test_reset_spawned_deletes_only_the_spawned_bodies():
    world, e = make()
    e.spawn(spawn_request(CUBE, name="cube"))
    world.step(5)
    ball = world.body("ball").position
    e.reset(R.SCOPE_SPAWNED)
    assert world.model.names == ("ground", "ball", "slab")
    assert world.step_index == 5 and np.array_equal(world.body("ball").position, ball)


def test_reset_all_is_the_scene_as_loaded():
    world, e = make()
    fresh = load_scene(SCENE)
    e.spawn(spawn_request(CUBE, name="cube"))
    e.delete("ball")
    world.step(7)
    e.reset(R.SCOPE_ALL)
    assert world.model.names == fresh.model.names and e.spawned == {}
    world.step(30)
    fresh.step(30)
    assert np.array_equal(world.state.pos, fresh.state.pos)


def test_unknown_reset_bits_are_unsupported():
    _, e = make()
    with pytest.raises(EntityError) as caught:
        e.reset(8)
    assert caught.value.code == Result.RESULT_FEATURE_UNSUPPORTED


def test_resource_pose_is_taken_relative_to_the_initial_pose_in_a_body_frame():
    world, e = make()
    r = spawn_request(CUBE + "position: [1.0, 0, 0]\n", name="cube", z=0.5)
    r.initial_pose.header.frame_id = "slab"  # slab at (3, 0, 1), turned 90° about z
    e.spawn(r)
    # initial pose (0, 0, 0.5) in the slab frame, then (1, 0, 0) in that pose's axes: slab +x is world +y
    assert world.body("cube").position == pytest.approx([3.0, 1.0, 1.5], abs=1e-12)


def test_set_state_in_a_body_frame_and_back():
    world, e = make()
    s = EntityState()
    s.header.frame_id = "slab"
    s.pose.position.x = 2.0
    s.twist.linear.x = 1.0
    e.set_state("ball", s)
    assert world.body("ball").position == pytest.approx([3.0, 2.0, 1.0], abs=1e-12)
    assert world.body("ball").velocity == pytest.approx([0.0, 1.0, 0.0], abs=1e-12)
    seen = e.state("ball", "slab")
    assert seen.pos == pytest.approx([2.0, 0.0, 0.0], abs=1e-12)


def test_static_bodies_take_no_velocity_and_planes_no_pose():
    _, e = make()
    s = EntityState()
    s.twist.linear.x = 1.0
    for name in ("ground",):
        with pytest.raises(EntityError) as caught:
            e.set_state(name, s)
        assert caught.value.code == Result.RESULT_OPERATION_FAILED


def test_filters_by_name_category_tags_and_overlap():
    world, e = make()
    e.spawn(spawn_request(CUBE, name="cube", z=10.0))
    f = EntityFilters()
    assert [world.model.names[i] for i in matching(world, f, e.spawned)] == ["ground", "ball", "slab", "cube"]
    f.filter = "^(ball|cube)$"
    assert [world.model.names[i] for i in matching(world, f, e.spawned)] == ["ball", "cube"]
    f = EntityFilters(categories=[EntityCategory(category=EntityCategory.CATEGORY_STATIC_OBJECT)])
    assert [world.model.names[i] for i in matching(world, f, e.spawned)] == ["ground"]
    f = EntityFilters(tags=TagsFilter(tags=["box", "spawned"], filter_mode=TagsFilter.FILTER_MODE_ALL))
    assert [world.model.names[i] for i in matching(world, f, e.spawned)] == ["cube"]
    f = EntityFilters(tags=TagsFilter(tags=["sphere", "plane"], filter_mode=TagsFilter.FILTER_MODE_ANY))
    assert [world.model.names[i] for i in matching(world, f, e.spawned)] == ["ground", "ball"]
    # a sphere of radius 0.5 around (3, 0.6, 1): reaches the slab (turned: 0.5 m along y), not the ball
    f = EntityFilters(bounds=Bounds(type=Bounds.TYPE_SPHERE, points=[Vector3(x=3.0, y=0.95, z=1.0), Vector3(x=0.5)]))
    assert [world.model.names[i] for i in matching(world, f, e.spawned)] == ["slab"]
    f.bounds.points[0].y = 1.05  # 0.05 m out of reach
    assert matching(world, f, e.spawned) == []
    with pytest.raises(EntityError) as caught:
        matching(world, EntityFilters(bounds=Bounds(type=Bounds.TYPE_CONVEX_HULL, points=[Vector3()] * 3)), {})
    assert caught.value.code == Result.RESULT_FEATURE_UNSUPPORTED


def test_bounds_and_info_come_from_the_shape():
    world, e = make()
    i = world.model.index
    b = bounds(world.model, i["slab"])
    assert b.type == Bounds.TYPE_BOX
    assert [(p.x, p.y, p.z) for p in b.points] == [(0.5, 0.2, 0.1), (-0.5, -0.2, -0.1)]
    b = bounds(world.model, i["ball"])
    assert b.type == Bounds.TYPE_SPHERE and b.points[1].x == 0.1
    assert bounds(world.model, i["ground"]).type == Bounds.TYPE_EMPTY
    ball = info(world.model, i["ball"], e.spawned)
    assert ball.category.category == EntityCategory.CATEGORY_OBJECT
    assert ball.tags[:3] == ["dynamic", "sphere", "scene"]


def test_spawn_names_renaming_and_namespaces():
    _, e = make()
    assert e.spawn(spawn_request(CUBE, name="ball", allow_renaming=True)) == "ball_1"
    assert e.spawn(spawn_request(CUBE, allow_renaming=True)) == "entity_1"
    assert e.spawn(spawn_request(CUBE, name="left", entity_namespace="robots/arm")) == "left"
    assert e.namespaces["left"] == "robots/arm"
    with pytest.raises(EntityError) as caught:
        e.spawn(spawn_request(CUBE))
    assert caught.value.code == SpawnEntity.Response.NAME_INVALID
