"""How a NURBS element's rational basis is evaluated: Bézier extraction against element-local Cox–de Boor.

    .venv/bin/python benchmarks/nurbs_basis.py [--repeats 7] [--points 27]

Same scene both ways: a closed quadratic pipe (radii 0.1 / 0.2, height 0.3, 2 × 16 × 4 elements),
``--points`` random parameter points per element. *Bézier*: every element carries its 27 Bézier
control weights, R_a = w_a B_a / W (Bernstein triangle per direction). *Local knots*: every element
carries its 2p knots per direction and the weights of its 27 control points, Cox–de Boor on those
knots. Both compute R and ∂R/∂ξ and sum the map x(ξ) and its Jacobian, as the engine's Newton steps
do. Prints the best and median time per point of each and their ratio; the two agree to round-off
(checked).
"""
import argparse
import time

import numpy as np

from mortar1d3d._config import njit
from mortar1d3d.nurbs import hollow_cylinder, knots as kv
from mortar1d3d.nurbs.basis import rational_bernstein, rational_local


@njit
def _bezier(control, weights, xi, out):
    R = np.empty(27)
    dR = np.empty((27, 3))
    for e in range(control.shape[0]):
        for q in range(xi.shape[1]):
            rational_bernstein(2, 2, 2, xi[e, q], weights[e], R, dR)
            s = 0.0
            for a in range(27):
                for i in range(3):
                    s += R[a] * control[e, a, i] + dR[a, i] * control[e, a, i]
            out[e, q] = s


@njit
def _local(control, weights, k0, k1, k2, xi, out):
    R = np.empty(27)
    dR = np.empty((27, 3))
    for e in range(control.shape[0]):
        for q in range(xi.shape[1]):
            rational_local(2, 2, 2, xi[e, q], k0[e], k1[e], k2[e], weights[e], R, dR)
            s = 0.0
            for a in range(27):
                for i in range(3):
                    s += R[a] * control[e, a, i] + dR[a, i] * control[e, a, i]
            out[e, q] = s


def scene(points, seed=0):
    patch = hollow_cylinder(0.1, 0.2, 0.3, angle=360.0, elements=(2, 16, 4)).patches[0]
    bez_control, bez_weights, functions, _ = patch.bezier_elements()
    cp_control = patch.control.reshape(-1, 3)[functions]
    cp_weights = patch.weights.reshape(-1)[functions]
    spans = [kv.spans(U, 2) for U in patch.knots]
    idx = np.unravel_index(np.arange(patch.n_elements), patch.element_shape)
    local = [np.array([U[k - 1: k + 3] for k in spans[d][idx[d]]]) for d, U in enumerate(patch.knots)]
    xi = np.random.default_rng(seed).uniform(-1, 1, (patch.n_elements, points, 3))
    return bez_control, bez_weights, cp_control, cp_weights, local, xi


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=7)
    parser.add_argument("--points", type=int, default=27)
    args = parser.parse_args(argv)
    bez_control, bez_weights, cp_control, cp_weights, local, xi = scene(args.points)
    out_b = np.empty(xi.shape[:2])
    out_l = np.empty(xi.shape[:2])
    _bezier(bez_control, bez_weights, xi, out_b)                       # compile
    _local(cp_control, cp_weights, *local, xi, out_l)
    scale = np.abs(out_b).max()
    print(f"agreement: max |difference| / max |value| = {np.abs(out_b - out_l).max() / scale:.1e}")
    times = {"bezier": [], "local knots": []}
    for _ in range(args.repeats):
        t0 = time.perf_counter()
        _bezier(bez_control, bez_weights, xi, out_b)
        t1 = time.perf_counter()
        _local(cp_control, cp_weights, *local, xi, out_l)
        t2 = time.perf_counter()
        times["bezier"].append(t1 - t0)
        times["local knots"].append(t2 - t1)
    n = xi.shape[0] * xi.shape[1]
    for name, t in times.items():
        print(f"{name:12s} best {1e9 * min(t) / n:7.1f} ns/point, median {1e9 * np.median(t) / n:7.1f} ns/point "
              f"({n} points)")
    print(f"local knots / bezier (medians): {np.median(times['local knots']) / np.median(times['bezier']):.2f}")


if __name__ == "__main__":
    main()
