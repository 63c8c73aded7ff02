"""Scaling of the distributed path (issue 23, docs/distributed.md): run it under mpiexec.

    mpiexec -n 1 python benchmarks/distributed_scaling.py --cells 12 --fibres 300     # reference
    mpiexec -n 2 python benchmarks/distributed_scaling.py --cells 12 --fibres 300     # strong scaling
    mpiexec -n 2 python benchmarks/distributed_scaling.py --cells 15 --fibres 600     # weak: ~2x the work
    python benchmarks/distributed_scaling.py --cells 12 --fibres 300 --partition-only  # METIS vs geometric
    python benchmarks/distributed_scaling.py --cells 24 --fibres 1200 --replicated-only  # input memory per rank
    mpiexec -n 2 python benchmarks/distributed_scaling.py --cells 12 --fibres 300 --nonlinear 2   # Newton on PETSc
    mpiexec -n 2 python benchmarks/distributed_scaling.py --cells 24 --fibres 1200 --petsc-options "-mortar_penalty_pc gamg"
    mpiexec --oversubscribe -n 4 python benchmarks/distributed_scaling.py --cells 20 --fibres 1200 --fibre-elements 20 > r.json
    python benchmarks/memory_fit.py r*.json        # the memory model from such runs (its docstring)

``--petsc-options`` inserts PETSc options before the solve: ``-mortar_penalty_pc gamg`` takes GAMG on
the whole penalty system instead of the auxiliary-space sweep (the default), ``-mortar_reuse_pc 0``
sets a preconditioner up for every Newton solve; the sweep's GAMG and beam solver take options with
the prefixes ``mortar_aux_`` and ``mortar_beam_`` (docs/distributed.md). One option alone starts with
a dash: give it as ``--petsc-options=-mortar_aux_ksp_view``. ``owned`` in the output: the
unknowns each rank owns; ``linear_solves``: over all solves, their count, CG iterations, set-ups and reuses, and rank 0's set-up and CG
seconds.

With ``--nonlinear STEPS`` the analysis is geometrically nonlinear (Saint Venant–Kirchhoff, STEPS
load steps of the library's Newton loop on PETSc) and the communication per Newton iteration is
measured: PETSc's own log of the load steps' stage (messages, their bytes, global reductions: what
the assembly, the matrix products, GAMG and the ghost updates send) and, counted separately, the
bytes each rank receives in the ghost updates of the iterate (the unknowns of its elements' nodes
that other ranks own, once per residual evaluation; the iterate, residual and increment are
distributed, nothing is gathered during the loop).

The scene is the benchmark cube (docs/conventions.md §5) with hexahedra, ``--fibres`` straight fibres
of 10 Hermite elements (``--fibre-elements``) as one beam entry, clamped at z = 0 and pulled at z = 1, linear (or nonlinear,
above), mortar penalty, CG with the penalty preconditioner to rtol 1e-8. Rank 0 prints the stage times (slowest rank, after a barrier),
each rank's CPU time per stage up to the barrier (its own work: on a loaded machine the fairer
measure of balance), the CG iterations, the vector entries each rank receives per matrix product (ghosts), the stored
entries per rank and the peak resident memory per rank. Run it twice and take the second run
(the first compiles the kernels into the cache).
"""
import argparse
import json
import os
import resource
import time

import numpy as np

import mortar1d3d as m13


def scene(cells, fibres, steps=None, elements=10):
    """The benchmark cube; ``steps``: nonlinear (Saint Venant–Kirchhoff) in that many load steps;
    ``elements``: Hermite elements per fibre."""
    beams, solid = m13.generate.fibre_cube(cells, fibres, elements)
    model, analysis = "linear_elastic", {"kinematics": "linear"}
    if steps:
        model, analysis = "saint_venant_kirchhoff", {"kinematics": "nonlinear", "steps": steps}
    return m13.Scene(solid={"mesh": solid, "material": {"model": model, "E": 1.0, "nu": 0.3}},
                     beams=[{"mesh": beams, "model": "torsion_free", "section": {"E": 100.0, "radius": 0.005}}],
                     dirichlet=[{"on": "solid:z_min", "value": [0, 0, 0]}],
                     load=[{"type": "traction", "on": "solid:z_max", "value": [0, 0, 0.01]}],
                     analysis={**analysis, "solver": "amg", "rtol": 1e-8, "backend": "petsc"})


