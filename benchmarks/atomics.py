"""Atomic instructions (reference counting) in the compiled kernels, per function (issue 22, item 1).

    .venv/bin/python benchmarks/atomics.py [--package CHECKOUT] [--scene hex8|hex27|tet10|nurbs27]
                                           [--integration element segment] [--roots NAME ...] [--all]

Numba counts the references of every array a compiled function receives: it increments the array's
reference count when the function starts and decrements it at its end (``NRT_incref``/``NRT_decref``,
each an atomic read-modify-write, ``lock``-prefixed on x86) unless its reference-count pruning pass
proves the pair removable. Inlined code pays nothing; a real call pays two atomic operations per
array argument whose pair survives. ``instructions.py`` cannot see this cost (one atomic operation is
one instruction, but costs tens of cycles), so this script counts them in the machine code itself.

It runs ``assemble_mortar`` on ``newton_path.py``'s scene once per ``--integration`` (so the kernels
are loaded from the cache, or compiled), then reads the optimised LLVM module of each root kernel (by
default the chunk functions of the point loops and of the segmentation, which the kernels call
through a symbol, and the rare path of locating a point: ``--roots`` names others, ``--all`` takes
every compiled function of the package): the module the cache keeps beside the machine code, from
which that code was made. Per function defined in it (the root and every callee LLVM did not
inline) it prints its LLVM instructions, its calls of ``NRT_incref`` in its entry block (run on every
call of the function; each is undone by one ``NRT_decref`` at its end, so a call costs twice as many
atomic operations), all its call sites of ``NRT_incref`` / ``NRT_decref``, atomic instructions
written out (an inlined increment) and its other calls. The counts are static (code, not executed
instructions) and do not depend on the load; with the calls per point of ``newton_path.py`` they give
the atomic operations per point.
"""
import argparse
import re
import sys
from collections import defaultdict
from pathlib import Path

from throughput import _package_root

# the package must be imported from the chosen checkout before anything imports it
sys.path.insert(0, str(_package_root(None)))

import mortar1d3d as m13  # noqa: E402
from newton_path import N_GAUSS, scene  # noqa: E402

#: the default roots: the loops over integration points and the segmentation's, each compiled on its own
ROOTS = ("_element_points_chunk", "_segment_points_chunk", "_pair_crossings_chunk", "_tile_chunk",
         "_check_tiling_chunk", "locate_rare")


def demangle(symbol):
    """``module.function`` of a Numba symbol (``_ZN<len><part>...`` up to its ABI tag), else the symbol."""
    if not symbol.startswith("_ZN"):
        return symbol
    parts, i = [], 3
    while i < len(symbol) and symbol[i].isdigit():
        j = i
        while symbol[j].isdigit():
            j += 1
        n = int(symbol[i:j])
        parts.append(symbol[j:j + n])
        i = j + n
    name = ".".join(parts) or symbol
    return re.sub(r"_([0-9a-f]{2})", lambda m: chr(int(m.group(1), 16)) if m.group(1) in ("3c", "3e", "2e") else m.group(0), name)


def optimised_module(library):
    """The optimised LLVM module of a compiled library, as text: the one the cache keeps beside the
    object code (a library loaded from the cache), else the library's final module."""
    module = library._shared_module if library._shared_module is not None else library._final_module
    return str(module)


def count_functions(text):
    """{symbol: counts} of the functions defined in an LLVM module's text: ``instructions``, ``entry``
    (calls of ``NRT_incref`` in the entry block, run on every call of the function), ``incref`` and
    ``decref`` (all their call sites), ``atomic`` (atomic instructions written out, ``atomicrmw`` /
    ``cmpxchg``: an inlined NRT_incref) and ``calls`` (calls of other functions, intrinsics not counted)."""
    counts = {}
    for match in re.finditer(r"^define [^@]*@\"?([^\"(]+)\"?\(.*?^}$", text, re.S | re.M):
        c = counts[match.group(1)] = defaultdict(int)
        entry = True        # before the first terminator: the entry block
        for line in match.group(0).splitlines()[1:-1]:
            if not line.startswith("  ") or line.lstrip().startswith(";"):
                continue
            c["instructions"] += 1
            if re.match(r"^\s+(br|ret|switch|unreachable|indirectbr)\b", line):
                entry = False
            elif "@NRT_incref(" in line:
                c["incref"] += 1
                c["entry"] += entry
            elif "@NRT_decref(" in line:
                c["decref"] += 1
            elif re.search(r"\b(atomicrmw|cmpxchg)\b", line):
                c["atomic"] += 1
            elif re.search(r"\bcall\b", line) and "@llvm." not in line:
                c["calls"] += 1
    return counts


def dispatchers():
    """(qualified name, dispatcher) of every compiled function of the package."""
    from numba.core.registry import CPUDispatcher

    seen = set()
    for name, module in sorted(sys.modules.items()):
        if not name.startswith("mortar1d3d") or module is None:
            continue
        for attr, value in sorted(vars(module).items()):
            if isinstance(value, CPUDispatcher) and id(value) not in seen and value.py_func.__module__ == name:
                seen.add(id(value))
                yield f"{name}.{value.py_func.__qualname__}", value


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--package", help="checkout whose package is counted (default: this one)")
    parser.add_argument("--scene", default="hex8", choices=("hex8", "hex27", "tet10", "nurbs27"))
    parser.add_argument("--integration", nargs="+", default=["element", "segment"])
    parser.add_argument("--roots", nargs="+", default=list(ROOTS), help="functions whose code is counted")
    parser.add_argument("--all", action="store_true", help="every compiled function of the package")
    args = parser.parse_args(argv)
    beams, solid_mesh = scene(args.scene, 20, 1000, 0.1)
    for integration in args.integration:
        m13.assemble_mortar(beams, solid_mesh, integration=integration, n_gauss=N_GAUSS)
    print(f"package {m13.__file__.rsplit('/', 2)[0]}; scene {args.scene}; integration {' '.join(args.integration)}")
    print("per function of each root's code (the root and the callees LLVM did not inline): LLVM instructions, "
          "NRT_incref calls on entry (each call of the function), NRT_incref / NRT_decref call sites, other atomic "
          "instructions, other calls")
    for qualname, dispatcher in dispatchers():
        if not args.all and qualname.rsplit(".", 1)[1] not in args.roots:
            continue
        for signature, cres in dispatcher.overloads.items():
            counts = count_functions(optimised_module(cres.library))
            counts = {k: v for k, v in counts.items() if k.startswith("_ZN10mortar1d3d")}
            entry = sum(c["entry"] for c in counts.values())
            print(f"\n{qualname} ({len(signature)} arguments): {entry} NRT_incref on entry in {len(counts)} functions")
            for symbol, c in sorted(counts.items(), key=lambda kv: (-kv[1]["entry"], demangle(kv[0]))):
                print(f"  {demangle(symbol)[:72]:72s} {c['instructions']:6d} {c['entry']:4d} "
                      f"{c['incref']:4d} / {c['decref']:4d} {c['atomic']:3d} {c['calls']:4d}")
    return 0


if __name__ == "__main__":
    main()
