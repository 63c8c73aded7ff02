"""Throughput of the whole ``assemble_mortar`` call (docs/conventions.md §5).

Scene ``generate.fibre_cube(20, 1000, 20)`` (8000 hex8, 1000 fibres of 20 Hermite elements),
``n_gauss = 4``; element-based and segment-based integration on straight fibres, segment-based
on curved (helical) fibres, and both on straight fibres in the cube with its interior nodes
moved (``conftest.DISTORTION``: no element affine, every location a Newton projection); each
with 1 Numba thread and with 2 threads. The timed call is the
whole ``assemble_mortar`` (search, segmentation, integration points, local operators, CSR,
certificate); JIT compilation is excluded by the session fixture ``warm_jit`` (tiny scene
first) plus one untimed warm-up round on the benchmark scene.

Figures in ``extra_info``: integration points, Gauss points per second (points / median
round time) in total and per thread, and the median per-stage ``ops.timings`` over the rounds.
"""
import resource
import statistics
import time

import numba
import pytest

import mortar1d3d as m13
from conftest import N_GAUSS, SCENE, TARGETS, available_cpus

ROUNDS = 10
WARMUP_ROUNDS = 1

VARIANTS = [  # (variant name, integration, curved, distorted solid)
    ("element-based, straight", "element", False, False),
    ("segment-based, straight", "segment", False, False),
    ("segment-based, curved", "segment", True, False),
    ("element-based, distorted hex8", "element", False, True),
    ("segment-based, distorted hex8", "segment", False, True),
]


@pytest.fixture(params=[1, 2], ids=["1thread", "2threads"])
def threads(request):
    n = request.param
    if n > numba.config.NUMBA_NUM_THREADS:
        pytest.skip(f"{n} threads requested, NUMBA_NUM_THREADS={numba.config.NUMBA_NUM_THREADS}")
    if n > available_cpus():
        pytest.skip(f"{n} threads requested, {available_cpus()} CPU(s) available")
    default = numba.get_num_threads()
    numba.set_num_threads(n)
    yield n
    numba.set_num_threads(default)


@pytest.mark.parametrize("variant,integration,curved,distorted", VARIANTS,
                         ids=[f"{i}-{'curved' if c else 'straight'}{'-distorted' if d else ''}"
                              for _, i, c, d in VARIANTS])
def test_assemble_mortar(benchmark, warm_jit, scene, threads, bench_results, variant, integration, curved, distorted):
    beams, solid = scene(curved, distorted)
    assert numba.get_num_threads() == threads
    records = []  # (wall time, n points, timings) of every call, warm-up rounds first

    def run():
        faults = resource.getrusage(resource.RUSAGE_SELF).ru_minflt
        t = time.perf_counter()
        ops = m13.assemble_mortar(beams, solid, integration=integration, n_gauss=N_GAUSS)
        t = time.perf_counter() - t
        faults = resource.getrusage(resource.RUSAGE_SELF).ru_minflt - faults
        records.append((t, ops.n_integration_points, ops.timings, ops.diagnostics, faults))

    benchmark.group = "assemble_mortar, fibre_cube(%d, %d, %d)" % SCENE
    benchmark.pedantic(run, rounds=ROUNDS, warmup_rounds=WARMUP_ROUNDS, iterations=1)

    timed = records[-ROUNDS:] if len(records) > ROUNDS else records
    n_points = timed[-1][1]
    assert n_points > 0 and all(r[1] == n_points for r in timed), "integration points differ between rounds"
    stats = benchmark.stats.stats if benchmark.stats is not None else None  # None with --benchmark-disable
    median = stats.median if stats is not None else statistics.median(r[0] for r in timed)
    best = stats.min if stats is not None else min(r[0] for r in timed)
    stages = {k: float(statistics.median(r[2][k] for r in timed)) for k in timed[-1][2]}
    gp_per_s = n_points / median
    target = TARGETS[f"{integration}_gp_per_s_per_core"]

    record = {
        "integration": integration, "curved": curved, "distorted": distorted, "threads": threads, "n_gauss": N_GAUSS,
        "scene": list(SCENE), "n_integration_points": n_points, "rounds": len(timed),
        "median_s": median, "min_s": best,
        "gp_per_s": gp_per_s, "gp_per_s_per_core": gp_per_s / threads,
        "gp_per_s_best": n_points / best,
        "target_gp_per_s_per_core": target,
        "timings_median_s": stages,
        "diagnostics": {k: int(v) for k, v in timed[-1][3].items()},
        # memory the call got fresh from the OS (each round's result is dropped, so glibc may
        # return the memory and the next call faults it in again: see benchmarks/README.md)
        "page_faults_per_call_median": float(statistics.median(r[4] for r in timed)),
    }
    benchmark.extra_info.update(record)
    bench_results["assembly"].setdefault(variant, {})[threads] = record


