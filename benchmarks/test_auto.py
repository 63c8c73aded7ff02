"""integration="auto" against element- and segment-based on the benchmark scene (issue 5).

Scene ``fibre_cube(20, 1000, 20)``, ``n_gauss = 4``, 1 Numba thread (per-core figures, like the
assembly benchmarks). Target of the issue: segment-based accuracy at <= 1.3x the element-based
time. The timed call (pytest-benchmark, 10 rounds after 1 warm-up round) is the whole
``assemble_mortar(..., integration="auto")``; before every round the setup function (untimed)
runs the element-based and the segment-based assembly of the same scene and records their wall
times, so the three medians come from interleaved calls under the same machine load.

``extra_info`` and ``benchmarks/results/auto.json``: medians, the ratio auto / element-based,
stage medians, points, and the errors of D and M of auto and element-based against segment-based
with 8 points per segment. The ratio is reported, not asserted (timings depend on the machine);
the accuracy is asserted (auto equals segment-based to round-off).
"""
import json
import statistics
import time

import numba
import scipy.sparse.linalg as spla

import mortar1d3d as m13
from conftest import HERE, N_GAUSS, SCENE

ROUNDS = 10
TARGET_RATIO = 1.3


def _relative(A, B):
    return float(spla.norm(A - B) / spla.norm(B))


def test_auto_vs_element(benchmark, warm_jit, scene):
    beams, solid = scene(False)
    default = numba.get_num_threads()
    numba.set_num_threads(1)
    try:
        small = m13.generate.fibre_cube(3, 2, 3)
        m13.assemble_mortar(*small, integration="auto", n_gauss=N_GAUSS)       # JIT outside the rounds
        others = {"element": [], "segment": []}
        auto = []
        ops = {}

        def setup():
            for integration in others:
                t0 = time.perf_counter()
                ops[integration] = m13.assemble_mortar(beams, solid, integration=integration, n_gauss=N_GAUSS)
                others[integration].append(time.perf_counter() - t0)

        def run():
            t0 = time.perf_counter()
            ops["auto"] = m13.assemble_mortar(beams, solid, integration="auto", n_gauss=N_GAUSS)
            auto.append((time.perf_counter() - t0, ops["auto"].timings))

        benchmark.group = "auto vs element, fibre_cube(%d, %d, %d)" % SCENE
        benchmark.pedantic(run, setup=setup, rounds=ROUNDS, warmup_rounds=1, iterations=1)
    finally:
        numba.set_num_threads(default)

    timed = auto[-ROUNDS:]
    median = {"auto": statistics.median(t for t, _ in timed),
              **{k: statistics.median(v[-ROUNDS:]) for k, v in others.items()}}
    reference = m13.assemble_mortar(beams, solid, integration="segment", n_gauss=8)
    errors = {k: {"D": _relative(ops[k].D, reference.D), "M": _relative(ops[k].M, reference.M)} for k in ops}
    record = {
        "scene": list(SCENE), "n_gauss": N_GAUSS, "threads": 1, "rounds": len(timed),
        "median_s": median, "auto_over_element": median["auto"] / median["element"],
        "segment_over_element": median["segment"] / median["element"], "target_ratio": TARGET_RATIO,
        "points": {k: ops[k].n_integration_points for k in ops},
        "auto_stages_median_s": {k: statistics.median(t[k] for _, t in timed) for k in timed[-1][1]},
        "errors_vs_segment_8": errors,
        "auto_diagnostics": {k: int(v) for k, v in ops["auto"].diagnostics.items()},
    }
    benchmark.extra_info.update(record)
    path = HERE / "results" / "auto.json"
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(record, indent=2) + "\n")
    # accuracy is a property, not a timing: auto must be segment-based to round-off here
    assert errors["auto"]["D"] < 1e-13 and errors["auto"]["M"] < 1e-13
    assert errors["element"]["M"] > 1e-6
