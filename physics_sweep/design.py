"""What a sweep varies: the `--vary` grammar, scene key paths by body name,
the grid or random design, and the seeds' perturbations of initial conditions.

Key paths are the ones scene errors print, with bodies (and any list of
named items) selectable by name: ``bodies[ball].restitution``,
``bodies[ball].position[2]``, ``effects.contacts.iterations``, ``dt``;
``bodies[*].restitution`` sets every body.

Values: ``a:b:n`` is n evenly spaced values from a to b (both included;
integers when a, b and the spacing are integers); ``v1,v2,...`` a list
(numbers, ``1/240``-style fractions, true/false, or words such as
integrator names). In a random design (`samples`) ``a:b`` is drawn uniformly
(integers when a and b are) and a list by equal chance.
"""
import itertools
import math
import re
from dataclasses import dataclass

import numpy as np


class SweepError(ValueError):
    """A sweep specified wrongly: the message names the option, the text and what was expected."""


_STEP = re.compile(r"\[([^\[\]]*)\]")
_NAME = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*$")
_INT = re.compile(r"^[-+]?\d+$")
_FRACTION = re.compile(r"^([-+]?\d+(?:\.\d*)?)/(\d+(?:\.\d*)?)$")
INITIAL_CONDITIONS = ("position", "velocity", "angular_velocity", "orientation")


# ---- key paths ------------------------------------------------------------
def parse_key(text, option="--vary"):
    """`bodies[ball].position[2]` → (("key", "bodies"), ("name", "ball"), ("key", "position"), ("index", 2))."""
    steps = []
    for part in text.split("."):
        head = part.split("[", 1)[0]
        if not _NAME.match(head) or _STEP.sub("", part[len(head):]):
            raise SweepError(f"{option} {text!r}: {part!r} is not a key (a name, then [index], [name] or [*])")
        steps.append(("key", head))
        for sel in _STEP.findall(part[len(head):]):
            steps.append(_selector(sel.strip(), text, option))
    return tuple(steps)


def _selector(sel, text, option):
    if sel == "*":
        return ("all", None)
    if _INT.match(sel):
        return ("index", int(sel))
    if _NAME.match(sel):
        return ("name", sel)
    raise SweepError(f"{option} {text!r}: [{sel}] selects nothing (an index, a body name or *)")


def key_text(steps):
    out = ""
    for kind, v in steps:
        out += (("." if out else "") + v if kind == "key" else
                f"[{'*' if kind == 'all' else v}]")
    return out


def set_key(scene, steps, value):
    """Set `value` at the key path in the scene dict (in place); mappings on
    the way are made when missing, lists must hold what is selected."""
    for parent, k in _slots(scene, steps, ""):
        parent[k] = value
    return scene


def get_key(scene, steps):
    """The values at a key path (a list: `[*]` selects several); missing → None."""
    out = []
    for parent, k in _slots(scene, steps, "", create=False):
        out.append(parent.get(k) if isinstance(parent, dict) else parent[k])
    return out


def _slots(node, steps, where, create=True):
    (kind, v), rest = steps[0], steps[1:]
    for k in _children(node, kind, v, where):
        if not rest:
            yield node, k
            continue
        here = where + (("." if where else "") + v if kind == "key" else f"[{v}]")
        if kind == "key" and node.get(k) is None:
            if not create:
                yield {}, None
                continue
            node[k] = {}
        yield from _slots(node[k], rest, here, create)


def _children(node, kind, v, where):
    at = where or "the scene"
    if kind == "key":
        if not isinstance(node, dict):
            raise SweepError(f"{at} is {type(node).__name__}, not a mapping with key {v!r}")
        return [v]
    if not isinstance(node, list):
        raise SweepError(f"{at} is {'missing' if node is None else type(node).__name__}, not a list to select from")
    return _list_children(node, kind, v, at)


def _list_children(node, kind, v, at):
    if kind == "all":
        return list(range(len(node)))
    if kind == "index":
        if not -len(node) <= v < len(node):
            raise SweepError(f"{at}[{v}]: index out of range ({len(node)} items)")
        return [v]
    names = [item.get("name") for item in node if isinstance(item, dict)]
    if v not in names:
        raise SweepError(f"{at}[{v}]: no item named {v!r}; names are: {', '.join(map(str, names))}")
    return [names.index(v)]


