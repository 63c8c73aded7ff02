"""Patch tests of mortar beam-to-solid coupling: segment-based integration is exact, element-based is not.

Three tests on straight Hermite beams embedded obliquely in affine hex8 and tet4 meshes. The
beam's line passes through a mesh node, along no face, across an interior edge and through
many faces, so segment ends fall on every kind of element boundary.

1. **Force patch test.** A constant and a linear line load λ(s) f (LM ``line2``, whose nodal
   values reproduce both exactly) are turned into nodal forces by the operators: ``−Mᵀλ`` on
   the solid and ``Dᵀλ`` on the beam. They are compared with the consistent nodal forces
   ``−∫ λ N_a ds`` and ``∫ λ H_k ds`` integrated *independently*: the crossing parameters of the
   line with every grid plane (and, for tets, every Kuhn plane ``u_i − u_j = k``) are computed in
   closed form in grid coordinates; between two consecutive crossings the global basis
   functions are polynomials along the line (hat-function products for hex8, Freudenthal
   barycentrics for tet4), integrated exactly by a 6-point Gauss rule.
2. **Displacement patch test.** A linear displacement field gives ``D d_B − M d_S = 0`` (and a
   zero point-wise gap) for every variant: a consistency check they all pass.
3. **Boundary-value patch test.** Linear kinematics, Lagrange multipliers. The solid's boundary
   nodes and the beam's end positions follow an affine field ``u = c + G x``; the beam carries
   an external line load ``q(s) f`` (exact consistent nodal forces) and the solid carries the
   opposite line load ``−q(s) f`` along the same line (exact consistent nodal forces). The
   affine field in solid and beam with ``λ = q`` satisfies every discrete equation of the
   continuous problem: the solid's and beam's internal forces vanish at free nodes for an
   affine state (constant stress, constant axial force, no curvature) and the coupling hands
   exactly ``q`` from the beam to the solid, where the applied ``−q`` balances it. The exact
   solution lies in the discrete spaces (affine displacements, linear λ), so a consistent
   discretisation reproduces it to round-off — that is what makes it a patch test. The
   discrete solution equals it *only if* ``Mᵀλ`` is integrated exactly: with element-based
   integration the solid receives slightly wrong nodal forces and the interior nodes move
   away from the affine field.

    python examples/patch_test.py [--out results/patch_test] [--no-plot]
"""
import argparse
import os
import sys
import time

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

import mortar1d3d as m13
from mortar1d3d._config import cached_kernel_files
from mortar1d3d.model import Model
from mortar1d3d.physics.coupling import Coupling

# -- geometry: grid coordinates u in [0, CELLS]^3, mapped affinely to x = ORIGIN + A u ------------
CELLS = 4
A = 0.25 * np.array([[1.0, 0.25, 0.1], [-0.15, 0.9, 0.2], [0.1, -0.2, 1.1]])
ORIGIN = np.array([0.3, -0.2, 0.1])
# the beam's line in grid coordinates: u(t) = P + t Q. t = 0 hits node (1, 1, 1), t = 1 the
# interior edge {u_x = 2, u_y = 3}; Q has no two equal components, so the line lies in no
# grid or Kuhn plane and crosses them obliquely.
P = np.array([1.0, 1.0, 1.0])
Q = np.array([1.0, 2.0, 0.7])
T0, T1 = -0.4, 1.35
BEAM_ELEMENTS = 3
DIRECTION = np.array([0.3, -1.0, 0.6])          # direction f of the line load λ(s) f
LOADS = {"constant": (1.0, 0.0), "linear": (0.4, 1.3)}   # λ(τ) = a + b τ, τ ∈ [0, 1] along the beam
GAUSS_COUNTS = [1, 2, 3, 4, 6, 8, 12, 16, 24, 32, 48, 64]


def to_x(u):
    return ORIGIN + np.asarray(u) @ A.T