@pytest.mark.parametrize("variant,integration,curved,distorted", VARIANTS,
                         ids=[f"{i}-{'curved' if c else 'straight'}{'-distorted' if d else ''}"
                              for _, i, c, d in VARIANTS])
def test_thread_speedup(benchmark, warm_jit, scene, bench_results, variant, integration, curved, distorted):
    """Paired rounds: the call with 1 thread, the call with 2 threads, the control with 1 and 2.

    A machine whose speed drifts within minutes (shared or virtual cores) makes the ratio of two
    medians taken a minute apart meaningless; the ratio within one round is not, and the control
    (benchmarks/control.py, as Numba schedules prange and with chunks claimed dynamically as the
    engine's kernels do) says what the machine gave two threads in that round. Each round
    runs the pair twice: with the previous result dropped first (fresh memory, as in
    ``test_assemble_mortar``: the call faults its memory in again) and with it still held (the
    memory is reused; what the engine's own parallel work gives). The benchmark time of this
    test is that of a whole round (not a figure of interest).
    """
    if numba.config.NUMBA_NUM_THREADS < 2 or available_cpus() < 2:
        pytest.skip("needs 2 threads and 2 CPUs")
    from control import control_times

    beams, solid = scene(curved, distorted)
    default = numba.get_num_threads()
    pairs = {"fresh": [], "held": []}
    controls = []
    claimed = []
    held = []

    def one_round():
        for regime in ("fresh", "held"):
            times = {}
            if regime == "held":    # so that the timed 1-thread call, too, runs with a result held
                held[:] = [m13.assemble_mortar(beams, solid, integration=integration, n_gauss=N_GAUSS)]
            for nt in (1, 2):
                if regime == "fresh":
                    held.clear()
                numba.set_num_threads(nt)
                t = time.perf_counter()
                ops = m13.assemble_mortar(beams, solid, integration=integration, n_gauss=N_GAUSS)
                times[nt] = time.perf_counter() - t
                held[:] = [ops] if regime == "held" else []
                del ops
            pairs[regime].append(times[1] / times[2])
        numba.set_num_threads(default)
        control = control_times()
        controls.append(control[1] / control[2])
        control = control_times(dynamic=True)
        claimed.append(control[1] / control[2])

    benchmark.group = "paired 1 -> 2 thread rounds, fibre_cube(%d, %d, %d)" % SCENE
    try:
        benchmark.pedantic(one_round, rounds=ROUNDS, warmup_rounds=WARMUP_ROUNDS, iterations=1)
    finally:
        numba.set_num_threads(default)
        held.clear()
    fresh, kept, controls, claimed = (pairs["fresh"][-ROUNDS:], pairs["held"][-ROUNDS:], controls[-ROUNDS:],
                                      claimed[-ROUNDS:])
    record = {"paired_speedup_median": statistics.median(kept), "paired_speedups": kept,
              "paired_speedup_fresh_median": statistics.median(fresh), "paired_speedups_fresh": fresh,
              "control_speedup_median": statistics.median(controls), "control_speedups": controls,
              "control_claimed_speedup_median": statistics.median(claimed), "control_claimed_speedups": claimed,
              # how much of what the machine gave two threads in each round the engine turned into speed
              "paired_over_claimed_median": statistics.median(k / c for k, c in zip(kept, claimed))}
    benchmark.extra_info.update(record)
    bench_results.setdefault("speedup", {})[variant] = record
