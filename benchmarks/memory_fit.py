"""The memory model of the distributed path (issue 23, docs/distributed.md): a least-squares fit of
what each rank holds to ``a + b · owned unknowns + c · unknowns of the model``, from the JSON lines of
``benchmarks/distributed_scaling.py`` runs at several rank counts and sizes (memory needs no cores:
the runs may be oversubscribed).

    mpiexec --oversubscribe -n 3 python benchmarks/distributed_scaling.py --cells 15 --fibres 600 > runs/c15-n3.json
    ...                                                                   # strong and weak series
    python benchmarks/memory_fit.py runs/*.json
    python benchmarks/memory_fit.py runs/*.json --project 1e8 --ranks 100 1000 10000
    python benchmarks/memory_fit.py runs/*.json --terms nnz unknowns      # per stored tangent entry

Every rank of every run is one point (its owned unknowns are the run's ``owned``); the fit is made
for the peak resident memory at the end of the solve stage (``memory_by_stage["solve"]``, the
process's peak so far: on rank 0 it leaves out the gathered result built after the solve) and, to
attribute the terms, for each stage's growth of the current resident memory (``setup``: the
memory at its end; then the growth over the previous stage; ``solve peak``: the solve's peak over
the memory before it). The stage fits add up to the peak's. Printed: the coefficients (MiB, KiB
per owned unknown, KiB per unknown of the model), the residual of every point and their RMS, and
with ``--project`` the fitted memory per rank at that size on the given rank counts.

``--terms`` chooses the regressors besides the constant: ``owned`` (unknowns the rank owns),
``nnz`` (stored entries of the rank's rows of the tangent), ``ghosts`` (vector entries it receives
per product), ``unknowns`` (of the model); coefficients in KiB per unit.
"""
import argparse
import json

import numpy as np

STAGES = ("setup", "partition", "coupling", "stiffness", "loads_supports")


TERMS = ("owned", "nnz", "ghosts", "unknowns")


def points(paths):
    """One row per rank of every run: (file, ranks, rank, {term: value}, {quantity: MiB})."""
    rows = []
    for path in paths:
        for line in open(path):
            line = line.strip()
            if not line.startswith("{"):
                continue
            run = json.loads(line)
            if "owned" not in run or "memory_by_stage" not in run:
                continue
            stages = run["memory_by_stage"]
            for rank, owned in enumerate(run["owned"]):
                current = [stages[s][rank][1] for s in STAGES]
                values = {"setup": current[0]}
                for k in range(1, len(STAGES)):
                    values[STAGES[k]] = current[k] - current[k - 1]
                values["solve peak"] = stages["solve"][rank][0] - current[-1]
                values["peak"] = stages["solve"][rank][0]
                terms = {"owned": owned, "nnz": run["nnz"][rank], "ghosts": run["ghosts"][rank],
                         "unknowns": run["unknowns"]}
                rows.append((path, run["ranks"], rank, terms, values))
    return rows


def design(rows, terms):
    """The least-squares matrix: a column of ones, then one per term."""
    return np.array([[1.0] + [t[name] for name in terms] for _, _, _, t, _ in rows])


def fit(rows, quantity, terms):
    """Least squares of ``quantity`` (MiB) to a + Σ b_k term_k: the coefficients (MiB, MiB per
    unit) and the residuals (MiB)."""
    X = design(rows, terms)
    y = np.array([v[quantity] for *_, v in rows])
    coef, *_ = np.linalg.lstsq(X, y, rcond=None)
    return coef, y - X @ coef


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("runs", nargs="+", help="JSON lines of benchmarks/distributed_scaling.py")
    parser.add_argument("--terms", nargs="+", choices=TERMS, default=["owned", "unknowns"])
    parser.add_argument("--project", type=float, default=None, metavar="UNKNOWNS",
                        help="with --terms owned unknowns: the fitted peak per rank at this size")
    parser.add_argument("--ranks", type=int, nargs="+", default=[100, 1000, 10000])
    args = parser.parse_args()
    rows = points(args.runs)
    terms = args.terms
    rank_of_X = np.linalg.matrix_rank(design(rows, terms))
    print(f"{len(rows)} points (rank, run) from {len(args.runs)} files; unknowns "
          f"{sorted({t['unknowns'] for _, _, _, t, _ in rows})}; design rank {rank_of_X} of {len(terms) + 1}")
    if rank_of_X < len(terms) + 1:
        raise SystemExit("the terms are not independent in these runs: add runs on more ranks or sizes")
    quantities = ["peak", *STAGES, "solve peak"]
    fits = {q: fit(rows, q, terms) for q in quantities}
    print(f"{'quantity':>16} {'a (MiB)':>9} " + " ".join(f"{'KiB/' + t:>14}" for t in terms)
          + f" {'RMS (MiB)':>10} {'max |res|':>10}")
    for q in quantities:
        coef, res = fits[q]
        print(f"{q:>16} {coef[0]:9.1f} " + " ".join(f"{1024 * c:14.4f}" for c in coef[1:])
              + f" {np.sqrt(np.mean(res ** 2)):10.1f} {np.abs(res).max():10.1f}")
    print("\nresiduals of the peak fit (MiB):")
    print(f"{'run':>20} {'ranks':>5} {'rank':>4} " + " ".join(f"{t:>9}" for t in terms)
          + f" {'peak':>8} {'fitted':>8} {'residual':>8}")
    _, res = fits["peak"]
    for (path, ranks, rank, t, v), r in zip(rows, res):
        print(f"{path.split('/')[-1][-20:]:>20} {ranks:5d} {rank:4d} " + " ".join(f"{t[name]:9d}" for name in terms)
              + f" {v['peak']:8.1f} {v['peak'] - r:8.1f} {r:8.1f}")
    if args.project and terms == ["owned", "unknowns"]:
        (a, b, c), _ = fits["peak"]
        print(f"\nprojected peak per rank at {args.project:.3g} unknowns (GiB: a + b owned + c unknowns):")
        for ranks in args.ranks:
            owned = args.project / ranks
            print(f"  {ranks:>6} ranks: {a / 1024:.2f} + {b * owned / 1024:.2f} + {c * args.project / 1024:.2f} "
                  f"= {(a + b * owned + c * args.project) / 1024:.1f} GiB")


if __name__ == "__main__":
    main()
