"""Compile (or load from Numba's on-disk cache) every kernel by running a tiny scene."""
import time


def warmup(verbose=False):
    """Touch every stage once: search, segmentation, both integrations, assembly, CSR.

    Kernels dispatch on integer element codes, so one small scene compiles everything that
    later scenes of any element type use. Returns the elapsed time in seconds.
    """
    from . import generate
    from .mortar.assemble import assemble_mortar

    t0 = time.perf_counter()
    beams, solid = generate.fibre_cube(2, 1, 2)
    for integration in ("segment", "element"):
        assemble_mortar(beams, solid, integration=integration, n_gauss=2)
    elapsed = time.perf_counter() - t0
    if verbose:
        print(f"mortar1d3d kernels ready in {elapsed:.2f} s")
    return elapsed
