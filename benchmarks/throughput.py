"""Standalone throughput of assemble_mortar outside pytest (best and median of repeated calls).

    .venv/bin/python benchmarks/throughput.py [--repeats 9] [--distort 0.1] [--drop] [--no-reuse]
                                              [--package CHECKOUT] [--scene-warmup]

Same scene as the pytest-benchmark harness (fibre_cube(20, 1000, 20), n_gauss=4, straight
fibres). Every round times each integration with 1 and then 2 threads back to back, and the
control of ``control.py`` (an embarrassingly parallel compute loop, as Numba schedules ``prange``
and with dynamically claimed chunks as the engine's kernels) with 1 and 2 threads. The
speed-up is given as the ratio of the medians and as the median of the per-round ratios
(paired: both calls of a round see the same machine state); the control's speed-up says what
the machine gave two threads in the same minutes. Each round also times the control serially on
each CPU in turn (pinned): on a VM one vCPU is often slower than the other, which caps what two
threads can give at 1 + t_fast / t_slow (two vCPUs that are equally fast alone may still slow each
other down when both are busy; only the 2-thread control shows that). The per-stage times are
those of the fastest call.

To compare two versions of the library on a shared machine, run this script alternately with
``--package`` naming each checkout and compare the lines ``per control``: each call's time divided
by the 1-thread control's time of the same round (median over the rounds), a figure in which the
machine's speed of the moment cancels.

The run time of kernels compiled at another LLVM optimisation level: ``NUMBA_OPT=N`` with a
cache directory of that level's own (Numba's cache does not record the level, so a shared one would
load kernels compiled at another), e.g. ``NUMBA_OPT=1 NUMBA_CACHE_DIR=CACHE_DIR_OPT1 ... --scene-warmup``.
"""
import argparse
import resource
import sys
import time
from pathlib import Path

import numba
import numpy as np


def _package_root(argv):
    """The checkout whose package is measured: ``--package DIR`` if given, else this one."""
    argv = sys.argv[1:] if argv is None else argv
    for i, a in enumerate(argv):
        if a == "--package" and i + 1 < len(argv):
            return Path(argv[i + 1]).resolve()
        if a.startswith("--package="):
            return Path(a.split("=", 1)[1]).resolve()
    return Path(__file__).resolve().parents[1]


# the package must be imported from the chosen checkout before anything imports it
sys.path.insert(0, str(_package_root(None)))

import mortar1d3d as m13  # noqa: E402
from _record import record  # noqa: E402
from control import control_times, core_times  # noqa: E402

THREADS = (1, 2)


def _timed(call):
    t0 = time.perf_counter()
    result = call()
    return time.perf_counter() - t0, result


def _faults():
    return resource.getrusage(resource.RUSAGE_SELF).ru_minflt


