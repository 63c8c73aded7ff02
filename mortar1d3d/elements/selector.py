"""Compile-time selection of a registry entry's kernel inside njit code.

A registry is a tuple of modules (element types) or descriptors (families), in code order. Kernels
dispatch on the integer code at run time, but the branch bodies are generated from the registry
when the kernel is compiled::

    for k in literal_unroll(CODES):        # CODES = (0, 1, ..., n - 1)
        if k == code:
            select(k, "shape")(xi, N)

``select(k, name)`` with a literal ``k`` and ``name`` resolves to ``getattr(registry[k], name)`` at
compile time, so the compiled code is the same as a hand-written ``if code == 0: ... elif ...``
chain calling each kernel directly (no function pointers), and one compiled kernel serves every
type, which Numba's on-disk cache can store. Adding a type to a registry adds its branch.
"""
from numba import types
from numba.extending import intrinsic

from .._unlinked import unlinked


def kernel_selector(registry, linked=None, returns=None):
    """A stand-in ``select(k, name)`` for use in njit code: the kernel ``name`` of ``registry[k]``.

    An intrinsic, not an ``@overload``: its value is the kernel itself (a dispatcher, which has no
    run-time data), typed when the caller is typed and emitted as nothing. An overload would compile
    an implementation function per (k, name) pair, one more compilation each (37 on a first run).

    ``linked``: if given, the codes whose kernels are called directly (compiled into the caller, so
    that LLVM can inline them); the other codes' kernels are called through
    :func:`mortar1d3d._unlinked.unlinked`: compiled once on their own, each caller holding a
    declaration. A scene of one element type then does not have the other types' code optimised
    again inside every kernel that dispatches over the registry.

    ``returns``: the kernels' return types by name (``{"shape": types.none, ...}``); the unlinked
    kernels named there are called lazily (``unlinked(kernel, returns=...)``): compiled at their
    first call, so a scene compiles only the kernels of the types it has.
    """
    wrappers = {}

    def selected(typingctx, code, name):
        kernel = getattr(registry[code], name)
        if linked is None or code in linked:
            return kernel
        if (code, name) not in wrappers:
            wrappers[code, name] = unlinked(kernel, returns=(returns or {}).get(name))
            typingctx.refresh()   # the new intrinsic registered itself with the typing registry
        return wrappers[code, name]

    @intrinsic
    def select(typingctx, k, name):
        if isinstance(k, types.IntegerLiteral) and isinstance(name, types.StringLiteral):
            kernel = selected(typingctx, k.literal_value, name.literal_value)

            def codegen(context, builder, signature, args):
                return context.get_dummy_value()

            return typingctx.resolve_value_type(kernel)(k, name), codegen

    return select