def solid_mesh(element="hexahedron"):
    """The affine image of the structured grid [0, CELLS]^3 (node numbering: lattice order)."""
    grid = m13.generate.box([0, 0, 0], [CELLS] * 3, (CELLS,) * 3, element)
    boundary = np.unique(np.concatenate([grid.point_sets[k] for k in grid.point_sets]))
    sets = {"boundary": boundary}
    return m13.SolidMesh(to_x(grid.points), grid.cells, point_sets=sets), grid.points


def beam_mesh(elements=BEAM_ELEMENTS):
    t = np.linspace(T0, T1, elements + 1)
    positions = to_x(P[None] + t[:, None] * Q[None])
    d = A @ Q
    tangents = np.tile(d / np.linalg.norm(d), (len(t), 1))
    cells = np.column_stack([np.arange(elements), np.arange(1, elements + 1)])
    return m13.BeamMesh.hermite(positions, tangents, cells), t


# -- exact consistent forces, independent of the library ------------------------------------------
def breakpoints(kind, t_nodes):
    """Every t in [T0, T1] where the line crosses a grid plane (and a Kuhn plane for tets)."""
    ts = list(t_nodes)
    for i in range(3):
        ts += [(k - P[i]) / Q[i] for k in range(CELLS + 1)]
    if kind == "tetra":
        for i in range(3):
            for j in range(i + 1, 3):
                for k in range(-CELLS, CELLS + 1):
                    ts.append((k - (P[i] - P[j])) / (Q[i] - Q[j]))
    ts = np.array([t for t in ts if T0 <= t <= T1])
    ts = np.sort(ts)
    return ts[np.concatenate([[True], np.diff(ts) > 1e-14])]


def node_id(ijk):
    n = CELLS + 1
    return int(ijk[0] + n * ijk[1] + n * n * ijk[2])


def global_basis(kind, u, cell):
    """(node ids, values) of the nonzero global P1/Q1 functions at grid point u in grid cell ``cell``."""
    y = u - cell
    if kind == "hexahedron":
        ids, vals = [], []
        for c in np.ndindex(2, 2, 2):
            w = np.prod([y[a] if c[a] else 1.0 - y[a] for a in range(3)])
            ids.append(node_id(cell + np.array(c)))
            vals.append(w)
        return ids, vals
    # Freudenthal (Kuhn) simplex of the ordering y_s0 >= y_s1 >= y_s2: vertices walk the unit
    # steps in that order; barycentric weights are differences of the sorted coordinates
    order = np.argsort(-y, kind="stable")
    ys = y[order]
    weights = [1.0 - ys[0], ys[0] - ys[1], ys[1] - ys[2], ys[2]]
    vertex = cell.copy()
    ids = [node_id(vertex)]
    for a in order:
        vertex = vertex.copy()
        vertex[a] += 1
        ids.append(node_id(vertex))
    return ids, weights


def hermite(eta, L):
    return np.array([(2 - 3 * eta + eta ** 3) / 4, L / 8 * (1 - eta - eta ** 2 + eta ** 3),
                     (2 + 3 * eta - eta ** 3) / 4, L / 8 * (-1 - eta + eta ** 2 + eta ** 3)])