# ---- values -----------------------------------------------------------------
def parse_scalar(text):
    t = text.strip()
    if t.lower() in ("true", "false"):
        return t.lower() == "true"
    if _INT.match(t):
        return int(t)
    m = _FRACTION.match(t)
    if m:
        return float(m.group(1)) / float(m.group(2))   # as Python evaluates 1/240
    try:
        return float(t)
    except ValueError:
        return t.strip("'\"")


@dataclass(frozen=True)
class Range:
    low: float
    high: float
    count: int = None      # None: only for a random design

    def grid(self):
        a, b, n = self.low, self.high, self.count
        if n == 1:
            return [a]
        if all(isinstance(x, int) for x in (a, b)) and (b - a) % (n - 1) == 0:
            return [a + i * (b - a) // (n - 1) for i in range(n)]
        return [float(a + (b - a) * i / (n - 1)) for i in range(n)]

    def draw(self, rng):
        if isinstance(self.low, int) and isinstance(self.high, int):
            return int(rng.integers(self.low, self.high + 1))
        return float(rng.uniform(self.low, self.high))


def parse_values(text, label):
    """`0:1:11` → Range; `1/240,1/480` → a list of values."""
    if ":" in text and "," not in text:
        return _parse_range(text, label)
    values = [parse_scalar(p) for p in text.split(",")]
    if any(v == "" for v in values):
        raise SweepError(f"--vary {label!r}: an empty value in {text!r}")
    return values


def _parse_range(text, label):
    parts = [parse_scalar(p) for p in text.split(":")]
    if len(parts) not in (2, 3) or not all(_is_number(p) for p in parts[:2]):
        raise SweepError(f"--vary {label!r}: a range is low:high:count (numbers), got {text!r}")
    count = parts[2] if len(parts) == 3 else None
    if count is not None and (not isinstance(count, int) or isinstance(count, bool) or count < 1):
        raise SweepError(f"--vary {label!r}: the count of low:high:count is an integer >= 1, got {text!r}")
    return Range(parts[0], parts[1], count)


def _is_number(v):
    return isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)


@dataclass(frozen=True)
class Vary:
    key: str
    steps: tuple
    values: object        # a list, or a Range

    @classmethod
    def parse(cls, spec):
        if "=" not in spec:
            raise SweepError(f"--vary {spec!r}: expected KEY=VALUES (e.g. 'bodies[ball].restitution=0:1:11')")
        key, text = (s.strip() for s in spec.split("=", 1))
        steps = parse_key(key)
        return cls(key_text(steps), steps, parse_values(text, spec))

    def grid(self):
        if isinstance(self.values, Range):
            if self.values.count is None:
                raise SweepError(f"--vary {self.key}: a grid needs a count (low:high:count); "
                                 "low:high alone is for a random design (--samples)")
            return self.values.grid()
        return list(self.values)

    def draw(self, rng):
        if isinstance(self.values, Range):
            return self.values.draw(rng)
        return self.values[int(rng.integers(len(self.values)))]

    def column_type(self):
        """'bool', 'int', 'float' or 'str': what every value of this key is."""
        r = self.values
        if isinstance(r, Range):      # a grid's own values (0:1:11 is floats); a random draw's ends
            vals = r.grid() if r.count is not None else [r.low, r.high]
        else:
            vals = r
        if all(isinstance(v, bool) for v in vals):
            return "bool"
        if all(isinstance(v, int) and not isinstance(v, bool) for v in vals):
            return "int"
        if all(_is_number(v) for v in vals):
            return "float"
        return "str"


