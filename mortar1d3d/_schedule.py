"""Dynamic scheduling of the kernels' parallel loops: each worker owns a part, idle ones steal.

``prange`` hands each thread one equal, contiguous share of the range before the loop starts
(Numba's OpenMP and workqueue layers; ``numba.set_parallel_chunksize`` does not change that on
them: measured with a loop whose first half costs ten times its second). A loop then lasts as
long as its slowest thread, and on a shared or virtual machine one thread is often slowed by a
neighbour for a while. The kernels therefore start one worker per thread and hand out chunks of
:data:`CHUNK` items from counters (atomic fetch-and-add). Worker ``w`` owns the ``w``-th
contiguous part of the chunks and claims from it first, in order; once its part is done it
claims chunks of the other parts (the next worker's first), so a slowed thread simply ends up
with fewer chunks. A worker is an ordinary compiled function, run once per worker index on the
package's one parallel loop (:mod:`mortar1d3d._parallel`)::

    @njit
    def _kernel_worker(worker, claims, n, ...):
        ... work buffers, once per worker ...
        begin, stop = claim(claims, n, worker)
        while begin < stop:
            for item in range(begin, stop):
                ...
            begin, stop = claim(claims, n, worker)

    claims = new_claims(n, workers)     # workers: numba.get_num_threads(), passed in
    _kernel_workers(workers, claims, n, ...)     # _kernel_workers = in_parallel(_kernel_worker)

Owning a part keeps consecutive kernels' work on the same thread where the machine allows it:
the engine's arrays (points, groups, LM rows) are all ordered by beam element, so the items a
thread writes in one loop are mostly the ones it reads in the next, from its own cache. (With a
single shared counter the chunks alternate between the threads at random, and each loop read
about half of its input from the other core's cache.)

A chunk's items and what they write do not depend on which thread claimed it, so results stay
bit-identical for any number of threads (partial sums are kept per chunk, ``begin // CHUNK``).
The worker count is an argument because ``numba.get_num_threads()`` inside a kernel keeps
Numba from caching it. (A generator yielding the claimed items would read better, but a cached
kernel that uses a cached generator breaks the compilation of the generator's next caller in a
later process: Numba 0.68, KeyError in ``get_generator_impl``.)
"""
import numba
import numpy as np
from numba import types
from numba.core import cgutils
from numba.extending import intrinsic

from ._config import CHUNK, njit


def workers():
    """The number of workers the kernels start: Numba's current thread count."""
    return numba.get_num_threads()


@intrinsic
def _fetch_add(typingctx, counter):
    """``counter[0] += 1`` atomically; returns the value before."""
    def codegen(context, builder, signature, args):
        array_type = signature.args[0]
        array = context.make_array(array_type)(context, builder, args[0])
        pointer = cgutils.get_item_pointer(context, builder, array_type, array,
                                           [context.get_constant(types.intp, 0)])
        # monotonic suffices: the counter only hands out chunk numbers; what the chunks write
        # is published by the join at the end of the parallel region
        return builder.atomic_rmw("add", pointer, context.get_constant(types.int64, 1), "monotonic")
    return types.int64(counter), codegen


@njit
def n_chunks(n, chunk):
    return (n + chunk - 1) // chunk


_LINE = 8      # int64 per worker row of the claims: 64 bytes apart, two workers' counters never share a cache line


@njit
def new_claims(n, workers):
    """The chunk counters of one loop over ``0..n-1`` run by ``workers`` workers.

    Row ``w``: the next unclaimed chunk of worker ``w``'s part and the end of that part.
    """
    chunks = n_chunks(n, CHUNK)
    claims = np.empty((workers, _LINE), dtype=np.int64)
    for w in range(workers):
        claims[w, 0] = w * chunks // workers
        claims[w, 1] = (w + 1) * chunks // workers
    return claims


@njit
def claim(claims, n, worker):
    """The items ``begin:stop`` of the next chunk for ``worker``: its own part's next one, else
    another part's; ``begin == stop`` when none is left."""
    workers = claims.shape[0]
    for k in range(workers):
        part = worker + k
        if part >= workers:
            part -= workers
        chunk = _fetch_add(claims[part])
        if chunk < claims[part, 1]:
            begin = chunk * CHUNK
            return begin, min(n, begin + CHUNK)
    return n, n