def exact_forces(kind, a, b, t_nodes, n_solid_nodes, weight=lambda t: 1.0):
    """Consistent nodal forces of the line load (a + b τ) f: solid (n_S, 3) = −∫λ N_a ds ⊗ f,
    beam (n_beam_nodes, 6) = ∫λ [H1, H2; H3, H4] ds ⊗ f (position and tangent DOFs)."""
    speed = np.linalg.norm(A @ Q)                       # ds/dt
    x, w = np.polynomial.legendre.leggauss(6)           # exact up to degree 11 (≤ 4 needed)
    cuts = breakpoints(kind, t_nodes)
    fs = np.zeros(n_solid_nodes)
    fb = np.zeros((len(t_nodes), 2))
    for ta, tb in zip(cuts[:-1], cuts[1:]):
        tm = 0.5 * (ta + tb)
        cell = np.minimum(np.floor(P + tm * Q).astype(int), CELLS - 1)
        e = min(np.searchsorted(t_nodes, tm) - 1, len(t_nodes) - 2)
        L = speed * (t_nodes[e + 1] - t_nodes[e])
        for xg, wg in zip(x, w):
            t = tm + 0.5 * (tb - ta) * xg
            ds = 0.5 * (tb - ta) * wg * speed
            lam = a + b * (t - T0) / (T1 - T0)
            ids, vals = global_basis(kind, P + t * Q, cell)
            for i, v in zip(ids, vals):
                fs[i] -= lam * v * ds
            eta = 2 * (t - t_nodes[e]) / (t_nodes[e + 1] - t_nodes[e]) - 1
            H = hermite(eta, L)
            fb[e] += lam * ds * H[:2]
            fb[e + 1] += lam * ds * H[2:]
    beam = np.concatenate([fb[:, :1, None] * DIRECTION, fb[:, 1:, None] * DIRECTION], axis=1).reshape(-1, 6)
    return fs[:, None] * DIRECTION[None], beam


def lm_vector(a, b, t_nodes):
    """LM nodal values of λ(τ) f (line2: the beam nodes)."""
    tau = (t_nodes - T0) / (T1 - T0)
    return ((a + b * tau)[:, None] * DIRECTION[None]).ravel()


