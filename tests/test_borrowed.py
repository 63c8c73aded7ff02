"""mortar1d3d._borrowed: arrays passed down compiled calls without reference counting.

A borrowed array must be the same array (data, shape, strides: writes reach the owner) with a null
memory-info pointer, other values must pass unchanged, and borrowing must leave the owner's
reference count as it was, however often a compiled function borrows it and passes it on.
"""
import sys

import numpy as np
from numba import njit, types
from numba.core import cgutils
from numba.extending import intrinsic

from mortar1d3d._borrowed import borrowed


@intrinsic
def _meminfo_address(typingctx, array):
    """The memory-info pointer of an array as an integer (0: none)."""
    def codegen(context, builder, signature, args):
        proxy = cgutils.create_struct_proxy(array)(context, builder, value=args[0])
        return builder.ptrtoint(proxy.meminfo, context.get_value_type(types.intp))

    return types.intp(array), codegen


@njit
def _addresses(a, b):
    a2, b2, k = borrowed(a, b, 3)
    return _meminfo_address(a), _meminfo_address(a2), _meminfo_address(b2[1:]), k


@njit(inline="never")
def _scaled_sum(a, b, k):
    s = 0.0
    for i in range(a.shape[0]):
        a[i] = k * b[i]
        s += a[i]
    return s


@njit
def _borrow_and_pass(a, b, k, calls):
    a, b, k = borrowed(a, b, k)
    total = 0.0
    for _ in range(calls):
        total += _scaled_sum(a[1:], b[1:], k)      # views of borrowed arrays, through a real call
    return total


def test_a_borrowed_array_has_no_memory_info_and_other_values_pass_unchanged():
    a = np.zeros(4)
    b = np.ones((3, 2))
    owner, view, sliced, k = _addresses(a, b)
    assert owner != 0
    assert view == 0 and sliced == 0
    assert k == 3


def test_borrowed_views_write_to_the_owner_and_keep_its_reference_count():
    a = np.zeros(6)
    b = np.arange(6.0)
    before = sys.getrefcount(a), sys.getrefcount(b)
    for _ in range(50):
        total = _borrow_and_pass(a, b, 2.0, 20)
    assert total == 20 * 2.0 * (1 + 2 + 3 + 4 + 5)
    np.testing.assert_array_equal(a, [0.0, 2.0, 4.0, 6.0, 8.0, 10.0])
    assert (sys.getrefcount(a), sys.getrefcount(b)) == before
