"""Several arrays carved from one allocation.

Every array of a call is fresh memory, and on Linux each 4 KiB page of it is faulted in on first
touch (on a virtual machine a few microseconds each: up to half of an ``assemble_mortar`` call
on the benchmark scene was page faults). NumPy asks the kernel for transparent huge pages
(``madvise``) for allocations of 4 MiB and more; arrays that are written together are therefore
carved from one such block, starting on a 2 MiB boundary, which faults in 2 MiB at a time (where
the kernel has transparent huge pages enabled; elsewhere nothing changes).
"""
import numpy as np

_ALIGN = 64
_HUGE_PAGE = 2 << 20


def carve(*specs):
    """Arrays ``(shape, dtype)`` as C-contiguous views of one new block (uninitialised).

    The views keep the block alive; they are independent arrays otherwise.
    """
    layout = []
    total = 0
    for shape, dtype in specs:
        dtype = np.dtype(dtype)
        shape = tuple(np.atleast_1d(shape).astype(int))
        n_bytes = int(np.prod(shape)) * dtype.itemsize
        total = -(-total // _ALIGN) * _ALIGN
        layout.append((total, n_bytes, shape, dtype))
        total += n_bytes
    # large blocks start on a huge-page boundary (the skipped head is never touched, so it
    # costs address space only): every page of the arrays is then a huge page
    # and end on one (a huge page needs its whole 2 MiB inside the allocation)
    if total >= _HUGE_PAGE:
        align = _HUGE_PAGE
        total = -(-total // _HUGE_PAGE) * _HUGE_PAGE
    else:
        align = _ALIGN
    block = np.empty(total + align, dtype=np.uint8)
    start = (-block.ctypes.data) % align
    return [block[start + offset:start + offset + n_bytes].view(dtype).reshape(shape)
            for offset, n_bytes, shape, dtype in layout]
