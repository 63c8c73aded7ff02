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

import numpy as np
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


def _run(tmp_path, code=RUN):
    """``code`` in a fresh process with the cache in ``tmp_path`` and its modules importable; its last
    line of output, as JSON (also used by tests/test_parallel.py)."""
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path / "cache"),
               PYTHONPATH=os.pathsep.join([str(tmp_path), str(ROOT)]))
    done = subprocess.run([sys.executable, "-c", code], env=env, cwd=tmp_path, capture_output=True, text=True)
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
    out["slots"] = sorted(set(re.findall(r"@\\"?([^\\" ]*)\\"? = external global", ir)))
    print(json.dumps(out))
""")


def test_the_other_types_map_is_called_through_a_symbol(tmp_path):
    """``projection.map_point`` (inlined into every function evaluating the map) writes out hex8 and
    calls every other type's map through a symbol: the caller's module holds its slot, defines none of
    the other types' code, and the map is still x(ξ) of the element (here x = 2ξ + 0.1 ξ0 ξ1 e_2,
    which both hex8 and hex27 interpolate exactly)."""
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path / "cache"), PYTHONPATH=str(ROOT))
    done = subprocess.run([sys.executable, "-c", MAP_RUN], env=env, cwd=tmp_path, capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    out = json.loads(done.stdout.strip().splitlines()[-1])
    for name in ("mortar1d3d.elements.solid.hex8", "mortar1d3d.elements.solid.hex27"):
        assert out[name] == pytest.approx([0.6, -0.4, 0.8 + 0.1 * 0.3 * -0.2], abs=1e-14)
    # lazily: the caller holds the slot of the other types' map, not even a declaration of its code
    assert any("_map_other" in name for name in out["slots"])
    assert not any("_map_other" in name or "hex27" in name or "tet10" in name or "nurbs27" in name
                   for name in out["defined"])


LAZY = textwrap.dedent("""
    import numpy as np
    from numba import prange, types
    from mortar1d3d._config import njit, njit_parallel
    from mortar1d3d._unlinked import unlinked

    @njit
    def rare(x, out):
        out[0] = np.cos(x) * 3.0
        return out[0] + 1.0

    rare_call = unlinked(rare, returns=types.float64)

    @njit_parallel
    def kernel(a, out, limit):
        total = np.zeros(a.shape[0])
        for i in prange(a.shape[0]):
            if a[i] > limit:
                total[i] = rare_call(a[i], out[i:i + 1])
            else:
                total[i] = a[i]
        return total

    @njit
    def by_type(k, x, out):
        # k is a literal: one compiled version per value in ``cases``
        if k == 0:
            out[0] = x + 1.0
        elif k == 1:
            out[0] = x * 2.0
        else:
            out[0] = x - 3.0

    by_type_call = unlinked(by_type, returns=types.none, cases=(0, 1, 2))

    @njit
    def typed(k, x):
        out = np.zeros(1)
        by_type_call(k, x, out)
        return out[0]

    @njit
    def wrong(x):
        return x

    wrong_call = unlinked(wrong, returns=types.int64)   # declared int64, returns float64

    @njit
    def calls_wrong(x):
        return wrong_call(x)
""")

LAZY_RUN = textwrap.dedent("""
    import json, sys, warnings
    warnings.simplefilter("error")
    import numpy as np
    import lazy_probe as p
    from mortar1d3d import _unlinked
    a = np.linspace(0.0, 1.0, 101)
    out = np.zeros_like(a)
    limit, k, then = float(sys.argv[1]), int(sys.argv[2]), sys.argv[3]
    total = p.kernel(a, out, limit)
    value = p.typed(k, 0.5)
    result = dict(total=total.tolist(), value=value,
                  kernel_misses=sum(p.kernel.stats.cache_misses.values()),
                  rare_signatures=len(p.rare.signatures),
                  rare_misses=sum(p.rare.stats.cache_misses.values()),
                  by_type=sorted(str(s[0]) for s in p.by_type.signatures),
                  by_type_misses=sum(p.by_type.stats.cache_misses.values()))
    if then == "compile_lazy":
        result["compiled"] = _unlinked.compile_lazy()
        result["rare_signatures_after"] = len(p.rare.signatures)
        result["by_type_after"] = len(p.by_type.signatures)
    if then == "wrong":
        try:
            p.calls_wrong(1.0)
        except RuntimeError as error:
            result["raised"] = str(error)
        result["failed"] = list(_unlinked.FAILED.values())
    print(json.dumps(result))
""")


def _lazy_run(tmp_path, limit, k, then="-"):
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path / "cache"),
               PYTHONPATH=os.pathsep.join([str(tmp_path), str(ROOT)]))
    done = subprocess.run([sys.executable, "-c", LAZY_RUN, str(limit), str(k), then], env=env, cwd=tmp_path,
                          capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    return json.loads(done.stdout.strip().splitlines()[-1])


def test_a_lazy_callee_compiles_at_its_first_call_only(tmp_path):
    """``unlinked(f, returns=...)``: compiling the caller does not compile ``f``, nor does loading the
    cached caller in another process; the first call (from a prange thread) compiles it, a later
    process loads it; the results are ``f``'s (the same operations, the same bits)."""
    (tmp_path / "lazy_probe.py").write_text(LAZY)
    a = np.linspace(0.0, 1.0, 101)
    never = _lazy_run(tmp_path, 2.0, 1)                # no point beyond 2: rare is never called
    assert never["total"] == a.tolist()
    assert (never["kernel_misses"], never["rare_signatures"]) == (1, 0)
    again = _lazy_run(tmp_path, 2.0, 1)                # the kernel from the cache: rare still not loaded
    assert (again["kernel_misses"], again["rare_signatures"]) == (0, 0)
    called = _lazy_run(tmp_path, 0.5, 1)               # now some points take the rare path
    expected = np.where(a > 0.5, np.cos(a) * 3.0 + 1.0, a)
    assert called["total"] == expected.tolist()
    assert (called["kernel_misses"], called["rare_signatures"], called["rare_misses"]) == (0, 1, 1)
    loaded = _lazy_run(tmp_path, 0.5, 1)               # and from the cache in the next process
    assert loaded["total"] == expected.tolist()
    assert (loaded["rare_signatures"], loaded["rare_misses"]) == (1, 0)


def test_lazy_cases_compile_one_version_per_value_used(tmp_path):
    """``cases``: one version of the callee per value of its first argument, with that argument a
    literal, compiled when the value is first met; :func:`compile_lazy` compiles the rest."""
    (tmp_path / "lazy_probe.py").write_text(LAZY)
    one = _lazy_run(tmp_path, 2.0, 1)
    assert one["value"] == 1.0 and one["by_type"] == ["Literal[int](1)"] and one["by_type_misses"] == 1
    again = _lazy_run(tmp_path, 2.0, 1)                # the literal version is cached like any other
    assert again["value"] == 1.0 and again["by_type_misses"] == 0
    two = _lazy_run(tmp_path, 2.0, 2)
    assert two["value"] == -2.5 and two["by_type"] == ["Literal[int](2)"]
    missing = _lazy_run(tmp_path, 2.0, 7)              # a value not listed: no call
    assert missing["value"] == 0.0 and missing["by_type"] == []
    everything = _lazy_run(tmp_path, 2.0, 0, "compile_lazy")
    assert everything["value"] == 1.5 and everything["by_type"] == ["Literal[int](0)"]
    # the rare callee and the two other cases: what the callers used in this process declare
    assert everything["compiled"] == 3
    assert (everything["rare_signatures_after"], everything["by_type_after"]) == (1, 3)


def test_a_lazy_callee_of_the_wrong_type_raises_instead_of_being_called(tmp_path):
    (tmp_path / "lazy_probe.py").write_text(LAZY)
    out = _lazy_run(tmp_path, 2.0, 0, "wrong")
    assert "could not be compiled" in out["raised"]
    assert len(out["failed"]) == 1 and "returns float64" in out["failed"][0]


SCENE_RUN = textwrap.dedent("""
    import json
    import mortar1d3d as m
    from mortar1d3d.elements.solid import registry
    from mortar1d3d.elements.beam import registry as beams
    from mortar1d3d.geometry import projection, search
    from mortar1d3d.integration import points
    b, s = m.generate.fibre_cube(3, 2, 3)
    m.assemble_mortar(b, s, integration="element")
    print(json.dumps(dict(
        solid_types={t.DESCRIPTOR.name: len(t.shape.signatures) + len(t.deriv.signatures)
                     for t in registry.SOLID_TYPES},
        other=[len(f.signatures) for f in (projection._map_other, projection._jacobian_other,
                                           projection.locate_rare, search.hull_planes, search._solid_hulls,
                                           search._solid_hulls_chunk, projection.certified_margin,
                                           search._sort_front)],
        bin_part=[str(sig[0]) for sig in search._bin_part.signatures],
        beam_type=b.element_type.code,
        chunks=[sorted(str(sig[0]) for sig in f.signatures)
                for f in (points._element_points_chunk, search._beam_frames_chunk)])))
""")


def test_a_hex8_element_based_call_compiles_only_what_it_runs():
    """The first element-based call of a hex8 scene with Hermite beams (the kernel cache of the test
    run, cold or warm) neither compiles nor loads another solid type's kernels, their map and
    Jacobian, the rare path of locating a point, the hull planes or the hull kernel (hex8 has none),
    the one-to-one certificate (its elements are affine) or numpy's sort of a long candidate list,
    and its beam loops exist for its beam type only: all are called lazily (``unlinked(...,
    returns=...)``) or skipped. ``_bin_part``, a worker of the package's parallel loop
    (mortar1d3d._parallel) called with its index, exists for int64 only."""
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    done = subprocess.run([sys.executable, "-c", SCENE_RUN], env=env, capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    out = json.loads(done.stdout.strip().splitlines()[-1])
    # hex8's kernels are linked into the dispatch (compiled with it on a cold cache, not loaded on a warm one)
    others = {name: n for name, n in out["solid_types"].items() if name != "hexahedron"}
    assert len(others) == len(out["solid_types"]) - 1 and others == {name: 0 for name in others}
    assert out["other"] == [0] * 8
    assert out["bin_part"] == ["int64"]
    assert out["chunks"] == [[f"Literal[int]({out['beam_type']})"]] * 2


OTHERS_RUN = textwrap.dedent("""
    import json
    import mortar1d3d as m
    from mortar1d3d.geometry import intersection, projection
    beams, solid = m.generate.fibre_cube(3, 6, 3)
    solid = m.generate.distort(solid, 0.1)
    ops = [m.assemble_mortar(beams, solid, integration=i, n_gauss=4) for i in ("segment", "element")]
    out = {f.__name__: len(f.signatures)
           for f in (projection._project_other, projection._polish_other, intersection._intersect_other,
                     projection._map_jacobian_other)}
    out["crossings"] = ops[0].diagnostics["face_crossings"]
    out["embedded"] = [o.embedded_length / o.beam_length for o in ops]
    print(json.dumps(out))
""")


def test_a_distorted_hex8_scene_never_compiles_the_other_types_newton_versions(tmp_path):
    """hex8's Newton projection, polishing step and face Newton sit behind one type test: a distorted
    hex8 scene (every location a Newton projection, crossings found by the face Newton) runs them
    without compiling or loading the shared version of the other types."""
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    done = subprocess.run([sys.executable, "-c", OTHERS_RUN], env=env, cwd=tmp_path, capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    out = json.loads(done.stdout.strip().splitlines()[-1])
    assert out["crossings"] > 0     # the face Newton ran (and every point of the distorted cube is a projection)
    assert out["embedded"] == pytest.approx([1.0, 1.0], rel=1e-12)
    assert {k: out[k] for k in ("_project_other", "_polish_other", "_intersect_other", "_map_jacobian_other")} == \
        {"_project_other": 0, "_polish_other": 0, "_intersect_other": 0, "_map_jacobian_other": 0}


WARMED_RUN = textwrap.dedent("""
    import json
    import sys
    import mortar1d3d as m
    from numba.core.dispatcher import Dispatcher

    def signatures():
        # every compiled function of the package and its signatures (compiled or loaded from the cache)
        return {f"{mod.__name__}.{k}": len(v.signatures) for mod in list(sys.modules.values())
                if getattr(mod, "__name__", "").startswith("mortar1d3d")
                for k, v in list(vars(mod).items()) if isinstance(v, Dispatcher)}

    out = {}
    for name in sys.argv[1:]:
        m.warmup(elements=[name], integrations=["segment", "element"], physics=False)
        before = signatures()
        # not warmup's scene: more elements and fibres, another distortion
        beams, _ = m.generate.fibre_cube(4, 8, 3)
        solid = m.generate.distort(m.generate.box((0, 0, 0), (1, 1, 1), (4, 4, 4), element=name), 0.12, seed=1)
        ops = [m.assemble_mortar(beams, solid, integration=i, n_gauss=4) for i in ("segment", "element")]
        after = signatures()
        out[name] = dict(new=sorted(k for k, n in after.items() if n != before.get(k, 0)),
                         crossings=ops[0].diagnostics["face_crossings"],
                         embedded=[o.embedded_length / o.beam_length for o in ops])
    print(json.dumps(out))
""")

#: what a scene may still compile after ``warmup(elements=...)`` (its docstring): the rare path of
#: locating a point and numpy's sort of a long candidate list, which the tiny scenes do not take
RARE = ("locate_rare", "search_inside", "_sort_front")


@pytest.mark.parametrize("name", ["hexahedron27", "tetra10", "wedge"])
def test_a_distorted_scene_after_its_types_warmup_compiles_nothing_but_the_rare_paths(tmp_path, name):
    """``warmup(elements=[T])`` runs a distorted tiny scene of T (T not hex8): a distorted scene of T
    afterwards (curved elements: Newton projection and polishing, face crossings by the face Newton, the
    one-to-one certificate) compiles nothing the tiny scene could have compiled. With an undistorted
    tiny box (affine elements) it compiled, at the user's first curved scene, ``certified_margin``,
    ``_project_other``, ``_polish_other`` and for hex27 ``_jacobian_other`` and ``_intersect_other``
    (one process per type: a type's warm-up compiles what the other types share). hex8's tiny scene
    stays undistorted (the demo's warm-up): its certificate compiles at a curved hex8 scene's first use."""
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    done = subprocess.run([sys.executable, "-c", WARMED_RUN, name], env=env, cwd=tmp_path, capture_output=True,
                          text=True)
    assert done.returncode == 0, done.stderr
    out = json.loads(done.stdout.strip().splitlines()[-1])[name]
    assert out["crossings"] > 0
    assert out["embedded"] == pytest.approx([1.0, 1.0], rel=1e-12)
    assert [f for f in out["new"] if not f.endswith(RARE)] == []
