"""Tutorial 8: a helical wire in a tube (a reinforced hose under internal pressure).

A curved beam needs the ``truss`` model (the torsion-free beam takes straight centrelines only),
and a curved body needs a mesh of its own. This script

1. builds a tube mesh by mapping a generated box in (ρ, θ, z) to x = ρ cos θ, y = ρ sin θ, z, and
   merging the nodes of the seam θ = 2π into those of θ = 0 (a mesh may not hold duplicate nodes);
   it names the node sets ``inner`` (ρ = r_inner) and ``bottom`` (z = 0);
2. winds a steel wire as a ``helix`` curve in the wall (ρ = 0.85): 4 turns over 80 % of the
   tube's length;
3. clamps the bottom, puts an internal ``pressure`` on the inner surface (positive pressure
   pushes into the body, i.e. outwards here), and solves with and without the wire.

It prints the certificates of the coupling (the whole wire lies in the wall: its embedded length
equals its length) and how much the wire reduces the radial expansion of the tube at mid-height.

Run it::

    python examples/tutorials/t08_helix_in_tube.py
"""
import argparse
import math

import numpy as np

import mortar1d3d as m13

R_INNER, R_OUTER, HEIGHT = 0.8, 1.0, 2.0
#: the wire's helix radius: inside the inner of the two element layers (ρ = 0.8 … 0.9), clear of
#: the layer face ρ = 0.9 also where its straight truss elements cut the curve's chords
R_WIRE = 0.85
E_RUBBER, NU = 1.0e3, 0.3
WIRE = {"E": 2.0e5, "radius": 0.01}
#: truss elements of the wire: not a multiple of the 24 sectors, so element ends and faces do not meet
ELEMENTS = 90


def tube(n_radial=2, n_around=24, n_height=8):
    """SolidMesh of the tube with point sets ``inner``, ``outer``, ``bottom``, ``top``."""
    box = m13.generate.box([R_INNER, 0, 0], [R_OUTER, 2 * math.pi, HEIGHT], (n_radial, n_around, n_height))
    rho, theta, z = box.points.T
    # the seam: nodes at θ = 2π are the nodes at θ = 0 with the same ρ and z
    on_seam = np.isclose(theta, 2 * math.pi)
    at_zero = np.flatnonzero(np.isclose(theta, 0.0))
    key = {(round(r, 12), round(h, 12)): i for i, r, h in zip(at_zero, rho[at_zero], z[at_zero])}
    target = np.arange(len(theta))
    target[on_seam] = [key[(round(r, 12), round(h, 12))] for r, h in zip(rho[on_seam], z[on_seam])]
    keep = ~on_seam
    renumber = np.cumsum(keep) - 1                        # new number of every kept node
    cells = renumber[target[box.cells["hexahedron"]]]
    points = np.column_stack([rho * np.cos(theta), rho * np.sin(theta), z])[keep]
    rho, z = rho[keep], z[keep]
    sets = {"inner": np.flatnonzero(np.isclose(rho, R_INNER)), "outer": np.flatnonzero(np.isclose(rho, R_OUTER)),
            "bottom": np.flatnonzero(np.isclose(z, 0.0)), "top": np.flatnonzero(np.isclose(z, HEIGHT))}
    return m13.SolidMesh(points, {"hexahedron": cells}, point_sets=sets)


def scene(solid, wire=True, pressure=1.0, elements=ELEMENTS):
    helix = {"centre": [0, 0, HEIGHT / 2], "axis": [0, 0, 1], "radius": R_WIRE,
             "length": 0.8 * HEIGHT, "turns": 4, "phase": 0.3}
    return m13.Scene(
        solid={"mesh": solid, "material": {"model": "linear_elastic", "E": E_RUBBER, "nu": NU}},
        beams=[{"curve": {"helix": helix}, "elements": elements, "model": "truss", "section": WIRE}] if wire else [],
        dirichlet=[{"on": "solid:bottom"}],
        load=[{"type": "pressure", "on": "solid:inner", "value": pressure}],
        analysis={"kinematics": "linear"})


def radial_expansion(result, solid):
    """Mean radial displacement of the outer surface's nodes at mid-height."""
    X = solid.points
    ring = solid.point_sets["outer"][np.isclose(X[solid.point_sets["outer"], 2], HEIGHT / 2)]
    radial = X[ring, :2] / np.linalg.norm(X[ring, :2], axis=1)[:, None]
    return float((result.solid_displacement[ring, :2] * radial).sum(axis=1).mean())


def run(verbose=True, **mesh):
    solid = tube(**mesh)
    with_wire = m13.solve(scene(solid, wire=True))
    without = m13.solve(scene(solid, wire=False))
    ops = with_wire.model.groups[0].operators
    turns, length, radius = 4, 0.8 * HEIGHT, R_WIRE
    result = {"nodes": solid.n_nodes, "elements": solid.n_elements,
              "helix_length": math.hypot(2 * math.pi * radius * turns, length),
              "beam_length": ops.beam_length, "embedded_length": ops.embedded_length,
              "constraint_residual": ops.constraint_residual, "segments": len(ops.segments),
              "expansion_with": radial_expansion(with_wire, solid), "expansion_without": radial_expansion(without, solid)}
    result["reduction"] = 1 - result["expansion_with"] / result["expansion_without"]
    if verbose:
        print(f"tube: {solid}")
        print(f"wire: helix of length {result['helix_length']:.6f}, as {ELEMENTS} truss elements {ops.beam_length:.6f}; "
              f"embedded {ops.embedded_length:.6f} in {len(ops.segments)} segments; "
              f"constraint residual {ops.constraint_residual:.1e}")
        print(f"radial expansion at mid-height: {result['expansion_without']:.6e} without the wire, "
              f"{result['expansion_with']:.6e} with it ({100 * result['reduction']:.1f} % less)")
    return result


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.parse_args()
    run()
