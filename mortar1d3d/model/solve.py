"""``solve``: a scene through the pipeline, one way.

    Scene ─ build ─▶ meshes, sets, DOF map ─ Model ─▶ physics ─ solvers.newton ─▶ z ─ Result ─▶ writers

:func:`~.build.build` makes the meshes, named sets and DOF map; :class:`~.model.Model` adds the
physics and checks the supports (:meth:`~.model.Model.prepare`); :mod:`mortar1d3d.solvers.newton`
solves the system (one linear step, or load steps of Newton iterations); the
:class:`~mortar1d3d.result.Result` holds the fields and writes them (:mod:`mortar1d3d.io.vtu`).
"""
import time

import numpy as np

from .._config import announce_compilation
from ..result import Result
from ..solvers.newton import solve_linear_step, solve_load_steps
from .build import as_scene, build
from .checks import check_linear_displacements
from .model import Model


def _print_step(record, index, _n):
    res = record.residuals[-1] if record.residuals else 0.0
    print(f"  step {index:4d}  load factor {record.load_factor:8.4f}  iterations {record.iterations:3d}  "
          f"residual {res:9.3e}" + (f"  (after {record.cuts} cut(s))" if record.cuts else "")
          + f"  {record.time:6.2f} s" + "".join(f"; {note}" for note in record.notes), flush=True)


def solve(scene, *, progress=False, parallel_output=None):
    """Run a scene: assemble what it needs, solve, return a :class:`~mortar1d3d.result.Result`.

    Parameters
    ----------
    scene : Scene or path to a TOML scene file
    progress : bool or callable
        True prints one line per load step; a callable gets ``(StepRecord, step_index, None)``.

    With ``analysis.backend = "petsc"`` the scene is assembled and solved on PETSc over the MPI
    ranks (:func:`mortar1d3d.distributed.solve.solve_distributed`): rank 0 gets the Result, the
    other ranks None; ``parallel_output`` (a directory, distributed runs only) has every rank
    write its own elements as ``.vtu`` pieces joined by ``.pvtu`` files and ``result.pvd``.

    Raises
    ------
    MissingPackageError
        ``analysis.backend = "petsc"`` without the ``mpi`` extra (names the missing package).
    SceneError
        Invalid scene, empty sets, or rigid-body motions not fixed (before any solve).
    ConvergenceError
        Newton's method gave up (message says where and what to try).

    Warns
    -----
    LargeDeformationWarning
        Linear kinematics, and a body moved by more than LINEAR_DISPLACEMENT_LIMIT of its size.
    """
    start = time.perf_counter()
    scene = as_scene(scene)
    if getattr(scene, "analysis", {}).get("backend") == "petsc":
        # distributed (docs/distributed.md): needs the mpi extra, names the missing package otherwise
        from ..distributed import require
        for name in ("mpi4py", "petsc4py", "pymetis"):
            require(name)
        from ..distributed.solve import solve_distributed
        return solve_distributed(scene, progress=progress, parallel_output=parallel_output)
    if parallel_output is not None:
        raise ValueError("parallel_output: per-rank output is written by distributed runs (analysis.backend = "
                         "\"petsc\"); a serial Result writes with Result.write")
    model = Model(build(scene))
    announce_compilation()      # after the scene's checks: an invalid scene fails without it
    model.prepare()
    callback = _print_step if progress is True else (progress or None)
    z0 = np.zeros(model.n_unknowns)
    if model.linear:
        model.counts["solver.linear"] += 1
        z, record, model.last_residual = solve_linear_step(model, z0, started=start)
        records, history = [record], [z.copy()]
        check_linear_displacements(model, z)
        if callback:
            callback(record, 1, 1)
    else:
        a = model.scene.analysis
        model.counts["solver.newton"] += 1
        z, records, history = solve_load_steps(model, z0, a["steps"], rtol=a["rtol"], increment_rtol=a["rtol"],
                                               max_iterations=a["max_iterations"], max_cuts=a["max_cuts"],
                                               progress=callback)
    return Result(model, z, records, history, wall_time=time.perf_counter() - start)
