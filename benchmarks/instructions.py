"""Instructions per assemble_mortar call, counted by valgrind (callgrind), for two checkouts.

    .venv/bin/python benchmarks/instructions.py [--package CHECKOUT ...] [--integration segment]
                                                [--stage call|search|points] [--distort 0.1]
                                                [--n 10] [--fibres 200] [--calls 3]
                                                [--element hexahedron|hexahedron27|tetra10|nurbs27] [--atomics]
                                                [--functions K]

On a shared, noisy machine seconds move by ±10 % from one run to the next; the number of executed
instructions does not (callgrind counts them on a simulated CPU, whatever else the machine does).
This script runs the library of each ``--package`` checkout (default: this one) in a child process
under ``valgrind --tool=callgrind``: the scene is built and assembled once (warm-up: the kernel
cache must already be filled, see below), then assembled ``--calls`` more times, and the same
child with no extra call is counted too. The difference divided by ``--calls`` is the count of
one call, free of the import, the scene generation and the warm-up. It prints the count of
every checkout, split into the compiled kernels (code valgrind sees without a name), the Python
interpreter, numpy/scipy and the rest, and each checkout's ratios to the first one.

``--atomics`` also counts the executed atomic instructions (valgrind's "global bus events",
``--collect-bus=yes``: every ``lock``-prefixed instruction), split the same way. In the kernels these
are the reference counting of arrays passed to compiled calls that Numba could not prune
(``benchmarks/atomics.py`` shows where they sit in the code): each costs tens of cycles, but counts
as one instruction above.

``--functions K`` also prints the K compiled functions that executed the most kernel instructions per
call. Valgrind sees Numba's code without symbols and names each piece by an address; the child
writes the entry address of every compiled function of the package (each dispatcher's compile
results), and each address is given to the nearest entry at or below it. Callees compiled into a
caller's code library (LLVM inlined them, or linked a private copy) count as the caller's, so a
Newton path's chunk function carries the projection it calls; what lies below every entry (the
parallel launch, Numba's runtime) is listed as such.

Counts say whether a version *does more work*. Two versions with equal counts and different
times differ in how the CPU runs the same work (code layout, branch prediction, memory), which
only timings (``throughput.py``) show.

The child runs with one Numba thread. Valgrind's simulated CPU lacks instruction sets of most
current hosts (AVX-512), so kernels cached for the host would not load under it, and Numba
compiles at about 1/50 of its normal speed there. The children therefore compile for a fixed
target that valgrind runs (``NUMBA_CPU_NAME=haswell`` with its features named in ``NUMBA_CPU_FEATURES``: AVX2) into a kernel cache of their own
(``--cache DIR``, one sub-directory per checkout), filled by a first run without valgrind. The
counts are those of this target's code, the same for every checkout compared, not of the code
the host runs. Right after a cache was filled, the first child under valgrind has been seen to
compile a kernel anyway (the count with no extra call then exceeds the other): the script
detects that and counts both again.
"""
import argparse
import os
import re
import subprocess
import sys
import tempfile
from pathlib import Path

HERE = Path(__file__).resolve()


def _stage_call(m13, beams, solid, args):
    """The call that is counted: a whole ``assemble_mortar``, or one stage of element-based
    integration (``--stage search``: the kernel input, i.e. solid and beam frames, the linearised
    maps and the candidate pairs; ``--stage points``: the integration points on a prepared input).
    Modules moved between versions; each stage is looked up where the checkout has it."""
    if args.stage == "call":
        return lambda: m13.assemble_mortar(beams, solid, integration=args.integration, n_gauss=4)
    import importlib
    def first(*names):
        for module, name in names:
            try:
                return getattr(importlib.import_module(module), name)
            except (ImportError, AttributeError):
                continue
        raise SystemExit(f"this checkout has none of {names}")
    kernel_input = first(("mortar1d3d.geometry.context", "KernelInput"), ("mortar1d3d.mortar.assemble", "KernelInput"))
    if args.stage == "search":
        return lambda: kernel_input(beams, solid)
    element_points = first(("mortar1d3d.integration.points", "element_points"),
                           ("mortar1d3d.integration.rules", "element_points"))
    ctx = kernel_input(beams, solid)
    return lambda: element_points(ctx, 4)


