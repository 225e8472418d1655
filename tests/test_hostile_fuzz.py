"""Hostile input in process: Hypothesis-generated commands and scene
documents, and the bounds of the node's parts (queue, parameters, unknown
topics, recording faults) without a ROS graph.

The engine and the loader may raise only their documented errors
(CommandError, SceneError; NonFiniteStateError is handled by the stepper,
which freezes the bodies), never anything else, and every case finishes in
bounded time (Hypothesis' deadline).
"""

import math
import types

import numpy as np
import pytest
import yaml
from diagnostic_msgs.msg import DiagnosticStatus
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from physics_core import CommandError, SceneError, load_scene
from physics_core.command_limits import MAX_FORCE, STATE_LIMIT, magnitude
from physics_node import parameters
from physics_node.commands import (
    DROP_REASONS,
    IMPULSE,
    OUT_OF_RANGE,
    QUEUE_FULL,
    UNKNOWN_FRAME,
    WRENCH,
    Command,
    check,
)
from physics_node.diagnostics import DiagnosticsWindow
from physics_node.limits import MAX_QUEUED_PER_BODY, MAX_QUEUED_TOTAL, UNKNOWN_TOPIC_EXPIRY_S, excerpt
from physics_node.stepping import Stepper

SCENE = {
    "dt": 0.01,
    "gravity": "earth",
    "effects": {"contacts": {"iterations": 4}},
    "bodies": [
        {"name": "ground", "shape": {"type": "plane"}},
        {"name": "ball", "shape": {"type": "sphere", "radius": 0.1}, "mass": 1.0, "position": [0, 0, 0.1]},
        {"name": "box", "shape": {"type": "box", "half_extents": [0.2, 0.2, 0.2]}, "mass": 4.0,
         "position": [1, 0, 0.2]},
        {"name": "speck", "shape": {"type": "sphere", "radius": 0.01}, "mass": 1e-12, "position": [50, 0, 5]},
    ],
}
FUZZ = settings(max_examples=60, deadline=2000, suppress_health_check=[HealthCheck.too_slow])

any_float = st.one_of(
    st.floats(allow_nan=True, allow_infinity=True, allow_subnormal=True),
    st.sampled_from([1e300, -1e300, 1e200, 5e-324, -0.0, MAX_FORCE, math.nextafter(MAX_FORCE, math.inf)]),
)
vector = st.tuples(any_float, any_float, any_float).map(np.array)
frames = st.one_of(st.sampled_from(["", "world", "ball", "box", "speck", "ground", "nowhere"]), st.text(max_size=300))
commands = st.builds(
    Command,
    st.sampled_from([WRENCH, IMPULSE]),
    st.sampled_from(["ball", "box", "speck", "ground"]),
    frames,
    vector,
    vector,
)


def _finite_state(world):
    s = world.state
    return all(np.all(np.abs(a) <= STATE_LIMIT) for a in (s.pos, s.quat, s.vel, s.omega))


@pytest.fixture(scope="module")
def world():
    """The world, its compiled kernels loaded by one step: the first example
    must not pay the kernel load against Hypothesis' deadline (on a loaded
    machine that load took longer than the deadline, which failed the test)."""
    w = load_scene(SCENE)
    w.step(1)
    w.reset()
    return w


@FUZZ
@given(st.lists(commands, min_size=1, max_size=8), st.integers(1, 4))
def test_fuzzed_commands_are_dropped_with_a_reason_or_applied_and_the_world_stays_finite(world, batch, steps):
    world.reset()
    stepper = Stepper(world, error_types=(CommandError,))
    for command in batch:
        reason = check(command, world.model)
        if reason is None:
            assert magnitude(command.force) <= MAX_FORCE
            assert stepper.submit(command) is None
        elif reason == OUT_OF_RANGE:
            assert max(magnitude(command.force), magnitude(command.torque)) > 1e7
        else:
            assert reason in DROP_REASONS
    for _ in range(steps):
        boundary = stepper.advance()
        assert boundary.failure is None, boundary.failure
        assert not boundary.rejected, boundary.rejected
    assert _finite_state(world)