# ---- perturbations of initial conditions -------------------------------------
@dataclass(frozen=True)
class Perturb:
    """Normal noise of std `sigma` on each component of an initial condition of
    the dynamic bodies (all of them, or `bodies[name]`); orientation gets a
    rotation by a random rotation vector of std `sigma` rad per component."""
    key: str
    body: str        # None: every dynamic body
    quantity: str
    sigma: float

    @classmethod
    def parse(cls, spec):
        key, _, sigma = spec.partition("=")
        m = re.match(r"^(?:bodies\[([A-Za-z_][A-Za-z0-9_]*|\*)\]\.)?([a-z_]+)$", key.strip())
        if not m or m.group(2) not in INITIAL_CONDITIONS:
            raise SweepError(f"--perturb {spec!r}: expected [bodies[NAME].]QUANTITY=SIGMA, QUANTITY one of "
                             + ", ".join(INITIAL_CONDITIONS))
        s = parse_scalar(sigma) if sigma else None
        if not _is_number(s) or s < 0:
            raise SweepError(f"--perturb {spec!r}: SIGMA is a number >= 0, got {sigma!r}")
        body = None if m.group(1) in (None, "*") else m.group(1)
        return cls(key.strip(), body, m.group(2), float(s))


def perturb(scene, perturbs, rng):
    """Apply each perturbation in order to the scene dict (in place), drawing
    from `rng` in scene body order so the same seed gives the same scene."""
    bodies = scene.get("bodies") or []
    for p in perturbs:
        if p.body is not None and p.body not in [b.get("name") for b in bodies]:
            raise SweepError(f"--perturb {p.key}: no body named {p.body!r}")
        for b in bodies:
            if _is_static(b) or (p.body is not None and b.get("name") != p.body):
                continue
            b[p.quantity] = _perturbed(b, p, rng)
    return scene


def _is_static(body):
    shape = body.get("shape") or {}
    return bool(body.get("static", shape.get("type") == "plane"))


def _perturbed(body, p, rng):
    if p.quantity == "orientation":
        q = np.asarray(body.get("orientation", [1.0, 0.0, 0.0, 0.0]), float)
        q = _quat_mul(_quat_exp(rng.normal(0.0, p.sigma, 3)), q / np.linalg.norm(q))
        return (q / np.linalg.norm(q)).tolist()
    v = np.asarray(body.get(p.quantity, [0.0, 0.0, 0.0]), float)
    return (v + rng.normal(0.0, p.sigma, 3)).tolist()


def _quat_exp(rotvec):
    angle = float(np.linalg.norm(rotvec))
    if angle == 0.0:
        return np.array([1.0, 0.0, 0.0, 0.0])
    return np.concatenate([[math.cos(angle / 2)], math.sin(angle / 2) * rotvec / angle])


def _quat_mul(a, b):
    aw, av, bw, bv = a[0], a[1:], b[0], b[1:]
    return np.concatenate([[aw * bw - av @ bv], aw * bv + bw * av + np.cross(av, bv)])


def seed_rng(design_seed, seed):
    """The generator of one seed: PCG64 from SeedSequence([design_seed, seed])."""
    return np.random.default_rng([int(design_seed), int(seed)])


# ---- the design ----------------------------------------------------------------
@dataclass(frozen=True)
class RunSpec:
    run_id: int
    params: tuple         # ((key, value), ...) in --vary order
    seed: int = None      # None: no perturbation


@dataclass(frozen=True)
class Design:
    vary: tuple = ()
    samples: int = None   # None: the full grid
    seeds: int = None     # None: one unperturbed run per point
    design_seed: int = 0

    @property
    def points(self):
        if self.samples is not None:
            return self.samples
        return math.prod(len(v.grid()) for v in self.vary)

    def __len__(self):
        return self.points * (self.seeds or 1)

    def _point_values(self):
        if self.samples is None:
            yield from itertools.product(*(v.grid() for v in self.vary))
            return
        rng = np.random.default_rng([int(self.design_seed), 2**32 - 1])  # apart from the seeds' streams
        for _ in range(self.samples):
            yield tuple(v.draw(rng) for v in self.vary)

    def runs(self):
        """Every run, lazily, in run_id order (point-major, then seed)."""
        keys = [v.key for v in self.vary]
        run_id = 0
        for values in self._point_values():
            params = tuple(zip(keys, values))
            for seed in (range(self.seeds) if self.seeds else (None,)):
                yield RunSpec(run_id, params, seed)
                run_id += 1

