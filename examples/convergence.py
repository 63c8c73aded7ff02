"""Spatial convergence of beam-to-solid coupling and the beam-to-solid element-size ratio.

A curved beam (a circular arc; truss elements, see *Beam model* below) is embedded in a cantilever block
(hex8, linear elastic, clamped at x = 0, bent by a downward traction at x = 1). The arc crosses
the block's neutral plane, so the coupling transfers axial and transverse force along the whole
beam. Linear kinematics. The solid mesh is refined by halving h_S; the beam element length h_B
follows at fixed ratios h_B/h_S ∈ {1/4, 1/2, 1, 2}. Three couplings, all penalty with the same
ε: mortar with segment-based integration, mortar with element-based integration, and point-wise
(Gauss-point) penalty.

Errors (relative L2 norms) of the solid displacement over the block and of the beam centreline
displacement along the arc are measured against the finest level of the same variant and ratio
(the meshes are nested, so the solid error is integrated exactly on the finest grid; the beam
is compared at the same curve parameters). Rates are log2 of successive error ratios.

The failure mode of point-wise coupling is over-constraint: one vector constraint per
integration point (here six per segment), more than the solid element can follow. In the
literature this is shown for beam elements much shorter than solid elements; in this problem
(penalty ε = 1e3 E, a linear truss beam) it shows for every ratio and most for h_B >= h_S: the
model stiffens (tip deflection 11 % low at h_S = 1/16, h_B/h_S = 1 and 2), the errors are up to 4x
those of mortar and the line load λ is rough. Mortar coupling averages the constraint against
the multiplier functions; its displacement errors and rates hardly depend on h_B/h_S in
[1/4, 2]. The line load λ, however, oscillates node to node for h_B/h_S <= 1/2 in every variant
(the multiplier space is then richer than the solid's trace along the beam); h_B/h_S between 1
and 2 gives smooth λ and optimal displacement convergence.

Beam model: the arc is modelled with axial (truss, ``line``) beam elements. The torsion-free
Hermite beam of :mod:`mortar1d3d.physics.beam` holds for initially straight beams only and
refuses the arc (SceneError): an energy of the curvature *magnitude* would give the
out-of-plane rotation of the arc's nodal tangents zero stiffness, which mortar coupling with
``line2`` multipliers does not constrain (measured before that check: four zero eigenvalues,
the tangent y-components, at h_S = 1/4, h_B/h_S = 1). The axial coupling force dominates here,
and the truss, embedded over its whole length, is held by the coupling.

    python examples/convergence.py [--out results/convergence] [--levels 4 8 16 32] [--no-plot]
"""
import argparse
import os
import sys
import time

import numpy as np

import mortar1d3d as m13

BLOCK = np.array([1.0, 0.25, 0.25])
RATIOS = (0.25, 0.5, 1.0, 2.0)
VARIANTS = {"mortar segment": {"constraint": "mortar", "integration": "segment"},
            "mortar element": {"constraint": "mortar", "integration": "element"},
            "gauss-point penalty": {"constraint": "gauss_point", "integration": "segment"}}
E_SOLID, NU = 1.0, 0.3
PENALTY = 1e3 * E_SOLID
SECTION = {"EA": 100.0 * E_SOLID * np.pi * 0.02 ** 2}
TRACTION = [0.0, 0.0, -1e-3]
# the arc: centre C, radius R, angles ±THETA in the xz-plane at y = 0.11 (no grid plane of any level)
C = np.array([0.5, 0.11, -0.83])
R = 1.0
THETA = 0.4115


def arc(theta):
    return C + R * np.array([np.sin(theta), 0.0, np.cos(theta)])


def arc_derivative(theta):
    return R * np.array([np.cos(theta), 0.0, -np.sin(theta)])


ARC_LENGTH = 2 * THETA * R


def beam_elements(n, ratio):
    """Beam elements for h_S = 1/n and h_B = ratio h_S."""
    return max(1, int(round(ARC_LENGTH * n / ratio)))


