"""Residual + tangent of the Total Lagrangian solid: 100k hexahedra (hex8), 1 and 2 threads.

Mesh ``generate.box((0, 0, 0), (1, 1, 1), (50, 50, 40), "hexahedron")`` (100 000 hex8,
106 131 nodes, 318 393 dofs), Neo-Hooke and Saint Venant–Kirchhoff at a random displacement
of 0.1 % of the size. The timed call is the whole ``SolidModel.evaluate(u)`` (kernel, fresh
f_int and CSR data arrays, the scipy CSR wrapper); the model set-up (reference derivatives,
CSR pattern, colouring) is timed once, separately. JIT compilation is excluded: a tiny model
runs first with every thread count, plus one untimed warm-up round.

Target (reported, never asserted): residual + tangent <= 1.5 s per call on one core.
Figures: ``extra_info`` of each benchmark and ``benchmarks/results/solid_latest.json``.
"""
import json
import statistics
import time

import numba
import numpy as np
import pytest

import mortar1d3d as m13
from conftest import HERE, available_cpus
from mortar1d3d.physics.materials import material
from mortar1d3d.physics.solid import SolidModel

CELLS = (50, 50, 40)
ROUNDS = 5
TARGET_S = 1.5
RESULTS_FILE = HERE / "results" / "solid_latest.json"
RECORDS = {}

VARIANTS = [  # (name, material, tangent)
    ("neo_hooke, f_int + K", "neo_hooke", True),
    ("saint_venant_kirchhoff, f_int + K", "saint_venant_kirchhoff", True),
    ("neo_hooke, f_int only", "neo_hooke", False),
]


@pytest.fixture(params=[1, 2], ids=["1thread", "2threads"])
def solid_threads(request):
    n = request.param
    if n > numba.config.NUMBA_NUM_THREADS or n > available_cpus():
        pytest.skip(f"{n} threads requested, NUMBA_NUM_THREADS={numba.config.NUMBA_NUM_THREADS}, "
                    f"{available_cpus()} CPU(s)")
    default = numba.get_num_threads()
    numba.set_num_threads(n)
    yield n
    numba.set_num_threads(default)


_MODELS = {}


@pytest.fixture(scope="session")
def solid_model():
    """``solid_model(material_name)`` -> SolidModel of the 100k-hex8 box, built once per session."""
    default = numba.get_num_threads()
    try:
        tiny = m13.generate.box((0, 0, 0), (1, 1, 1), (2, 2, 2), "hexahedron")
        for threads in sorted({1, min(2, numba.config.NUMBA_NUM_THREADS)}):
            numba.set_num_threads(threads)
            for name in ("neo_hooke", "saint_venant_kirchhoff"):
                SolidModel(tiny, material(name, 1.0, 0.3)).evaluate(np.zeros(3 * tiny.n_nodes))
    finally:
        numba.set_num_threads(default)

    def get(name):
        if name not in _MODELS:
            mesh = m13.generate.box((0, 0, 0), (1, 1, 1), CELLS, "hexahedron")
            t = time.perf_counter()
            model = SolidModel(mesh, material(name, 100.0, 0.3))
            _MODELS[name] = (model, time.perf_counter() - t)
        return _MODELS[name]
    return get


@pytest.mark.parametrize("variant,name,tangent", VARIANTS, ids=[v[0].replace(", ", "-").replace(" ", "")
                                                                 for v in VARIANTS])
def test_solid_evaluate(benchmark, solid_model, solid_threads, variant, name, tangent):
    model, setup_s = solid_model(name)
    u = 1e-3 * np.random.default_rng(0).uniform(-1.0, 1.0, model.n_dofs)
    times, cpu = [], []

    def run():
        t, c = time.perf_counter(), time.process_time()
        f, K = model.evaluate(u, tangent=tangent)
        times.append(time.perf_counter() - t)
        cpu.append(time.process_time() - c)
        return f, K

    benchmark.group = f"SolidModel.evaluate, {model.mesh.n_elements} hex8"
    f, K = benchmark.pedantic(run, rounds=ROUNDS, warmup_rounds=1, iterations=1)
    assert np.isfinite(f).all() and (K is not None) == tangent
    timed = times[-ROUNDS:]
    stats = benchmark.stats.stats if benchmark.stats is not None else None
    median = stats.median if stats is not None else statistics.median(timed)
    best = stats.min if stats is not None else min(timed)
    n_el = model.mesh.n_elements
    record = {
        "variant": variant, "threads": solid_threads, "n_elements": n_el, "n_dofs": model.n_dofs,
        "nnz": int(K.nnz) if K is not None else None, "n_colours": model.n_colours,
        "median_s": median, "min_s": best,
        # CPU seconds of the process (all threads): on a loaded machine the wall time also
        # counts the time the threads wait for a core
        "cpu_median_s": statistics.median(cpu[-ROUNDS:]), "cpu_min_s": min(cpu[-ROUNDS:]), "elements_per_s": n_el / median,
        "elements_per_s_per_thread": n_el / median / solid_threads, "setup_s": setup_s,
        "target_s_one_core": TARGET_S if tangent else None,
    }
    benchmark.extra_info.update(record)
    RECORDS.setdefault(variant, {})[solid_threads] = record
    RESULTS_FILE.parent.mkdir(parents=True, exist_ok=True)
    RESULTS_FILE.write_text(json.dumps({"mesh": {"box_cells": list(CELLS), "element": "hexahedron"},
                                        "target_s_one_core": TARGET_S, "cpus_available": available_cpus(),
                                        "records": RECORDS}, indent=2) + "\n")
