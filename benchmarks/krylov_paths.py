"""Every Krylov path of the linear solvers: iterations, status and seconds per case.

    .venv/bin/python benchmarks/krylov_paths.py [--cases tests penalty scenes] [--n 10 20] [--scene-n 20]

``tests``: the problems of tests/test_linear_solvers.py and tests/test_solver_paths.py that run CG,
MINRES or GMRES (the clamped hex8 box with a coupled spring chain, 3.9k and 12k unknowns: AMG-CG,
auxiliary-space CG at ε = 1e3 and 1e4 E, the block solver with each primal block; the rebar prism
and fibre_cube(4, 60, 8) through ``solve``; the ν = 0.4999 neo-Hooke block whose tangent breaks CG
down). ``penalty``: the auxiliary-space CG of benchmarks/penalty_solve.py for ``--n``.
``scenes``: the eight iterative runs of benchmarks/scene_solve.py on ``fibre_cube(--scene-n, 1000,
20)``. One row per case: the linear solves it made, their CG/MINRES iterations, statuses and the
largest residual, set-up and solve seconds (summed over its solves), and the notes of fallbacks.
"""
import argparse
import os
import sys
import time
import warnings
from collections import Counter
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))                       # measure this checkout's package
sys.path.insert(1, str(ROOT / "tests"))
sys.path.insert(2, str(ROOT / "benchmarks"))

import mortar1d3d as m13                            # noqa: E402
import mortar1d3d.solvers.linear as linear          # noqa: E402

RECORD = []


def _recording(function):
    def wrapper(*args, **kwargs):
        out = function(*args, **kwargs)
        RECORD.append(out[-1])
        return out
    return wrapper


linear.solve_linear = _recording(linear.solve_linear)     # Model.solve_linear imports them from here
linear.solve_saddle = _recording(linear.solve_saddle)


def tests_cases():
    import test_linear_solvers as tl
    import test_solver_paths as tp
    medium = tl.coupled_problem((16, 8, 8))
    fine = tl.coupled_problem((24, 12, 12))
    P = tl.follow_prolongation(medium)
    yield "box 3.9k amg eps=20", lambda: linear.solve_linear(tl.penalty_matrix(medium, 20.0), medium["b"], "amg",
                                                              near_nullspace=medium["R"])
    for factor in (1e3, 1e4):
        yield f"box 3.9k aux eps={factor:g}", lambda f=factor: linear.solve_linear(
            tl.penalty_matrix(medium, f), medium["b"], "aux", near_nullspace=medium["R"], solid=medium["solid"],
            beam=medium["beam"], prolongation=P)
    yield "box 3.9k plain amg eps=1e3", lambda: linear.solve_linear(
        tl.penalty_matrix(medium, 1e3), medium["b"], "amg", near_nullspace=medium["R"], maxiter=2000)
    for name, prob in (("3.9k", medium), ("12k", fine)):
        c = tl._constraint_rhs(prob)
        for primal in ("monolithic", "split"):
            yield f"box {name} block {primal}", lambda p=prob, c=c, q=primal: linear.solve_saddle(
                p["K"], p["B"], p["kappa"], p["b"], c, "block", solid=p["solid"], beam=p["beam"],
                near_nullspace=p["R"], primal=q)
    yield "prism 26x4x4 lagrange auto", lambda: m13.solve(tp.rebar_prism((26, 4, 4), "auto"))
    yield "cube(4,60,8) penalty amg", lambda: m13.solve(tp.fibre_cube_scene(4, 60, 8, "amg", "penalty"))
    yield "cube(4,60,8) lagrange block", lambda: m13.solve(tp.fibre_cube_scene(4, 60, 8, "block", "lagrange"))
    yield "cube(6,300,8) aux rtol 1e-12", lambda: m13.solve(_tight(tp.fibre_cube_scene(6, 300, 8, "auto")))
    yield "neo-Hooke 0.4999 amg (breakdown)", lambda: m13.solve(tp.triaxial_block("amg"))


def _tight(scene):
    scene.analysis["rtol"] = 1e-12
    return scene


def penalty_cases(sizes):
    import penalty_solve
    for n in sizes:
        def run(n=n):
            model, A, b, _ = penalty_solve.system(n, 1e3)
            return linear.solve_linear(A, b, rtol=1e-8, maxiter=2000, method="aux", block_size=3,
                                       near_nullspace=model.rigid_body_modes()[model.free], **model._follow_split())
        yield f"penalty_solve n={n} aux", run


def scene_cases(n):
    import scene_solve
    for enforcement in ("penalty", "lagrange"):
        for load in ("traction", "weight"):
            for rtol in (1e-8, 1e-12):
                solver = "block" if enforcement == "lagrange" else "amg"
                yield f"scene({n}) {enforcement} {load} {rtol:g}", lambda e=enforcement, l=load, r=rtol, s=solver: \
                    m13.solve(scene_solve.scene(n, 1000, 20, e, l, s, r))


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--cases", nargs="+", default=["tests", "penalty"], choices=["tests", "penalty", "scenes"])
    parser.add_argument("--n", type=int, nargs="+", default=[10, 20])
    parser.add_argument("--scene-n", type=int, default=20)
    args = parser.parse_args()
    print(f"load average {os.getloadavg()[0]:.2f}")
    print(f"{'case':<36}{'solves':>7}{'its':>7}  {'status':<22}{'residual':>9}{'setup s':>9}{'solve s':>9}"
          f"{'wall s':>8}  notes")
    cases = []
    if "tests" in args.cases:
        cases += list(tests_cases())
    if "penalty" in args.cases:
        cases += list(penalty_cases(args.n))
    if "scenes" in args.cases:
        cases += list(scene_cases(args.scene_n))
    for name, run in cases:
        RECORD.clear()
        start = time.perf_counter()
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                run()
            failure = ""
        except Exception as error:           # report and go on
            failure = f"{type(error).__name__}: {str(error)[:90]}"
        wall = time.perf_counter() - start
        iterative = [i for i in RECORD if i["method"] != "direct"]
        status = Counter(i.get("status", "converged") for i in iterative)
        notes = sorted({i["note"] for i in RECORD if "note" in i})
        print(f"{name:<36}{len(iterative):>7}{sum(i['iterations'] for i in iterative):>7}  "
              f"{','.join(f'{k}:{v}' for k, v in sorted(status.items())):<22}"
              f"{max((i['residual'] for i in iterative), default=0.0):>9.1e}"
              f"{sum(i['setup_time'] for i in iterative):>9.2f}{sum(i['solve_time'] for i in iterative):>9.2f}"
              f"{wall:>8.1f}  {failure or '; '.join(notes)}", flush=True)


if __name__ == "__main__":
    main()
