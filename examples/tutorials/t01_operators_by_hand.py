"""Tutorial 1: D, M and κ by hand on one element.

One straight beam element inside one hexahedron, small enough to integrate with pencil and paper.
The script assembles the mortar operators with the library and prints them next to the numbers
worked out by hand on the page "Theory for students" (docs/theory.md), so you can check each
entry yourself.

The set-up
----------
* Solid: one trilinear hexahedron (``hexahedron``, 8 nodes) filling the unit cube [0, 1]³.
* Beam: one Hermite element along x at y = 1/4, z = 1/2, from x = 0 to x = 1 (length L = 1),
  so the whole beam lies inside the cube.
* Lagrange multipliers: ``line2``, i.e. two linear functions Φ1 = 1 − x, Φ2 = x along the beam.

What you should find (the integrals are over the arc length s = x):

* κ_j = ∫ Φ_j ds = 1/2 for both multiplier nodes.
* D couples multipliers and beam DOFs: ∫ Φ1 H1 ds = 7/20, ∫ Φ1 H2 ds = 1/20 (a tangent DOF),
  ∫ Φ1 H3 ds = 3/20, ∫ Φ1 H4 ds = −1/30, and mirrored for Φ2.
* M couples multipliers and solid nodes: N_a(x, 1/4, 1/2) = X_a(x) · Y_a · Z_a with
  Y_a = 3/4 (nodes at y = 0) or 1/4 (y = 1) and Z_a = 1/2, and ∫ Φ1 (1 − x) dx = 1/3,
  ∫ Φ1 x dx = 1/6. So M[Φ1, node (0, 0, 0)] = 1/3 · 3/4 · 1/2 = 1/8.

A second beam that sticks half out of the cube (x from −1/2 to 1/2) shows that only the embedded
part is integrated: κ = (1/8, 3/8), whose sum is the embedded length 1/2.

Run it::

    python examples/tutorials/t01_operators_by_hand.py
"""
from fractions import Fraction

import numpy as np

import mortar1d3d as m13


def one_hex():
    """The unit cube as one hex8 in VTK node order (bottom face z = 0 anticlockwise, then top)."""
    points = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0],
                       [0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1]], dtype=float)
    return m13.SolidMesh(points, {"hexahedron": np.array([[0, 1, 2, 3, 4, 5, 6, 7]])})


def straight_beam(start, end):
    """One Hermite beam element from ``start`` to ``end`` (unit tangents along the chord)."""
    start, end = np.asarray(start, float), np.asarray(end, float)
    t = (end - start) / np.linalg.norm(end - start)
    return m13.BeamMesh.hermite([start, end], [t, t], [[0, 1]])


def scalar_blocks(ops):
    """The scalar matrices behind the 3 × 3 identity blocks: row 3 j + i, column 3 a + i (or 6 k + i
    for Hermite DOFs) all carry the same number for i = 0, 1, 2; take component x (i = 0)."""
    D = ops.D.toarray()[0::3, :]          # rows of LM node j, component x
    M = ops.M.toarray()[0::3, 0::3]       # columns of solid node a, component x
    # Hermite node k has 6 DOFs [r_x, r_y, r_z, t_x, t_y, t_z]: keep r_x and t_x per node
    D = D[:, [0, 3, 6, 9]]                # columns: r1, t1, r2, t2  (H1, H2, H3, H4)
    return D, M


def run(verbose=True):
    solid = one_hex()
    beam = straight_beam([0, 0.25, 0.5], [1, 0.25, 0.5])
    ops = m13.assemble_mortar(beam, solid, integration="segment", lm="line2", n_gauss=6)
    D, M = scalar_blocks(ops)

    # the same numbers by hand (see the docstring); Fraction keeps them exact
    f = Fraction
    D_hand = np.array([[f(7, 20), f(1, 20), f(3, 20), f(-1, 30)],
                       [f(3, 20), f(1, 30), f(7, 20), f(-1, 20)]])
    X = {0: (f(1, 3), f(1, 6)), 1: (f(1, 6), f(1, 3))}            # ∫ Φ_j (1 − x), ∫ Φ_j x
    M_hand = np.empty((2, 8), dtype=object)
    for a, (x, y, z) in enumerate(solid.points):
        for j in (0, 1):
            M_hand[j, a] = X[j][int(x)] * (f(3, 4) if y == 0 else f(1, 4)) * f(1, 2)
    kappa_hand = np.array([f(1, 2), f(1, 2)])

    # half of a second beam outside the cube: only x in [0, 1/2] is coupled
    half = m13.assemble_mortar(straight_beam([-0.5, 0.25, 0.5], [0.5, 0.25, 0.5]), solid)

    out = {"D": D, "M": M, "kappa": ops.kappa.copy(),
           "D_error": np.abs(D - D_hand.astype(float)).max(),
           "M_error": np.abs(M - M_hand.astype(float)).max(),
           "kappa_error": np.abs(ops.kappa - kappa_hand.astype(float)).max(),
           "embedded_length": ops.embedded_length, "constraint_residual": ops.constraint_residual,
           "half_kappa": half.kappa.copy(), "half_embedded_length": half.embedded_length}
    if verbose:
        np.set_printoptions(precision=6, suppress=True)
        print("κ (library):", ops.kappa, "  by hand: [1/2, 1/2]")
        print("D, columns H1 (r1), H2 (t1), H3 (r2), H4 (t2):")
        print(D)
        print("  by hand:", [[str(v) for v in row] for row in D_hand])
        print("M, columns the 8 solid nodes in VTK order:")
        print(M)
        print("  by hand:", [[str(v) for v in row] for row in M_hand])
        print(f"largest difference to the hand values: D {out['D_error']:.1e}, M {out['M_error']:.1e}, "
              f"κ {out['kappa_error']:.1e}")
        print(f"certificates: embedded length {ops.embedded_length:.15f} of {ops.beam_length:.15f}, "
              f"constraint residual {ops.constraint_residual:.1e}")
        print(f"half-embedded beam: κ = {half.kappa}, embedded length {half.embedded_length:.15f} "
              f"(by hand: [1/8, 3/8], 1/2)")
    return out


if __name__ == "__main__":
    run()
