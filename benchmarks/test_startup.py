"""Start-up time and peak memory, each measured in a fresh Python process (docs/conventions.md §5).

* cold start: ``import mortar1d3d`` + segment- and element-based assembly of a tiny scene with
  ``NUMBA_CACHE_DIR`` pointing to an empty directory, i.e. every kernel is JIT-compiled;
* warm start: the same command again with the same, now populated, cache directory (the
  kernels are loaded from Numba's on-disk cache); target: <= 2 s;
* peak memory: ``resource.getrusage(RUSAGE_SELF).ru_maxrss`` of a process that assembles the
  benchmark scene fibre_cube(20, 1000, 20) segment-based (kernels from the warm cache, JIT
  warmed on a tiny scene first; the high-water mark before the assembly is reported as well).
  ``ru_maxrss`` only ever grows, and the interpreter + Numba/LLVM + scene may already set it
  before the assembly starts; so on Linux the child also resets the peak (``VmHWM``, via
  ``/proc/self/clear_refs``) right before the call and reports the assembly's own peak RSS and
  its increment over the RSS before the call.

Each measurement is one pytest-benchmark benchmark with a single round (the timed quantity is
the wall time of the subprocess, interpreter start included); the in-process time printed by
the child is what the summary compares with the target.
"""
import json
import os
import shutil
import subprocess
import sys
import tempfile
import textwrap
from pathlib import Path

import pytest

from conftest import N_GAUSS, REPO, SCENE, TARGETS

STARTUP_CODE = (
    "import time; t=time.perf_counter(); import mortar1d3d as m; b,s=m.generate.fibre_cube(3,2,3); "
    "m.assemble_mortar(b,s,integration='segment'); m.assemble_mortar(b,s,integration='element'); "
    "print(time.perf_counter()-t)"
)

MEMORY_CODE = textwrap.dedent(f"""
    import json, resource, time
    import numba
    import mortar1d3d as m

    def maxrss_mib():
        return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0   # KiB on Linux

    def status_mib(key):   # VmRSS / VmHWM from /proc/self/status (Linux), else None
        try:
            with open("/proc/self/status") as f:
                for line in f:
                    if line.startswith(key + ":"):
                        return int(line.split()[1]) / 1024.0
        except OSError:
            pass
        return None

    def reset_peak():      # Linux >= 4.0: VmHWM := VmRSS
        try:
            with open("/proc/self/clear_refs", "w") as f:
                f.write("5")
            return True
        except OSError:
            return False

    b, s = m.generate.fibre_cube(3, 2, 3)
    m.assemble_mortar(b, s, integration="segment", n_gauss={N_GAUSS})
    after_jit = maxrss_mib()
    b, s = m.generate.fibre_cube{SCENE}
    before = maxrss_mib()
    rss_before = status_mib("VmRSS")
    reset = reset_peak() and status_mib("VmHWM") is not None
    t = time.perf_counter()
    ops = m.assemble_mortar(b, s, integration="segment", n_gauss={N_GAUSS})
    dt = time.perf_counter() - t
    hwm = status_mib("VmHWM") if reset else None
    print(json.dumps(dict(maxrss_mib=max(before, maxrss_mib()), maxrss_before_assembly_mib=before,
                          maxrss_after_jit_mib=after_jit, rss_before_assembly_mib=rss_before,
                          assembly_peak_rss_mib=hwm,
                          assembly_increment_mib=None if hwm is None else hwm - rss_before,
                          assembly_s=dt, n_integration_points=ops.n_integration_points,
                          threads=numba.get_num_threads())))
""")


def run_child(code, cache_dir):
    env = dict(os.environ, NUMBA_CACHE_DIR=str(cache_dir))
    proc = subprocess.run([sys.executable, "-c", code], cwd=REPO, env=env, capture_output=True, text=True,
                          timeout=1200)
    if proc.returncode != 0:
        raise RuntimeError(f"child process failed ({proc.returncode}):\n{proc.stderr[-4000:]}")
    return proc.stdout.strip().splitlines()[-1]


def cache_files(cache_dir):
    return sorted(p for p in cache_dir.rglob("*") if p.suffix in (".nbi", ".nbc"))


@pytest.fixture(scope="module")
def cache_dir():
    """A fresh, empty NUMBA_CACHE_DIR shared by the cold start, the warm start and the memory run.

    Deliberately not under pytest's ``tmp_path_factory``: its base directory is pruned by other
    pytest sessions of the same user (only the newest three are kept), which on a shared machine
    can delete the cache between the cold and the warm start.
    """
    path = Path(tempfile.mkdtemp(prefix="mortar1d3d-bench-numba-cache-"))
    yield path
    shutil.rmtree(path, ignore_errors=True)


def ensure_populated(cache_dir):
    """Fill the cache untimed if the cold-start benchmark did not run (e.g. with -k warm)."""
    if not any(cache_dir.rglob("*.nbi")):
        run_child(STARTUP_CODE, cache_dir)


def startup_benchmark(benchmark, cache_dir, kind, bench_results):
    out = {}

    def run():
        out["stdout"] = run_child(STARTUP_CODE, cache_dir)

    benchmark.group = "start-up (fresh process)"
    benchmark.pedantic(run, rounds=1, warmup_rounds=0, iterations=1)
    in_process = float(out["stdout"])
    wall = benchmark.stats.stats.median if benchmark.stats is not None else float("nan")
    files = cache_files(cache_dir)
    record = {"in_process_s": in_process, "wall_s": wall, "numba_cache_dir": str(cache_dir),
              "cache_files": len(files), "command": STARTUP_CODE}
    if kind == "warm":
        record["target_s"] = TARGETS["warm_start_s"]
    benchmark.extra_info.update(record)
    bench_results["startup"][kind] = record
    assert files, "NUMBA_CACHE_DIR stayed empty: the kernels were not cached"
    return record


def test_cold_start(benchmark, cache_dir, bench_results):
    assert not cache_files(cache_dir)
    startup_benchmark(benchmark, cache_dir, "cold", bench_results)


def test_warm_start(benchmark, cache_dir, bench_results):
    ensure_populated(cache_dir)
    startup_benchmark(benchmark, cache_dir, "warm", bench_results)


def test_peak_memory(benchmark, cache_dir, bench_results):
    ensure_populated(cache_dir)
    out = {}

    def run():
        out["stdout"] = run_child(MEMORY_CODE, cache_dir)

    benchmark.group = "peak memory (fresh process)"
    benchmark.pedantic(run, rounds=1, warmup_rounds=0, iterations=1)
    record = json.loads(out["stdout"])
    record["scene"] = list(SCENE)
    record["integration"] = "segment"
    record["n_gauss"] = N_GAUSS
    benchmark.extra_info.update(record)
    bench_results["memory"] = record
