"""JIT settings in one place.

Every kernel in the package is compiled with :data:`njit`, so that the on-disk cache
(``cache=True``) is used everywhere and the options can be changed for all kernels at once.
Nothing compiles at import time: kernels are compiled lazily on first call (or by
:func:`mortar1d3d.warmup`).
"""
import hashlib
import os
from pathlib import Path

import numba


#: subpackages without kernels, whose edits cannot change a compiled kernel (they only call the
#: kernels and no kernel module imports from them; tests/test_config.py checks both): left out of
#: the cache key, so editing them keeps the compiled kernels
KERNEL_FREE = ("study", "distributed", "model")


def _source_fingerprint(root=None, skip=KERNEL_FREE):
    """Hash of the package's source files (of the ``*.py`` files below ``root``, default: this package,
    except the top-level folders named in ``skip``).

    Numba's cache checks only the file of the cached function itself, not of the kernels it
    calls from other modules, nor the module-level tables (element data, quadrature) it froze in
    as constants: after editing a callee or a table, a stale caller would be loaded. Keying the
    cache directory by the package's sources makes any such edit start a fresh cache.
    """
    digest = hashlib.sha1()
    root = Path(__file__).resolve().parent if root is None else Path(root)
    for path in sorted(root.rglob("*.py")):
        if path.relative_to(root).parts[0] in skip:
            continue
        digest.update(str(path.relative_to(root)).encode())
        digest.update(path.read_bytes())
    return digest.hexdigest()[:16]


def _configure_cache():
    base = os.environ.get("NUMBA_CACHE_DIR")
    if not base:
        package_cache = Path(__file__).resolve().parent / "__pycache__"
        base = package_cache if os.access(package_cache.parent, os.W_OK) else Path.home() / ".cache" / "mortar1d3d"
    directory = Path(base) / f"mortar1d3d-{_source_fingerprint()}"
    numba.config.CACHE_DIR = str(directory)
    _prune_caches(directory)
    return directory


#: caches of other source versions kept beside the current one (most recently used first)
KEEP_OTHER_CACHES = 3


def _prune_caches(current, keep=KEEP_OTHER_CACHES):
    """Remove all but the ``keep`` newest caches of other source versions (about 10 MB each).

    Every edit of the package makes a new cache directory (see :func:`_source_fingerprint`); a
    development checkout would otherwise collect one per edit. Caches of recent versions stay,
    for switching between branches. Only directories named like ours are touched, and a failure
    to remove one (another process using it, permissions) leaves it for next time.
    """
    import shutil

    try:
        others = [p for p in current.parent.glob("mortar1d3d-*") if p.is_dir() and p.name != current.name
                  and len(p.name) == len(current.name)]
        others.sort(key=lambda p: p.stat().st_mtime, reverse=True)
    except OSError:
        return
    for old in others[keep:]:
        shutil.rmtree(old, ignore_errors=True)


#: where compiled kernels are cached (set before any kernel is decorated)
CACHE_DIR = _configure_cache()



def cached_kernel_files(directory=None):
    """Number of compiled-kernel index files (``*.nbi``) in the cache of this source version.

    Numba writes one per cached function when it compiles it: the count grows during a run
    exactly when something was compiled rather than loaded.
    """
    directory = Path(CACHE_DIR if directory is None else directory)
    try:
        return sum(1 for _ in directory.rglob("*.nbi"))
    except OSError:
        return 0


#: whether the cache of this source version held no compiled kernel when the package was imported
#: (a first run after installing or editing the package): :func:`announce_compilation` says so once
CACHE_WAS_COLD = cached_kernel_files() == 0
_announced = False

#: the first-run compile time to announce (docs/performance.md measures it: about a minute for the
#: mortar engine, one to three for everything, on two cores)
COLD_COMPILE_NOTE = "about 1-3 minutes, once"


def announce_compilation(stream=None):
    """On a cold cache, say once per process that the kernels are being compiled and for how long.

    Called by the entry points (:func:`~mortar1d3d.solve`, :func:`~mortar1d3d.assemble_mortar`,
    :func:`~mortar1d3d.warmup`) before their first kernel call; prints nothing when the cache
    already held kernels at import time, or when ``MORTAR1D3D_QUIET_COMPILE`` is set to a
    non-empty value. Writes to ``stream`` (default ``sys.stderr``), so that piped stdout stays
    clean. Returns True when it printed.
    """
    global _announced
    if _announced or not CACHE_WAS_COLD or os.environ.get("MORTAR1D3D_QUIET_COMPILE"):
        return False
    _announced = True
    import sys
    print(f"mortar1d3d: first run of this version: compiling the Numba kernels ({COLD_COMPILE_NOTE}; "
          f"later runs load them from {CACHE_DIR})", file=sys.stderr if stream is None else stream, flush=True)
    return True


#: Options shared by all kernels. ``fastmath`` stays off: the geometry relies on IEEE
#: comparisons (inside tests, merging tolerances) and bit-identical results across threads.
JIT_OPTIONS = dict(cache=True, nogil=True, fastmath=False, error_model="numpy")

njit = numba.njit(**JIT_OPTIONS)
njit_parallel = numba.njit(parallel=True, **JIT_OPTIONS)
#: :data:`njit` that inlines at numba IR level: a helper called from a Gauss point loop with an
#: array argument otherwise costs a reference count increment and decrement of that array per call
#: (LLVM inlines the arithmetic but keeps the atomic refcount operations)
njit_inline = numba.njit(inline="always", **JIT_OPTIONS)

# Relative tolerances (docs/conventions.md §2). Distances are relative to the element size h.
NEWTON_RESIDUAL_TOL = 1e-12   # |x(xi) - p| <= tol * h
PARAMETER_TOL = 1e-9          # inside test of points and of face crossings (parameter space)
#: a segment's owner must contain its midpoint to this (parameter space): far below PARAMETER_TOL,
#: so that a piece of beam passing outside an element within the crossings' tolerance band is not
#: coupled; the embedded length then follows the geometry continuously (a band of 1e-9 would add
#: and drop pieces of its own width as a beam moves across its edge)
SEGMENT_OWNER_TOL = 1e-11
#: face crossings closer than this along the beam (relative to the solid element size h) are one cut:
#: the same crossing found twice, or one point of a shared face seen from both sides (round-off apart)
MERGE_TOL = 64 * 2.220446049250313e-16
#: a piece between two crossings of the same face of its owner is inside only if its midpoint lies on
#: the owner's side of that face to round-off (parameter space): a tangential touch is decided by the
#: face condition, never by the piece's length
TOUCH_TOL = 64 * 2.220446049250313e-16
NEWTON_MAX_ITERATIONS = 20

#: items per parallel chunk: work buffers are allocated once per chunk, never per item, and the
#: chunking does not depend on the number of threads (results are bit-identical for any count)
CHUNK = 64
