"""Cost per Newton iteration of the rotational coupling on the PETSc backend, against without it.

    mpiexec -n N python benchmarks/distributed_rotational_cost.py [--size 32x64] [--rounds 3]

The scene of ``benchmarks/rotational_coupling.py`` (a block of C × 3 × 3 hex8 cells clamped at
x = 0 with a steel ``simo_reissner`` fibre of E elements on its axis, twisted at its free end;
``--size CxE``), nonlinear, one load step, MUMPS (``solver = "direct"``), ``backend = "petsc"``,
METIS partition, in three variants: ``none`` (no rotational coupling, a rotation support at the
fibre's start), ``penalty`` and ``lagrange`` (``coupling.rotational``, polar triad, line3). Each
round solves the three in turn in the same MPI job (so the machine's load of the moment is shared
by the three) and takes, per variant, the solve stage's CPU seconds per Newton iteration (the
largest over the ranks: ``result.distributed["cpu"]``, each rank's own clock up to the stage's
barrier; Open MPI's waiting ranks poll, so it includes waiting) and the wall seconds per Newton
iteration, counting every Newton iteration made (one linear solve each: those of a load step that
did not converge and was cut too). Rank 0 prints one JSON line per variant with the medians over
the rounds of these and of their ratios to ``none`` in the same round, the Newton iterations of
the converged steps (``newton``) and all of them (``iterations``), the unknowns and the load
average (``os.getloadavg``) at the end.
"""
import argparse
import json
import os
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))     # measure this checkout's package
sys.path.insert(0, str(Path(__file__).resolve().parent))

from mortar1d3d.distributed.petsc import petsc  # noqa: E402
from mortar1d3d.distributed.solve import solve_distributed  # noqa: E402

from rotational_coupling import VARIANTS, scene  # noqa: E402


def run(cells, elements, variant, comm):
    sc = scene(cells, elements, variant)
    sc.analysis = {**sc.analysis, "steps": 1, "backend": "petsc"}
    result = solve_distributed(sc, comm=comm)
    if comm.getRank() != 0:
        return None
    info = result.distributed
    # every Newton iteration made, those of a step that was cut and repeated too: one linear solve each
    iterations = info["linear_solves"]["solves"]
    cpu = max(c["solve"] for c in info["cpu"])
    return {"newton": [s.iterations for s in result.steps], "iterations": iterations, "unknowns": info["unknowns"],
            "cpu": cpu / iterations, "wall": info["timings"]["solve"] / iterations}


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--size", default="32x64", help="solid cells along the fibre x fibre elements")
    parser.add_argument("--rounds", type=int, default=3)
    args = parser.parse_args()
    comm = petsc().COMM_WORLD
    cells, elements = (int(v) for v in args.size.split("x"))
    for v in VARIANTS:
        run(cells, elements, v, comm)                      # warm-up: compilation, caches
    rounds = []
    for _ in range(args.rounds):
        rounds.append({v: run(cells, elements, v, comm) for v in VARIANTS})
    if comm.getRank() != 0:
        return
    for v in VARIANTS:
        out = {"ranks": comm.getSize(), "size": args.size, "variant": v, "unknowns": rounds[0][v]["unknowns"],
               "newton": rounds[0][v]["newton"], "iterations": rounds[0][v]["iterations"], "rounds": args.rounds}
        for key in ("cpu", "wall"):
            out[f"{key}_per_iteration"] = float(np.median([r[v][key] for r in rounds]))
            out[f"{key}_ratio_to_none"] = float(np.median([r[v][key] / r["none"][key] for r in rounds]))
        out["load"] = os.getloadavg()[0]
        print(json.dumps(out), flush=True)


if __name__ == "__main__":
    main()
