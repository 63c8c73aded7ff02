"""Tutorial 5: D and M in your own solver, with plain numpy and scipy.

Say you have your own finite element code for the solid and for the beams, and want only the
coupling from mortar1d3d. This script plays that role: it builds a linear elastic hex8 stiffness
and a truss stiffness *by hand* (about 40 lines, below), takes D, M and κ from
``mortar1d3d.assemble_mortar``, and couples them

* with a penalty:    (K + ε Bᵀ diag(κ)⁻¹ B) u = f,            B = [−M, D];
* with Lagrange multipliers:  [[K, Bᵀ], [B, 0]] [u; λ] = [f; 0].

The DOF layouts are those of mortar1d3d (docs/conventions.md §2): solid node a has DOFs 3a + i,
a ``line`` beam node k has 3k + i, and row 3j + i of D and M belongs to multiplier node j. So
u = [u_S | u_B] and B acts on it directly. κ is per multiplier node: each of its entries scales
the three rows 3j, 3j + 1, 3j + 2.

The scene: a bar 1 × 0.2 × 0.2 of 10 × 2 × 2 hex8 with a stiff truss along it, clamped at x = 0
(the solid's face; the coupling holds the truss), pulled at x = 1 by point forces on the end face's nodes. The
recipe's displacements are compared with ``mortar1d3d.solve`` of the same scene: they agree to
4e-11 (penalty; the penalty's conditioning) and 1e-12 (Lagrange multipliers), relative to the
largest displacement.

Run it::

    python examples/tutorials/t05_own_solver.py
"""
import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

import mortar1d3d as m13

E, NU = 1.0e4, 0.3                    # solid
EA = 1.0e3                            # truss
PENALTY = 1.0e3 * E
LOAD = np.array([1.0, 0.0, -0.5]) * 1e-3     # on every node of the end face x = 1
BOX, CELLS, TRUSS = [[0, 0, 0], [1, 0.2, 0.2]], (10, 2, 2), [[0, 0.1, 0.1], [1, 0.1, 0.1]]


# -- "your own code": a hex8 stiffness and a truss stiffness ----------------------------------------
def hex8_stiffness(points, cells, E, nu):
    """Global (3 n, 3 n) linear elastic stiffness of trilinear hexahedra (VTK node order, 2×2×2 Gauss)."""
    lam, mu = E * nu / ((1 + nu) * (1 - 2 * nu)), E / (2 * (1 + nu))
    C = np.zeros((6, 6))
    C[:3, :3] = lam
    C[np.arange(3), np.arange(3)] += 2 * mu
    C[np.arange(3, 6), np.arange(3, 6)] = mu
    corners = np.array([[-1, -1, -1], [1, -1, -1], [1, 1, -1], [-1, 1, -1],
                        [-1, -1, 1], [1, -1, 1], [1, 1, 1], [-1, 1, 1]], dtype=float)
    g = 1 / np.sqrt(3)
    rows, cols, vals = [], [], []
    for cell in cells:
        X = points[cell]
        Ke = np.zeros((24, 24))
        for q in np.array(np.meshgrid([-g, g], [-g, g], [-g, g])).reshape(3, -1).T:
            # dN/dξ of the 8 trilinear functions N_a = Π (1 + ξ_i c_ai) / 8
            f = 1 + corners * q
            dN = np.stack([corners[:, i] * np.prod(np.delete(f, i, axis=1), axis=1) / 8 for i in range(3)], axis=1)
            J = X.T @ dN
            dNdx = dN @ np.linalg.inv(J)
            Bq = np.zeros((6, 24))
            for a in range(8):
                bx, by, bz = dNdx[a]
                Bq[:, 3 * a:3 * a + 3] = [[bx, 0, 0], [0, by, 0], [0, 0, bz], [by, bx, 0], [0, bz, by], [bz, 0, bx]]
            Ke += Bq.T @ C @ Bq * np.linalg.det(J)
        dofs = (3 * cell[:, None] + np.arange(3)).ravel()
        rows.append(np.repeat(dofs, 24))
        cols.append(np.tile(dofs, 24))
        vals.append(Ke.ravel())
    n = 3 * len(points)
    return sp.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(n, n))


def truss_stiffness(positions, elements, EA):
    """Global (3 n, 3 n) stiffness of 2-node bars: EA/L (e eᵀ) blocks, e the unit direction."""
    n = 3 * len(positions)
    K = sp.lil_matrix((n, n))
    for i, j in elements:
        d = positions[j] - positions[i]
        L = np.linalg.norm(d)
        k = EA / L * np.outer(d / L, d / L)
        for a, b, s in ((i, i, 1), (j, j, 1), (i, j, -1), (j, i, -1)):
            K[3 * a:3 * a + 3, 3 * b:3 * b + 3] += s * k
    return K.tocsr()


