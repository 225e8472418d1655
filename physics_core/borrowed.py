"""Borrowed views: the step loop's inputs without reference counting.

Numba counts references to every array a compiled function receives or
unpacks from a tuple, with an atomic add and subtract each time. The step
passes its state, model and scratch (about 100 arrays) down through the
stages, and on a one-body scene those counts were most of the step: about
1,000 atomic operations, 6 µs of a 9 µs step (measured with a counter on
NRT_incref/NRT_decref).

`borrow(x)` returns the same arrays (same data, shape, strides and type)
with no owner attached, so counting them is a test of a null pointer.
That is safe only while the caller keeps the originals alive and no
borrowed array is stored anywhere that outlives the call: run_steps borrows
what World.step hands it for the length of the call, and nothing in a step
keeps an input array (the warm cache and the event log store arrays they
allocate themselves). Tuples (and named tuples) are borrowed member by
member, typed lists as the list (its items are counted as before: a
borrowed list keeps them); anything else is passed through unchanged.
"""
from numba import types
from numba.core import cgutils
from numba.extending import intrinsic


def _borrowed(context, builder, typ, value):
    if isinstance(typ, types.Array):
        ary = context.make_array(typ)(context, builder, value=value)
        ary.meminfo = cgutils.get_null_value(ary.meminfo.type)
        ary.parent = cgutils.get_null_value(ary.parent.type)
        return ary._getvalue()
    if isinstance(typ, types.ListType):
        # a typed list is (meminfo, data): the data pointer is all its
        # methods use, and the items keep their own counts
        lst = cgutils.create_struct_proxy(typ)(context, builder, value=value)
        lst.meminfo = cgutils.get_null_value(lst.meminfo.type)
        return lst._getvalue()
    if isinstance(typ, types.BaseTuple):
        out = value
        for i, member in enumerate(typ):
            item = builder.extract_value(value, i)
            out = builder.insert_value(out, _borrowed(context, builder, member, item), i)
        return out
    context.nrt.incref(builder, typ, value)     # returned as a new reference
    return value


@intrinsic
def borrow(typingctx, x):
    """x with every array in it (nested tuples too) unowned; same type."""
    def codegen(context, builder, signature, args):
        return _borrowed(context, builder, signature.args[0], args[0])
    return x(x), codegen


@intrinsic
def keep_alive(typingctx, owner):
    """A use of `owner` that does nothing: the owner of borrowed arrays made
    inside a compiled function is kept until this point (numba frees a
    variable after its last use). One call per owner: a tuple built for the
    call would count references to each member."""
    def codegen(context, builder, signature, args):
        return context.get_dummy_value()
    return types.none(owner), codegen
