"""Tutorial 9: the accuracy-vs-time trade-off in miniature.

``make report`` measures how accurate D and M are for what they cost, on many scenes. This script
does the same on one small scene in a few seconds, so you can see the shape of the result and try
your own mesh: 30 curved fibres (helices) in a hex27 cube whose interior nodes are moved (curved
element faces, so no integration is exact), integrated

* element-based with 1 … 16 Gauss points per beam element,
* segment-based with 1 … 8 points per segment,
* ``auto`` with 1 … 8 points,

each compared with a reference (segment-based with 16 points per segment): the relative Frobenius
error of M, and the wall time of the call (one thread, the best of three; times vary with the machine and its
load, errors do not). Curved fibres in curved elements make no integrand a polynomial, so no
variant is exact; but on segments the integrand is smooth and the error falls fast with n (1e-7
with 6 points, 6e-10 with 8), while element-based integration is still at 3e-4 with 16 points per
beam element, held back by the kinks at the element faces (tutorial 2). Here ``auto`` finds no
beam element that provably stays inside one solid element, so it uses the segment-based points.

Run it::

    python examples/tutorials/t09_accuracy_vs_time.py [--out results/tutorials] [--no-plot]
"""
import time
from pathlib import Path

import numba
import numpy as np
import scipy.sparse.linalg as spla

import mortar1d3d as m13
from _tutorial import main, save_figure

VARIANTS = {"element": (1, 2, 4, 8, 16), "segment": (1, 2, 3, 4, 6, 8), "auto": (1, 2, 3, 4, 6, 8)}
REFERENCE = ("segment", 16)


def scene(cells=4, fibres=30, elements=6):
    """Helical fibres in a distorted hex27 cube (curved faces)."""
    beams, _ = m13.generate.fibre_cube(cells, fibres, elements, curved=True, seed=7)
    solid = m13.generate.distort(m13.generate.box([0, 0, 0], [1, 1, 1], (cells,) * 3, "hexahedron27"), 0.1, seed=1)
    return beams, solid


def best_time(beams, solid, integration, n, repeats=3):
    best, ops = np.inf, None
    for _ in range(repeats):
        t0 = time.perf_counter()
        ops = m13.assemble_mortar(beams, solid, integration=integration, n_gauss=n)
        best = min(best, time.perf_counter() - t0)
    return ops, best


def run(variants=VARIANTS, out=None, plot=True, verbose=True, repeats=3):
    beams, solid = scene()
    for integration in variants:                       # compile (or load) every kernel first: untimed
        m13.assemble_mortar(beams, solid, integration=integration, n_gauss=1)
    ref = m13.assemble_mortar(beams, solid, integration=REFERENCE[0], n_gauss=REFERENCE[1]).M
    rows = []
    # one thread: on a shared machine a second thread waiting for its core would time the machine
    threads = numba.get_num_threads()
    numba.set_num_threads(1)
    try:
        for integration, counts in variants.items():
            for n in counts:
                ops, seconds = best_time(beams, solid, integration, n, repeats)
                error = spla.norm(ops.M - ref) / spla.norm(ref)
                rows.append((integration, n, ops.n_integration_points, error, seconds))
    finally:
        numba.set_num_threads(threads)
    if verbose:
        print(f"{solid}; {beams}")
        print(f"{'integration':<12}{'n':>4}{'points':>9}{'M error':>11}{'time [ms]':>11}")
        for integration, n, points, error, seconds in rows:
            print(f"{integration:<12}{n:>4}{points:>9}{error:>11.2e}{1e3 * seconds:>11.2f}")
    if plot:
        _plot(rows, Path(out or "results/tutorials"))
    return rows


def _plot(rows, out):
    import matplotlib
    import matplotlib.ticker
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(6, 4.2))
    for integration, style in (("element", "o-"), ("segment", "s-"), ("auto", "^--")):
        mine = [r for r in rows if r[0] == integration]
        ax.loglog([1e3 * r[4] for r in mine], [max(r[3], 1e-17) for r in mine], style, label=integration)
    ax.xaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())
    ax.set_xlabel("wall time of assemble_mortar [ms], one thread")
    ax.set_ylabel("relative error of M")
    ax.legend(loc="lower left")
    save_figure(fig, out, "accuracy_vs_time.png")


if __name__ == "__main__":
    main(run, __doc__)
