"""Calls through mortar1d3d._unlinked.

The unlinked call must give the callee's results, keep the callee's code out of the caller's
module, and leave both cachable: a second process loads both and compiles nothing, also when the
callee's own cache entry is gone (it is then compiled again, under another Numba name).
"""
import json
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]

MODULE = textwrap.dedent("""
    import numpy as np
    from numba import prange
    from mortar1d3d._config import njit, njit_parallel
    from mortar1d3d._unlinked import unlinked

    @njit
    def chunk(begin, stop, a, out):
        s = 0.0
        for i in range(begin, stop):
            out[i] = np.sin(a[i]) * 2.0
            s += out[i]
        return s

    chunk_call = unlinked(chunk)

    @njit_parallel
    def kernel(a, out, n_chunks):
        total = np.zeros(n_chunks)
        n = a.shape[0]
        for c in prange(n_chunks):
            total[c] = chunk_call(c * n // n_chunks, (c + 1) * n // n_chunks, a, out)
        return total.sum()
""")

RUN = textwrap.dedent("""
    import json, re, warnings
    warnings.simplefilter("error")   # a "Cannot cache" NumbaWarning fails the run
    import numpy as np
    import unlinked_probe as p
    a = np.linspace(0.0, 1.0, 1001)
    out = np.zeros_like(a)
    total = p.kernel(a, out, 7)
    defined = None
    if p.kernel.stats.cache_misses:   # compiled here: the kernel's code can be inspected
        ir = "".join(p.kernel.inspect_llvm().values())
        defined = sorted(set(re.findall(r"define [^@]*@\\"?([^\\"(]*)", ir)))
    print(json.dumps(dict(total=total, out=out.tolist(), expected=(2.0 * np.sin(a)).tolist(),
                          kernel_hits=sum(p.kernel.stats.cache_hits.values()),
                          kernel_misses=sum(p.kernel.stats.cache_misses.values()),
                          chunk_hits=sum(p.chunk.stats.cache_hits.values()),
                          chunk_misses=sum(p.chunk.stats.cache_misses.values()), defined=defined)))
""")


def _run(tmp_path):
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path / "cache"),
               PYTHONPATH=os.pathsep.join([str(tmp_path), str(ROOT)]))
    done = subprocess.run([sys.executable, "-c", RUN], env=env, cwd=tmp_path, capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    return json.loads(done.stdout.strip().splitlines()[-1])


def test_unlinked_call_results_code_and_cache(tmp_path):
    (tmp_path / "unlinked_probe.py").write_text(MODULE)
    first = _run(tmp_path)
    assert first["out"] == first["expected"]   # the same operations, so the same bits
    assert first["total"] == pytest.approx(sum(first["expected"]), rel=1e-14)
    assert (first["kernel_misses"], first["chunk_misses"]) == (1, 1)
    # the callee's code is not in the caller: only the kernel, its parallel body and their wrappers
    assert first["defined"] and not any("chunk" in name for name in first["defined"])
    second = _run(tmp_path)
    assert second["out"] == first["out"] and second["total"] == first["total"]
    assert (second["kernel_hits"], second["kernel_misses"], second["chunk_hits"], second["chunk_misses"]) == (1, 0, 1, 0)
    # the callee's cache entry gone: it is compiled again before the cached caller is loaded
    removed = [f for f in (tmp_path / "cache").rglob("unlinked_probe.chunk-*") if f.unlink() is None]
    assert removed
    third = _run(tmp_path)
    assert third["out"] == first["out"] and third["total"] == first["total"]
    assert (third["kernel_hits"], third["kernel_misses"], third["chunk_misses"]) == (1, 0, 1)



def test_an_older_numba_gets_the_ordinary_call(monkeypatch):
    """Below SUPPORTED_FROM the wrapper is the kernel itself (an ordinary, linked call); from it on,
    a different function (the intrinsic)."""
    from mortar1d3d import _unlinked
    from mortar1d3d.integration.points import _segment_points_chunk
    assert _unlinked.unlinked(_segment_points_chunk) is not _segment_points_chunk
    monkeypatch.setattr(_unlinked, "SUPPORTED_FROM", (99, 0))
    assert _unlinked.unlinked(_segment_points_chunk) is _segment_points_chunk


NESTED = textwrap.dedent("""
    import numpy as np
    from mortar1d3d._config import njit
    from mortar1d3d._unlinked import unlinked

    @njit
    def leaf(x, out):
        out[0] = np.cos(x) * 3.0

    leaf_call = unlinked(leaf)

    @njit
    def middle(x, out):
        leaf_call(x, out)
        return out[0] + 1.0

    @njit
    def outer(x, out):
        return middle(x, out) * 2.0
""")

NESTED_RUN = textwrap.dedent("""
    import json, sys, warnings
    warnings.simplefilter("error")
    import numpy as np
    import nested_probe as p
    out = np.zeros(1)
    f = getattr(p, sys.argv[1])
    value = f(0.25, out)
    print(json.dumps(dict(value=value, misses=sum(f.stats.cache_misses.values()),
                          hits=sum(f.stats.cache_hits.values()))))
""")


def test_a_caller_of_an_unlinked_caller_compiled_after_a_cache_load(tmp_path):
    """``middle`` calls through the symbol and is loaded from the cache in the process that compiles
    ``outer``: ``outer``'s cache entry must still register the symbol when a third process loads it
    (the hooks are put back on the loaded library, see ``_keep_hooks_on_load``)."""
    import numpy as np

    (tmp_path / "nested_probe.py").write_text(NESTED)
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path / "cache"),
               PYTHONPATH=os.pathsep.join([str(tmp_path), str(ROOT)]))

    def run(name):
        done = subprocess.run([sys.executable, "-c", NESTED_RUN, name], env=env, cwd=tmp_path,
                              capture_output=True, text=True)
        assert done.returncode == 0, done.stderr
        return json.loads(done.stdout.strip().splitlines()[-1])

    expected = (np.cos(0.25) * 3.0 + 1.0) * 2.0
    assert run("middle")["misses"] == 1                      # middle (and leaf) compiled and cached
    second = run("outer")                                    # middle loaded, outer compiled
    assert (second["value"], second["misses"]) == (expected, 1)
    third = run("outer")                                     # outer loaded: its hook registers leaf
    assert (third["value"], third["misses"], third["hits"]) == (expected, 0, 1)


