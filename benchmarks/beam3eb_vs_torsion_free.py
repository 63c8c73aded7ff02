"""4C's beam3eb element against the library's torsion_free beam on 4C's line3 bar, with the beam mesh refined.

The bar of 4C's ``beam3eb_static_beam_to_solid_volume_meshtying_mortar_penalty_line3`` input file
(10 HEX27, a line-loaded fibre of 7 BEAM3EB elements, mortar line3 penalty) is solved with its
beam meshed by n = 7, 14, ... elements, once with each beam model. Both converge to the same
solution; the table gives each one's distance from the finest ``beam3eb`` solution and from 4C's
reference values (which belong to n = 7). Usage: ``python benchmarks/beam3eb_vs_torsion_free.py``
(needs the 4C input folder, see docs/fourc.md).
"""
import sys
import warnings
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

NAME = "beam3eb_static_beam_to_solid_volume_meshtying_mortar_penalty_line3.4C.yaml"


def solve_with(path, model, n):
    """(node id -> displacement) of 4C's result nodes, beam meshed by n elements of ``model``."""
    import mortar1d3d as m13
    from mortar1d3d.io.fourc import read_4c, scene_from_4c
    fc = read_4c(path)
    scene, nodes = scene_from_4c(fc)
    mesh = scene.beams[0]["mesh"]
    entry = {"curve": {"line": [mesh.positions[0], mesh.positions[-1]]}, "elements": n, "model": model,
             "section": dict(scene.beams[0]["section"])}
    scene.beams[0] = m13.Scene(beams=[entry]).beams[0]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        result = m13.solve(scene)
    out = {}
    for e in fc.results:
        if e.special or e.node in out:
            continue
        body, row = nodes[e.node]
        if body == "solid":
            out[e.node] = result.solid_displacement[row]
        else:     # a beam node of the file: the start of the beam (node 190) keeps row 0
            out[e.node] = result.beam_displacement[0 if row == 0 else row * n // (mesh.n_nodes - 1)]
    return out, fc


def main():
    from mortar1d3d.io.fourc import input_folder
    folder = input_folder(Path(__file__).resolve().parent.parent)
    if folder is None:
        print("no 4C input folder (see docs/fourc.md)")
        return 0
    path = folder / NAME
    sizes = (7, 14, 28, 56, 112)
    runs = {(m, n): solve_with(path, m, n)[0] for m in ("beam3eb", "torsion_free") for n in sizes}
    _, fc = solve_with(path, "beam3eb", 7)
    ref4c = {}
    for e in fc.results:
        if not e.special:
            ref4c.setdefault(e.node, np.zeros(3))["xyz".index(e.quantity[-1])] = e.value
    finest = runs[("beam3eb", sizes[-1])]
    print(f"| model | beam elements | max dev. from 4C | max dev. from beam3eb n={sizes[-1]} |")
    print("|---|---:|---:|---:|")
    for m in ("beam3eb", "torsion_free"):
        for n in sizes:
            u = runs[(m, n)]
            d4c = max(np.abs(u[k] - ref4c[k]).max() for k in ref4c)
            dfine = max(np.abs(u[k] - finest[k]).max() for k in finest)
            print(f"| {m} | {n} | {d4c:.2e} | {dfine:.2e} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