# -- the coupling from mortar1d3d ------------------------------------------------------------------
def recipe(enforcement):
    solid = m13.generate.box(*BOX, CELLS, "hexahedron")
    nodes = np.linspace(*np.array(TRUSS), CELLS[0] + 1)
    beams = m13.BeamMesh.lagrange(nodes, np.column_stack([np.arange(CELLS[0]), np.arange(1, CELLS[0] + 1)]))
    ops = m13.assemble_mortar(beams, solid, integration="segment", lm="line2")

    n_s, n_b = 3 * solid.n_nodes, 3 * beams.positions.shape[0]
    K = sp.block_diag([hex8_stiffness(solid.points, solid.cells["hexahedron"], E, NU),
                       truss_stiffness(beams.positions, beams.elements, EA)]).tocsr()
    B = sp.hstack([-ops.M, ops.D]).tocsr()                    # B u = D u_B − M u_S
    f = np.zeros(n_s + n_b)
    end = solid.point_sets["x_max"]
    f[(3 * end[:, None] + np.arange(3)).ravel()] = np.tile(LOAD, len(end))
    # the solid's face x = 0 is clamped; the truss is held by the coupling alone (fixing its first
    # node too would make that node's constraint rows act on fixed DOFs only: a zero row of B)
    fixed = (3 * solid.point_sets["x_min"][:, None] + np.arange(3)).ravel()
    free = np.setdiff1d(np.arange(n_s + n_b), fixed)

    if enforcement == "penalty":
        kappa = np.repeat(ops.kappa, 3)                      # one κ_j for the rows 3j, 3j+1, 3j+2
        scale = np.divide(1.0, kappa, out=np.zeros_like(kappa), where=kappa > 0)
        A = (K + PENALTY * B.T @ sp.diags(scale) @ B).tocsr()
        u = np.zeros(n_s + n_b)
        u[free] = spla.spsolve(A[free][:, free].tocsc(), f[free])
    else:
        used = np.flatnonzero(np.repeat(ops.kappa, 3) > 0)     # rows of multiplier nodes that touch the solid
        Bf = B[used][:, free]
        A = sp.bmat([[K[free][:, free], Bf.T], [Bf, None]]).tocsc()
        x = spla.spsolve(A, np.concatenate([f[free], np.zeros(len(used))]))
        u = np.zeros(n_s + n_b)
        u[free] = x[:len(free)]
    return u[:n_s].reshape(-1, 3), u[n_s:].reshape(-1, 3), ops


def library(enforcement):
    """The same problem through mortar1d3d's own model and solve."""
    coupling = {"integration": "segment", "lm": "line2", "enforcement": enforcement}
    if enforcement == "penalty":
        coupling["penalty"] = PENALTY
    scene = m13.Scene(
        solid={"mesh": {"box": BOX, "cells": list(CELLS)}, "material": {"model": "linear_elastic", "E": E, "nu": NU}},
        beams=[{"curve": {"line": TRUSS}, "elements": CELLS[0], "model": "truss", "section": {"EA": EA}}],
        coupling=coupling, dirichlet=[{"on": "solid:x_min"}],
        load=[{"type": "point", "on": "solid:x_max", "value": LOAD.tolist()}], analysis={"kinematics": "linear"})
    result = m13.solve(scene)
    return result.solid_displacement, result.beam_displacement


def run(verbose=True):
    out = {}
    for enforcement in ("penalty", "lagrange"):
        u_s, u_b, ops = recipe(enforcement)
        v_s, v_b = library(enforcement)
        out[enforcement] = {"tip": u_b[-1].copy(), "difference": max(np.abs(u_s - v_s).max(), np.abs(u_b - v_b).max())
                            / np.abs(v_s).max()}
        if verbose:
            print(f"{enforcement:>8}: truss tip displacement {u_b[-1]}, largest difference to "
                  f"mortar1d3d.solve {out[enforcement]['difference']:.1e} (relative)")
    out["D_shape"], out["M_shape"] = ops.D.shape, ops.M.shape
    if verbose:
        print(f"D {ops.D.shape}, M {ops.M.shape}, κ {ops.kappa.shape}")
    return out


if __name__ == "__main__":
    run()
