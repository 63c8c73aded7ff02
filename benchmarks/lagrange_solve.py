"""Lagrange multipliers against penalty on the same scene, every linear-solver path.

    python benchmarks/lagrange_solve.py [--cases 15:155 20:1000] [--elements 10] [--rtol 1e-8]
                                        [--direct 15] [--repeat 2] [--krylov minres gmres]

The scene of the 4C-style fibre cube: ``fibre_cube(n, fibres, elements)`` (hex8 solid E = 1e9,
ν = 0.3, clamped at x = 0, a traction on x = 1; straight torsion-free fibres E = 2e11, radius
1 cm; mortar coupling with line2 multipliers), linear, once with ``enforcement = "penalty"``
(default ε = 1e3 E) and once with ``"lagrange"``. Both reduced systems (Dirichlet DOFs
eliminated) come from the model as ``Model.solve_linear`` sees them. Solved with:

- ``penalty aux``: CG + the auxiliary-space preconditioner (what ``solver = "amg"``/``"auto"``
  runs), the control every Lagrange row is divided by;
- ``penalty direct`` and ``lagrange direct`` (``--direct n``: SuperLU; the saddle point
  scaled by γ);
- ``lagrange <krylov>``: the block solver (``solver = "block"``) with each Krylov method of
  ``--krylov`` (``minres``: the block-diagonal preconditioner; ``gmres``: the block-triangular
  one, right-preconditioned GMRES).

One row per run: unknowns (primal + multipliers), set-up and solve wall seconds, process CPU
seconds of set-up + solve, iterations, the true relative residual, ``|u - u_dir|`` (the
displacements' difference to the direct Lagrange solution where that ran, relative to its
largest entry; for penalty rows this includes the penalty's own error), the ratios of wall and
CPU seconds and iterations to ``penalty aux`` of the same case in the same run, the peak
resident memory so far, and the 1-minute load average (wall seconds on a shared machine are
only comparable at the same load; CPU seconds are the steadier figure). ``--repeat k`` keeps the
run of least CPU time of k.
"""
import argparse
import os
import sys
import time
import warnings
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))     # measure this checkout's package

import mortar1d3d as m13  # noqa: E402
from mortar1d3d.model import Model  # noqa: E402
from mortar1d3d.solvers.linear import solve_linear, solve_saddle  # noqa: E402
from _record import record  # noqa: E402
from penalty_solve import peak_memory_gb  # noqa: E402


def scene(n, fibres, elements, enforcement):
    beams, solid = m13.generate.fibre_cube(n, fibres, elements)
    return m13.Scene(solid={"mesh": solid, "material": {"model": "linear_elastic", "E": 1e9, "nu": 0.3}},
                     beams=[{"mesh": beams, "section": {"E": 2e11, "radius": 0.01}}],
                     coupling={"enforcement": enforcement, "lm": "line2"},
                     dirichlet=[{"on": "solid:x_min"}],
                     load=[{"type": "traction", "on": "solid:x_max", "value": [0, 0, -1e6]}],
                     analysis={"kinematics": "linear", "solver": "auto"})


def system(n, fibres, elements, enforcement):
    """(model, A, b, assembly seconds): the reduced linear system of the first solve."""
    start = time.perf_counter()
    model = Model(scene(n, fibres, elements, enforcement)).prepare()
    r, K = model.residual(np.zeros(model.n_unknowns), 1.0)
    free = model.free
    return model, K[free][:, free].tocsr(), -r[free], time.perf_counter() - start


def saddle_parts(model, A, b):
    """What ``Model.solve_linear`` hands to ``solve_saddle``: (K, B, kappa, b, c, options)."""
    free = model.free
    primal = free < model.n_displacement_dofs
    p, q = np.flatnonzero(primal), np.flatnonzero(~primal)
    K, B = A[p][:, p].tocsr(), A[q][:, p].tocsr()
    kappa = np.concatenate([np.repeat(g.operators.kappa[g.coupling.coupled], 3) for g in model.groups])
    solid = np.flatnonzero(free[p] < 3 * model.n_solid_nodes)
    beam = np.flatnonzero(free[p] >= 3 * model.n_solid_nodes)
    options = dict(solid=solid, beam=beam, near_nullspace=model.rigid_body_modes()[free[p]], block_size=3,
                   dependent=model._dependent_multipliers(B, beam),
                   prolongation=model._follow_split()["prolongation"])
    return K, B, kappa, b[p], b[q], options, p


