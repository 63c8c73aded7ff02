"""Workers run on the package's one parallel loop (mortar1d3d._parallel).

The call must run every worker index once with the caller's arrays (the same bits as the loop it
replaces), keep the kernel free of a parallel loop of its own, leave kernel, worker and driver
cachable (a second process loads them and compiles nothing), and raise when a worker raises.
"""
import textwrap

from test_unlinked import _run as run_probe

MODULE = textwrap.dedent("""
    import numpy as np
    from numba import prange
    from mortar1d3d._config import njit, njit_parallel
    from mortar1d3d._parallel import in_parallel

    @njit
    def worker(i, n_parts, a, out, scale, hits):
        hits[i] += 1
        for k in range(i * a.shape[0] // n_parts, (i + 1) * a.shape[0] // n_parts):
            if a[k] < 0.0:
                raise ValueError("negative")
            out[k] = np.sin(a[k]) * scale

    workers = in_parallel(worker)

    @njit
    def kernel(a, out, n_parts):
        hits = np.zeros(n_parts, dtype=np.int64)
        workers(n_parts, n_parts, a, out, 2.0, hits)
        return hits

    @njit_parallel
    def loop(a, out, n_parts):
        for i in prange(n_parts):
            for k in range(i * a.shape[0] // n_parts, (i + 1) * a.shape[0] // n_parts):
                out[k] = np.sin(a[k]) * 2.0
""")

RUN = textwrap.dedent("""
    import json, sys, warnings
    warnings.simplefilter("error")   # a "Cannot cache" NumbaWarning fails the run
    import numpy as np
    import parallel_probe as p
    from mortar1d3d import _parallel
    a = np.linspace(0.0, 3.0, 1001)
    out, reference = np.zeros_like(a), np.zeros_like(a)
    hits = p.kernel(a, out, 7)
    p.loop(a, reference, 7)
    raised = ""
    try:
        p.kernel(-a - 1.0, out.copy(), 7)
    except RuntimeError as error:
        raised = str(error)
    stats = lambda f: [sum(f.stats.cache_hits.values()), sum(f.stats.cache_misses.values())]
    kernel_ir = "".join(p.kernel.inspect_llvm().values()) if p.kernel.stats.cache_misses else ""
    print(json.dumps(dict(same=bool(np.array_equal(out, reference)), hits=hits.tolist(), raised=raised,
                          kernel=stats(p.kernel), worker=stats(p.worker), drive=stats(_parallel._drive),
                          kernel_has_parallel_loop="gufunc" in kernel_ir)))
""")


def _run(tmp_path):
    return run_probe(tmp_path, RUN)


def test_workers_on_the_shared_loop_results_errors_and_cache(tmp_path):
    (tmp_path / "parallel_probe.py").write_text(MODULE)
    first = _run(tmp_path)
    assert first["same"]                         # the loop's own results, bit for bit
    assert first["hits"] == [1] * 7              # every index once
    assert "parallel worker of worker raised" in first["raised"]
    assert first["kernel"][1] == 1 and first["worker"][1] == 1
    assert not first["kernel_has_parallel_loop"]   # the kernel launches no parallel region of its own
    second = _run(tmp_path)
    assert second["same"] and second["hits"] == [1] * 7 and second["raised"] == first["raised"]
    # everything loaded from the cache, nothing compiled
    assert [second["kernel"][1], second["worker"][1], second["drive"][1]] == [0, 0, 0]
    assert second["kernel"][0] == 1 and second["worker"][0] >= 1 and second["drive"][0] >= 1
