"""Linear solve of the penalty system of ``fibre_cube(n, 1000, 20)`` against the solid it sits in.

    python benchmarks/penalty_solve.py --n 20 40 [--direct 20] [--plain 10] [--schur 20 40] [--penalty-factor 1e3] [--profile] [--cprofile 25] [--cprofile-solve 25]
                                       [--repeat 3] [--aux 0:0 1:0.02:1e-3:f 1:0.02:1e-3:f:sparsify=1e-3:compensation=abs]

The system is the linearised model (solid: linear elastic E = 1e9, ν = 0.3, clamped at x = 0,
traction on x = 1; 1000 torsion-free fibres E = 2e11, radius 3 mm; mortar penalty ε =
factor · E_solid, default 1e3 as in scenes without a penalty), Dirichlet DOFs eliminated.
For every n it first solves **the solid alone** (the same scene without fibres, what the coupled
solve is compared with: CG + smoothed-aggregation AMG, the path ``solver = "amg"`` takes there),
then the coupled system, and prints for each solver the unknowns (solid + beam), assembly time,
setup and solve seconds, CG iterations, the true relative residual, the difference to the
direct solution where that was computed, the process CPU seconds of setup + solve (on a
loaded machine closer to the idle wall time than the wall time is) and of the set-up alone
(``set cpu``: the AMG hierarchy, or the auxiliary space, built before ``solve_linear`` is called), the ratios of wall time,
CPU time and iterations to the solid alone (measured in the same run), and the peak resident
memory of the process so far (each solver's preconditioner is released once its row is measured). Solvers: ``solid`` (the solid alone), ``aux<k>-<θ>`` (CG + auxiliary-space
preconditioner, what ``solver = "amg"``/``"auto"`` runs for penalty-coupled beams, with ``k`` Jacobi
steps on its prolongation (``harmonic``: the beams' exact response, ``harmonic_prolongation``) and strength
threshold ``θ`` in its AMG, ``--aux k:θ[:drop[:f]] ...``:
the default ``1:0.05:1e-3:f`` is the preconditioner's default (``1:0.02:1e-3:f`` before session sixteen), ``0:0`` its settings before the smoothed prolongation (``LUMPED``),
``LUMPED``; further ``:key=value`` fields: ``sparsify=δ`` builds its AMG from ``A_aux`` without the 3x3
blocks below ``δ`` of their diagonal blocks, ``compensation=none|abs|signed`` what they leave on the
diagonal (``drop_weak_blocks``), ``sparsify_scope=smoother`` only the finest level's smoother on it), ``amg`` (CG +
smoothed aggregation on the whole matrix, the path before the auxiliary space; ``--plain``, slow
at large ε), ``schur`` (CG on the solid's Schur complement with the auxiliary space's V-cycle,
``--schur``, ``schur<k>-<θ>``) and ``direct`` (SuperLU, ``--direct``). ``--profile`` adds where the auxiliary-space
set-up and its applications spent their time (:attr:`AuxiliarySpacePreconditioner.timings`) and, for
every AMG hierarchy (the solid alone's, the auxiliary space's), its levels, operator complexity
(entries of all levels over the finest's), entries per row of the finest level (scalar rows, 3x3
blocks counted as 9 entries) and the size of the coarsest; for the auxiliary space also the entries
of ``A`` and of its block ``A_BS`` (what CG's product and an application multiply with besides the
V-cycle) and the entries per row of ``A_aux`` itself, and the user and system CPU seconds and minor page faults of every set-up
(the solid's AMG hierarchy, the auxiliary space: fresh memory that the kernel faults in and zeroes is
system time); ``--cprofile K`` prints the K functions that took the most CPU seconds of the auxiliary
space's set-up, ``--cprofile-solve K`` those of every solver's solve after its set-up (CG, the
preconditioner's applications); ``--small-pages`` keeps NumPy from asking for huge pages, so that those faults count the
fresh memory of a set-up in 4 KiB pages.
The 1-minute load average is printed with every row: wall times on a shared machine are only
comparable at the same load; ``--repeat k`` keeps the fastest of k solves of each system.
"""
import argparse
import cProfile
import os
import pstats
import resource
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))     # measure this checkout's package

import mortar1d3d as m13  # noqa: E402
from _record import record  # noqa: E402
from mortar1d3d.model import Model  # noqa: E402
from mortar1d3d.solvers.linear import AuxiliarySpacePreconditioner, LinearSolverError, build_amg, solve_linear  # noqa: E402


