"""Demo: mortar operators for 1000 fibres embedded in a cube (the benchmark scene).

Assembles D, M and κ with segment-based and element-based integration, prints the built-in
certificates and the throughput, writes the segmentation for ParaView and a plot of where the
time goes and how element-based integration converges to the segment-based operators.

    python examples/fibre_cube_demo.py --out results/demo [--cells 20 --fibres 1000 --elements 20]
"""
import argparse
import os
import time

import numpy as np
import scipy.sparse.linalg as spla

import mortar1d3d as m13
from mortar1d3d.io.vtu import write_mortar


def relative_error(A, B):
    """Relative Frobenius norm ‖A - B‖ / ‖B‖ of two sparse matrices."""
    return spla.norm(A - B) / spla.norm(B)


def overwrite_note(out):
    """Where the results go, and whether an earlier run's files there are overwritten."""
    earlier = sorted(os.listdir(out)) if os.path.isdir(out) else []
    if earlier:
        return (f"writing to {out}/: overwriting the {len(earlier)} files of an earlier run there "
                "(use --out DIR to keep them)")
    return f"writing to {out}/"


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--out", default="results/demo", help="output directory")
    parser.add_argument("--cells", type=int, default=20, help="hex8 cells per cube edge")
    parser.add_argument("--fibres", type=int, default=1000)
    parser.add_argument("--elements", type=int, default=20, help="Hermite elements per fibre")
    parser.add_argument("--curved", action="store_true", help="helical instead of straight fibres")
    parser.add_argument("--no-plot", action="store_true")
    args = parser.parse_args(argv)
    print(overwrite_note(args.out), flush=True)
    os.makedirs(args.out, exist_ok=True)

    # compile what this scene runs (hex8, both integrations) before timing it; m13.warmup() without
    # arguments would compile every element type and the physics as well
    print("compiling / loading kernels ...", flush=True)
    m13.warmup(verbose=True, elements=["hexahedron"], integrations=["segment", "element"], physics=False)
    beams, solid = m13.generate.fibre_cube(args.cells, args.fibres, args.elements, curved=args.curved)
    print(f"scene: {solid}\n       {beams}")

    results = {}
    for integration in ("segment", "element"):
        t0 = time.perf_counter()
        ops = m13.assemble_mortar(beams, solid, integration=integration, n_gauss=4)
        elapsed = time.perf_counter() - t0
        results[integration] = ops
        print(f"\n{integration}-based integration, 4 Gauss points")
        print(f"  segments / integration points : {len(ops.segments)} / {ops.n_integration_points}")
        print(f"  D {ops.D.shape}, nnz {ops.D.nnz};  M {ops.M.shape}, nnz {ops.M.nnz}")
        print(f"  certificate Σκ = {ops.embedded_length:.12g}  (beam length {ops.beam_length:.12g})")
        print(f"  certificate ‖D q_B - M X_S‖/‖D q_B‖ = {ops.constraint_residual:.2e}")
        print(f"  time {elapsed * 1e3:.1f} ms  ->  {ops.n_integration_points / elapsed:.3g} Gauss points/s")
        print("  stages [ms]: " + ", ".join(f"{k} {v * 1e3:.1f}" for k, v in ops.timings.items() if k != "total"))

    # element-based integration against the segment-based operators, as the Gauss count grows
    reference = m13.assemble_mortar(beams, solid, integration="segment", n_gauss=8)
    counts = [1, 2, 3, 4, 6, 8, 12, 16, 24, 32]
    errors = [relative_error(m13.assemble_mortar(beams, solid, integration="element", n_gauss=n).M, reference.M)
              for n in counts]
    segment_error = relative_error(results["segment"].M, reference.M)
    print("\nrelative error of M against segment-based (8 points per segment):")
    print("  element-based: " + ", ".join(f"n={n}: {e:.1e}" for n, e in zip(counts, errors)))
    print(f"  segment-based, 4 points: {segment_error:.1e}")

    paths = write_mortar(args.out, beams, solid, results["segment"], prefix="fibre_cube")
    print(f"\nwrote {len(paths)} files for ParaView: open {os.path.join(args.out, 'fibre_cube.pvd')}")
    np.savetxt(os.path.join(args.out, "element_based_error.csv"), np.column_stack([counts, errors]),
               delimiter=",", header="n_gauss,relative_error_M", comments="")
    if not args.no_plot:
        plot(args.out, results, counts, errors, segment_error)


def plot(out, results, counts, errors, segment_error):
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print("matplotlib is not installed: no plot (pip install matplotlib)")
        return
    fig, (ax0, ax1) = plt.subplots(1, 2, figsize=(11, 4.2))
    stages = ["search", "segmentation", "integration_points", "assembly", "csr"]
    for i, (name, ops) in enumerate(results.items()):
        bottom = 0.0
        for j, stage in enumerate(stages):
            value = ops.timings.get(stage, 0.0) * 1e3
            ax0.bar(i, value, bottom=bottom, color=f"C{j}", label=stage if i == 0 else None)
            bottom += value
    ax0.set_xticks(range(len(results)), [f"{k}-based" for k in results])
    ax0.set_ylabel("wall time [ms]")
    ax0.set_title("assemble_mortar: time per stage (4 Gauss points)")
    ax0.legend(fontsize=8)
    ax1.loglog(counts, errors, "o-", label="element-based")
    ax1.axhline(max(segment_error, 1e-16), color="C1", ls="--", label="segment-based, 4 points")
    ax1.set_xlabel("Gauss points per beam element")
    ax1.set_ylabel("relative error of M (Frobenius)")
    ax1.set_title("element-based integration: kinks at element faces")
    ax1.legend(fontsize=8)
    fig.tight_layout()
    path = os.path.join(out, "fibre_cube.png")
    fig.savefig(path, dpi=120)
    print(f"wrote plot {path}")


if __name__ == "__main__":
    main()
