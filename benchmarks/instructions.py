"""Instructions per assemble_mortar call, counted by valgrind (callgrind), for two checkouts.

    .venv/bin/python benchmarks/instructions.py [--package CHECKOUT ...] [--integration segment]
                                                [--distort 0.1] [--n 10] [--fibres 200] [--calls 3]

On a shared, noisy machine seconds move by ±10 % from one run to the next; the number of executed
instructions does not (callgrind counts them on a simulated CPU, whatever else the machine does).
This script runs the library of each ``--package`` checkout (default: this one) in a child process
under ``valgrind --tool=callgrind``: the scene is built and assembled once (warm-up: the kernel
cache must already be filled, see below), then assembled ``--calls`` more times, and the same
child with no extra call is counted too. The difference divided by ``--calls`` is the count of
one call, free of the import, the scene generation and the warm-up. It prints the count of
every checkout and its ratio to the first one.

Counts say whether a version *does more work*. Two versions with equal counts and different
times differ in how the CPU runs the same work (code layout, branch prediction, memory), which
only timings (``throughput.py``) show.

The child runs with one Numba thread. Valgrind's simulated CPU lacks instruction sets of most
current hosts (AVX-512), so kernels cached for the host would not load under it, and Numba
compiles at about 1/50 of its normal speed there. The children therefore compile for a fixed
target that valgrind runs (``NUMBA_CPU_NAME=haswell`` with its features named in ``NUMBA_CPU_FEATURES``: AVX2) into a kernel cache of their own
(``--cache DIR``, one sub-directory per checkout), filled by a first run without valgrind. The
counts are those of this target's code, the same for every checkout compared, not of the code
the host runs.
"""
import argparse
import os
import re
import subprocess
import sys
import tempfile
from pathlib import Path

HERE = Path(__file__).resolve()


def _child(args):
    sys.path.insert(0, str(Path(args.package).resolve()))
    import numba
    import mortar1d3d as m13
    if not Path(m13.__file__).resolve().is_relative_to(Path(args.package).resolve()):
        raise SystemExit(f"imported {m13.__file__}, not the package of {args.package}")
    numba.set_num_threads(1)
    beams, solid = m13.generate.fibre_cube(args.n, args.fibres, args.n)
    if args.distort:
        solid = m13.generate.distort(solid, args.distort, seed=1)
    m13.assemble_mortar(beams, solid, integration=args.integration, n_gauss=4)
    for _ in range(args.child_calls):
        m13.assemble_mortar(beams, solid, integration=args.integration, n_gauss=4)


def _environment(package, args):
    cache = Path(args.cache) / package.name
    return dict(os.environ, NUMBA_NUM_THREADS="1", NUMBA_CPU_NAME=TARGET, NUMBA_CPU_FEATURES=TARGET_FEATURES,
                NUMBA_CACHE_DIR=str(cache))


#: the CPU the children compile for: one whose instruction sets valgrind simulates
TARGET = "haswell"
#: its instruction sets, named explicitly: otherwise Numba asks the CPU it runs on, and valgrind's
#: answer differs from the host's (the cache would then miss under valgrind)
TARGET_FEATURES = "+sse2,+sse3,+ssse3,+sse4.1,+sse4.2,+popcnt,+avx,+avx2,+fma,+bmi,+bmi2,+lzcnt,+movbe,+f16c,+cx16"


def _count(package, args, calls):
    """Instructions executed by a child that makes ``calls`` extra calls (callgrind's total)."""
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "callgrind.out"
        cmd = ["valgrind", "--tool=callgrind", f"--callgrind-out-file={out}", "--dump-instr=no",
               sys.executable, str(HERE), "--child", "--package", str(package), "--integration",
               args.integration, "--distort", str(args.distort), "--n", str(args.n), "--fibres",
               str(args.fibres), "--child-calls", str(calls)]
        done = subprocess.run(cmd, env=_environment(package, args), capture_output=True, text=True)
        if done.returncode != 0:
            raise SystemExit(f"child failed ({package}, {calls} calls):\n{done.stderr[-2000:]}")
        match = re.search(r"^summary:\s+(\d+)", out.read_text(), re.MULTILINE)
        if match is None:
            raise SystemExit(f"no instruction total in callgrind's output for {package}")
        return int(match.group(1))


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--package", action="append", metavar="CHECKOUT",
                        help="checkout whose package is counted (repeat for several; default: this one)")
    parser.add_argument("--integration", default="segment", choices=("segment", "element", "auto"))
    parser.add_argument("--distort", type=float, default=0.1, metavar="A",
                        help="move interior solid nodes by up to A times the element size (0: regular)")
    parser.add_argument("--n", type=int, default=10, help="solid elements per edge (default 10)")
    parser.add_argument("--fibres", type=int, default=200)
    parser.add_argument("--calls", type=int, default=3, help="counted calls (default 3)")
    parser.add_argument("--cache", default=str(Path(tempfile.gettempdir()) / "mortar1d3d-callgrind-cache"),
                        help="kernel cache of the children (default: in the temporary directory)")
    parser.add_argument("--child", action="store_true", help=argparse.SUPPRESS)
    parser.add_argument("--child-calls", type=int, default=0, help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.child:
        args.package = args.package[0]
        return _child(args)
    packages = [Path(p).resolve() for p in (args.package or [HERE.parents[1]])]
    counts = []
    for package in packages:
        # fill the kernel cache without valgrind
        subprocess.run([sys.executable, str(HERE), "--child", "--package", str(package), "--integration",
                        args.integration, "--distort", str(args.distort), "--n", str(args.n), "--fibres",
                        str(args.fibres)], check=True, env=_environment(package, args))
        base = _count(package, args, 0)
        more = _count(package, args, args.calls)
        counts.append((more - base) / args.calls)
        print(f"{package}: {counts[-1]:.4e} instructions per {args.integration} call "
              f"(fibre_cube({args.n}, {args.fibres}, {args.n}), distort {args.distort}, n_gauss 4, 1 thread)",
              flush=True)
    for package, c in zip(packages[1:], counts[1:]):
        print(f"{package.name} / {packages[0].name}: {c / counts[0]:.4f}")


if __name__ == "__main__":
    main()