def force_errors(ops, kind, a, b, t_nodes, exact=None):
    """Relative max errors of −Mᵀλ and Dᵀλ against the exact consistent forces."""
    fs, fb = exact if exact is not None else exact_forces(kind, a, b, t_nodes, ops.M.shape[1] // 3)
    lam = lm_vector(a, b, t_nodes)
    solid = -(ops.M.T @ lam).reshape(-1, 3)
    beam = (ops.D.T @ lam).reshape(-1, 6)
    return (np.abs(solid - fs).max() / np.abs(fs).max(), np.abs(beam - fb).max() / np.abs(fb).max())


def force_patch_test():
    """{(element, load, integration, n_gauss): (solid error, beam error)}"""
    beams, t_nodes = beam_mesh()
    rows = {}
    for kind in ("hexahedron", "tetra"):
        solid, _ = solid_mesh(kind)
        exact = {name: exact_forces(kind, a, b, t_nodes, solid.n_nodes) for name, (a, b) in LOADS.items()}
        ops = m13.assemble_mortar(beams, solid, integration="segment", n_gauss=6)
        for name, (a, b) in LOADS.items():
            rows[(kind, name, "segment", 6)] = force_errors(ops, kind, a, b, t_nodes, exact[name])
        for n in GAUSS_COUNTS:
            ops = m13.assemble_mortar(beams, solid, integration="element", n_gauss=n)
            for name, (a, b) in LOADS.items():
                rows[(kind, name, "element", n)] = force_errors(ops, kind, a, b, t_nodes, exact[name])
    return rows


# -- displacement patch test ------------------------------------------------------------------------
G_AFFINE = np.array([[0.3, -0.1, 0.2], [0.05, -0.2, 0.1], [0.15, 0.25, -0.1]])
C_AFFINE = np.array([0.1, -0.3, 0.2])


def affine(x):
    return C_AFFINE + np.asarray(x) @ G_AFFINE.T


def displacement_patch_test(elements=("hexahedron", "tetra", "hexahedron20", "hexahedron27", "tetra10")):
    """max |D d_B − M d_S| / max|D q_B| per (element, integration, lm), and the Gauss-point gap."""
    beams, _ = beam_mesh()
    d_B = np.hstack([affine(beams.positions), beams.tangents @ G_AFFINE.T]).ravel()
    rows = {}
    for kind in elements:
        solid, _ = solid_mesh(kind)
        d_S = affine(solid.points).ravel()
        for integration in ("segment", "element"):
            for lm in ("line2", "line3", "line4"):
                ops = m13.assemble_mortar(beams, solid, integration=integration, n_gauss=3, lm=lm)
                scale = np.abs(ops.D @ d_B).max()
                rows[(kind, "mortar", integration, lm)] = np.abs(ops.D @ d_B - ops.M @ d_S).max() / scale
            n_S = 3 * solid.n_nodes
            coupling = Coupling(ops, beams, solid, n_S, n_S + beams.n_centreline_dofs, constraint="gauss_point")
            gap = coupling.G @ np.concatenate([d_S, d_B])
            rows[(kind, "gauss_point", integration, "-")] = np.abs(gap).max() / np.abs(d_S).max()
    return rows


# -- boundary-value patch test ----------------------------------------------------------------------
def boundary_value_patch_test(kind="hexahedron", integration="segment", n_gauss=6, load=(1.0, 0.5)):
    """Solve the patch problem of the module docstring; returns a dict of errors and fields."""
    solid, _ = solid_mesh(kind)
    beams, t_nodes = beam_mesh()
    E = 100.0
    scene = m13.Scene(solid={"mesh": solid, "material": {"model": "linear_elastic", "E": E, "nu": 0.3}},
                      beams=[{"mesh": beams, "section": {"EA": 5.0, "EI": 0.02}}],
                      coupling={"integration": integration, "enforcement": "lagrange", "n_gauss": n_gauss},
                      dirichlet=[{"on": "solid:boundary"}, {"on": "beam:0:start"}, {"on": "beam:0:end"}],
                      analysis={"kinematics": "linear"})
    model = Model(scene).prepare()
    n = model.n_displacement_dofs
    g = model.groups[0]
    exact = np.zeros(model.n_unknowns)
    exact[: 3 * solid.n_nodes] = affine(solid.points).ravel()
    exact[g.dof_offset: n] = np.hstack([affine(beams.positions), beams.tangents @ G_AFFINE.T]).ravel()
    # external loads: q f on the beam, −q f on the solid, both exactly integrated
    a, b = load
    fs, fb = exact_forces(kind, a, b, t_nodes, solid.n_nodes)
    f = np.zeros(model.n_unknowns)
    f[: 3 * solid.n_nodes] = fs.ravel()         # exact_forces gives −∫ q N_a: the solid's −q load
    f[g.dof_offset: n] = fb.ravel()
    _, K = model.residual(np.zeros(model.n_unknowns), 1.0)
    fixed, free = model.fixed, model.free
    z = np.zeros(model.n_unknowns)
    z[fixed] = exact[fixed]
    rhs = f[free] - K[free][:, fixed] @ z[fixed]
    z[free] = spla.spsolve(sp.csc_matrix(K[free][:, free]), rhs)
    u_S = z[: 3 * solid.n_nodes].reshape(-1, 3)
    u_B = z[g.dof_offset: n].reshape(-1, 6)[:, :3]
    lam = g.coupling.line_load(z[:n], z[n:])
    lam_exact = lm_vector(a, b, t_nodes).reshape(-1, 3)
    scale_u = np.abs(exact[: 3 * solid.n_nodes]).max()
    solid_error = np.abs(u_S - exact[: 3 * solid.n_nodes].reshape(-1, 3))
    return {"solid": solid_error.max() / scale_u,
            "beam": np.abs(u_B - affine(beams.positions)).max() / scale_u,
            "lambda": np.abs(lam - lam_exact).max() / np.abs(lam_exact).max(),
            "mesh": solid, "displacement": u_S, "error": solid_error, "beams": beams}


# -- output -------------------------------------------------------------------------------------------
def plot(rows, path):
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print("matplotlib is not installed: no plot (pip install matplotlib)")
        return False
    fig, ax = plt.subplots(figsize=(6.4, 4.4))
    styles = {"hexahedron": "o-", "tetra": "s--"}
    for kind in ("hexahedron", "tetra"):
        for load in LOADS:
            e = [max(rows[(kind, load, "element", n)][0], 1e-17) for n in GAUSS_COUNTS]
            ax.loglog(GAUSS_COUNTS, e, styles[kind], label=f"element-based, {kind}, {load} λ",
                      alpha=1.0 if load == "constant" else 0.6)
            s = max(rows[(kind, load, "segment", 6)][0], 1e-17)
            ax.axhline(s, color="grey", lw=0.8, ls=":")
    ax.text(GAUSS_COUNTS[0], 3e-16, "segment-based (6 points per segment): round-off", fontsize=8, va="bottom")
    ax.set_xlabel("Gauss points per beam element (element-based)")
    ax.set_ylabel("max |−Mᵀλ − exact| / max |exact|")
    ax.set_title("Force patch test: consistent solid nodal forces")
    ax.set_ylim(1e-17, 1)
    ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=130)
    plt.close(fig)
    return True