#: PETSc log events whose messages the benchmark reports apart (they nest: GAMG's set-up runs matrix
#: products and assemblies of its own, counted in those events too)
EVENTS = ("MatMult", "MatAssemblyBegin", "PCSetUp")


def _stage_messages(path, name="mortar1d3d solve"):
    """Messages (count over all ranks), their mean length in bytes and the global reductions of
    the PETSc log stage ``name``, read from the ``Summary of Stages`` of PETSc's log (``path``),
    and the bytes sent in each of :data:`EVENTS` within the stage (its event table)."""
    lines = open(path).read().splitlines()
    out = None
    for line in lines:
        if line.strip().split(":")[1:2] and line.split(":")[1].strip() == name:
            v = line.split(":")[2].split()
            out = {"messages": float(v[4]), "mean_bytes": float(v[6]), "reductions": float(v[8]), "events": {}}
            break
    if out is None:
        raise ValueError(f"{path}: no stage {name!r} in PETSc's log")
    inside = False
    for line in lines:
        if line.startswith("--- Event Stage"):
            inside = line.split(":", 1)[1].strip() == name
        elif inside and line.split() and line.split()[0] in EVENTS:
            v = line.split()
            out["events"][v[0]] = float(v[7]) * float(v[8])           # messages × mean length
    return out


def replicated_memory(cells, fibres):
    """Resident memory (MiB) after each replicated stage of a distributed run, as every rank runs
    it (the scene built, its dead loads, the partition of the whole model into 2 parts, the
    numbering): what every rank holds whatever the number of ranks."""
    from mortar1d3d.distributed import partition
    from mortar1d3d.distributed.numbering import Numbering
    from mortar1d3d.distributed.solve import SystemLayout, _BodyLoads, _memory_mib
    from mortar1d3d.model.build import build
    from mortar1d3d.model.model import Model
    out = {"start": _memory_mib()[1]}
    sc = scene(cells, fibres, 1)
    out["scene"] = _memory_mib()[1]
    model = Model(build(sc))
    model._body_loads = _BodyLoads()
    model.solid_physics = model._body_loads
    model._prepare_loads()
    out["model"] = _memory_mib()[1]
    part = partition(model.solid_mesh, [g.mesh for g in model.groups], 2, "metis")
    out["partition"] = _memory_mib()[1]
    numbering = Numbering.of(part, model.solid_mesh, [g.mesh for g in model.groups], sc.coupling["lm"])
    SystemLayout.of(numbering, model.dofmap, [g.type.dofs_per_node for g in model.groups])
    out["numbering"] = _memory_mib()[1]
    return {"cells": cells, "fibres": fibres, "unknowns": model.n_displacement_dofs, "peak_MiB": _memory_mib()[0],
            "current_MiB": {k: round(v, 1) for k, v in out.items()}}