def timed(solve):
    cpu = time.process_time()
    u, info = solve()
    info["cpu_time"] = time.process_time() - cpu
    info["load"] = os.getloadavg()[0]
    info["memory"] = peak_memory_gb()
    return u, info


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--cases", nargs="+", default=["15:155"], help="n:fibres")
    parser.add_argument("--elements", type=int, default=10, help="beam elements per fibre")
    parser.add_argument("--rtol", type=float, default=1e-8)
    parser.add_argument("--direct", type=int, nargs="*", default=[15], help="sizes n to also solve directly")
    parser.add_argument("--krylov", nargs="+", default=["minres", "gmres"], choices=["minres", "gmres"])
    parser.add_argument("--repeat", type=int, default=1)
    args = parser.parse_args(argv)
    warnings.simplefilter("ignore")
    print(f"fibre_cube(n, fibres, {args.elements}), line2 multipliers, rtol {args.rtol:g}, "
          f"load average {os.getloadavg()[0]:.2f}")
    print(f"{'case':>8} {'path':>16} {'unknowns':>9} {'setup s':>8} {'solve s':>8} {'cpu s':>7} {'its':>5} "
          f"{'rel. res':>8} {'|u-u_dir|':>9} {'t/pen':>6} {'cpu/pen':>7} {'it/pen':>6} {'mem GB':>6} {'load':>5}")
    for case in args.cases:
        n, fibres = (int(v) for v in case.split(":"))
        runs = []
        model, A, b, _ = system(n, fibres, args.elements, "penalty")
        split = model._follow_split()
        R = model.rigid_body_modes()[model.free]
        pen = dict(A=A, b=b)
        runs.append(("penalty aux", A.shape[0], lambda: solve_linear(
            pen["A"], pen["b"], "aux", rtol=args.rtol, maxiter=2000, near_nullspace=R, block_size=3, **split)))
        if n in args.direct:
            runs.append(("penalty direct", A.shape[0], lambda: solve_linear(pen["A"], pen["b"], "direct")))
        model_l, A_l, b_l, _ = system(n, fibres, args.elements, "lagrange")
        K, B, kappa, bp, c, options, _ = saddle_parts(model_l, A_l, b_l)
        size = A_l.shape[0]

        def lagrange(method, **extra):
            def run():
                u, _, info = solve_saddle(K, B, kappa, bp, c, method, rtol=args.rtol, maxiter=2000,
                                          **options, **extra)
                return u, info
            return run
        if n in args.direct:
            runs.append(("lagrange direct", size, lagrange("direct")))
        for krylov in args.krylov:
            runs.append((f"lagrange {krylov}", size, lagrange("block", krylov=krylov)))
        results = {}
        for name, unknowns, solve in runs:
            best = None
            for _ in range(args.repeat):
                out = timed(solve)
                if best is None or out[1]["cpu_time"] < best[1]["cpu_time"]:
                    best = out
            results[name] = (unknowns,) + best
        n_primal = K.shape[0]
        reference = results.get("lagrange direct", (None, None))[1]
        base = results["penalty aux"][2]
        base_total = base["setup_time"] + base["solve_time"]
        for name, (unknowns, u, info) in results.items():
            diff = "" if reference is None or name == "lagrange direct" else \
                f"{np.abs(u[:n_primal] - reference).max() / np.abs(reference).max():9.1e}"
            total = info["setup_time"] + info["solve_time"]
            print(f"{case:>8} {name:>16} {unknowns:9d} {info['setup_time']:8.2f} {info['solve_time']:8.2f} "
                  f"{info['cpu_time']:7.2f} {info['iterations']:5d} {info['residual']:8.1e} {diff:>9} "
                  f"{total / base_total:6.2f} {info['cpu_time'] / base['cpu_time']:7.2f} "
                  f"{info['iterations'] / max(base['iterations'], 1):6.2f} {info['memory']:6.2f} "
                  f"{info['load']:5.1f}", flush=True)
            record("lagrange_solve", case=case, path=name, unknowns=int(unknowns), cpu_s=info["cpu_time"],
                   iterations=int(info["iterations"]), cpu_per_penalty=info["cpu_time"] / base["cpu_time"],
                   load=info["load"])


if __name__ == "__main__":
    main()
