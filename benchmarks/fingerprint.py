"""Every number a restructuring must not change, written to one file and compared bit for bit.

``python benchmarks/fingerprint.py --write before.npz`` (on the commit before a change), then
``python benchmarks/fingerprint.py --check before.npz`` (after it): the mortar operators (D, M, κ,
segments, integration points) of the benchmark scene in its straight, curved and distorted variants
for every integration, of a smaller cube of distorted tetra10 and hexahedron27 elements (the scenes of
``newton_path.py``) for every integration, of every solid element type with curved beams and every multiplier type, and
the solutions of the example scene and of a penalty, a Lagrange and a nonlinear solve. ``--check``
lists every array that differs in any bit (and by how much) and exits 1 if one does.

``--set nurbs`` collects instead the NURBS pipe of ``newton_path.py --scene nurbs27`` (384 ``nurbs27``
elements, 40 helices) for every integration, ``--set all`` both; the default, ``standard``, is the
set above. To compare another checkout's package, run this script with ``PYTHONPATH=CHECKOUT``.
"""
import argparse
import sys
import warnings
from pathlib import Path

import numpy as np

import mortar1d3d as m13

ROOT = Path(__file__).resolve().parents[1]


def _operators(out, key, beams, solid, **kwargs):
    ops = m13.assemble_mortar(beams, solid, **kwargs)
    for name in ("D", "M"):
        matrix = getattr(ops, name).tocsr()
        out[f"{key}/{name}.data"] = matrix.data
        out[f"{key}/{name}.indices"] = matrix.indices
        out[f"{key}/{name}.indptr"] = matrix.indptr
    out[f"{key}/kappa"] = ops.kappa
    for field in ("beam_element", "solid_element", "eta_start", "eta_end"):
        out[f"{key}/segments.{field}"] = ops.segments[field]
    for field, values in ops.point_fields.items():
        out[f"{key}/points.{field}"] = np.asarray(values)


def _result(out, key, scene):
    result = m13.solve(scene)
    out[f"{key}/solid_displacement"] = result.solid_displacement
    out[f"{key}/beam_displacement"] = result.beam_displacement
    out[f"{key}/line_load"] = result.line_load


def collect_nurbs(out):
    """The NURBS pipe of ``newton_path.py --scene nurbs27`` (``nurbs_throughput.py``'s meshes)."""
    sys.path.insert(0, str(ROOT / "benchmarks"))
    from nurbs_throughput import helices, meshes
    beams, solid = helices(40), meshes((2, 24, 8))[0]
    for integration in ("element", "segment", "auto"):
        _operators(out, f"nurbs27-pipe-{integration}", beams, solid, integration=integration, n_gauss=4)
    return out


def collect(which="standard"):
    out = {}
    if which in ("nurbs", "all"):
        collect_nurbs(out)
        if which == "nurbs":
            return out
    beams, solid = m13.generate.fibre_cube(20, 1000, 20)
    curved, _ = m13.generate.fibre_cube(20, 1000, 20, curved=True)
    distorted = m13.generate.distort(solid, 0.1, seed=1)
    for name, b, s in (("straight", beams, solid), ("curved", curved, solid), ("distorted", beams, distorted)):
        for integration in ("element", "segment", "auto"):
            _operators(out, f"cube-{name}-{integration}", b, s, integration=integration, n_gauss=4)
    # the quadratic scenes of newton_path.py (smaller): straight fibres through curved tet10 and hex27
    fibres, _ = m13.generate.fibre_cube(8, 100, 8)
    for element in ("tetra10", "hexahedron27"):
        box = m13.generate.distort(m13.generate.box((0, 0, 0), (1, 1, 1), (8, 8, 8), element), 0.1, seed=1)
        for integration in ("element", "segment", "auto"):
            _operators(out, f"cube8-{element}-{integration}", fibres, box, integration=integration, n_gauss=4)
    few = m13.generate.random_curved_beams(6, 5, seed=3)
    for element in ("hexahedron", "hexahedron20", "hexahedron27", "tetra", "tetra10"):
        box = m13.generate.distort(m13.generate.box((0, 0, 0), (1, 1, 1), (3, 3, 3), element), 0.1, seed=2)
        for lm in ("line2", "line3", "line4"):
            _operators(out, f"{element}-{lm}", few, box, integration="segment", lm=lm, n_gauss=5)
    scene_file = ROOT / "examples" / "scenes" / "rebar_cantilever.toml"
    _result(out, "rebar_cantilever", m13.Scene.from_toml(scene_file))
    for variant, changes in (("lagrange", dict(enforcement="lagrange")), ("linear", None)):
        scene = m13.Scene.from_toml(scene_file)
        if variant == "linear":
            scene.analysis["kinematics"] = "linear"
        else:
            scene.coupling.update(changes)
        _result(out, f"rebar_cantilever-{variant}", scene)
    return out


def check(reference, current):
    differ = []
    for key in sorted(set(reference) | set(current)):
        if key not in reference or key not in current:
            differ.append(f"{key}: only in {'the reference' if key in reference else 'this run'}")
            continue
        a, b = reference[key], current[key]
        if a.shape != b.shape or a.dtype != b.dtype:
            differ.append(f"{key}: shape/dtype {a.shape} {a.dtype} -> {b.shape} {b.dtype}")
        elif a.tobytes() != b.tobytes():
            gap = float(np.max(np.abs(a.astype(float) - b.astype(float)))) if a.size else 0.0
            differ.append(f"{key}: {np.count_nonzero(a != b)} of {a.size} entries differ (max {gap:.3e})")
    return differ


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    group = parser.add_mutually_exclusive_group(required=True)
    group.add_argument("--write", metavar="FILE", help="write the arrays of this checkout")
    group.add_argument("--check", metavar="FILE", help="compare this checkout's arrays with FILE, bit for bit")
    parser.add_argument("--set", default="standard", choices=("standard", "nurbs", "all"),
                        help="the scenes (default: standard; nurbs: the NURBS pipe only; all: both)")
    args = parser.parse_args(argv)
    print(f"package {m13.__file__.rsplit('/', 2)[0]}")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        current = collect(args.set)
    if args.write:
        np.savez_compressed(args.write, **current)
        print(f"wrote {len(current)} arrays to {args.write}")
        return 0
    with np.load(args.check) as data:
        reference = {k: data[k] for k in data.files}
    differ = check(reference, current)
    print(f"{len(current)} arrays compared with {args.check}: "
          + ("all bit-identical" if not differ else f"{len(differ)} differ"))
    for line in differ:
        print("  " + line)
    return 1 if differ else 0


if __name__ == "__main__":
    sys.exit(main())