def scene(n, ratio, variant):
    return m13.Scene(
        solid={"mesh": {"box": [[0, 0, 0], BLOCK.tolist()], "cells": [n, n // 4, n // 4], "element": "hexahedron"},
               "material": {"model": "linear_elastic", "E": E_SOLID, "nu": NU}},
        beams=[{"curve": {"function": arc, "derivative": arc_derivative, "t": [-THETA, THETA]},
                "elements": beam_elements(n, ratio), "model": "truss", "section": SECTION}],
        coupling={**VARIANTS[variant], "enforcement": "penalty", "penalty": PENALTY, "n_gauss": 6},
        dirichlet=[{"on": "solid:x_min"}],
        load=[{"type": "traction", "on": "solid:x_max", "value": TRACTION}],
        analysis={"kinematics": "linear", "solver": "direct"})


# -- evaluation of the discrete fields at given points (nested structured meshes) ---------------------
def solid_field(u, n, X):
    """Trilinear hex8 field of the box mesh with cells (n, n/4, n/4) at points X (m, 3)."""
    cells = np.array([n, n // 4, n // 4])
    h = BLOCK / cells
    s = X / h
    c = np.clip(np.floor(s).astype(int), 0, cells - 1)
    y = s - c
    U = u.reshape(cells[2] + 1, cells[1] + 1, cells[0] + 1, 3)      # nodes: x fastest
    out = np.zeros((len(X), 3))
    for i, j, k in np.ndindex(2, 2, 2):
        w = (y[:, 0] if i else 1 - y[:, 0]) * (y[:, 1] if j else 1 - y[:, 1]) * (y[:, 2] if k else 1 - y[:, 2])
        out += w[:, None] * U[c[:, 2] + k, c[:, 1] + j, c[:, 0] + i]
    return out


def solid_quadrature(n):
    """2x2x2 Gauss points and weights on every cell of the level-n grid."""
    cells = np.array([n, n // 4, n // 4])
    h = BLOCK / cells
    g = 0.5 * (1 + np.array([-1, 1]) / np.sqrt(3))
    idx = np.stack(np.meshgrid(*[np.arange(c) for c in cells], indexing="ij"), -1).reshape(-1, 3)
    local = np.stack(np.meshgrid(g, g, g, indexing="ij"), -1).reshape(-1, 3)
    X = ((idx[:, None, :] + local[None]) * h).reshape(-1, 3)
    return X, np.full(len(X), np.prod(h) / 8)


def beam_field(u, theta):
    """Linear (truss) centreline displacement at curve parameters theta; nodes at equal
    parameter steps, so the parameter maps linearly to η in each element."""
    m = len(u) - 1
    s = (theta + THETA) / (2 * THETA) * m
    e = np.clip(np.floor(s).astype(int), 0, m - 1)
    w = (s - e)[:, None]
    return (1 - w) * u[e] + w * u[e + 1]


def beam_quadrature(pieces=256):
    x, w = np.polynomial.legendre.leggauss(4)
    edges = np.linspace(-THETA, THETA, pieces + 1)
    mid, half = 0.5 * (edges[1:] + edges[:-1]), 0.5 * np.diff(edges)
    theta = (mid[:, None] + half[:, None] * x[None]).ravel()
    return theta, (half[:, None] * w[None]).ravel() * R


def run(levels=(4, 8, 16, 32), ratios=RATIOS, variants=tuple(VARIANTS), verbose=True):
    """Solve every (variant, ratio, level); return errors, rates and the line loads."""
    finest = levels[-1]
    Xs, ws = solid_quadrature(finest)
    thetas, wb = beam_quadrature()
    out = {"levels": levels, "errors": {}, "rates": {}, "line_load": {}, "tip": {}}
    for variant in variants:
        for ratio in ratios:
            fields = {}
            for n in levels:
                t0 = time.perf_counter()
                res = m13.solve(scene(n, ratio, variant))
                fields[n] = (solid_field(res.solid_displacement.ravel(), n, Xs),
                             beam_field(res.beam_displacement, thetas))
                # λ along the beam, at the LM (beam) nodes, against the arc length
                m = beam_elements(n, ratio)
                out["line_load"][(variant, ratio, n)] = (np.linspace(0, ARC_LENGTH, m + 1), res.line_load.copy())
                tip = np.isclose(res.model.solid_mesh.points[:, 0], BLOCK[0])
                out["tip"][(variant, ratio, n)] = -res.solid_displacement[tip, 2].mean()
                if verbose:
                    print(f"  {variant:20s} h_B/h_S {ratio:4.2f}  n {n:3d}  beam elements {m:4d}  "
                          f"tip {out['tip'][(variant, ratio, n)]:.6e}  {time.perf_counter() - t0:5.2f} s", flush=True)
            ref_S, ref_B = fields[finest]
            norm_S = np.sqrt(ws @ (ref_S ** 2).sum(1))
            norm_B = np.sqrt(wb @ (ref_B ** 2).sum(1))
            e_S = [np.sqrt(ws @ ((fields[n][0] - ref_S) ** 2).sum(1)) / norm_S for n in levels[:-1]]
            e_B = [np.sqrt(wb @ ((fields[n][1] - ref_B) ** 2).sum(1)) / norm_B for n in levels[:-1]]
            out["errors"][(variant, ratio)] = (np.array(e_S), np.array(e_B))
            out["rates"][(variant, ratio)] = (np.log2(np.array(e_S[:-1]) / e_S[1:]),
                                              np.log2(np.array(e_B[:-1]) / e_B[1:]))
    return out


def print_tables(out):
    levels = out["levels"]
    print(f"\nrelative L2 errors against level n = {levels[-1]} (h_S = 1/n) and rates log2(e_n / e_2n)")
    head = "  ".join(f"n={n:<3d}" + " " * 4 for n in levels[:-1])
    for what, k in (("solid", 0), ("beam centreline", 1)):
        print(f"\n{what}:")
        print(f"  {'variant':20s} {'h_B/h_S':>7s}   {head}  rates")
        for (variant, ratio), errs in out["errors"].items():
            e = "  ".join(f"{v:9.3e}" for v in errs[k])
            r = " ".join(f"{v:5.2f}" for v in out["rates"][(variant, ratio)][k])
            print(f"  {variant:20s} {ratio:7.2f}   {e}  {r}")


def plot(out, path, lam_level):
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print("matplotlib is not installed: no plot (pip install matplotlib)")
        return False
    fig = figure(out, lam_level)
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return True


def figure(out, lam_level):
    """The figure of :func:`plot`: error against h_S for solid and beam, λ_z along the beam per
    variant, and one panel holding the legends (so that none covers a curve)."""
    import matplotlib.pyplot as plt
    from matplotlib.lines import Line2D
    from matplotlib.ticker import FuncFormatter, LogLocator, NullFormatter, NullLocator
    levels = out["levels"]
    h = 1.0 / np.array(levels[:-1])
    variants = list(dict.fromkeys(v for v, _ in out["errors"]))
    ratios = list(dict.fromkeys(r for _, r in out["errors"]))
    fig, axes = plt.subplots(2, 2 + len(variants) // 2, figsize=(15, 8.5))
    axes = axes.ravel()
    markers = {"mortar segment": "o-", "mortar element": "s--", "gauss-point penalty": "^:"}
    colours = dict(zip(ratios, plt.rcParams["axes.prop_cycle"].by_key()["color"]))
    for k, (ax, what) in enumerate(zip(axes[:2], ("solid", "beam centreline"))):
        for (variant, ratio), errs in out["errors"].items():
            ax.loglog(h, errs[k], markers[variant], color=colours[ratio], label=f"{variant}, h_B/h_S={ratio:g}")
        ax.loglog(h, 0.5 * errs[k][0] * (h / h[0]) ** 2, "k-", lw=0.6, label="slope 2")
        ax.loglog(h, 0.5 * errs[k][0] * (h / h[0]), "k--", lw=0.6, label="slope 1")
        ax.set_xlabel("h_S")
        ax.set_ylabel(f"relative L2 error, {what}")
        ax.set_title(f"{what} displacement vs level n={levels[-1]}")
        # readable ticks: h_S as the fractions it is, the error at 1, 2, 5 × 10^k as plain numbers
        ax.set_xticks(h, [f"1/{n}" for n in levels[:-1]])
        ax.xaxis.set_minor_locator(NullLocator())         # the default labels minor ticks as 1.4×10⁻¹ ...
        ax.yaxis.set_major_locator(LogLocator(subs=(1.0, 2.0, 5.0)))
        ax.yaxis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:g}"))
        ax.yaxis.set_minor_formatter(NullFormatter())
        ax.invert_xaxis()
    for ax, variant in zip(axes[2:], variants):
        for ratio in ratios:
            s, lam = out["line_load"][(variant, ratio, lam_level)]
            ax.plot(s, lam[:, 2], ".-", ms=3, lw=0.8, color=colours[ratio], label=f"h_B/h_S={ratio:g}")
        ax.set_xlabel("arc length s")
        ax.set_ylabel("λ_z (line load at LM nodes)")
        ax.set_title(f"{variant}, h_S = 1/{lam_level}")
    # legends in their own panel: in the data panels they covered curves. Styles and colours
    # separately, with handles long enough to show the dashes.
    legend_ax = axes[-1]
    legend_ax.axis("off")
    styles = [Line2D([], [], color="k", ls=markers[v][1:], marker=markers[v][0], label=v) for v in variants]
    styles += [Line2D([], [], color="k", lw=0.6, ls="-", label="slope 2"),
               Line2D([], [], color="k", lw=0.6, ls="--", label="slope 1")]
    first = legend_ax.legend(handles=styles, loc="upper left", title="coupling (error panels)", fontsize=9,
                             handlelength=4)
    legend_ax.add_artist(first)
    legend_ax.legend(handles=[Line2D([], [], color=colours[r], lw=2, label=f"h_B/h_S = {r:g}") for r in ratios],
                     loc="lower left", title="beam / solid element size (all panels)", fontsize=9)
    for ax in axes[2 + len(variants):-1]:
        ax.axis("off")
    fig.tight_layout()
    return fig


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--out", default="results/convergence")
    parser.add_argument("--levels", type=int, nargs="+", default=[4, 8, 16, 32])
    parser.add_argument("--no-plot", action="store_true")
    args = parser.parse_args(argv)
    if any(n % 4 for n in args.levels):
        parser.error("levels must be multiples of 4 (cells n x n/4 x n/4)")
    os.makedirs(args.out, exist_ok=True)
    start = time.perf_counter()
    out = run(tuple(args.levels))
    print_tables(out)
    lam_level = args.levels[-2] if len(args.levels) > 1 else args.levels[0]
    print(f"\ntip deflection (mean u_z at x = 1) at h_S = 1/{lam_level}: over-constraint shows as stiffening")
    for variant in VARIANTS:
        print(f"  {variant:20s} " + "  ".join(f"h_B/h_S={r:4.2f}: {out['tip'][(variant, r, lam_level)]:.6e}"
                                          for r in RATIOS))
    res = m13.solve(scene(lam_level, 0.5, "mortar segment"))
    res.write(os.path.join(args.out, "vtu"))
    if not args.no_plot and plot(out, os.path.join(args.out, "convergence.png"), lam_level):
        print(f"\nplot: {os.path.join(args.out, 'convergence.png')}")
    print(f"VTU: {os.path.join(args.out, 'vtu')} (mortar segment, h_B/h_S = 0.5, h_S = 1/{lam_level})")
    print(f"run time {time.perf_counter() - start:.1f} s")
    return out


if __name__ == "__main__":
    main(sys.argv[1:])
