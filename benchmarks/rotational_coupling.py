"""Cost of one Newton iteration of a coupled Simo–Reissner scene with and without rotational coupling.

    python benchmarks/rotational_coupling.py [--sizes 4x8 8x16 16x32] [--rounds 5] [--threads 1]

Scene (per size ``CxE``): a block [0, 1] × [-0.1, 0.1]² of C × 3 × 3 hex8 cells, clamped at x = 0,
with a steel ``simo_reissner`` fibre of E elements on its axis (penalty positional coupling,
segment-based integration), twisted by forces on two edges of its free end (the scene of
``examples/scenes/twisted_fibre.toml``). Three variants: ``none`` (no rotational coupling, a
rotation support at the fibre's start), ``penalty`` and ``lagrange`` (``coupling.rotational``,
polar triad, line3). Each is solved (one load step) and then timed at its converged state:

- ``iteration``: one Newton iteration, ``Model.residual`` with the tangent plus the reduced
  sparse-LU solve;
- ``coupling``: the rotational coupling's own part, residual and tangent
  (``RotationalCoupling.evaluate``, or ``constraint`` for Lagrange), also per integration point.

Every round measures the 1-thread control loop of ``benchmarks/control.py`` first and each time
is divided by it ("per control": the machine's speed of the moment cancels); the script prints
medians over the rounds of those ratios, the control's median in seconds, the ratio of the
iteration to that of ``none``, and the load average. The Numba threads are set to ``--threads``.
"""
import argparse
import os
import sys
import time
from pathlib import Path

import numba
import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))     # measure this checkout's package

import mortar1d3d as m13  # noqa: E402
from mortar1d3d.model import Model  # noqa: E402
from mortar1d3d.solvers.newton import solve_load_steps  # noqa: E402

from control import control_times  # noqa: E402

VARIANTS = ("none", "penalty", "lagrange")


def scene(cells, elements, variant):
    coupling = {} if variant == "none" else {"rotational": {"enforcement": variant}}
    dirichlet = [{"on": "solid:x_min"}] + ([{"on": "beam:0:start", "rotation": [0, 0, 0]}] if variant == "none"
                                           else [])
    edge = {z: {"inside": [[1, -0.1, z], [1, 0.1, z]]} for z in (-0.1, 0.1)}
    return m13.Scene(solid={"mesh": {"box": [[0, -0.1, -0.1], [1, 0.1, 0.1]], "cells": [cells, 3, 3]},
                            "material": {"model": "saint_venant_kirchhoff", "E": 50e6, "nu": 0.3}},
                     beams=[{"curve": {"line": [[0, 0, 0], [1, 0, 0]]}, "elements": elements, "model": "simo_reissner",
                             "section": {"E": 200e9, "nu": 0.3, "radius": 0.015}}],
                     coupling=coupling, dirichlet=dirichlet,
                     load=[{"type": "point", "on": edge[0.1], "value": [0, -1500, 0]},
                           {"type": "point", "on": edge[-0.1], "value": [0, 1500, 0]}],
                     analysis={"kinematics": "nonlinear", "solver": "direct"})


def prepared(cells, elements, variant):
    m = Model(scene(cells, elements, variant)).prepare()
    z, _, _ = solve_load_steps(m, np.zeros(m.n_unknowns), 1)
    return m, z


def timed(fn):
    start = time.perf_counter()
    fn()
    return time.perf_counter() - start


def iteration(m, z):
    r, K = m.residual(z, 1.0)
    m.solve_linear(K[m.free][:, m.free], -r[m.free])


def coupling_part(m, z):
    g = m.groups[0]
    rc = g.rotational
    u, psi = z[:3 * m.n_solid_nodes], z[g.rotations.slice].reshape(-1, 3)
    if rc.enforcement == "lagrange":
        n = m.n_displacement_dofs
        return lambda: rc.constraint(u, psi, z[n: n + rc.n_multipliers], tangent=True)
    return lambda: rc.evaluate(u, psi, tangent=True)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", nargs="+", default=["4x8", "8x16", "16x32"],
                        help="solid cells along the fibre x fibre elements")
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--threads", type=int, default=1)
    args = parser.parse_args()
    numba.set_num_threads(args.threads)
    print(f"threads {numba.get_num_threads()}; times per control (the 1-thread control loop of the same round), "
          "medians over the rounds")
    print(f"{'size':>6} {'variant':>9} {'unknowns':>8} {'points':>6} {'iteration':>9} {'/none':>6} "
          f"{'coupling':>9} {'per point':>10} {'control s':>9} {'load':>5}")
    for size in args.sizes:
        cells, elements = (int(v) for v in size.split("x"))
        models = {v: prepared(cells, elements, v) for v in VARIANTS}
        calls = {v: (lambda m=m, z=z: iteration(m, z)) for v, (m, z) in models.items()}
        parts = {v: coupling_part(*models[v]) for v in VARIANTS if v != "none"}
        for fn in list(calls.values()) + list(parts.values()):
            fn()                                        # warm-up (compilation, caches, factorisation paths)
        ratios = {v: [] for v in VARIANTS}
        part_ratios = {v: [] for v in parts}
        controls = []
        for _ in range(args.rounds):
            control = control_times(threads=(1,))[1]
            controls.append(control)
            for v in VARIANTS:
                ratios[v].append(timed(calls[v]) / control)
                if v in parts:
                    part_ratios[v].append(timed(parts[v]) / control)
        base = float(np.median(ratios["none"]))
        for v in VARIANTS:
            m = models[v][0]
            rc = m.groups[0].rotational
            it = float(np.median(ratios[v]))
            line = f"{size:>6} {v:>9} {m.n_unknowns:8d} {rc.n_points if rc else 0:6d} {it:9.4f} {it / base:6.2f} "
            if v in parts:
                part = float(np.median(part_ratios[v]))
                line += f"{part:9.4f} {part / rc.n_points:10.2e} "
            else:
                line += f"{'-':>9} {'-':>10} "
            print(line + f"{float(np.median(controls)):9.3f} {os.getloadavg()[0]:5.2f}", flush=True)


if __name__ == "__main__":
    main()
