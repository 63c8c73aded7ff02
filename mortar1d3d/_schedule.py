"""Dynamic scheduling of the kernels' parallel loops.

``prange`` hands each thread one equal, contiguous share of the range before the loop starts
(Numba's OpenMP and workqueue layers; ``numba.set_parallel_chunksize`` does not change that on
them: measured with a loop whose first half costs ten times its second). A loop then lasts as
long as its slowest thread, and on a shared or virtual machine one thread is often slowed by a
neighbour for a while. The kernels therefore start one worker per thread, and every worker
claims chunks of :data:`CHUNK` items from a shared counter (an atomic fetch-and-add) until none
are left: a slowed thread simply claims fewer chunks. ::

    claims = new_claims()
    for worker in prange(workers):      # workers: numba.get_num_threads(), passed in
        ... work buffers, once per worker ...
        begin, stop = claim(claims, n)
        while begin < stop:
            for item in range(begin, stop):
                ...
            begin, stop = claim(claims, n)

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


@njit
def new_claims():
    """The chunk counter of one loop."""
    return np.zeros(1, dtype=np.int64)


@njit
def claim(claims, n):
    """The items ``begin:stop`` of the next unclaimed chunk of 0..n-1; ``begin == stop`` when none is left."""
    begin = min(n, _fetch_add(claims) * CHUNK)
    return begin, min(n, begin + CHUNK)
