"""The step loop's inputs as one compiled object, built once, passed every call.

world.step(n) used to hand the compiled loop about 75 arrays, typed lists
and scalars as separate arguments. Numba's dispatcher types and unboxes each
argument on every call: about 16 µs a call, twice the whole compiled step
of a one-body scene, paid by every world.step(1) a ROS timer makes.

`StepInputs` is a Numba structure reference (numba.experimental.structref)
holding them all: the dispatcher then types and unboxes one object (about
1 µs). `pack(...)` builds it through an ordinary typed call, so its fields
have exactly the types of the arrays given (nothing is trusted blindly);
the World packs again whenever one of those arrays is replaced (a body
added or removed, a reset, bodies woken from Python, a state array
assigned: the last is what `same_arrays` detects). The structure keeps a reference to
every array it holds, so none of them can be freed while it is in use.

`compiled_entry` then skips the dispatcher itself: the compiled function
for the packed inputs' types, called directly (0.36 µs a call instead of
0.99 µs on a one-sphere world).
"""
from numba import njit, typeof, types
from numba.experimental import structref

FIELDS = ("idata", "body", "loads", "masses", "work", "contacts",
          "warm_keys", "warm_values", "event_ints", "event_floats", "event_counts", "scratch",
          "adaptive", "prof")


@structref.register
class StepInputsType(types.StructRef):
    def preprocess_fields(self, fields):
        return tuple((name, types.unliteral(typ)) for name, typ in fields)


class StepInputs(structref.StructRefProxy):
    """Opaque from Python: read the World's own attributes instead."""


structref.define_constructor(StepInputs, StepInputsType, FIELDS)
structref.define_boxing(StepInputsType, StepInputs)


@njit(cache=True)
def pack(idata, body, loads, masses, work, contacts, warm_keys, warm_values,
         event_ints, event_floats, event_counts, scratch, adaptive, prof):
    """The StepInputs of these arguments (see step_loop.run_steps for each)."""
    return StepInputs(idata, body, loads, masses, work, contacts, warm_keys,
                      warm_values, event_ints, event_floats, event_counts, scratch, adaptive, prof)


def state_arrays(state):
    """What the World cannot see replaced: the state arrays the step reads and
    writes (anyone may assign one). Everything else in the inputs is the
    World's own or its contact system's, replaced only in World._build and
    World.refresh_awake (which reset() ends with), and those drop the packed
    inputs themselves."""
    return (state.pos, state.quat, state.vel, state.omega, state.awake,
            state.user_force, state.user_force_offset, state.user_torque)


def same_arrays(arrays, state):
    """Whether `state` still holds exactly these arrays (state_arrays), by
    identity: about 0.1 µs, against 0.37 µs for comparing a tuple of their
    ids made anew, on every world.step call."""
    pos, quat, vel, omega, awake, force, offset, torque = arrays
    return (state.pos is pos and state.quat is quat and state.vel is vel
            and state.omega is omega and state.awake is awake and state.user_force is force
            and state.user_force_offset is offset and state.user_torque is torque)


def compiled_entry(dispatcher, args):
    """The compiled function `dispatcher` runs for arguments of the types of
    `args`, to be called directly: the dispatcher types every argument and
    looks its signature up on each call, where the World's are of fixed
    types (the packed inputs', then int, int, float, int) for as long as
    the inputs live. Compiled, or loaded from the kernel cache, if this
    process has not yet. Where numba lacks these internals the dispatcher
    itself is returned, which runs the same code."""
    sig = tuple(typeof(a) for a in args)
    try:
        if sig not in dispatcher.overloads:
            dispatcher.compile(sig)
        return dispatcher.overloads[sig].entry_point
    except (AttributeError, KeyError, TypeError):
        return dispatcher