def system(n, penalty_factor, fibres=True):
    """(model, A, b, assembly seconds) of the reduced linear penalty system (``fibres=False``:
    the solid alone, same mesh, material, supports and load)."""
    beams, solid = m13.generate.fibre_cube(n, 1000, 20)
    options = dict(solid={"mesh": solid, "material": {"model": "linear_elastic", "E": 1e9, "nu": 0.3}},
                   dirichlet=[{"on": "solid:x_min"}],
                   load=[{"type": "traction", "on": "solid:x_max", "value": [0, 0, -1e6]}],
                   analysis={"kinematics": "linear", "solver": "amg"})
    if fibres:
        options.update(beams=[{"mesh": beams, "section": {"E": 2e11, "radius": 0.003}}],
                       coupling={"penalty": penalty_factor * 1e9})
    start = time.perf_counter()
    model = Model(m13.Scene(**options)).prepare()
    z = np.zeros(model.n_unknowns)
    r, K = model.residual(z, 1.0)
    free = model.free
    A = K[free][:, free].tocsr()
    b = -r[free]
    return model, A, b, time.perf_counter() - start


def aux_variant(spec):
    """``K:THETA[:DROP[:f]][:key=value...]`` of ``--aux`` as (k, θ, drop, filter, {key: value}):
    keyword arguments of :class:`AuxiliarySpacePreconditioner` (``sparsify`` a float, ``compensation``)."""
    fields = spec.split(":")
    plain = [f for f in fields if "=" not in f] + ["0", ""]
    extra = {key: float(value) if key == "sparsify" else value
             for key, value in (f.split("=", 1) for f in fields if "=" in f)}
    steps = plain[0] if plain[0] == "harmonic" else int(plain[0])
    return steps, float(plain[1]), float(plain[2]), plain[3] == "f", extra


def hierarchy(ml):
    """One line on an AMG hierarchy: levels, operator complexity, the finest and coarsest levels."""
    fine, coarse = ml.levels[0].A, ml.levels[-1].A
    return (f"AMG: {len(ml.levels)} levels, operator complexity {ml.operator_complexity():.2f}, finest "
            f"{fine.shape[0]} rows / {fine.nnz / fine.shape[0]:.1f} entries per row, coarsest {coarse.shape[0]} rows")


def peak_memory_gb():
    """Peak resident memory of this process so far (Linux: ru_maxrss in KiB)."""
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 2**20


def top_functions(profiler, k, what):
    """Print the ``k`` functions that took the most CPU seconds (own time) under ``profiler``."""
    print(f"      {what}, CPU seconds by function (cProfile, top {k} by own time):", flush=True)
    pstats.Stats(profiler, stream=sys.stdout).sort_stats("tottime").print_stats(k)


