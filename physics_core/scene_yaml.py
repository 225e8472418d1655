"""Scene YAML to Python data, quickly, with the same result as `yaml.load`.

PyYAML's C loader still builds a Python node object for every scalar,
resolves its tag through a Python method and constructs it through another:
about 15 µs per scalar, 3-5 s for a scene of 10,000 bodies (200,000
scalars). libyaml's event stream of the same file takes under 0.3 s. So the
data is built from the events here, for the plain documents scenes are made
of: untagged mappings, sequences and scalars, scalar keys, no merge keys.
Plain scalars get their tag from the loader's own implicit resolvers, in its
order (so `1e6` is a float as SceneYamlLoader says), and the common forms
(decimal ints, floats, str, bool, null) are built directly; any other tag
goes through the loader's constructor.

Anything else (an explicit tag, an alias, a merge key `<<`, a key that is a
mapping or a sequence, a second document, a tag the fast path does not
build) hands the whole text to `yaml.load`, so what the loader accepts,
builds or refuses, and how it says so, is unchanged; the fast path only
ever returns what `yaml.load` would. tests/test_scene_yaml.py holds the two
equal on generated documents.
"""
import re

import yaml
from yaml.constructor import SafeConstructor
from yaml.nodes import ScalarNode

_STR = "tag:yaml.org,2002:str"
_INT = "tag:yaml.org,2002:int"
_FLOAT = "tag:yaml.org,2002:float"
_BOOL = "tag:yaml.org,2002:bool"
_NULL = "tag:yaml.org,2002:null"
# A decimal int as YAML 1.1 writes it; 0x.., 0b.., octal 0.., 1_000 and
# sexagesimal 1:30 go through the constructor.
_DECIMAL_INT = re.compile(r"[-+]?(?:0|[1-9][0-9]*)\Z")


class _Unusual(Exception):
    """The document needs the full loader."""


def load_yaml(text, loader):
    """`yaml.load(text, Loader=loader)`, faster for plain documents."""
    try:
        return _EventBuilder(loader).build(yaml.parse(text, Loader=loader))
    except _Unusual:
        return yaml.load(text, Loader=loader)


class _EventBuilder:
    def __init__(self, loader):
        self._resolvers = loader.yaml_implicit_resolvers
        self._wildcard = self._resolvers.get(None, [])
        self._constructor = SafeConstructor()
        self._bool = SafeConstructor.bool_values
        self._stack = []  # [container, key or _NO_KEY] of the open mappings and sequences
        self._result = None
        self._documents = 0

    def build(self, events):
        for event in events:
            kind = type(event)
            if kind is yaml.ScalarEvent:
                self._add(self._scalar(event))
            elif kind is yaml.MappingStartEvent or kind is yaml.SequenceStartEvent:
                self._open(event, {} if kind is yaml.MappingStartEvent else [])
            elif kind is yaml.MappingEndEvent or kind is yaml.SequenceEndEvent:
                self._add(self._stack.pop()[0])
            else:
                self._other(kind)
        return self._result

    def _other(self, kind):
        if kind is yaml.DocumentStartEvent:
            self._documents += 1
            if self._documents > 1:
                raise _Unusual  # the loader's "expected a single document" error
        elif kind is yaml.AliasEvent:
            raise _Unusual

    def _open(self, event, container):
        if event.tag is not None:
            raise _Unusual  # !!map, !!omap, !!set, !custom
        if self._stack and type(self._stack[-1][0]) is dict and self._stack[-1][1] is _NO_KEY:
            raise _Unusual  # a mapping or sequence as a key
        self._stack.append([container, _NO_KEY])

    def _add(self, value):
        if not self._stack:
            self._result = value
            return
        top = self._stack[-1]
        container = top[0]
        if type(container) is list:
            container.append(value)
        elif top[1] is _NO_KEY:
            top[1] = value
        else:
            container[top[1]] = value  # a repeated key: the last value, as the loader keeps it
            top[1] = _NO_KEY

    def _scalar(self, event):
        value, tag = event.value, event.tag
        if tag is not None:
            raise _Unusual  # explicit tags (!!float, !custom, the non-specific "!")
        if not event.implicit[0]:
            return value  # quoted: a string
        tag = self._resolve(value)
        if tag == _STR:
            return value
        if tag == _FLOAT:
            return self._float(value)
        if tag == _INT and _DECIMAL_INT.match(value):
            return int(value)
        if tag == _NULL:
            return None
        if tag == _BOOL:
            return self._bool[value.lower()]
        return self._construct(tag, value)  # a merge key `<<` among the rest

    def _resolve(self, value):
        """The loader's Resolver.resolve for a plain scalar."""
        for tag, regexp in self._resolvers.get(value[:1], ()):
            if regexp.match(value):
                return tag
        for tag, regexp in self._wildcard:
            if regexp.match(value):
                return tag
        return _STR

    def _float(self, value):
        # float() reads every form the float resolvers match except the ones
        # it raises on (.inf, .nan, 1:30.5, 1__0.5), which the constructor reads.
        try:
            return float(value)
        except ValueError:
            return self._construct(_FLOAT, value)

    def _construct(self, tag, value):
        construct = self._constructor.yaml_constructors.get(tag)
        if construct is None or tag not in (_INT, _FLOAT):
            raise _Unusual  # merge keys, timestamps, =, and anything the loader may refuse
        return construct(self._constructor, ScalarNode(tag, value))


_NO_KEY = object()
