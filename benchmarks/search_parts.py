"""The parts of the search stage (the kernel input of ``assemble_mortar``) timed one by one.

    .venv/bin/python benchmarks/search_parts.py [--package CHECKOUT] [--repeats 40] [--n 20] [--fibres 1000]
                                                [--scene cube|hex8|hex27|tet10]

Scene ``fibre_cube(n, fibres, 20)`` (the benchmark cube by default, undistorted), or with ``--scene`` one
of ``newton_path.py``'s distorted cubes (hex8, hex27, tet10), 1 thread. Prints the best of
``--repeats`` calls of each part in ms: the solid frames (boxes, sizes, origins), the linearised
maps (with the one-to-one certificates of curved elements, in checkouts that compute them there
rather than on first use), the beam frames (coefficients and boxes), the candidate pairs, and,
where the checkout has them, the hull planes and the pairs they drop (``solid_hulls``,
``hull_pairs``; the planes of the elements the kernel input asks for: every element, or in a checkout
whose ``solid_hulls`` takes ``elements`` those of the box pairs), and their sum. The ``search`` stage of ``throughput.py`` is about that sum; this
says which part moved. To compare two versions run it alternately with ``--package`` naming each
checkout (as ``throughput.py``); the best of many calls moves little with the machine's load, but
alternate the runs anyway.
"""
import argparse
import inspect
import sys
import time

import numpy as np

from throughput import _package_root

# the package must be imported from the chosen checkout before anything imports it
sys.path.insert(0, str(_package_root(None)))

import numba  # noqa: E402

import mortar1d3d as m13  # noqa: E402
from mortar1d3d._schedule import workers  # noqa: E402
from mortar1d3d.geometry import projection, search  # noqa: E402


def best_ms(call, repeats):
    """Best wall time of ``repeats`` calls of ``call`` after one warm-up call, in ms."""
    call()
    times = []
    for _ in range(repeats):
        t = time.perf_counter()
        call()
        times.append(time.perf_counter() - t)
    return 1e3 * min(times)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--package", help="checkout whose package is measured (default: this one)")
    parser.add_argument("--repeats", type=int, default=40)
    parser.add_argument("--n", type=int, default=20)
    parser.add_argument("--fibres", type=int, default=1000)
    parser.add_argument("--scene", default="cube", choices=("cube", "hex8", "hex27", "tet10"),
                        help="cube: fibre_cube as generated (default); the others: newton_path.py's scenes "
                             "(distorted by 0.1 cells)")
    args = parser.parse_args(argv)
    numba.set_num_threads(1)
    if args.scene == "cube":
        beams, solid = m13.generate.fibre_cube(args.n, args.fibres, 20)
    else:
        from newton_path import scene
        beams, solid = scene(args.scene, args.n, args.fibres, 0.1)
    points = getattr(solid, "kernel_points", solid.points)      # older checkouts: no weights column
    boxes, size, origin = search.solid_frames(solid)
    table = np.empty((solid.n_elements, 5, 3))
    beam_boxes = search.beam_frames(beams)[2]
    parts = {
        "solid_frames": lambda: search.solid_frames(solid),
        "linear_maps": lambda: projection.linear_maps(points, solid.connectivity, solid.element_codes, origin,
                                                      size, table, workers()),
        "beam_frames": lambda: search.beam_frames(beams),
        "candidate_pairs": lambda: search.find_candidate_pairs(beam_boxes, boxes),
    }
    if hasattr(search, "solid_hulls"):
        hull = search.solid_hulls(points, solid.connectivity, solid.element_codes, origin, size)
        Q, beam_origin, beam_boxes, _ = search.beam_frames(beams)
        offsets, pair_solid = search.find_candidate_pairs(beam_boxes, boxes)
        # a checkout whose kernel input asks for the planes of its box pairs' elements only is timed so
        hulls_of = {}
        if "elements" in inspect.signature(search.solid_hulls).parameters:
            hulls_of["elements"] = pair_solid
        parts["solid_hulls"] = lambda: search.solid_hulls(points, solid.connectivity, solid.element_codes, origin,
                                                          size, **hulls_of)
        parts["hull_pairs"] = lambda: search.hull_pairs(offsets, pair_solid, hull, origin, beams.element_type.code, Q,
                                                        beams.lengths, beam_origin, beam_boxes)
    print(f"package {m13.__file__.rsplit('/', 2)[0]}: scene {args.scene}, fibre_cube({args.n}, {args.fibres}, 20), "
          f"{solid.n_elements} solid elements, 1 thread, best of {args.repeats} calls [ms]")
    total = 0.0
    for name, call in parts.items():
        best = best_ms(call, args.repeats)
        total += best
        print(f"  {name:16s} {best:8.3f}")
    print(f"  {'sum':16s} {total:8.3f}")


if __name__ == "__main__":
    main()
