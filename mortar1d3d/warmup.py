"""Compile (or load from Numba's on-disk cache) every kernel by running tiny scenes."""
import time

#: the integrations :func:`warmup` runs by default
INTEGRATIONS = ("segment", "element", "auto")


def _engine_scene(name):
    """(beams, solid) of a tiny scene of solid element type ``name``: a fibre in a 2 x 2 x 2 box for
    hex8, six fibres in a distorted 3 x 3 x 3 box for the other Lagrange types, a fibre along a
    quarter of a hollow cylinder (rational weights) for NURBS.

    The other types' box is distorted (:func:`~mortar1d3d.generate.distort`: its interior nodes
    moved), so that its elements are curved as in their scenes: an undistorted box's elements are
    affine, located without a Newton step, and left the Newton versions a curved element runs
    (projection, polishing, face crossings) and its one-to-one certificate to be compiled at a
    user's first curved scene (one fibre in 2 x 2 x 2 elements met neither a crossing that needs the
    face Newton nor a point that needs the certificate). hex8's Newton path is compiled into the
    kernels whatever the scene; its certificate and the rare paths, which the distorted scene also
    runs (about 4 CPU s of compiling), are left to a hex8 scene's first use (the demo's scene is
    undistorted)."""
    import numpy as np

    from . import generate
    from .elements import solid_element

    element = solid_element(name)
    if name == "hexahedron":
        return generate.fibre_cube(2, 1, 2)
    beams, _ = generate.fibre_cube(3, 6, 3)
    if not element.rational:
        return beams, generate.distort(generate.box((0.0, 0.0, 0.0), (1.0, 1.0, 1.0), (3, 3, 3), element=name), 0.1)
    from . import nurbs

    pipe = nurbs.hollow_cylinder(0.2, 0.3, 1.0, angle=90.0, elements=(1, 2, 2), degree=element.degree)
    x, y = 0.25 * np.cos(np.radians(30.0)), 0.25 * np.sin(np.radians(30.0))   # inside an element, not on a face
    return generate.straight_beams([[[x, y, 0.1], [x, y, 0.9]]], 2), nurbs.bezier_mesh(pipe).solid


def warmup(verbose=False, elements=None, integrations=INTEGRATIONS, physics=True):
    """Compile (or load) the kernels a run needs before the run, so that its timings hold no compile.

    By default every kernel: the mortar engine (search, segmentation, both integrations, assembly,
    CSR, point projection) on a tiny hex8 scene, the physics (solid, torsion-free beam, truss,
    coupling, pressure) and, last, every element type's kernels and the rare paths that kernels
    call lazily (:mod:`mortar1d3d._unlinked`).

    ``elements`` (meshio names of solid element types, e.g. ``["hexahedron"]``) limits the engine
    to tiny scenes of those types with the given ``integrations`` and leaves out the lazy callees
    those scenes do not run: what a scene of those types compiles on its first call, paid up front.
    The tiny scenes of the types other than hex8 are distorted (curved elements: the Newton
    projection, the face Newton of the crossings and the one-to-one certificate run). A path they
    do not take (a rare fallback of locating a point, numpy's sort of a long candidate list, and for
    hex8 the certificate of a curved element) still compiles when a later scene first takes it.
    ``physics=False`` leaves out the physics.
    Returns the elapsed time in seconds.
    """
    from ._config import announce_compilation
    from ._unlinked import compile_lazy
    from .elements import solid_element
    from .model import solve
    from .geometry.projection import project_points
    from .mortar.assemble import assemble_mortar
    from .scene import Scene

    names = ["hexahedron"] if elements is None else [solid_element(name).name for name in elements]
    integrations = tuple(integrations)
    for integration in integrations:
        if integration not in INTEGRATIONS:
            raise ValueError(f"warmup: unknown integration {integration!r}; known: {', '.join(INTEGRATIONS)}")
    announce_compilation()
    t0 = time.perf_counter()
    for name in names:
        beams, solid = _engine_scene(name)
        for integration in integrations:
            # the certificate's kernel compiles on its first reading (MortarOperators.constraint_residual)
            assemble_mortar(beams, solid, integration=integration, n_gauss=2).constraint_residual
        project_points(solid, beams.positions, 0)
    t1 = time.perf_counter()
    box = {"box": [[0, 0, 0], [1, 0.2, 0.2]], "cells": [2, 1, 1]}
    for model, material in (("torsion_free", "neo_hooke"), ("truss", "saint_venant_kirchhoff")) if physics else ():
        solve(Scene(solid={"mesh": box, "material": {"model": material, "E": 1.0, "nu": 0.3}},
                    beams=[{"curve": {"line": [[0.1, 0.1, 0.1], [0.9, 0.1, 0.1]]}, "elements": 2, "model": model,
                            "section": {"EA": 1.0} if model == "truss" else {"EA": 1.0, "EI": 0.01}}],
                    coupling={"constraint": "gauss_point"} if model == "truss" else None,
                    dirichlet=[{"on": "solid:x_min"}],
                    load=[{"type": "pressure", "on": "solid:z_max", "value": 1e-3}],
                    analysis={"steps": 1}))
    if elements is None:
        compile_lazy()
    elapsed = time.perf_counter() - t0
    if verbose:
        scope = "" if elements is None else f" for {', '.join(names)}"
        print(f"mortar1d3d kernels{scope} ready in {elapsed:.2f} s (engine {t1 - t0:.2f} s, "
              f"physics {elapsed - (t1 - t0):.2f} s)")
    return elapsed