def test_a_bounded_force_on_a_speck_freezes_it_and_the_rest_step_on(world):
    """The engine's own error for a finite command that still breaks the
    state: the stepper undoes the step, freezes the speck, steps the rest."""
    world.reset()
    stepper = Stepper(world, error_types=(CommandError,))
    assert stepper.submit(Command(WRENCH, "speck", "world", np.array([MAX_FORCE, 0, 0]), np.zeros(3))) is None
    speck_at = world.state.pos[3].copy()
    boundary = stepper.advance()
    assert boundary.isolated == ["speck"] and boundary.failure is None
    assert boundary.faults[0].stage == "integrate" and boundary.faults[0].bodies == (3,)
    assert np.array_equal(world.state.pos[3], speck_at)
    assert world.step_index == 1
    for _ in range(50):
        assert stepper.advance().failure is None
    assert np.all(world.state.pos[3] == speck_at), "frozen where it was"
    assert world.state.pos[1][2] == pytest.approx(0.1, abs=0.01), "the ball still rests on the ground"
    stepper.reset()
    assert not world.model.is_static[3] and stepper.isolated == []


def test_the_command_queue_stops_at_its_bounds(world):
    world.reset()
    stepper = Stepper(world)
    push = Command(IMPULSE, "ball", "world", np.array([0, 0, 1e-9]), np.zeros(3))
    accepted = [stepper.submit(push) for _ in range(MAX_QUEUED_PER_BODY + 5)]
    assert accepted.count(None) == MAX_QUEUED_PER_BODY and accepted.count(QUEUE_FULL) == 5
    assert len(stepper.advance().applied) == MAX_QUEUED_PER_BODY
    assert stepper.submit(push) is None, "the bound is per boundary: the queue is free again"
    stepper.reset()
    # The total bound, over more bodies than it takes to reach it (the queue
    # itself never looks the body up).
    many = [Command(IMPULSE, f"b{k % 50}", "world", np.zeros(3), np.zeros(3)) for k in range(MAX_QUEUED_TOTAL + 7)]
    accepted = [stepper.submit(c) for c in many]
    assert accepted.count(QUEUE_FULL) == 7 and stepper.pending == MAX_QUEUED_TOTAL
    assert len(stepper.reset()) == MAX_QUEUED_TOTAL and stepper.pending == 0


def test_the_frame_and_load_checks_name_their_reason(world):
    too_big = Command(WRENCH, "ball", "world", np.array([1e300, 0, 0]), np.zeros(3))
    assert check(too_big, world.model) == OUT_OF_RANGE
    assert check(Command(IMPULSE, "ball", "world", np.array([1e200, 0, 0]), np.zeros(3)), world.model) == OUT_OF_RANGE
    assert check(Command(WRENCH, "ball", "x" * 10_000, np.ones(3), np.zeros(3)), world.model) == UNKNOWN_FRAME
    with pytest.raises(CommandError, match="beyond the limit"):
        world.apply_torque("ball", [0, 0, 1e300])
    with pytest.raises(CommandError, match="beyond the limit"):
        world.apply_force("ball", [1, 0, 0], point=[1e12, 0, 0])


# -- scene documents -------------------------------------------------------------

KEYS = ["name", "dt", "bodies", "shape", "type", "radius", "mass", "position", "gravity", "effects", "contacts",
        "static", "half_extents", "orientation", "springs", "friction", "a", "b", "material", "drag", "density"]