def _speedups(times):
    one, two = np.array(times[1]), np.array(times[2])
    return np.median(one) / np.median(two), np.median(one / two)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--repeats", type=int, default=9)
    parser.add_argument("--distort", type=float, default=0.0, metavar="A",
                        help="move the cube's interior nodes by up to A cells (generate.distort, seed 1): "
                             "no element affine, every location a Newton projection")
    parser.add_argument("--drop", action="store_true",
                        help="drop each result before the next call (as make bench does): glibc may then return "
                             "the memory to the OS and every call faults it in again")
    parser.add_argument("--no-reuse", action="store_true",
                        help="every big block fresh from the allocator (mortar1d3d._memory.POOL_LIMIT = 0); with "
                             "--drop: the memory regime before the engine reused its blocks")
    parser.add_argument("--package", metavar="CHECKOUT", default=None,
                        help="measure the mortar1d3d package of another checkout (a directory holding mortar1d3d/) "
                             "with this harness, e.g. an older commit in a git worktree")
    parser.add_argument("--scene-warmup", action="store_true",
                        help="compile by one call of each integration on the scene instead of mortar1d3d.warmup() "
                             "(only the kernels measured: quicker from an empty cache, e.g. a cache directory per "
                             "NUMBA_OPT level)")
    parser.add_argument("--full", type=float, default=1.85, metavar="X",
                        help="also report the speed-up over the rounds whose control reached X (default 1.85)")
    args = parser.parse_args(argv)
    beams, solid = m13.generate.fibre_cube(20, 1000, 20)
    if args.distort:
        solid = m13.generate.distort(solid, args.distort, seed=1)
    if args.no_reuse:
        from mortar1d3d import _memory
        _memory.POOL_LIMIT = 0
    if args.scene_warmup:
        for integration in ("element", "segment"):
            m13.assemble_mortar(beams, solid, integration=integration, n_gauss=4)
    else:
        m13.warmup()
    print(f"package {Path(m13.__file__).resolve().parent}")
    print(f"threading layer {numba.threading_layer()}, NUMBA_NUM_THREADS {numba.config.NUMBA_NUM_THREADS}"
          + (f", cube distorted by {args.distort} cells" if args.distort else ""))
    integrations = ("element", "segment")
    calls = {(i, nt): [] for i in integrations for nt in THREADS}
    control = {nt: [] for nt in THREADS}
    claimed = {nt: [] for nt in THREADS}
    n_points = {}
    cores = []
    for _ in range(args.repeats):
        cores.append(core_times())
        for nt, t in control_times(THREADS).items():
            control[nt].append(t)
        for nt, t in control_times(THREADS, dynamic=True).items():
            claimed[nt].append(t)
        for integration in integrations:
            for nt in THREADS:
                numba.set_num_threads(nt)
                if args.drop:
                    ops = None
                faults = _faults()
                t, ops = _timed(lambda: m13.assemble_mortar(beams, solid, integration=integration, n_gauss=4))
                calls[integration, nt].append((t, ops.timings, _faults() - faults))
                n_points[integration] = ops.n_integration_points
    for integration in integrations:
        for nt in THREADS:
            runs = calls[integration, nt]
            times = np.array([t for t, _, _ in runs])
            best_time, best_stages, _ = min(runs, key=lambda c: c[0])
            n = n_points[integration]
            print(f"{integration:8s} {nt} thread(s): best {best_time * 1e3:6.1f} ms = {n / best_time:.3g} GP/s, "
                  f"median {np.median(times) * 1e3:6.1f} ms = {n / np.median(times):.3g} GP/s; stages of best [ms]: "
                  + ", ".join(f"{k} {v * 1e3:.1f}" for k, v in best_stages.items() if k != "total")
                  + f"; page faults per call {np.median([f for _, _, f in runs]):.0f}")
        of_medians, paired = _speedups({nt: [t for t, _, _ in calls[integration, nt]] for nt in THREADS})
        print(f"{integration:8s} 2-thread speed-up: {of_medians:.2f}x (medians), "
              f"{paired:.2f}x (median of paired rounds)")
    for label, times in (("control", control), ("claimed", claimed)):
        of_medians, paired = _speedups(times)
        print(f"{label}  1 / 2 threads median {np.median(times[1]) * 1e3:.1f} / {np.median(times[2]) * 1e3:.1f} ms: "
              f"speed-up {of_medians:.2f}x (medians), {paired:.2f}x (median of paired rounds)"
              + ("  [prange as Numba schedules it]" if label == "control" else "  [chunks claimed dynamically]"))
    # paired (per-round) 1/2-thread ratios of the engine and of both controls
    ratio = {i: np.array([t for t, _, _ in calls[i, 1]]) / np.array([t for t, _, _ in calls[i, 2]])
             for i in integrations}
    control_ratio = np.array(control[1]) / np.array(control[2])
    claimed_ratio = np.array(claimed[1]) / np.array(claimed[2])
    # each call against the 1-thread control of its round: comparable between runs and versions
    for integration in integrations:
        for nt in THREADS:
            per = np.array([t for t, _, _ in calls[integration, nt]]) / np.array(control[1])
            print(f"{integration:8s} {nt} thread(s) per control: median {np.median(per):.3f} "
                  f"(range {per.min():.3f}-{per.max():.3f})")
    for integration in integrations:
        print(f"{integration:8s} speed-up / the claimed control's of the same round: median "
              f"{np.median(ratio[integration] / claimed_ratio):.2f}")
        one = np.array([t for t, _, _ in calls[integration, 1]])
        record("throughput", distort=args.distort, integration=integration,
               gp_per_s_1thread=float(n_points[integration] / np.median(one)),
               gp_per_s_1thread_best=float(n_points[integration] / one.min()),
               per_control_1thread=float(np.median(one / np.array(control[1]))),
               control_1thread_s=float(np.median(control[1])),
               of_claimed=float(np.median(ratio[integration] / claimed_ratio)),
               claimed_speedup=float(np.median(claimed_ratio)))
    if cores and cores[0]:
        per_cpu = {cpu: np.median([c[cpu] for c in cores]) for cpu in cores[0]}
        ceiling = np.array([1.0 + min(c.values()) / max(c.values()) for c in cores])
        print("cores (control serially, pinned to each CPU): "
              + ", ".join(f"cpu{cpu} {t * 1e3:.0f} ms" for cpu, t in per_cpu.items())
              + f" (medians); 1 + t_fast / t_slow per round: median {np.median(ceiling):.2f}x, "
              f"range {ceiling.min():.2f}x-{ceiling.max():.2f}x")
    # the engine's speed-up in the rounds where the machine gave two threads nearly two cores
    good = control_ratio >= args.full
    for integration in integrations:
        r = ratio[integration]
        if good.any():
            print(f"{integration:8s} rounds with control >= {args.full}x ({good.sum()} of {len(good)}): "
                  f"speed-up median {np.median(r[good]):.2f}x (min {r[good].min():.2f}x); "
                  f"other rounds {np.median(r[~good]) if (~good).any() else float('nan'):.2f}x")


if __name__ == "__main__":
    main()