def _child(args):
    sys.path.insert(0, str(Path(args.package).resolve()))
    import numba
    import mortar1d3d as m13
    if not Path(m13.__file__).resolve().is_relative_to(Path(args.package).resolve()):
        raise SystemExit(f"imported {m13.__file__}, not the package of {args.package}")
    numba.set_num_threads(1)
    beams, solid = m13.generate.fibre_cube(args.n, args.fibres, args.n)
    if args.element == "nurbs27":
        # newton_path.py's nurbs27 scene: the NURBS pipe of nurbs_throughput.py (384 elements) with 40
        # helices (--n, --fibres, --distort do not apply); mortar1d3d is already the checkout's
        sys.path.insert(0, str(HERE.parent))
        from nurbs_throughput import helices, meshes
        beams, solid = helices(40), meshes((2, 24, 8))[0]
        args.distort = 0.0
    elif args.element != "hexahedron":
        # the same cube as quadratic elements (as newton_path.py's hex27 and tet10 scenes)
        solid = m13.generate.box((0.0, 0.0, 0.0), (1.0, 1.0, 1.0), (args.n,) * 3, element=args.element)
    if args.distort:
        solid = m13.generate.distort(solid, args.distort, seed=1)
    m13.assemble_mortar(beams, solid, integration=args.integration, n_gauss=4)
    call = _stage_call(m13, beams, solid, args)
    call()
    for _ in range(args.child_calls):
        call()
    if args.entries:
        _write_entries(args.entries)


def _write_entries(path):
    """Write the entry address and name of every compiled function of the package loaded in this
    process (``--functions``), one line ``address name`` each: each dispatcher's compile results,
    found as module attributes of the ``mortar1d3d`` modules. (Only entry points: a code library
    loaded from the cache keeps no object code whose symbol table would name the callees inside it.)"""
    from numba.core.registry import CPUDispatcher
    entries = {}
    for name, module in list(sys.modules.items()):
        if not (name == "mortar1d3d" or name.startswith("mortar1d3d.")):
            continue
        for attr in list(vars(module).values()):
            if not isinstance(attr, CPUDispatcher):
                continue
            for argtypes, cres in list(attr.overloads.items()):
                try:
                    address = cres.library.get_pointer_to_function(cres.fndesc.llvm_func_name)
                except Exception:
                    continue
                if address:
                    literal = [str(t.literal_value) for t in argtypes if hasattr(t, "literal_value")]
                    entries[address] = (f"{attr.py_func.__module__}.{attr.py_func.__qualname__}"
                                        + (f"[{','.join(literal)}]" if literal else ""))
    with open(path, "w") as f:
        for address in sorted(entries):
            f.write(f"{address:x} {entries[address]}\n")


def _environment(package, args):
    cache = Path(args.cache) / package.name
    # one thread everywhere: BLAS threads that spin while waiting would add instructions at random
    return dict(os.environ, NUMBA_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1", OMP_NUM_THREADS="1",
                MKL_NUM_THREADS="1", NUMBA_CPU_NAME=TARGET, NUMBA_CPU_FEATURES=TARGET_FEATURES,
                NUMBA_CACHE_DIR=str(cache))


#: the CPU the children compile for: one whose instruction sets valgrind simulates
TARGET = "haswell"
#: its instruction sets, named explicitly: otherwise Numba asks the CPU it runs on, and valgrind's
#: answer differs from the host's (the cache would then miss under valgrind)
TARGET_FEATURES = "+sse2,+sse3,+ssse3,+sse4.1,+sse4.2,+popcnt,+avx,+avx2,+fma,+bmi,+bmi2,+lzcnt,+movbe,+f16c,+cx16"