def run(A, b, rtol, maxiter, options, split, profile, cprofile=0, cprofile_solve=0):
    """One timed solve: (x, info) with ``cpu_time``, ``load``, ``memory`` added (and ``timings``
    of the auxiliary space and ``setup_usage`` with ``profile``). ``options["smoothing"]`` (aux and schur): ``(k, θ, drop, filter)``,
    the auxiliary space is built here with those settings; ``cprofile > 0`` prints the functions that took
    the most CPU seconds of its set-up (cProfile with a CPU clock; not timed: the profiler's own cost)."""
    setup = 0.0
    usage = resource.getrusage(resource.RUSAGE_SELF)
    cpu = time.process_time()
    options = dict(options)
    smoothing = options.pop("smoothing", None)
    t = time.perf_counter()
    if smoothing is not None:
        smoothing, theta, drop, filt, extra = smoothing
        R_solid = options["near_nullspace"][split["solid"]]
        profiler = cProfile.Profile(time.process_time) if cprofile else None
        if profiler is not None:
            profiler.enable()
        options = dict(options, preconditioner=AuxiliarySpacePreconditioner(
            A, split["solid"], split["beam"], split["prolongation"], R_solid, block_size=3,
            smoothing=smoothing, theta=theta, drop=drop, filter_entries=filt, **extra))
        if profiler is not None:
            profiler.disable()
            top_functions(profiler, cprofile, "set-up")
    elif options["method"] == "amg":      # the hierarchy solve_linear would build, built here to time it
        options = dict(options, preconditioner=build_amg(A, options["near_nullspace"], block_size=options["block_size"]))
    setup = time.perf_counter() - t
    setup_cpu = time.process_time() - cpu
    after = resource.getrusage(resource.RUSAGE_SELF)
    setup_usage = (after.ru_utime - usage.ru_utime, after.ru_stime - usage.ru_stime, after.ru_minflt - usage.ru_minflt)
    profiler = cProfile.Profile(time.process_time) if cprofile_solve else None
    if profiler is not None:
        profiler.enable()
    x, info = solve_linear(A, b, rtol=rtol, maxiter=maxiter, **options)
    if profiler is not None:
        profiler.disable()
        top_functions(profiler, cprofile_solve, "solve after the set-up")
    info["setup_time"] += setup
    info["setup_cpu"] = setup_cpu
    if profile:
        info["setup_usage"] = setup_usage
        pre = info["preconditioner"]
        if smoothing is None:
            info["hierarchy"] = hierarchy(pre)
        else:
            info["timings"] = pre.timings
            sparse = pre.sparse_auxiliary
            info["hierarchy"] = (f"A {A.nnz} entries (A_BS {pre.A_bs.nnz}); "
                                 f"A_aux {pre.auxiliary_nnz / len(split['solid']):.1f} entries per row"
                                 + ("" if sparse is None else f", sparsified {sparse.nnz / sparse.shape[0]:.1f}")
                                 + "; " + hierarchy(pre.amg))
    info["cpu_time"] = time.process_time() - cpu
    # the preconditioner is not needed after this: dropped, so that the next variant's peak memory
    # does not include it (the 1M-unknown case)
    info.pop("preconditioner", None)
    info["load"] = os.getloadavg()[0]
    info["memory"] = peak_memory_gb()
    return x, info


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--n", type=int, nargs="+", default=[20, 40])
    parser.add_argument("--direct", type=int, nargs="*", default=[], help="sizes n to also solve directly")
    parser.add_argument("--plain", type=int, nargs="*", default=[], help="sizes n to also solve with plain AMG")
    parser.add_argument("--schur", type=int, nargs="*", default=[],
                        help="sizes n to also solve by CG on the solid's Schur complement (method 'schur')")
    parser.add_argument("--aux", nargs="+", default=["1:0.05:1e-3:f"], metavar="K:THETA[:DROP[:f]]",
                        help="auxiliary spaces to run: K Jacobi steps on the prolongation (0: the lumped "
                             "follow operator; 'harmonic': the beams' exact response), strength threshold THETA of its AMG, relative drop threshold "
                             "of the smoothed prolongation (default 0), ':f' for the AMG's filter_entries; "
                             "one aux (and schur) row each, named aux<K>-<THETA>[-<DROP>][f]. Default: the "
                             "preconditioner's defaults; 0:0 is AuxiliarySpacePreconditioner.LUMPED")
    parser.add_argument("--penalty-factor", type=float, default=1e3)
    parser.add_argument("--rtol", type=float, default=1e-8)
    parser.add_argument("--maxiter", type=int, default=2000,
                        help="CG iterations before a solver's row says it did not converge")
    parser.add_argument("--profile", action="store_true", help="print where the auxiliary space spends its time")
    parser.add_argument("--cprofile", type=int, default=0, metavar="K",
                        help="print the K functions that took the most CPU seconds of each auxiliary space's "
                             "set-up (the first of --repeat; cProfile, whose own cost is in that run's figures)")
    parser.add_argument("--cprofile-solve", type=int, default=0, metavar="K",
                        help="print the K functions that took the most CPU seconds of the solve after the "
                             "set-up (CG and its preconditioner applications; the first of --repeat of every "
                             "solver row, the solid alone's too; cProfile, whose own cost is in that run's figures)")
    parser.add_argument("--small-pages", action="store_true",
                        help="NumPy's big arrays in 4 KiB pages (no madvise for huge pages), so that the minor "
                             "page faults of a set-up (--profile) count its fresh memory in 4 KiB units")
    parser.add_argument("--repeat", type=int, default=1,
                        help="solve each system this many times and keep the fastest (CPU seconds) run")
    args = parser.parse_args(argv)
    if args.small_pages:
        np._core.multiarray._set_madvise_hugepage(False)
    print(f"penalty ε = {args.penalty_factor:g} E_solid, rtol {args.rtol:g}")
    print(f"{'n':>3} {'solid':>7} {'beam':>7} {'asm s':>6} {'solver':>12} {'setup s':>8} {'solve s':>8} "
          f"{'total s':>8} {'cpu s':>7} {'set cpu':>7} {'its':>5} {'rel. res':>8} {'|x-x_dir|':>9} "
          f"{'t/solid':>7} {'cpu/sol':>7} {'it/sol':>6} {'mem GB':>6} {'load':>5}")
    for n in args.n:
        runs = []
        model, A, b, t_asm = system(n, args.penalty_factor, fibres=False)
        R = model.rigid_body_modes()[model.free]
        runs.append(("solid", f"{n:3d} {A.shape[0]:7d} {0:7d} {t_asm:6.1f}", A, b,
                     dict(method="amg", near_nullspace=R, block_size=3)))
        model, A, b, t_asm = system(n, args.penalty_factor)
        R = model.rigid_body_modes()[model.free]
        split = model._follow_split()
        sizes = f"{n:3d} {len(split['solid']):7d} {len(split['beam']):7d} {t_asm:6.1f}"
        variants = [aux_variant(v) for v in args.aux]
        for method in ("aux", "schur") if n in args.schur else ("aux",):
            for k, theta, drop, filt, extra in variants:
                runs.append((f"{method}{k}-{theta:g}" + (f"-{drop:g}" if drop else "") + ("f" if filt else "")
                             + "".join(f"-{value:g}" if isinstance(value, float) else f"-{value}"
                                       for value in extra.values()), sizes, A, b,
                             dict(method=method, near_nullspace=R, block_size=3,
                                  smoothing=(k, theta, drop, filt, extra), **split)))
        if n in args.plain:
            runs.append(("amg", sizes, A, b, dict(method="amg", near_nullspace=R, block_size=3)))
        if n in args.direct:
            runs.append(("direct", sizes, A, b, dict(method="direct")))
        results = {}
        for name, sizes, A, b, kw in runs:
            best = None
            for _ in range(args.repeat):
                try:
                    x, info = run(A, b, args.rtol, args.maxiter, kw, split,
                                  args.profile and name.startswith(("aux", "solid")),
                                  args.cprofile if best is None and name.startswith("aux") else 0,
                                  args.cprofile_solve if best is None else 0)
                except LinearSolverError as error:      # a variant that does not converge: say so, go on
                    print(f"{sizes} {name:>12} did not converge: {str(error).split('. Try')[0]}", flush=True)
                    break
                if best is None or info["cpu_time"] < best[1]["cpu_time"]:
                    best = (x, info)
            if best is not None:
                results[name] = (sizes,) + best
        x_direct = results.get("direct", (None, None))[1]
        base = results["solid"][2]
        for name, (sizes, x, info) in results.items():
            diff = "" if x_direct is None or name in ("direct", "solid") else \
                f"{np.linalg.norm(x - x_direct) / np.linalg.norm(x_direct):9.1e}"
            total = info["setup_time"] + info["solve_time"]
            ratios = (total / (base["setup_time"] + base["solve_time"]), info["cpu_time"] / base["cpu_time"],
                      info["iterations"] / max(base["iterations"], 1))
            print(f"{sizes} {name:>12} {info['setup_time']:8.1f} {info['solve_time']:8.1f} {total:8.1f} "
                  f"{info['cpu_time']:7.1f} {info['setup_cpu']:7.2f} {info['iterations']:5d} {info['residual']:8.1e} {diff:>9} "
                  f"{ratios[0]:7.2f} {ratios[1]:7.2f} {ratios[2]:6.2f} {info['memory']:6.2f} {info['load']:5.1f}",
                  flush=True)
            record("penalty_solve", n=n, solver=name, unknowns=int(x.shape[0]), cpu_s=info["cpu_time"], setup_cpu_s=info["setup_cpu"],
                   iterations=int(info["iterations"]), cpu_per_solid=ratios[1], iterations_per_solid=ratios[2],
                   peak_memory_gb=info["memory"], load=info["load"])
            if "timings" in info:
                print("      " + ", ".join(f"{k} {v:.2f} s" for k, v in info["timings"].items()), flush=True)
            if "setup_usage" in info:
                print("      set-up CPU: user {:.2f} s, system {:.2f} s, {} minor page faults".format(*info["setup_usage"]),
                      flush=True)
            if "hierarchy" in info:
                print("      " + info["hierarchy"], flush=True)


if __name__ == "__main__":
    main()
