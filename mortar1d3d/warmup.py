"""Compile (or load from Numba's on-disk cache) every kernel by running tiny scenes."""
import time


def warmup(verbose=False):
    """Touch every stage once: the mortar engine (search, segmentation, both integrations,
    assembly, CSR, point projection) and the physics (solid, torsion-free beam, truss, coupling, pressure).

    Kernels dispatch on integer element codes, so small scenes compile everything that later
    scenes of any element type use, except what the kernels call lazily (the other element types'
    functions, the rare path of locating a point: :mod:`mortar1d3d._unlinked`), compiled last.
    Returns the elapsed time in seconds.
    """
    from . import generate
    from ._config import announce_compilation
    from ._unlinked import compile_lazy
    from .model import solve
    from .geometry.projection import project_points
    from .mortar.assemble import assemble_mortar
    from .scene import Scene

    announce_compilation()
    t0 = time.perf_counter()
    beams, solid = generate.fibre_cube(2, 1, 2)
    for integration in ("segment", "element", "auto"):
        assemble_mortar(beams, solid, integration=integration, n_gauss=2)
    project_points(solid, beams.positions, 0)
    t1 = time.perf_counter()
    box = {"box": [[0, 0, 0], [1, 0.2, 0.2]], "cells": [2, 1, 1]}
    for model, material in (("torsion_free", "neo_hooke"), ("truss", "saint_venant_kirchhoff")):
        solve(Scene(solid={"mesh": box, "material": {"model": material, "E": 1.0, "nu": 0.3}},
                    beams=[{"curve": {"line": [[0.1, 0.1, 0.1], [0.9, 0.1, 0.1]]}, "elements": 2, "model": model,
                            "section": {"EA": 1.0} if model == "truss" else {"EA": 1.0, "EI": 0.01}}],
                    coupling={"constraint": "gauss_point"} if model == "truss" else None,
                    dirichlet=[{"on": "solid:x_min"}],
                    load=[{"type": "pressure", "on": "solid:z_max", "value": 1e-3}],
                    analysis={"steps": 1}))
    compile_lazy()
    elapsed = time.perf_counter() - t0
    if verbose:
        print(f"mortar1d3d kernels ready in {elapsed:.2f} s (engine {t1 - t0:.2f} s, physics {elapsed - (t1 - t0):.2f} s)")
    return elapsed
