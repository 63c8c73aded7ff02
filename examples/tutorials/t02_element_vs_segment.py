"""Tutorial 2: element-based against segment-based integration on one beam crossing three hexes.

A single straight beam element runs obliquely through a row of three hex8 elements. Along the
beam, the solid's shape function of a node on a shared face is linear-ish inside each element and
has a *kink* where the beam crosses the face: its slope jumps. Gauss points placed on the whole
beam element (element-based integration) cannot see the kink, so M is integrated with an error
that falls only slowly with more points. Cutting the beam at the faces (segment-based
integration) leaves smooth polynomial pieces, which Gauss rules integrate exactly.

The script

1. assembles M segment-based (exact) and element-based with 2 … 64 Gauss points and prints the
   relative error of M;
2. checks the segment-based M against an independent integration: the crossings x = 1 and x = 2
   of the line are computed by hand and each piece integrated with a 10-point Gauss rule, with
   the trilinear shape functions written out here;
3. plots (``element_vs_segment.png``) Φ1 · N_a along the beam for the nodes of the face x = 1,
   with the crossings marked, and the error against the number of Gauss points.

Run it::

    python examples/tutorials/t02_element_vs_segment.py [--out results/tutorials] [--no-plot]
"""
from pathlib import Path

import numpy as np

import mortar1d3d as m13
from _tutorial import main, save_figure

START, END = np.array([0.1, 0.2, 0.3]), np.array([2.9, 0.7, 0.9])   # the beam, from x = 0.1 to 2.9
GAUSS_COUNTS = (2, 4, 8, 16, 32, 64)


def setup():
    """Three unit hex8 along x ([0, 3] × [0, 1] × [0, 1]) and one Hermite element from START to END."""
    solid = m13.generate.box([0, 0, 0], [3, 1, 1], (3, 1, 1), "hexahedron")
    t = (END - START) / np.linalg.norm(END - START)
    beam = m13.BeamMesh.hermite([START, END], [t, t], [[0, 1]])
    return solid, beam


def trilinear(points, x):
    """Values (n, n_nodes) of the global piecewise-trilinear hat functions of the unit grid at x (n, 3)."""
    # each node's hat function is a product of 1D hats max(0, 1 − |x_i − X_i|) on a unit grid
    return np.prod(np.clip(1.0 - np.abs(x[:, None, :] - points[None, :, :]), 0.0, None), axis=2)


def exact_M(solid, length):
    """Scalar M (2, n_nodes) integrated piece by piece between the face crossings x = 1 and x = 2."""
    # τ ∈ [0, 1] along the beam; the line crosses x = 1 and x = 2 at these τ
    cuts = [0.0, (1 - START[0]) / (END[0] - START[0]), (2 - START[0]) / (END[0] - START[0]), 1.0]
    g, w = np.polynomial.legendre.leggauss(10)
    M = np.zeros((2, solid.n_nodes))
    for a, b in zip(cuts[:-1], cuts[1:]):
        tau = a + (b - a) * (g + 1) / 2
        weight = w * (b - a) / 2 * length                      # ds = L dτ
        N = trilinear(solid.points, START + tau[:, None] * (END - START))
        phi = np.stack([1 - tau, tau])                          # line2 multipliers
        M += (phi * weight) @ N
    return M


def run(gauss_counts=GAUSS_COUNTS, out=None, plot=True, verbose=True):
    solid, beam = setup()
    length = float(np.linalg.norm(END - START))
    segment = m13.assemble_mortar(beam, solid, integration="segment", n_gauss=6)
    M_seg = segment.M.toarray()[0::3, 0::3]
    M_exact = exact_M(solid, length)
    errors = {}
    for n in gauss_counts:
        element = m13.assemble_mortar(beam, solid, integration="element", n_gauss=n)
        M_el = element.M.toarray()[0::3, 0::3]
        errors[n] = np.linalg.norm(M_el - M_seg) / np.linalg.norm(M_seg)
    result = {"segment_vs_exact": np.abs(M_seg - M_exact).max(), "element_errors": errors,
              "segments": len(segment.segments),
              "crossings": sorted({round(float(e), 12) for e in segment.segments["eta_end"][:-1]})}
    if verbose:
        print(f"segment-based: {result['segments']} segments, cut at η = {result['crossings']}")
        print(f"segment-based M against the hand-cut integration: largest difference "
              f"{result['segment_vs_exact']:.1e}")
        print("element-based M, relative error against segment-based:")
        for n, e in errors.items():
            print(f"  {n:3d} Gauss points: {e:.2e}")
    if plot:
        _plot(solid, errors, Path(out or "results/tutorials"))
    return result


def _plot(solid, errors, out):
    import matplotlib
    import matplotlib.ticker
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    tau = np.linspace(0, 1, 1001)
    N = trilinear(solid.points, START + tau[:, None] * (END - START))
    on_face = np.flatnonzero(np.isclose(solid.points[:, 0], 1.0))
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(11, 4))
    for a in on_face:
        ax1.plot(tau, (1 - tau) * N[:, a], label=f"node {a} at {solid.points[a].round(1).tolist()}")
    for x in (1, 2):
        ax1.axvline((x - START[0]) / (END[0] - START[0]), color="0.6", ls=":")
    ax1.set_xlabel("τ along the beam (dotted: faces x = 1, x = 2)")
    ax1.set_ylabel("Φ1 · N_a")
    ax1.set_title("integrand of M: kinks at the element faces")
    ax1.legend(fontsize=7, loc="upper right")
    ax2.loglog(list(errors), list(errors.values()), "o-", label="element-based")
    ax2.set_xticks(list(errors), [str(n) for n in errors])
    ax2.xaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())
    ax2.set_xlabel("Gauss points per beam element")
    ax2.set_ylabel("relative error of M")
    ax2.set_title("segment-based is exact (error 0)")
    ax2.legend()
    save_figure(fig, out, "element_vs_segment.png")


if __name__ == "__main__":
    main(run, __doc__)
