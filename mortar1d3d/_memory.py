"""Several arrays carved from one allocation.

Every array of a call is fresh memory, and on Linux each 4 KiB page of it is faulted in on first
touch (on a virtual machine a few microseconds each: up to half of an ``assemble_mortar`` call
on the benchmark scene was page faults). NumPy asks the kernel for transparent huge pages
(``madvise``) for allocations of 4 MiB and more; arrays that are written together are therefore
carved from one such block, starting on a 2 MiB boundary, which faults in 2 MiB at a time (where
the kernel has transparent huge pages enabled; elsewhere nothing changes).

Such blocks are also reused: a block all of whose arrays are gone (the caller dropped the
result) serves the next call of about its size, instead of going back to the OS and being faulted
in (and zeroed) again, which on this project's VM cost about 3.6 ms of a 41 ms element-based call
on the benchmark scene and scales badly with threads (``benchmarks/throughput.py --drop`` with and
without ``--no-reuse``). Unused blocks are kept up to :data:`POOL_LIMIT` bytes or, if more, up to
the most the pool has had in use at once (so that calls of any size, repeated, find their blocks:
at 1e7 integration points an ``assemble_mortar`` call carves several GB, whose fresh huge pages cost
more system time than the call's own work); a block that must be new first gives back unused
blocks of at least its size, oldest first (they fitted no request: the sizes have changed).
"""
import sys
import threading

import numpy as np

_ALIGN = 64
_HUGE_PAGE = 2 << 20

#: bytes of unused blocks kept for reuse at least (more if the pool has had more in use at once;
#: 0: no reuse, every block fresh from the allocator)
POOL_LIMIT = 256 << 20
_pool = []                  # every large block handed out and not yet given back (oldest first)
_pool_lock = threading.Lock()
_most_in_use = 0            # the most bytes of pooled blocks in use at once, since the last release_pool()
#: bytes of the new blocks made so far (not taken from the pool), a count for benchmarks
new_bytes = 0


def _in_use(i):
    # references to _pool[i]: the pool's list and getrefcount's argument; every array carved
    # from the block, or derived from such an array, holds one more (NumPy views refer to the
    # array that owns the memory)
    return sys.getrefcount(_pool[i]) > 2


def _block(n_bytes):
    """A block of at least ``n_bytes`` (a multiple of 2 MiB): an unused pooled one of about that size, or new."""
    global _most_in_use, new_bytes
    if POOL_LIMIT <= 0:
        new_bytes += n_bytes
        return np.empty(n_bytes, dtype=np.uint8)
    with _pool_lock:
        best = -1
        for i in range(len(_pool)):
            size = _pool[i].nbytes
            if n_bytes <= size <= n_bytes + n_bytes // 4 + _HUGE_PAGE and not _in_use(i):
                if best < 0 or size < _pool[best].nbytes:
                    best = i
        if best >= 0:
            block = _pool.pop(best)
        else:
            # no unused block fits: give back unused ones (oldest first) of at least this size before
            # the new block is made, so that a change of sizes does not add the new blocks to the old
            freed = i = 0
            while freed < n_bytes and i < len(_pool):
                if _in_use(i):
                    i += 1
                else:
                    freed += _pool.pop(i).nbytes
            block = np.empty(n_bytes, dtype=np.uint8)
            new_bytes += n_bytes
        _pool.append(block)     # most recently used last
        in_use = block.nbytes + sum(_pool[i].nbytes for i in range(len(_pool) - 1) if _in_use(i))
        _most_in_use = max(_most_in_use, in_use)
        unused = 0
        for i in range(len(_pool) - 2, -1, -1):
            if not _in_use(i):
                unused += _pool[i].nbytes
                if unused > max(POOL_LIMIT, _most_in_use):
                    del _pool[i]
        return block


def release_pool():
    """Give every unused pooled block back (to the allocator, which returns large ones to the OS), and
    forget the most bytes in use at once (unused blocks are kept up to :data:`POOL_LIMIT` again)."""
    global _most_in_use
    with _pool_lock:
        _most_in_use = 0
        for i in range(len(_pool) - 1, -1, -1):
            if not _in_use(i):
                del _pool[i]


def pool_bytes():
    """Bytes of the pooled blocks: (in use, unused)."""
    with _pool_lock:
        used = [_in_use(i) for i in range(len(_pool))]
        return (sum(b.nbytes for b, u in zip(_pool, used) if u), sum(b.nbytes for b, u in zip(_pool, used) if not u))


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
        block = _block(total + align)
    else:
        align = _ALIGN
        block = np.empty(total + align, dtype=np.uint8)
    start = (-block.ctypes.data) % align
    return [block[start + offset:start + offset + n_bytes].view(dtype).reshape(shape)
            for offset, n_bytes, shape, dtype in layout]