scalars = st.one_of(
    st.none(), st.booleans(), st.integers(min_value=-(10**30), max_value=10**30), any_float,
    st.text(max_size=40), st.sampled_from(["sphere", "box", "plane", "earth", "steel", "1e6", "ball"]),
)
keys = st.one_of(st.sampled_from(KEYS), st.text(max_size=12), st.integers(-3, 3))
trees = st.recursive(
    scalars,
    lambda inner: st.one_of(st.lists(inner, max_size=5), st.dictionaries(keys, inner, max_size=6)),
    max_leaves=40,
)
documents = st.one_of(trees, st.dictionaries(st.sampled_from(KEYS), trees, max_size=8))


@FUZZ
@given(documents)
def test_fuzzed_scene_documents_raise_only_scene_errors(tmp_path_factory, doc):
    path = tmp_path_factory.mktemp("fuzz") / "scene.yaml"
    try:
        path.write_text(yaml.safe_dump(doc, allow_unicode=True))
    except yaml.YAMLError:
        return  # not a document yaml can write; nothing for the loader to read
    try:
        world = load_scene(path)
    except SceneError as exc:
        assert len(str(exc)) < 2_000
        return
    assert world.model.n >= 1


@FUZZ
@given(st.binary(max_size=2_000))
def test_fuzzed_bytes_raise_only_scene_errors(tmp_path_factory, data):
    path = tmp_path_factory.mktemp("bytes") / "scene.yaml"
    path.write_bytes(data)
    try:
        load_scene(path)
    except SceneError as exc:
        assert len(str(exc)) < 2_000


def test_an_alias_bomb_is_refused_before_it_expands(tmp_path):
    path = tmp_path / "bomb.yaml"
    lines = ['a: &a ["lol", "lol", "lol", "lol", "lol", "lol", "lol", "lol", "lol"]']
    lines += [f"{chr(98 + i)}: &{chr(98 + i)} [{', '.join(['*' + chr(97 + i)] * 9)}]" for i in range(8)]
    path.write_text("\n".join(lines) + "\nbodies: *i\n")
    with pytest.raises(SceneError, match="aliases") as info:
        load_scene(path)
    assert len(str(info.value)) < 400


def test_a_long_bad_value_is_quoted_short(tmp_path):
    path = tmp_path / "long.yaml"
    path.write_text("dt: " + repr("x" * 100_000) + "\n")
    with pytest.raises(SceneError) as info:
        load_scene(path)
    assert len(str(info.value)) < 400


def test_unreadable_paths_are_scene_errors_naming_them(tmp_path):
    binary = tmp_path / "binary.yaml"
    binary.write_bytes(bytes(range(256)))
    for path, says in ((tmp_path, "a folder"), (tmp_path / "missing.yaml", "No such file"),
                       (binary, "UTF-8"), ("/dev/zero", "at most")):
        with pytest.raises(SceneError, match=says) as info:
            load_scene(path)
        assert str(path) in str(info.value) and "\n" not in str(info.value)


def test_body_count_and_file_size_limits(tmp_path):
    body = "  - {{name: b{i}, shape: {{type: sphere, radius: 0.1}}, mass: 1, position: [{i}, 0, 0]}}\n"
    path = tmp_path / "twelve.yaml"
    path.write_text("bodies:\n" + "".join(body.format(i=i) for i in range(12)))
    with pytest.raises(SceneError, match="at most 10 bodies"):
        load_scene(path, max_bodies=10)
    assert load_scene(path, max_bodies=12).model.n == 12
    big = tmp_path / "big.yaml"
    big.write_text("# " + "x" * (2 << 20) + "\n")
    with pytest.raises(SceneError, match="at most"):
        load_scene(big, max_bodies=100)


# -- parameters ---------------------------------------------------------------------


@pytest.mark.parametrize(
    "name, value",
    [("real_time_factor", 1e308), ("real_time_factor", math.inf), ("real_time_factor", math.nan),
     ("real_time_factor", -1), ("duration", 1e10), ("command_timeout", -0.5), ("publish_every", 0),
     ("publish_every", 10**30), ("max_bodies", 0), ("real_time_factor", 10**400)],
)
def test_out_of_range_parameters_are_refused_with_their_range(name, value):
    with pytest.raises(parameters.ParameterValueError, match=name):
        parameters.coerce(name, value)