def partition_quality(cells, fibres, parts=(2, 4, 8)):
    from mortar1d3d.distributed import partition
    beams, solid = m13.generate.fibre_cube(cells, fibres, 10)
    rows = []
    for n in parts:
        for method in ("metis", "geometric"):
            t = time.perf_counter()
            p = partition(solid, [beams], n, method)
            rows.append({"parts": n, "method": method, "seconds": round(time.perf_counter() - t, 3),
                         **{k: p.stats[k] for k in ("cut_pairs", "cut_solid_edges", "ghost_solid")},
                         "max_over_mean_elements": round(max(np.add(p.stats["solid_per_part"], p.stats["beam_per_part"]))
                                                         / ((solid.n_elements + beams.n_elements) / n), 3)})
    return rows


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cells", type=int, default=12)
    parser.add_argument("--fibres", type=int, default=300)
    parser.add_argument("--fibre-elements", type=int, default=10, metavar="N",
                        help="elements per fibre (default 10; --fibre-elements equal to --cells keeps a beam "
                             "element one cell long at every size: the tangent's stencil then stays the same)")
    parser.add_argument("--partition-only", action="store_true")
    parser.add_argument("--replicated-only", action="store_true")
    parser.add_argument("--nonlinear", type=int, default=0, metavar="STEPS",
                        help="nonlinear in STEPS load steps; measures the communication per Newton iteration")
    parser.add_argument("--petsc-options", default="", metavar="OPTIONS",
                        help="PETSc options for the solve, e.g. \"-mortar_penalty_pc gamg -pc_gamg_threshold 0.02\" "
                             "(docs/distributed.md: the penalty preconditioners)")
    args = parser.parse_args()
    if args.replicated_only:
        print(json.dumps(replicated_memory(args.cells, args.fibres)))
        return
    if args.partition_only:
        for row in partition_quality(args.cells, args.fibres):
            print(json.dumps(row))
        return
    import tempfile
    from mortar1d3d.distributed.petsc import petsc
    PETSc = petsc()
    comm = PETSc.COMM_WORLD
    if args.petsc_options:
        PETSc.Options().insertString(args.petsc_options)
    if args.nonlinear:
        PETSc.Log.begin()
    start = time.perf_counter()
    result = m13.solve(scene(args.cells, args.fibres, args.nonlinear, args.fibre_elements))
    wall = time.perf_counter() - start
    memory = comm.tompi4py().gather(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0, root=0)
    traffic = {}
    if args.nonlinear:
        log = comm.tompi4py().bcast(tempfile.mktemp(suffix=".log") if comm.getRank() == 0 else None, root=0)
        PETSc.Log.view(PETSc.Viewer().createASCII(log, comm=comm))
        if result is not None:
            newton = sum(s.iterations for s in result.steps)
            # the residual evaluations: one per Newton iteration and one more per step (the converged one)
            stage = _stage_messages(log)
            os.remove(log)
            traffic = {"newton_iterations": newton, "residual_evaluations": newton + len(result.steps),
                       "petsc_messages_per_iteration": round(stage["messages"] / newton, 1),
                       "petsc_bytes_per_iteration": round(stage["messages"] * stage["mean_bytes"] / newton),
                       "reductions_per_iteration": round(stage["reductions"] / newton, 1),
                       "bytes_per_iteration_by_event": {k: round(v / newton) for k, v in stage["events"].items()},
                       "ghost_bytes_per_iteration_per_rank": [
                           round(8 * g * result.distributed["traffic"]["ghost_updates"] / newton)
                           for g in result.distributed["traffic"]["ghost_entries"]]}
    if result is not None:
        info = result.distributed
        print(json.dumps({"ranks": info["ranks"], "cells": args.cells, "fibres": args.fibres,
                          "fibre_elements": args.fibre_elements, **traffic,
                          "unknowns": info["unknowns"], "owned": info["owned"], "iterations": info["iterations"],
                          "wall": round(wall, 3),
                          "ksp": info["ksp"], "pc": info["pc"], "petsc_options": args.petsc_options,
                          # over all solves (Newton: every iteration): KSP iterations, set-up and solve seconds (rank 0)
                          "linear_solves": {k: round(v, 3) for k, v in info["linear_solves"].items()},
                          "timings": {k: round(v, 3) for k, v in info["timings"].items()},
                          "cpu_per_rank": {k: [round(c[k], 3) for c in info["cpu"]] for k in info["cpu"][0]},
                          "ghosts": info["traffic"]["ghosts"], "nnz": info["traffic"]["nnz"],
                          "peak_MiB": [round(m, 1) for m in memory],
                          # per stage and rank: (peak, current) resident MiB at the stage's end
                          "memory_by_stage": {k: [[round(v, 1) if v is not None else None for v in m[k]]
                                                  for m in info["memory"]] for k in info["memory"][0]}}))


if __name__ == "__main__":
    main()
