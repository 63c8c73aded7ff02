"""Linear solves of a nonlinear analysis: Krylov tolerance and preconditioner reuse.

    python benchmarks/newton_solve.py [--n 10] [--fibres 300] [--elements 10] [--steps 3]
                                      [--enforcement penalty lagrange] [--variants before tolerance after]

``fibre_cube(n, fibres, elements)`` in a Saint Venant–Kirchhoff cube (E = 1e9, ν = 0.3) clamped at
x = 0, bent by a traction of 2e7 on x = 1 in ``--steps`` load steps, nonlinear kinematics, straight
torsion-free fibres E = 2e11, radius 1 cm, mortar coupling (line2 multipliers), solved by
``mortar1d3d.solve`` with the iterative solver (``amg``: auxiliary-space CG for penalty; ``block``
for Lagrange multipliers). Variants, all in one process:

- ``before``: every Newton iteration's linear solve asked for ``LINEAR_RTOL_FACTOR · rtol``, a new
  preconditioner per solve, block-diagonal MINRES for Lagrange (the code before issue 22's item 3);
- ``tolerance``: the linear tolerance from the Newton target (``LINEAR_RTOL_FACTOR · rtol ·
  ‖r_0‖ / ‖r_k‖``), a new preconditioner per solve, GMRES;
- ``after``: that tolerance and the preconditioner kept across Newton iterations while it serves
  (:class:`~mortar1d3d.solvers.reuse.ReusedPreconditioner`), GMRES.

One row per run: Newton iterations (= linear solves), preconditioner set-ups, Krylov iterations,
set-up and solve seconds summed over the linear solves, process CPU and wall seconds of the whole
``solve``, the largest difference of the displacements to the first variant's (relative to the
largest displacement), and the 1-minute load average. CPU seconds are the figure to compare on a
shared machine.
"""
import argparse
import functools
import os
import sys
import time
import warnings
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))     # measure this checkout's package

import mortar1d3d as m13  # noqa: E402
import mortar1d3d.solvers.linear as linear  # noqa: E402
from mortar1d3d.model import Model  # noqa: E402
from mortar1d3d.solvers.newton import LINEAR_RTOL_FACTOR  # noqa: E402

SOLVE_SADDLE = linear.solve_saddle
RECORD = []


def scene(n, fibres, elements, steps, enforcement):
    beams, solid = m13.generate.fibre_cube(n, fibres, elements)
    return m13.Scene(solid={"mesh": solid, "material": {"model": "saint_venant_kirchhoff", "E": 1e9, "nu": 0.3}},
                     beams=[{"mesh": beams, "section": {"E": 2e11, "radius": 0.01}}],
                     coupling={"enforcement": enforcement, "lm": "line2"},
                     dirichlet=[{"on": "solid:x_min"}],
                     load=[{"type": "traction", "on": "solid:x_max", "value": [0, 0, -2e7]}],
                     analysis={"kinematics": "nonlinear", "steps": steps,
                               "solver": "block" if enforcement == "lagrange" else "amg"})


def run(variant, options):
    """``solve`` of one variant: (result, totals)."""
    RECORD.clear()
    original = Model.solve_linear
    before = variant == "before"
    Model.reuse_preconditioner = variant == "after"
    linear.solve_saddle = functools.partial(SOLVE_SADDLE, krylov="minres") if before else SOLVE_SADDLE

    def recording(model, A, b, x0=None, rtol=None):
        if before:          # the fixed target of every Newton iteration before
            rtol = LINEAR_RTOL_FACTOR * model.scene.analysis["rtol"]
        x = original(model, A, b, x0, rtol)
        RECORD.append(model.last_linear_info)
        return x
    Model.solve_linear = recording
    try:
        cpu, wall = time.process_time(), time.perf_counter()
        result = m13.solve(scene(**options))
        cpu, wall = time.process_time() - cpu, time.perf_counter() - wall
    finally:
        Model.solve_linear = original
        Model.reuse_preconditioner = True
        linear.solve_saddle = SOLVE_SADDLE
    totals = dict(solves=len(RECORD), builds=sum(not i.get("reused", False) for i in RECORD),
                  iterations=sum(i["iterations"] for i in RECORD), setup=sum(i["setup_time"] for i in RECORD),
                  solve=sum(i["solve_time"] for i in RECORD), cpu=cpu, wall=wall, load=os.getloadavg()[0])
    return result, totals


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--n", type=int, default=10)
    parser.add_argument("--fibres", type=int, default=300)
    parser.add_argument("--elements", type=int, default=10)
    parser.add_argument("--steps", type=int, default=3)
    parser.add_argument("--enforcement", nargs="+", default=["penalty", "lagrange"])
    parser.add_argument("--variants", nargs="+", default=["before", "tolerance", "after"],
                        choices=["before", "tolerance", "after"])
    args = parser.parse_args(argv)
    warnings.simplefilter("ignore")
    print(f"fibre_cube({args.n}, {args.fibres}, {args.elements}), nonlinear, {args.steps} steps; "
          f"load average {os.getloadavg()[0]:.2f}")
    print(f"{'enforcement':<12}{'variant':<10}{'newton':>7}{'set-ups':>8}{'its':>6}{'setup s':>9}{'solve s':>9}"
          f"{'cpu s':>8}{'wall s':>8}{'cpu/bef':>8}{'diff':>9}{'load':>6}")
    for enforcement in args.enforcement:      # compile and import everything before timing
        run("after", dict(n=2, fibres=4, elements=2, steps=1, enforcement=enforcement))
    for enforcement in args.enforcement:
        first = base = None
        for variant in args.variants:
            result, t = run(variant, dict(n=args.n, fibres=args.fibres, elements=args.elements, steps=args.steps,
                                          enforcement=enforcement))
            u = result.solid_displacement
            first = u if first is None else first
            base = t if base is None else base
            print(f"{enforcement:<12}{variant:<10}{t['solves']:>7}{t['builds']:>8}{t['iterations']:>6}"
                  f"{t['setup']:>9.2f}{t['solve']:>9.2f}{t['cpu']:>8.2f}{t['wall']:>8.2f}"
                  f"{t['cpu'] / base['cpu']:>8.2f}{np.abs(u - first).max() / np.abs(first).max():>9.1e}"
                  f"{t['load']:>6.1f}", flush=True)


if __name__ == "__main__":
    main()
