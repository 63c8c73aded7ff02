"""Scaling of the distributed path (issue 23, docs/distributed.md): run it under mpiexec.

    mpiexec -n 1 python benchmarks/distributed_scaling.py --cells 12 --fibres 300     # reference
    mpiexec -n 2 python benchmarks/distributed_scaling.py --cells 12 --fibres 300     # strong scaling
    mpiexec -n 2 python benchmarks/distributed_scaling.py --cells 15 --fibres 600     # weak: ~2x the work
    python benchmarks/distributed_scaling.py --cells 12 --fibres 300 --partition-only  # METIS vs geometric

The scene is the benchmark cube (docs/conventions.md §5) with hexahedra, ``--fibres`` straight fibres
of 10 Hermite elements as one beam entry, clamped at z = 0 and pulled at z = 1, linear, mortar
penalty, CG + GAMG to rtol 1e-8. Rank 0 prints the stage times (slowest rank, after a barrier),
each rank's CPU time per stage up to the barrier (its own work: on a loaded machine the fairer
measure of balance), the CG iterations, the vector entries each rank receives per matrix product (ghosts), the stored
entries per rank and the peak resident memory per rank. Run it twice and take the second run
(the first compiles the kernels into the cache).
"""
import argparse
import json
import resource
import time

import numpy as np

import mortar1d3d as m13


def scene(cells, fibres):
    beams, solid = m13.generate.fibre_cube(cells, fibres, 10)
    return m13.Scene(solid={"mesh": solid, "material": {"model": "linear_elastic", "E": 1.0, "nu": 0.3}},
                     beams=[{"mesh": beams, "model": "torsion_free", "section": {"E": 100.0, "radius": 0.005}}],
                     dirichlet=[{"on": "solid:z_min", "value": [0, 0, 0]}],
                     load=[{"type": "traction", "on": "solid:z_max", "value": [0, 0, 0.01]}],
                     analysis={"kinematics": "linear", "solver": "amg", "rtol": 1e-8, "backend": "petsc"})


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
    parser.add_argument("--partition-only", action="store_true")
    args = parser.parse_args()
    if args.partition_only:
        for row in partition_quality(args.cells, args.fibres):
            print(json.dumps(row))
        return
    from mortar1d3d.distributed.petsc import petsc
    comm = petsc().COMM_WORLD
    start = time.perf_counter()
    result = m13.solve(scene(args.cells, args.fibres))
    wall = time.perf_counter() - start
    memory = comm.tompi4py().gather(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0, root=0)
    if result is not None:
        info = result.distributed
        print(json.dumps({"ranks": info["ranks"], "cells": args.cells, "fibres": args.fibres,
                          "unknowns": info["unknowns"], "iterations": info["iterations"], "wall": round(wall, 3),
                          "timings": {k: round(v, 3) for k, v in info["timings"].items()},
                          "cpu_per_rank": {k: [round(c[k], 3) for c in info["cpu"]] for k in info["cpu"][0]},
                          "ghosts": info["traffic"]["ghosts"], "nnz": info["traffic"]["nnz"],
                          "peak_MiB": [round(m, 1) for m in memory]}))


if __name__ == "__main__":
    main()
