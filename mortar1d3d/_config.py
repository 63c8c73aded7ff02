"""JIT settings in one place.

Every kernel in the package is compiled with :data:`njit`, so that the on-disk cache
(``cache=True``) is used everywhere and the options can be changed for all kernels at once.
Nothing compiles at import time: kernels are compiled lazily on first call (or by
:func:`mortar1d3d.warmup`).
"""
import numba

#: Options shared by all kernels. ``fastmath`` stays off: the geometry relies on IEEE
#: comparisons (inside tests, merging tolerances) and bit-identical results across threads.
JIT_OPTIONS = dict(cache=True, nogil=True, fastmath=False, error_model="numpy")

njit = numba.njit(**JIT_OPTIONS)
njit_parallel = numba.njit(parallel=True, **JIT_OPTIONS)

# Relative tolerances (design.md §2). Distances are relative to the element size h.
NEWTON_RESIDUAL_TOL = 1e-12   # |x(xi) - p| <= tol * h
PARAMETER_TOL = 1e-9          # inside test, merging of intersection points (parameter space)
NEWTON_MAX_ITERATIONS = 20

#: items per parallel chunk: work buffers are allocated once per chunk, never per item, and the
#: chunking does not depend on the number of threads (results are bit-identical for any count)
CHUNK = 64
