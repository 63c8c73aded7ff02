"""Arrays handed down a chain of compiled calls without reference counting.

Every compiled function increments the reference count of each array it receives when it starts
and decrements it at its end (``NRT_incref`` / ``NRT_decref`` on the array's memory-info
pointer: an atomic read-modify-write each, tens of cycles), unless Numba's reference-count pruning
pass removes the pair. It cannot where the function calls another one that LLVM does not inline
(an error returned by the callee leaves the function without the decrement, so the pass cannot
prove the pair redundant) nor where LLVM merged the decrements of several paths: on the Newton path
of the integration points about 60 atomic operations per point remained (``benchmarks/atomics.py``
shows where, ``benchmarks/instructions.py --atomics`` counts them).

Both runtime functions skip a null memory-info pointer, so an array whose pointer is null is
passed down any number of calls without one atomic operation (a call and a comparison each
remain). :func:`borrowed` returns such an array: the same data, shape and strides, no memory
info. Its owner must outlive every use: call it on arrays that a kernel received or allocated and
keeps for the whole of the calls that take the borrowed view, and never return the view, store it
in a container or let it escape the kernel otherwise. Views sliced from a borrowed array are
borrowed too (they copy its null pointer).
"""
from numba.core import cgutils, types
from numba.extending import intrinsic


@intrinsic
def borrowed(typingctx, *values):
    """``values`` as a tuple, each array without its memory info (see the module's docstring), any
    other value as it is; compiled code only."""
    types_in = tuple(values)

    def codegen(context, builder, signature, args):
        out = []
        for value, t in zip(cgutils.unpack_tuple(builder, args[0]), types_in):
            if isinstance(t, types.Array):
                view = cgutils.create_struct_proxy(t)(context, builder, value=value)
                view.meminfo = cgutils.get_null_value(view.meminfo.type)
                value = view._getvalue()
            out.append(value)
        return context.make_tuple(builder, signature.return_type, out)

    return types.Tuple(types_in)(types.StarArgTuple.from_types(types_in)), codegen
