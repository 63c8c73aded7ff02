"""Assembly throughput on a NURBS pipe next to hex27 on the same geometry (issue 19).

    .venv/bin/python benchmarks/nurbs_throughput.py [--repeats 5] [--elements 2 24 8] [--helices 40]

The solid: a closed pipe (radii 0.2 / 0.3, height 1) of ``--elements`` (radial, circumferential, axial)
quadratic NURBS elements, as ``nurbs27`` (rational Bézier) elements, and as ``hexahedron27`` elements
whose nodes are the exact pipe's points at the same elements' lattice parameters (the same
element layout; the Lagrange mesh only approximates the circle). The beams: ``--helices`` helices
of radius 0.265 in the wall (off the element interface at 0.25) (winding ±45°, two families), 16 Hermite elements each. Each repeat times
``assemble_mortar`` (segment- and element-based, n_gauss 6, line2) on both meshes; printed: the best
and median wall time and Gauss points per second, with the threads Numba uses, and the time ratio (the meshes alternate
within each round).
"""
import argparse
import time

import numba
import numpy as np

import mortar1d3d as m13
from mortar1d3d import nurbs
from mortar1d3d.elements.solid.hex_family import QUADRATIC_NODES


def meshes(elements):
    solid = nurbs.hollow_cylinder(0.2, 0.3, 1.0, angle=360.0, elements=tuple(elements))
    bezier = nurbs.bezier_mesh(solid).solid
    patch = solid.patches[0]
    X = patch.evaluate_elements(QUADRATIC_NODES).reshape(-1, 3)
    key = np.round(X / 1e-10).astype(np.int64)
    _, first, inverse = np.unique(key, axis=0, return_index=True, return_inverse=True)
    hex27 = m13.SolidMesh(X[first], {"hexahedron27": inverse.reshape(-1, 27)})
    return bezier, hex27


def helices(n, radius=0.265, angle=45.0, elements=16):
    beams = []
    pitch = 2 * np.pi * radius / np.tan(np.radians(angle))        # axial rise per turn
    turns = 0.9 / pitch
    for k in range(n):
        sign = 1.0 if k % 2 == 0 else -1.0
        phase = 2 * np.pi * k / n

        def f(t, sign=sign, phase=phase):
            a = phase + sign * 2 * np.pi * turns * t
            return np.array([radius * np.cos(a), radius * np.sin(a), 0.05 + 0.9 * t])

        def df(t, sign=sign, phase=phase):
            a = phase + sign * 2 * np.pi * turns * t
            w = sign * 2 * np.pi * turns
            return np.array([-radius * w * np.sin(a), radius * w * np.cos(a), 0.9])

        beams.append(m13.BeamMesh.from_curve(f, df, 0.0, 1.0, elements))
    return m13.BeamMesh.join(beams)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--elements", type=int, nargs=3, default=[2, 24, 8])
    parser.add_argument("--helices", type=int, default=40)
    args = parser.parse_args(argv)
    bezier, hex27 = meshes(args.elements)
    beams = helices(args.helices)
    print(f"threads {numba.get_num_threads()}; {bezier.n_elements} elements; {beams.n_elements} beam elements")
    for integration in ("segment", "element"):
        solids = (("nurbs27", bezier), ("hexahedron27", hex27))
        ops = {name: m13.assemble_mortar(beams, solid, integration=integration, n_gauss=6)     # compile, warm
               for name, solid in solids}
        times = {name: [] for name, _ in solids}
        for _ in range(args.repeats):
            # the two meshes alternate, so that both see the same load of a shared machine
            for name, solid in solids:
                t0 = time.perf_counter()
                ops[name] = m13.assemble_mortar(beams, solid, integration=integration, n_gauss=6)
                times[name].append(time.perf_counter() - t0)
        for name, _ in solids:
            t, n = times[name], ops[name].n_integration_points
            print(f"{integration:8s} {name:13s} best {min(t) * 1e3:8.1f} ms, median {np.median(t) * 1e3:8.1f} ms, "
                  f"{n} points, {n / min(t) / 1e3:8.1f} k points/s (best); coupled "
                  f"{ops[name].embedded_length:.6f} of {ops[name].beam_length:.6f}, residual "
                  f"{ops[name].constraint_residual:.1e}")
        ratio = np.array(times["nurbs27"]) / np.array(times["hexahedron27"])
        print(f"{integration:8s} nurbs27 / hexahedron27 per round: median {np.median(ratio):.2f}, "
              f"best rounds {min(times['nurbs27']) / min(times['hexahedron27']):.2f}")

if __name__ == "__main__":
    main()