def test_descriptors_carry_the_ranges():
    d = parameters.descriptor("real_time_factor")
    assert (d.floating_point_range[0].from_value, d.floating_point_range[0].to_value) == (0.0, 1000.0)
    d = parameters.descriptor("publish_every")
    assert (d.integer_range[0].from_value, d.integer_range[0].step) == (1, 1)


# -- unknown-body topics expire; recording faults; diagnostics --------------------------------


class _FakeGraphNode:
    def __init__(self, topics):
        self.topics = topics
        self.publishers = {}
        self.destroyed = []

    def get_fully_qualified_name(self):
        return "/physics"

    def get_topic_names_and_types(self):
        return [(t, ["geometry_msgs/msg/WrenchStamped"]) for t in self.topics]

    def create_subscription(self, _type, topic, _callback, _qos, **_kw):
        node = self
        return types.SimpleNamespace(topic=topic, get_publisher_count=lambda: node.publishers.get(topic, 1))

    def destroy_subscription(self, sub):
        self.destroyed.append(sub.topic)


def test_unknown_body_subscriptions_are_capped_spread_and_expire():
    from physics_node.limits import MAX_UNKNOWN_BODY_TOPICS, UNKNOWN_TOPICS_PER_SCAN
    from physics_node.unknown_bodies import UnknownBodyTopics

    node = _FakeGraphNode([f"/physics/ghost{i}/wrench" for i in range(MAX_UNKNOWN_BODY_TOPICS + 10)])
    topics = UnknownBodyTopics(node, ("ball",), lambda *a: None)
    assert topics.scan(now=0.0) == UNKNOWN_TOPICS_PER_SCAN
    t = 0.0
    while topics.scan(now=t):
        t += 0.5
    assert len(topics.subscriptions) == MAX_UNKNOWN_BODY_TOPICS and len(topics.ignored) == 10
    node.publishers = {topic: 0 for topic in node.topics}  # every publisher left
    node.topics = []
    topics.scan(now=t + 1.0)
    assert not node.destroyed
    topics.scan(now=t + 1.0 + UNKNOWN_TOPIC_EXPIRY_S)
    assert len(node.destroyed) == MAX_UNKNOWN_BODY_TOPICS and not topics.subscriptions


def test_a_recording_error_stops_the_recording_and_reports_error_level(world, tmp_path):
    from physics_node.outputs import Outputs
    from physics_node.recorder import RecorderError
    from physics_node.recording_control import RecordingControl

    errors = []

    class Failing:
        path = str(tmp_path / "x.mcap")
        closed = False

        def write(self, *a):
            raise RecorderError("writing failed") from OSError(28, "No space left on device")

        def close(self):
            self.closed = True

    outputs = Outputs.__new__(Outputs)
    outputs.recorder = recorder = Failing()
    outputs._tap, outputs._channels = None, {}
    node = types.SimpleNamespace(
        get_logger=lambda: types.SimpleNamespace(error=errors.append), stepper=types.SimpleNamespace(resets=0),
        outputs=outputs,
    )
    control = RecordingControl(node)
    control.recorder = recorder
    outputs._on_record_error = control.failed
    outputs._record(recorder.write, "/topic", None, b"", 0, 0)
    outputs._record(recorder.write, "/topic", None, b"", 0, 0)  # no recording any more: nothing more happens
    assert outputs.recorder is None and control.recorder is None and recorder.closed
    assert "No space left on device" in control.error and len(errors) == 1
    window = DiagnosticsWindow(world, ("queue_full",))
    msg = window.report(0, "physics", False, 1.0, recorder.path, recording_error=control.error)
    assert msg.status[0].level == DiagnosticStatus.ERROR


def test_excerpt_caps_text_and_says_how_long_it_was():
    assert excerpt("x" * 10_000).endswith("(10000 characters)") and len(excerpt("x" * 10_000)) < 250
