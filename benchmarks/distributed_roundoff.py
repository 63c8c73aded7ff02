"""Why the distributed tests compare the rebar cantilever at a penalty of 100 E (issue 23).

At the scene file's penalty (1000 E) the distributed Newton run and the serial one differ by about
1.5e-10 (relative, largest over the load steps). This script separates the possible causes on the
rebar cantilever (examples/scenes/rebar_cantilever.toml, nonlinear, 4 load steps, direct solvers):

* the Newton stopping point: both runs with ``analysis.rtol`` 1e-8 (the scene's) and 1e-12;
* the linear solve: MUMPS followed by three steps of iterative refinement (PETSc Richardson with
  the LU as preconditioner, on the true residual) instead of one LU solve;
* the conditioning itself: two *serial* runs that differ only in the ordering and pivoting of
  SuperLU (the library's symmetric mode against COLAMD with partial pivoting).

Run it under MPI (it prints from rank 0; the serial runs are repeated on every rank)::

    mpiexec -n 1 python benchmarks/distributed_roundoff.py
    mpiexec -n 2 python benchmarks/distributed_roundoff.py
    mpiexec -n 2 python benchmarks/distributed_roundoff.py --scene examples/scenes/reinforced_pipe.toml
"""
import json
import tomllib
from pathlib import Path

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

import mortar1d3d as m13
import mortar1d3d.solvers.linear as serial_linear
from mortar1d3d.distributed.petsc import petsc
from mortar1d3d.distributed.solve import solve_distributed

SCENE = Path(__file__).resolve().parents[1] / "examples" / "scenes" / "rebar_cantilever.toml"


def scene_at(path, penalty, **analysis):
    """The scene file ``path`` (the rebar cantilever, or ``--scene``) at the given penalty, direct
    solvers; a nonlinear scene in 4 load steps."""
    data = tomllib.loads(path.read_text())
    data["coupling"]["penalty"] = penalty
    if data.get("analysis", {}).get("kinematics", "linear") == "nonlinear":
        analysis = {"steps": 4, **analysis}
    else:
        analysis.pop("rtol", None)
    data.setdefault("analysis", {}).update({"solver": "direct", **analysis})
    return m13.Scene.from_dict(data, base_dir=path.parent)


def difference(a, b):
    """Largest relative 2-norm difference of the converged states over the load steps."""
    return float(max(np.linalg.norm(x - y) / np.linalg.norm(y) for x, y in zip(a.history, b.history)))


def refined(run):
    """``run()`` with every PETSc solve followed by iterative refinement (3 Richardson steps)."""
    options = petsc().Options()
    settings = {"ksp_type": "richardson", "ksp_convergence_test": "skip", "ksp_max_it": 3,
                "ksp_norm_type": "unpreconditioned"}
    for key, value in settings.items():
        options[key] = value
    try:
        return run()
    finally:
        for key in settings:
            del options[key]


def colamd(run):
    """``run()`` with the serial direct solver factorising by COLAMD with partial pivoting."""
    original = serial_linear.factorize
    serial_linear.factorize = lambda A, symmetric_positive, saddle=False: spla.splu(sp.csc_matrix(A),
                                                                                  permc_spec="COLAMD")
    try:
        return run()
    finally:
        serial_linear.factorize = original


def main(argv=None):
    import argparse
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--scene", type=Path, default=SCENE,
                        help="a scene file with a solid and penalty coupling (default: the rebar cantilever)")
    path = parser.parse_args(argv).scene.resolve()
    E = tomllib.loads(path.read_text())["solid"]["material"]["E"]
    comm = petsc().COMM_WORLD
    rows = []
    for factor in (100.0, 1000.0):
        penalty = factor * E
        row = {"ranks": comm.getSize(), "penalty_over_E": factor}
        for rtol in (1e-8, 1e-12):
            serial = m13.solve(scene_at(path, penalty, rtol=rtol))
            dist = solve_distributed(scene_at(path, penalty, rtol=rtol, backend="petsc"), comm=comm)
            if dist is not None:
                row[f"petsc_vs_serial_rtol_{rtol:g}"] = difference(dist, serial)
                row[f"iterations_rtol_{rtol:g}"] = [[s.iterations for s in r.steps] for r in (serial, dist)]
                row[f"final_residual_rtol_{rtol:g}"] = max(s.residuals[-1] / s.residuals[0] for s in dist.steps)
        serial = m13.solve(scene_at(path, penalty))
        dist = refined(lambda: solve_distributed(scene_at(path, penalty, backend="petsc"), comm=comm))
        if dist is not None:
            row["petsc_refined_vs_serial"] = difference(dist, serial)
        row["serial_colamd_vs_serial"] = difference(colamd(lambda: m13.solve(scene_at(path, penalty))), serial)
        rows.append(row)
    if comm.getRank() == 0:
        for row in rows:
            print(json.dumps({k: (float(f"{v:.3g}") if isinstance(v, float) else v) for k, v in row.items()}))


if __name__ == "__main__":
    main()