def _by_function(path, entries_path):
    """Kernel instructions of a callgrind output per compiled function (``--functions``). Valgrind
    sees Numba's code without symbols and names each piece of it by an address; each address is
    given to the compiled function whose entry point (written by the child, :func:`_write_entries`)
    is the nearest one at or below it. What LLVM inlined counts as its caller's; code between
    entries that are not listed (a ``prange`` kernel's body, wrappers) counts as the entry before
    it, so read the names as \"this function and what follows it in memory\"."""
    import bisect
    starts, names = [], []
    for line in Path(entries_path).read_text().splitlines():
        address, name = line.split(" ", 1)
        starts.append(int(address, 16))
        names.append(name)
    text = subprocess.run(["callgrind_annotate", "--inclusive=no", "--threshold=100", "--show=Ir", str(path)],
                          capture_output=True, text=True, check=True).stdout
    totals = {}
    for line in text.splitlines():
        # e.g. "  679,642 ( 0.03%)  ???:0x00000000049367a8 [???]" (a suffix "'2": a recursion level)
        match = re.match(r"\s*([\d,]+) \(\s*[\d.]+%\)\s+\?\?\?:0x([0-9a-fA-F]+)(?:'\d+)?\s+\[\?\?\?\]\s*$", line)
        if not match:
            continue
        address = int(match.group(2), 16)
        i = bisect.bisect_right(starts, address) - 1
        name = names[i] if i >= 0 else "(below every entry)"
        totals[name] = totals.get(name, 0) + int(match.group(1).replace(",", ""))
    return totals


def _by_object(path, event="Ir"):
    """Instructions (``event`` "Ir"; "Ge": atomic instructions, see ``--atomics``) of a callgrind output
    per object: "kernels" (Numba's code, which valgrind sees without a name), "python" (the
    interpreter), "numpy/scipy" and "other" (libc, LLVM, ...)."""
    text = subprocess.run(["callgrind_annotate", "--inclusive=no", "--threshold=100", f"--show={event}", str(path)],
                          capture_output=True, text=True, check=True).stdout
    parts = dict.fromkeys(PARTS, 0)
    for line in text.splitlines():
        match = re.match(r"\s*([\d,]+) \(\s*[\d.]+%\)\s+.*\[(.*)\]\s*$", line)
        if match:
            obj = Path(match.group(2)).name
            part = ("kernels" if obj == "???" else "python" if obj.startswith("libpython")
                    else "numpy/scipy" if ("umath" in obj or "openblas" in obj or obj.startswith("_"))
                    else "other")
            parts[part] += int(match.group(1).replace(",", ""))
    return parts


PARTS = ("kernels", "python", "numpy/scipy", "other")


