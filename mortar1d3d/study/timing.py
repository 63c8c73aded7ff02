"""What the study measures with the clock: one assembly, its growth with the points, a fresh start.

:func:`time_assembly` times one variant on one scene (stages and memory peak too), :func:`scaling`
the growth of segment-based assembly with the number of integration points, :func:`startup` the
cold and warm start of a fresh process.
"""
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
import tracemalloc
from pathlib import Path

import numpy as np

from .. import generate
from ..mortar.assemble import assemble_mortar

#: the stages of ``ops.timings`` the study reports (``other``: the rest of the total)
STAGES = ("search", "segmentation", "integration_points", "assembly", "csr", "other")


def stage_times(timings):
    """The stages of ``ops.timings``, plus ``other``: the rest of the total (certificates, point records)."""
    out = {k: timings.get(k, 0.0) for k in STAGES[:-1]}
    out["other"] = max(0.0, timings.get("total", 0.0) - sum(out.values()))
    return out


def time_assembly(beams, solid, integration, n_gauss, lm="line2", repeats=5, memory=False, warmup=True):
    """Median wall time of ``assemble_mortar`` and its stages; the operators of the last call.

    One untimed call first (JIT compilation or cache loading; skipped with ``warmup=False``
    when the kernels are known to be compiled). With ``memory``, one more call
    under ``tracemalloc`` gives the peak of Python/NumPy allocations (bytes) during a call:
    allocated, not necessarily touched, memory (``np.empty`` buffers count in full).

    Returns
    -------
    record : dict
        ``time_s`` (median), ``min_s``, ``stages_s`` (median per stage), ``points``,
        ``segments``, ``peak_bytes`` (or None).
    ops : MortarOperators
    """
    if warmup:
        assemble_mortar(beams, solid, integration=integration, n_gauss=n_gauss, lm=lm)
    peak = None
    if memory:
        tracemalloc.start()
        try:
            assemble_mortar(beams, solid, integration=integration, n_gauss=n_gauss, lm=lm)
            peak = tracemalloc.get_traced_memory()[1]
        finally:
            tracemalloc.stop()
    times, stages = [], {k: [] for k in STAGES}
    ops = None
    for _ in range(max(1, repeats)):
        ops = None          # at most one result alive: large scenes stay within memory
        t0 = time.perf_counter()
        ops = assemble_mortar(beams, solid, integration=integration, n_gauss=n_gauss, lm=lm)
        times.append(time.perf_counter() - t0)
        for k, v in stage_times(ops.timings).items():
            stages[k].append(v)
    record = {"time_s": statistics.median(times), "min_s": min(times),
              "stages_s": {k: statistics.median(v) for k, v in stages.items()},
              "points": ops.n_integration_points, "segments": len(ops.segments), "peak_bytes": peak}
    return record, ops


def scaling(config, progress=None):
    """Time and memory of segment-based assembly (n_gauss 4) of fibre_cube(20, F, 20) vs points."""
    per_fibre = None
    rows = []
    for target in config.scaling_points:
        if per_fibre is None:
            b, s = generate.fibre_cube(20, 10, 20)
            per_fibre = assemble_mortar(b, s, integration="segment", n_gauss=4).n_integration_points / 10
        fibres = max(1, int(round(target / per_fibre)))
        beams, solid = generate.fibre_cube(20, fibres, 20)
        repeats = 3 if target <= 1e6 else 1
        # the first (smallest) size compiles; larger ones need no untimed call
        rec, ops = time_assembly(beams, solid, "segment", 4, repeats=repeats, memory=config.memory,
                                 warmup=not rows)
        rec.update(target=target, fibres=fibres)
        rows.append(rec)
        del beams, solid, ops
        if progress:
            mem = "" if rec["peak_bytes"] is None else f", peak {rec['peak_bytes'] / 2**20:.0f} MiB"
            progress(f"  {rec['points']:>9d} points: {rec['time_s'] * 1e3:9.1f} ms{mem}")
    pts = np.array([r["points"] for r in rows], dtype=float)
    t = np.array([r["time_s"] for r in rows])
    fit = {"time_slope": float(np.polyfit(np.log10(pts), np.log10(t), 1)[0]) if len(rows) > 1 else None}
    big = pts >= 1e4
    if big.sum() >= 2:
        fit["time_slope_from_1e4"] = float(np.polyfit(np.log10(pts[big]), np.log10(t[big]), 1)[0])
    if config.memory and len(rows) > 1:
        m = np.array([r["peak_bytes"] for r in rows], dtype=float)
        fit["memory_slope"] = float(np.polyfit(np.log10(pts), np.log10(m), 1)[0])
        fit["bytes_per_point_largest"] = float(m[-1] / pts[-1])
    return {"rows": rows, "fit": fit}


STARTUP_CODE = ("import time; t=time.perf_counter(); import mortar1d3d as m; b,s=m.generate.fibre_cube(3,2,3); "
                "[m.assemble_mortar(b,s,integration=i) for i in ('segment','element','auto')]; "
                "print(time.perf_counter()-t)")


def startup(cold=True):
    """Import + tiny assembly (segment, element, auto) in a fresh process: cold and warm cache.

    Cold: ``NUMBA_CACHE_DIR`` pointing to an empty directory (every kernel compiles); warm: the
    same directory again. Without ``cold``, only a warm start with the default cache directory
    (filled by this process).
    """
    root = Path(__file__).resolve().parents[2]          # the directory holding the package mortar1d3d
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(root), os.environ.get("PYTHONPATH", "")]))

    def run(env):
        t0 = time.perf_counter()
        out = subprocess.run([sys.executable, "-c", STARTUP_CODE], env=env, capture_output=True, text=True,
                             timeout=1800, cwd=str(root))
        wall = time.perf_counter() - t0
        if out.returncode != 0:
            raise RuntimeError(f"start-up subprocess failed: {out.stderr[-2000:]}")
        return {"in_process_s": float(out.stdout.strip().splitlines()[-1]), "wall_s": wall}

    result = {}
    if cold:
        cache = tempfile.mkdtemp(prefix="mortar1d3d-cold-")
        try:
            env_cold = dict(env, NUMBA_CACHE_DIR=cache)
            result["cold"] = run(env_cold)
            result["warm"] = run(env_cold)
        finally:
            shutil.rmtree(cache, ignore_errors=True)
    else:
        result["warm"] = run(env)
    return result


