"""The fast scene YAML reader (physics_core/scene_yaml.py) returns exactly
what `yaml.load` with the scene loader returns, or raises the error it
raises: on the shipped scenes, on the scalars YAML 1.1 resolves in odd ways,
on the forms that need the full loader, and on generated documents."""

import math
from pathlib import Path

import pytest
import yaml
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from physics_core.scene_loader import SceneYamlLoader
from physics_core.scene_yaml import load_yaml

REPO = Path(__file__).resolve().parents[1]


def full(text):
    return yaml.load(text, Loader=SceneYamlLoader)


def same(a, b):
    """Equal data, types included (1 is not 1.0 nor True), NaN equal to NaN, -0.0 apart from 0.0."""
    if type(a) is not type(b):
        return False
    if isinstance(a, dict):
        return len(a) == len(b) and all(same(ka, kb) and same(a[ka], b[kb]) for ka, kb in zip(a, b))
    if isinstance(a, list):
        return len(a) == len(b) and all(same(x, y) for x, y in zip(a, b))
    if isinstance(a, float):
        return (math.isnan(a) and math.isnan(b)) or (a == b and math.copysign(1, a) == math.copysign(1, b))
    return a == b


def assert_same_as_the_loader(text):
    try:
        expected = full(text)
    except (yaml.YAMLError, RecursionError, ValueError, TypeError) as exc:
        with pytest.raises(type(exc)) as got:
            load_yaml(text, SceneYamlLoader)
        assert str(got.value) == str(exc)
        return
    assert same(load_yaml(text, SceneYamlLoader), expected), text


@pytest.mark.parametrize("path", sorted((REPO / "scenes").glob("*.yaml")), ids=lambda p: p.name)
def test_every_shipped_scene_reads_the_same(path):
    assert_same_as_the_loader(path.read_text())


SCALARS = [
    "1", "-0", "+7", "0", "012", "0x1F", "0b101", "1_000", "1:30", "190:20:30", "-1:30",
    "1.5", "-0.0", "1.", ".5", "1e6", "1.0e6", "2E-3", "1.5e+3", "1_000.5", "1__0.5", "1_.5", "6.8523015e+5",
    "1:30.5", ".inf", "-.inf", "+.INF", ".nan", ".NaN", "inf", "nan", "1e", "e5",
    "yes", "No", "ON", "off", "true", "False", "y", "n", "~", "null", "Null", "", "=", "<<",
    "2001-12-14", "2001-12-14t21:59:43.10-05:00", "a b", "'quoted 1'", '"2.0"', "!!float 1", "!!str 1.5",
    "!!int '7'", "! 1", "!custom x", "!!binary aGVsbG8=", "0o17", "0.1.2", "-", "- 1",
]


@pytest.mark.parametrize("scalar", SCALARS)
def test_a_scalar_as_value_and_as_key_reads_as_the_loader_reads_it(scalar):
    assert_same_as_the_loader(f"v: {scalar}\n")
    assert_same_as_the_loader(f"- {scalar}\n")
    assert_same_as_the_loader(f"{{{scalar}: 1}}\n")


@pytest.mark.parametrize(
    "text",
    [
        "",
        "# only a comment\n",
        "a: 1\n---\nb: 2\n",
        "a: 1\n---\nb: [\n",
        "a: &x 1\nb: *x\n",
        "a: &x {c: 1}\n",
        "base: {a: 1}\nm:\n  <<: {a: 2, b: 3}\n  b: 4\n",
        "? [1, 2]\n: x\n",
        "? {a: 1}\n: x\n",
        "a: 1\na: 2\n",
        "!!map {a: 1}\n",
        "!!set {a, b}\n",
        "!!omap [a: 1, b: 2]\n",
        "a: [1, [2, [3, {b: .5}]]]\n",
        "bodies: [\n",
        "a: b: c\n",
        "[" * 2000 + "]" * 2000,
        "\t a: 1\n",
        "a: 'it''s'\nb: \"\\u00e9\\x41\"\n",
        "a: |\n  two\n  lines\n",
    ],
)
def test_documents_needing_the_full_loader_read_or_fail_as_it_does(text):
    assert_same_as_the_loader(text)


scalar_text = st.one_of(
    st.sampled_from(SCALARS),
    st.text(alphabet="0123456789.eE+-_:xbo", min_size=1, max_size=8),
    st.floats(allow_nan=True).map(repr),
    st.integers(-10**20, 10**20).map(str),
)


def _document(depth):
    if depth == 0:
        return scalar_text
    inner = _document(depth - 1)
    mapping = st.lists(st.tuples(scalar_text, inner), max_size=4).map(
        lambda pairs: "{" + ", ".join(f"{k}: {v}" for k, v in pairs) + "}"
    )
    sequence = st.lists(inner, max_size=4).map(lambda items: "[" + ", ".join(items) + "]")
    return st.one_of(scalar_text, mapping, sequence)


@settings(max_examples=300, deadline=2000, suppress_health_check=[HealthCheck.too_slow])
@given(_document(3))
def test_generated_flow_documents_read_as_the_loader_reads_them(text):
    assert_same_as_the_loader(text + "\n")


@settings(max_examples=100, deadline=2000, suppress_health_check=[HealthCheck.too_slow])
@given(st.recursive(
    st.one_of(st.none(), st.booleans(), st.integers(), st.floats(allow_nan=True), st.text(max_size=10)),
    lambda children: st.one_of(st.lists(children, max_size=4),
                               st.dictionaries(st.text(max_size=6), children, max_size=4)),
    max_leaves=20,
))
def test_generated_block_documents_read_as_the_loader_reads_them(data):
    assert_same_as_the_loader(yaml.safe_dump(data, allow_unicode=True))
