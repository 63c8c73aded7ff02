"""The penalty preconditioners of the PETSc backend on beams with rotations (issue 23).

The rebar cantilever (examples/scenes/rebar_cantilever.toml) with a ``simo_reissner`` rebar, its
start held in position and rotation, at a penalty of 100 E (as the tests), linear (``solver =
"amg"``: CG) and nonlinear in 2 load steps (``solver = "auto"``: GMRES, the tangent is not
symmetric). For each preconditioner it prints the Krylov iterations summed over the run's linear
solves, the Newton iterations per step, and the largest relative difference of the steps' states
from the serial direct run (displacements and rotation vectors apart):

* ``aux``: the auxiliary-space sweep (the default; its beam block holds the rotation unknowns,
  block Jacobi with a sparse LU per rank over blocks of whole beams: exact);
* ``aux-rank``: the same over the blocks of each rank's owned beam unknowns
  (``-mortar_beam_blocks rank``, the sweep before: inexact for a beam the partition cuts);
* ``aux-mumps``: the same with MUMPS on the whole beam block (``-mortar_beam_pc_type lu
  -mortar_beam_pc_factor_mat_solver_type mumps``);
* ``gamg``: GAMG on the whole system (``-mortar_penalty_pc gamg``).

Run it under MPI (it prints JSON lines from rank 0; the partition is METIS)::

    mpiexec -n 1 python benchmarks/distributed_rotations.py
    mpiexec -n 3 python benchmarks/distributed_rotations.py
"""
import json
import tomllib
from pathlib import Path

import numpy as np

import mortar1d3d as m13
from mortar1d3d.distributed.petsc import petsc
from mortar1d3d.distributed.solve import solve_distributed

SCENE = Path(__file__).resolve().parents[1] / "examples" / "scenes" / "rebar_cantilever.toml"
PRECONDITIONERS = {
    "aux": {"mortar_penalty_pc": "aux"},
    "aux-rank": {"mortar_penalty_pc": "aux", "mortar_beam_blocks": "rank"},
    "aux-mumps": {"mortar_penalty_pc": "aux", "mortar_beam_pc_type": "lu",
                  "mortar_beam_pc_factor_mat_solver_type": "mumps"},
    "gamg": {"mortar_penalty_pc": "gamg"},
}


def rebar(kinematics, **analysis):
    data = tomllib.loads(SCENE.read_text())
    data["coupling"]["penalty"] = 3e12
    data["beams"][0].update(model="simo_reissner", section={"E": 200e9, "nu": 0.3, "radius": 0.01})
    data["dirichlet"][1]["rotation"] = [0.0, 0.0, 0.0]
    data["analysis"] = {"kinematics": kinematics, "steps": 2, "solver": "direct", **analysis}
    return m13.Scene.from_dict(data)


def differences(serial, result):
    """Largest relative difference over the steps, of the displacements and of the rotation vectors."""
    model = serial.model
    rotation = np.zeros(len(serial.z), dtype=bool)
    for g in model.groups:
        rotation[g.rotations.slice] = True
    out = {}
    for name, mask in (("positions", ~rotation), ("rotations", rotation)):
        out[name] = float(max(np.linalg.norm(h[mask] - h0[mask]) / np.linalg.norm(h0[mask])
                              for h, h0 in zip(result.history, serial.history)))
    return out


def main():
    PETSc = petsc()
    comm = PETSc.COMM_WORLD
    options = PETSc.Options()
    for kinematics, solver in (("linear", "amg"), ("nonlinear", "auto")):
        serial = m13.solve(rebar(kinematics))
        for name, settings in PRECONDITIONERS.items():
            for key, value in settings.items():
                options[key] = value
            try:
                result = solve_distributed(rebar(kinematics, solver=solver, backend="petsc"), comm=comm)
            finally:
                for key in settings:
                    del options[key]
            if comm.getRank() == 0:
                info = result.distributed
                print(json.dumps({"ranks": comm.getSize(), "kinematics": kinematics, "preconditioner": name,
                                  "ksp": info["ksp"], "krylov_iterations": info["linear_solves"]["iterations"],
                                  "linear_solves": info["linear_solves"]["solves"],
                                  "newton": [s.iterations for s in result.steps],
                                  "serial_newton": [s.iterations for s in serial.steps],
                                  **differences(serial, result)}))


if __name__ == "__main__":
    main()
