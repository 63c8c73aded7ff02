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
from numba.extending import overload


def kernel_selector(registry):
    """A stand-in ``select(k, name)`` for use in njit code: the kernel ``name`` of ``registry[k]``."""

    def select(k, name):
        raise TypeError("kernel_selector stand-ins are for njit code only")

    @overload(select)
    def _select(k, name):
        if isinstance(k, types.IntegerLiteral) and isinstance(name, types.StringLiteral):
            kernel = getattr(registry[k.literal_value], name.literal_value)
            return lambda k, name: kernel

    return select