def _count(package, args, calls):
    """Instructions executed by a child that makes ``calls`` extra calls: {"Ir": {part: count}}, and with
    ``--atomics`` the atomic instructions too ({"Ge": {part: count}}); with ``--functions`` the kernels'
    instructions per compiled function too ({"functions": {name: count}})."""
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "callgrind.out"
        entries = Path(tmp) / "entries.txt"
        cmd = ["valgrind", "--tool=callgrind", f"--callgrind-out-file={out}", f"--collect-bus={'yes' if args.atomics else 'no'}",
               sys.executable, str(HERE), "--child", "--package", str(package), "--integration",
               args.integration, "--distort", str(args.distort), "--n", str(args.n), "--fibres",
               str(args.fibres), "--element", args.element, "--stage", args.stage, "--child-calls", str(calls)]
        if args.functions:
            cmd += ["--entries", str(entries)]
        done = subprocess.run(cmd, env=_environment(package, args), capture_output=True, text=True)
        if done.returncode != 0:
            raise SystemExit(f"child failed ({package}, {calls} calls):\n{done.stderr[-2000:]}")
        counts = {event: _by_object(out, event) for event in (("Ir", "Ge") if args.atomics else ("Ir",))}
        if args.functions:
            counts["functions"] = _by_function(out, entries)
        return counts


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--package", action="append", metavar="CHECKOUT",
                        help="checkout whose package is counted (repeat for several; default: this one)")
    parser.add_argument("--integration", default="segment", choices=("segment", "element", "auto"))
    parser.add_argument("--distort", type=float, default=0.1, metavar="A",
                        help="move interior solid nodes by up to A times the element size (0: regular)")
    parser.add_argument("--n", type=int, default=10, help="solid elements per edge (default 10)")
    parser.add_argument("--element", default="hexahedron", choices=("hexahedron", "hexahedron27", "tetra10", "nurbs27"),
                        help="solid element type of the cube (default hexahedron: fibre_cube's own mesh); nurbs27: "
                             "newton_path.py's NURBS pipe with 40 helices instead of the cube")
    parser.add_argument("--fibres", type=int, default=200)
    parser.add_argument("--stage", default="call", choices=("call", "search", "points"),
                        help="count whole assemble_mortar calls (default) or one stage of element-based "
                             "integration: search (kernel input) or points (integration points)")
    parser.add_argument("--calls", type=int, default=3, help="counted calls (default 3)")
    parser.add_argument("--cache", default=str(Path(tempfile.gettempdir()) / "mortar1d3d-callgrind-cache"),
                        help="kernel cache of the children (default: in the temporary directory)")
    parser.add_argument("--atomics", action="store_true",
                        help="count the executed atomic (lock-prefixed) instructions too: callgrind's global "
                             "bus events, e.g. the reference counting of arrays passed to compiled calls")
    parser.add_argument("--functions", type=int, default=0, metavar="K",
                        help="also print the K compiled functions with the most kernel instructions per call "
                             "(each address given to the nearest compiled entry point below it; inlined code "
                             "counts as its caller's)")
    parser.add_argument("--child", action="store_true", help=argparse.SUPPRESS)
    parser.add_argument("--entries", help=argparse.SUPPRESS)
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
                        str(args.fibres), "--element", args.element], check=True, env=_environment(package, args))
        base = _count(package, args, 0)
        more = _count(package, args, args.calls)
        if any(more["Ir"][k] < base["Ir"][k] for k in ("kernels",)) or sum(more["Ir"].values()) < sum(base["Ir"].values()):
            # a kernel the first run under valgrind did not find in the cache was compiled there
            # (seen right after a checkout's cache was filled); both counts again, now warm
            print(f"{package}: the counted runs compiled a kernel; counting again", flush=True)
            base = _count(package, args, 0)
            more = _count(package, args, args.calls)
            if sum(more["Ir"].values()) < sum(base["Ir"].values()):
                raise SystemExit(f"{package}: counts still inconsistent (compilation inside the counted runs?)")
        per_call = {event: {k: (more[event][k] - base[event][k]) / args.calls for k in PARTS}
                    for event in base if event != "functions"}
        counts.append(per_call)
        what = f"{args.integration} call" if args.stage == "call" else f"'{args.stage}' stage"
        scene = ("NURBS pipe, 40 helices" if args.element == "nurbs27"
                 else f"fibre_cube({args.n}, {args.fibres}, {args.n}), {args.element}, distort {args.distort}")
        for event, name in (("Ir", "instructions"), ("Ge", "atomic instructions")):
            if event in per_call:
                print(f"{package}: {sum(per_call[event].values()):.4e} {name} per {what} ({scene}, n_gauss 4, "
                      "1 thread): " + ", ".join(f"{k} {v:.4e}" for k, v in per_call[event].items()), flush=True)
        if args.functions:
            names = set(more["functions"]) | set(base["functions"])
            diff = {n: (more["functions"].get(n, 0) - base["functions"].get(n, 0)) / args.calls for n in names}
            for n in sorted(diff, key=diff.get, reverse=True)[:args.functions]:
                print(f"    {diff[n]:.4e}  {n}", flush=True)
    for package, c in zip(packages[1:], counts[1:]):
        for event, name in (("Ir", "instructions"), ("Ge", "atomic instructions")):
            if event not in c:
                continue
            first, this = counts[0][event], c[event]
            total = sum(first.values())
            print(f"{package.name} / {packages[0].name}, {name}: total "
                  + (f"{sum(this.values()) / total:.4f}" if total else "-") + ", "
                  + ", ".join(f"{k} {this[k] / first[k]:.4f}" for k in PARTS if first[k]))

if __name__ == "__main__":
    main()