MAP_RUN = textwrap.dedent("""
    import json, re
    import numpy as np
    from mortar1d3d.elements.solid import dispatch, hex8, hex27
    from mortar1d3d.geometry import projection as pr
    out = {}
    for module in (hex8, hex27):
        code = module.DESCRIPTOR.code
        # the reference nodes moved by a fixed, smooth map: x = 2 ξ + 0.1 ξ0 ξ1 (a curved element)
        ref = dispatch.REFERENCE_NODES[code, : dispatch.N_NODES[code]]
        X = np.zeros((dispatch.MAX_NODES, 4))
        X[: len(ref), :3] = 2.0 * ref
        X[: len(ref), 2] += 0.1 * ref[:, 0] * ref[:, 1]
        xi = np.array([0.3, -0.2, 0.4])
        trial = np.zeros(3)
        pr.store_residual(code, X, 0.0, 0.0, 0.0, xi, trial, np.empty(dispatch.MAX_NODES))
        out[module.__name__] = (-trial).tolist()
    ir = "".join(pr.store_residual.inspect_llvm().values())
    out["defined"] = sorted(set(re.findall(r"define [^@]*@\\"?([^\\"(]*)", ir)))
    out["declared"] = sorted(set(re.findall(r"declare [^@]*@\\"?([^\\"(]*)", ir)))
    print(json.dumps(out))
""")


def test_the_other_types_map_is_called_through_a_symbol(tmp_path):
    """``projection.map_point`` (inlined into every function evaluating the map) writes out hex8 and
    calls every other type's map through a symbol: the caller's module declares it, defines none of
    the other types' code, and the map is still x(ξ) of the element (here x = 2ξ + 0.1 ξ0 ξ1 e_2,
    which both hex8 and hex27 interpolate exactly)."""
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path / "cache"), PYTHONPATH=str(ROOT))
    done = subprocess.run([sys.executable, "-c", MAP_RUN], env=env, cwd=tmp_path, capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    out = json.loads(done.stdout.strip().splitlines()[-1])
    for name in ("mortar1d3d.elements.solid.hex8", "mortar1d3d.elements.solid.hex27"):
        assert out[name] == pytest.approx([0.6, -0.4, 0.8 + 0.1 * 0.3 * -0.2], abs=1e-14)
    assert any("_map_other" in name for name in out["declared"])
    assert not any("_map_other" in name or "hex27" in name or "tet10" in name or "nurbs27" in name
                   for name in out["defined"])