def run_time_line(seconds, compiled):
    """The closing line: the run time, and whether it includes compiling kernels (``compiled``: the
    number of kernels Numba compiled and cached during the run, 0 when all were loaded)."""
    note = (f"including Numba compilation of {compiled} kernels on a cold cache" if compiled
            else "kernels loaded from the cache")
    return f"run time {seconds:.1f} s ({note})"


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--out", default="results/patch_test")
    parser.add_argument("--no-plot", action="store_true")
    args = parser.parse_args(argv)
    os.makedirs(args.out, exist_ok=True)
    start = time.perf_counter()
    compiled_before = cached_kernel_files()

    print("1. force patch test: relative max error of the coupling forces (line2 LM, 3 beam elements)")
    rows = force_patch_test()
    print(f"  {'mesh':10s} {'λ':8s} {'integration':12s} {'n_gauss':>7s} {'−Mᵀλ (solid)':>14s} {'Dᵀλ (beam)':>12s}")
    for (kind, load, integration, n), (es, eb) in rows.items():
        print(f"  {kind:10s} {load:8s} {integration:12s} {n:7d} {es:14.2e} {eb:12.2e}")

    print("\n2. displacement patch test: max |D d_B − M d_S| / max |D d_B| for a linear field")
    disp = displacement_patch_test()
    for (kind, constraint, integration, lm), e in disp.items():
        print(f"  {kind:13s} {constraint:12s} {integration:8s} {lm:6s} {e:9.2e}")

    print("\n3. boundary-value patch test (Lagrange multipliers, linear kinematics): relative max error")
    print(f"  {'mesh':10s} {'integration':12s} {'n_gauss':>7s} {'u_solid':>10s} {'u_beam':>10s} {'λ':>10s}")
    bvp = {}
    for kind in ("hexahedron", "tetra"):
        for integration, n in (("segment", 6), ("element", 6), ("element", 32)):
            out = boundary_value_patch_test(kind, integration, n)
            bvp[(kind, integration, n)] = out
            print(f"  {kind:10s} {integration:12s} {n:7d} {out['solid']:10.2e} {out['beam']:10.2e} {out['lambda']:10.2e}")

    from mortar1d3d.io import write_beams, write_solid
    for (kind, integration, n), out in bvp.items():
        write_solid(os.path.join(args.out, f"bvp_{kind}_{integration}{n}.vtu"), out["mesh"],
                    point_data={"displacement": out["displacement"], "error": out["error"]})
    write_beams(os.path.join(args.out, "beam.vtu"), bvp[("hexahedron", "segment", 6)]["beams"])
    if not args.no_plot and plot(rows, os.path.join(args.out, "patch_test.png")):
        print(f"\nplot: {os.path.join(args.out, 'patch_test.png')}")
    print(f"VTU: {args.out}/bvp_*.vtu, beam.vtu")
    print(run_time_line(time.perf_counter() - start, cached_kernel_files() - compiled_before))
    return rows, disp, bvp


if __name__ == "__main__":
    main(sys.argv[1:])
