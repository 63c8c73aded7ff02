"""Tutorial 6: a mesh from a file, with named sets (gmsh physical groups, meshio point sets).

Meshes made elsewhere come with names for their parts: gmsh calls them *physical groups*, Abaqus
*node sets*, and so on. A scene refers to a solid mesh's node sets as ``solid:<name>``. mortar1d3d
takes them from meshio's ``point_sets`` of the file, which is exactly what some formats give and not
what others give:

* an **Abaqus** ``.inp`` file's node sets (``*NSET``) arrive as ``point_sets``: a scene file can
  name them directly (``on = "solid:clamped"``);
* a **gmsh** ``.msh`` file's physical groups arrive as cell data (``gmsh:physical``, one tag per
  cell) with their names in ``field_data``; they have to be turned into point sets first, in a few
  lines of Python (``gmsh_point_sets`` below).

To stay self-contained (no gmsh needed), the script writes both files itself from a generated
box: a hex8 block 1 × 0.2 × 0.2 whose end faces are quad cells in the physical groups "clamped"
and "loaded". It then reads them back as a user would, solves a fibre-reinforced block clamped on
"clamped" and pulled on "loaded", and checks that the result is the same as with the generated
box's own sets ``solid:x_min`` / ``solid:x_max``.

Run it::

    python examples/tutorials/t06_named_sets.py [--out results/tutorials]
"""
import warnings
from pathlib import Path

import meshio
import numpy as np

import mortar1d3d as m13
from _tutorial import main

BOX, CELLS = [[0, 0, 0], [1, 0.2, 0.2]], (8, 2, 2)
#: the six faces of a VTK hexahedron as local node numbers
HEX_FACES = [[0, 3, 7, 4], [1, 2, 6, 5], [0, 1, 5, 4], [3, 2, 6, 7], [0, 1, 2, 3], [4, 5, 6, 7]]


def end_face_quads(solid, nodes):
    """Quad cells (k, 4): the faces of hexahedra all of whose nodes are in ``nodes``."""
    hexes = solid.cells["hexahedron"]
    inside = np.isin(hexes, nodes)
    return np.array([hexes[c, f] for c in range(len(hexes)) for f in HEX_FACES if inside[c, f].all()])


def write_files(out):
    """A gmsh 2.2 file with physical groups and an Abaqus file with node sets, of the same block."""
    box = m13.generate.box(*BOX, CELLS, "hexahedron")
    clamped = end_face_quads(box, box.point_sets["x_min"])
    loaded = end_face_quads(box, box.point_sets["x_max"])
    hexes = box.cells["hexahedron"]
    gmsh = meshio.Mesh(
        box.points, [("hexahedron", hexes), ("quad", np.vstack([clamped, loaded]))],
        cell_data={"gmsh:physical": [np.full(len(hexes), 1), np.r_[np.full(len(clamped), 2), np.full(len(loaded), 3)]],
                   "gmsh:geometrical": [np.full(len(hexes), 1), np.r_[np.full(len(clamped), 1), np.full(len(loaded), 2)]]},
        field_data={"block": np.array([1, 3]), "clamped": np.array([2, 2]), "loaded": np.array([3, 2])})
    meshio.write(out / "block.msh", gmsh, file_format="gmsh22", binary=False)
    abaqus = meshio.Mesh(box.points, [("hexahedron", hexes)],
                         point_sets={"clamped": box.point_sets["x_min"], "loaded": box.point_sets["x_max"]})
    meshio.write(out / "block.inp", abaqus)
    return out / "block.msh", out / "block.inp"


def gmsh_point_sets(mesh):
    """Add a point set per physical group of a meshio mesh read from gmsh: the nodes of its cells."""
    for name, (tag, _dimension) in mesh.field_data.items():
        nodes = [block.data[mesh.cell_data["gmsh:physical"][k] == tag].ravel() for k, block in enumerate(mesh.cells)]
        mesh.point_sets[name] = np.unique(np.concatenate(nodes))
    return mesh


def scene(mesh, clamped, loaded):
    """The block with one stiff fibre along its axis, clamped on one set and pulled on the other."""
    return m13.Scene(
        solid={"mesh": mesh, "material": {"model": "linear_elastic", "E": 1e4, "nu": 0.3}},
        beams=[{"curve": {"line": [[0, 0.1, 0.1], [1, 0.1, 0.1]]}, "elements": 8, "model": "truss",
                "section": {"EA": 50.0}}],
        dirichlet=[{"on": clamped}],
        load=[{"type": "traction", "on": loaded, "value": [1.0, 0.0, -0.5]}],
        analysis={"kinematics": "linear"})


def run(out=None, verbose=True):
    out = Path(out or "results/tutorials") / "named_sets"
    out.mkdir(parents=True, exist_ok=True)
    msh, inp = write_files(out)

    # 1. gmsh: physical groups -> point sets, then a SolidMesh (the quads are skipped, with a warning)
    mesh = gmsh_point_sets(meshio.read(msh))
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        solid = m13.SolidMesh.from_meshio(mesh)
    skipped = [str(w.message) for w in caught]
    from_gmsh = m13.solve(scene(solid, "solid:clamped", "solid:loaded"))

    # 2. Abaqus: the node sets are point sets already; the scene names the file like a TOML file would
    from_abaqus = m13.solve(scene(str(inp), "solid:clamped", "solid:loaded"))

    # 3. the generated box with its own face sets
    reference = m13.solve(scene({"box": BOX, "cells": list(CELLS)}, "solid:x_min", "solid:x_max"))

    u_ref = reference.solid_displacement
    result = {"sets": {k: len(v) for k, v in mesh.point_sets.items()}, "skipped": skipped,
              "gmsh_difference": np.abs(from_gmsh.solid_displacement - u_ref).max() / np.abs(u_ref).max(),
              "abaqus_difference": np.abs(from_abaqus.solid_displacement - u_ref).max() / np.abs(u_ref).max(),
              "tip": u_ref[:, 2].min()}
    if verbose:
        print(f"wrote {msh.name} and {inp.name} to {out}")
        print(f"gmsh physical groups as point sets: {result['sets']}")
        print(f"SolidMesh.from_meshio warned: {skipped[0] if skipped else 'nothing'}")
        print(f"largest vertical displacement {result['tip']:.6e}")
        print(f"difference to the generated box's sets: gmsh {result['gmsh_difference']:.1e}, "
              f"Abaqus {result['abaqus_difference']:.1e} (relative)")
    return result


if __name__ == "__main__":
    main(run, __doc__, plots=False)
