"""Cold start of a checkout's package: a fresh process, an empty kernel cache, one compile.

    .venv/bin/python benchmarks/cold_start.py [--package CHECKOUT] [--what first|element|warmup|demo]
                                              [--elements NAME ...] [--kernels 25]

``--what first`` (default): ``import mortar1d3d`` and the first segment- and element-based
assembly of a tiny hex8 scene (``STARTUP_CODE`` of ``test_startup.py``); ``--what warmup``:
``mortar1d3d.warmup()``, every kernel. The child runs with ``NUMBA_CACHE_DIR`` pointing to a new
empty directory (removed afterwards) and the package of ``CHECKOUT`` (default: this one) first
on its path; its wall time and CPU seconds (user + system) are printed and it is an error if the
package came from elsewhere.

``--kernels N`` also prints where the compile time goes: Numba's compile events are recorded in
the child and the N functions with the largest *own* compile time are listed (the CPU time
between the start and end of a function's compilation minus that of the compilations nested in
it: a kernel compiles the functions it calls first; CPU, not wall time, so that the figures hold
on a loaded machine), the part of it Numba spent holding the LLVM lock (optimisation and machine
code), the number of type signatures each was compiled for, and the sum over all functions,
which is the time spent compiling. ``--dump FILE`` writes every compilation (function, own CPU
and LLVM seconds, argument types) as JSON, e.g. to find functions compiled for several
signatures. It then lists the own CPU time by stage: each of Numba's compiler passes
(``nopython_type_inference``, ``native_lowering``, ...; without the compilations nested in them),
LLVM split by what it does (parsing the IR text, function passes, linking the callees' modules,
module passes, machine code), and saving to and looking up the on-disk cache. Recording adds a
little to the wall time.

``--summarise A.json B.json [--group NAME=PATTERN,...]`` compiles nothing: it prints the own
compile time of earlier dumps by module, side by side, and the totals of named groups of
functions (e.g. ``--group rare=search_inside,locate_rare``; a pattern ending in ``$`` matches the end
of a name). ``--summarise A.json --split PATTERN ...`` instead lists, per function whose name contains
a pattern (``all``: every function), its own time split into typing (``nopython_type_inference``),
lowering (``native_lowering``, ``native_parfor_lowering``), LLVM (every ``LLVM:`` stage) and the rest
(Numba's other passes, the dispatcher), its compilations, and how often it was inlined at Numba IR
level (``inline="always"``: call sites, and in how many functions; each copy is typed and lowered
again in its caller): ``--dump`` records each compilation's stages and the functions inlined into it.

``--what element``: ``import mortar1d3d`` and the first element-based assembly of the same scene
alone (what a user of element-based integration waits for on a first run). ``--what demo``: the
warm-up the demo runs before its first result, ``warmup(elements=["hexahedron"],
integrations=["segment", "element"], physics=False)`` (the engine's kernels a hex8 scene runs);
with ``--elements NAME ...`` (meshio names, e.g. ``hexahedron27``) the same warm-up for those element
types instead of hex8 (what a user of curved elements would run before a first scene).

``--warm [N]``: afterwards the same code N (default 1) more times, each in a fresh process with the
now populated cache (the warm start: every kernel loaded, nothing compiled); their CPU seconds and
the in-process time the code prints are reported as well, and, with ``--kernels``, their compile
events (there should be none: a kernel that compiles again in every process, e.g. after a "Cannot
cache" warning, shows up here). ``--cache DIR`` uses and keeps DIR as the cache instead of a new
empty one: to pair warm starts of two versions, populate a directory per version once, then
alternate ``--cache DIR_A --package A --warm 4`` and the same for B.

Numba's settings reach the child through the environment, e.g. ``NUMBA_OPT=1`` for the LLVM
optimisation level (the cache directory is new in every run, so no kernel compiled at another
level is loaded).

To compare two versions, pair whole runs of this script so that both see the machine of the same
minutes: alternate the two commands (A B A B ...) and compare their CPU seconds (user + system of
the whole process, e.g. from ``/usr/bin/time``) run by run::

    /usr/bin/time -f "%U %S" .venv/bin/python benchmarks/cold_start.py --package OLD
    /usr/bin/time -f "%U %S" .venv/bin/python benchmarks/cold_start.py --package .
"""
import argparse
import os
import resource
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from _record import record
from test_startup import STARTUP_CODE

WARMUP_CODE = "import time; t=time.perf_counter(); import mortar1d3d as m; m.warmup(); print(time.perf_counter()-t)"
#: what the demo (examples/fibre_cube_demo.py) compiles before its first result: the engine's
#: kernels for hex8, both integrations, no physics
DEMO_CODE = ("import time; t=time.perf_counter(); import mortar1d3d as m; "
             "m.warmup(elements=['hexahedron'], integrations=['segment', 'element'], physics=False); "
             "print(time.perf_counter()-t)")
#: the element-based half of STARTUP_CODE alone
ELEMENT_CODE = STARTUP_CODE.replace("m.assemble_mortar(b,s,integration='segment'); ", "")
assert ELEMENT_CODE != STARTUP_CODE

#: run in the child before the measured code when ``--kernels`` is given: records Numba's compile
#: events and prints the functions with the largest own compile time when the child exits
RECORDER_CODE = """
import atexit, collections, time
from numba.core import event as _event
from numba.core import caching as _caching
_spans = []
# own CPU seconds by stage: every compiler pass by name, LLVM (the outermost holds of Numba's LLVM
# lock), saving to and loading from the on-disk cache, and the rest of a compilation (dispatcher)
_stages = collections.defaultdict(float)
_frames = []   # open frames: [kind, name, start, nested]; a frame's own time excludes nested frames
def _push(kind, name):
    _frames.append([kind, name, time.process_time(), 0.0])
def _pop():
    kind, name, start, nested = _frames.pop()
    total = time.process_time() - start
    if _frames:
        _frames[-1][3] += total
    _stages[name] += total - nested
    if _compiles.stack:      # the same split per compilation (the innermost open one)
        _compiles.stack[-1][3][name] += total - nested
    return total
class _Listener(_event.Listener):
    # per open compilation: its start (CPU seconds of the process), the CPU seconds of the
    # compilations nested in it and its own CPU seconds holding the LLVM lock
    def __init__(self):
        self.stack = []
    def on_start(self, ev):
        self.stack.append([time.process_time(), 0.0, 0.0, collections.defaultdict(float), collections.Counter()])
        _push("compile", "rest of a compilation (dispatcher, outside the passes)")
    def on_end(self, ev):
        _pop()
        start, nested, llvm, stages, inlined = self.stack.pop()
        total = time.process_time() - start
        if self.stack:
            self.stack[-1][1] += total
        d = ev.data.get("dispatcher")
        name = getattr(getattr(d, "py_func", None), "__qualname__", str(d))
        module = getattr(getattr(d, "py_func", None), "__module__", "?")
        _spans.append((module + "." + name, total - nested, llvm, str(ev.data.get("args")), dict(stages),
                       dict(inlined)))
_compiles = _Listener()
# functions inlined at Numba IR level (inline="always") into the open compilation, by name: each
# copy is typed and lowered again as part of its caller
from numba.core import inline_closurecall as _icc
_inline_function = _icc.InlineWorker.inline_function
def _counted_inline(self, caller_ir, block, i, function, *args, **kwargs):
    if _compiles.stack:
        _compiles.stack[-1][4][getattr(function, "__module__", "?") + "." + function.__qualname__] += 1
    return _inline_function(self, caller_ir, block, i, function, *args, **kwargs)
_icc.InlineWorker.inline_function = _counted_inline
class _PassListener(_event.Listener):
    def on_start(self, ev):
        _push("pass", "pass " + ev.data["name"].split(" [")[0])
    def on_end(self, ev):
        _pop()
class _LLVMListener(_event.Listener):
    # the outermost holds of the LLVM lock (optimisation, machine code), given to the innermost
    # open compilation: the one whose library is being finalised
    def __init__(self):
        self.depth = 0
    def on_start(self, ev):
        self.depth += 1
        if self.depth == 1:
            self.start = time.process_time()
            # inside a timed LLVM call (below) the time stays with that call's stage
            self.pushed = not (_frames and _frames[-1][1].startswith("LLVM: "))
            if self.pushed:
                _push("llvm", "LLVM: other calls (Numba's LLVM lock held)")
    def on_end(self, ev):
        self.depth -= 1
        if self.depth == 0:
            if self.pushed:
                _pop()
            if _compiles.stack:
                _compiles.stack[-1][2] += time.process_time() - self.start
def _timed(method, name):
    def wrapper(*args, **kwargs):
        _push("cache", name)
        try:
            return method(*args, **kwargs)
        finally:
            _pop()
    return wrapper
_caching.Cache.save_overload = _timed(_caching.Cache.save_overload, "saving to the on-disk cache")
_caching.Cache.load_overload = _timed(_caching.Cache.load_overload, "looking up (loading from) the on-disk cache")
# the LLVM lock's time split by what LLVM does (the lock is also held by these calls, inside them)
from llvmlite import binding as _ll
from llvmlite.binding import newpassmanagers as _npm
from numba.core import codegen as _codegen
_ll.parse_assembly = _timed(_ll.parse_assembly, "LLVM: parsing IR text")
_ll.ModuleRef.link_in = _timed(_ll.ModuleRef.link_in, "LLVM: linking callees' modules (link_in, clone)")
_ll.ModuleRef.clone = _timed(_ll.ModuleRef.clone, "LLVM: linking callees' modules (link_in, clone)")
_npm.FunctionPassManager.run = _timed(_npm.NewPassManager.run, "LLVM: function passes (per function, when lowered)")
_npm.ModulePassManager.run = _timed(_npm.NewPassManager.run, "LLVM: module passes (after linking: inlining, optimisation)")
_codegen.JitEngine.finalize_object = _timed(_codegen.JitEngine.finalize_object, "LLVM: machine code (MCJIT)")
_codegen.JitEngine.get_function_address = _timed(_codegen.JitEngine.get_function_address, "LLVM: machine code (MCJIT)")
_codegen.JitEngine.get_global_value_address = _timed(_codegen.JitEngine.get_global_value_address,
                                                     "LLVM: machine code (MCJIT)")
_codegen.JitEngine.add_module = _timed(_codegen.JitEngine.add_module, "LLVM: machine code (MCJIT)")
_ll.TargetMachine.emit_object = _timed(_ll.TargetMachine.emit_object, "LLVM: machine code (MCJIT)")
_ll.ModuleRef.__str__ = _timed(_ll.ModuleRef.__str__, "LLVM: printing and verifying IR")
_ll.ModuleRef.verify = _timed(_ll.ModuleRef.verify, "LLVM: printing and verifying IR")
_event.register("numba:llvm_lock", _LLVMListener())
_event.register("numba:compile", _compiles)
_event.register("numba:run_pass", _PassListener())
def _report():
    own = collections.defaultdict(float)
    own_llvm = collections.defaultdict(float)
    count = collections.Counter()
    for name, t, llvm, _args, _split, _inlined in _spans:
        own[name] += t
        own_llvm[name] += llvm
        count[name] += 1
    if DUMP:
        import json
        with open(DUMP, "w") as f:
            json.dump([{"function": n, "own_cpu_seconds": t, "own_llvm_seconds": l, "args": a, "stages": st,
                        "inlined": il} for n, t, l, a, st, il in _spans], f, indent=0)
    top = sorted(own.items(), key=lambda kv: -kv[1])[:KERNELS]
    total = sum(own.values())
    print(f"compiling: {total:.1f} CPU s ({sum(own_llvm.values()):.1f} s of it in LLVM) in {len(_spans)} "
          f"compilations of {len(own)} functions; the {len(top)} largest (own CPU time, LLVM part, signatures):",
          flush=True)
    for name, t in top:
        print(f"  {t:7.2f} s  {100 * t / total:5.1f} %  LLVM {own_llvm[name]:6.2f} s  x{count[name]}  {name}",
              flush=True)
    staged = sum(_stages.values())
    print(f"by stage (own CPU s; {staged:.1f} s in all, compiling and the cache; stages above 0.1 s):", flush=True)
    for name, t in sorted(_stages.items(), key=lambda kv: -kv[1]):
        if t >= 0.1:
            print(f"  {t:7.2f} s  {100 * t / staged:5.1f} %  {name}", flush=True)
atexit.register(_report)
"""


def _child(code, env, root, show):
    """Run ``code`` in a new interpreter: its wall and CPU seconds (user + system) and the time it
    printed itself on its last line (from before ``import mortar1d3d`` to the end)."""
    t0 = time.perf_counter()
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    proc = subprocess.run([sys.executable, "-c", code], env=env, cwd=root, check=True, text=True,
                          stdout=subprocess.PIPE)
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    own, other = None, []
    for line in proc.stdout.splitlines():      # the measured code's one number; the recorder's report after it
        try:
            own = float(line)
        except ValueError:
            other.append(line)
    if show:
        print("\n".join(other), flush=True)
    return {"wall_s": wall, "cpu_s": (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime),
            "in_process_s": own}


def _matches(function, patterns):
    """Whether the dotted name ``function`` contains one of ``patterns`` (a pattern ending in ``$``: ends with
    it, e.g. ``search._find_pairs$`` without ``_find_pairs_chunk``; ``all``: every function)."""
    return any(function.endswith(p[:-1]) if p.endswith("$") else (p == "all" or p in function) for p in patterns)


def summarise(dumps, groups=()):
    """Own compile CPU seconds (LLVM part) by module of every ``--dump`` file, side by side, and of
    each group of functions named by a ``NAME=PATTERN[,PATTERN...]`` (a function is in the group when
    its dotted name contains one of the patterns); nothing is compiled."""
    import collections
    import json

    tables = []
    for dump in dumps:
        rows = json.loads(Path(dump).read_text())
        by_module = collections.defaultdict(lambda: [0.0, 0.0, 0])
        by_group = collections.defaultdict(lambda: [0.0, 0.0, 0])
        for row in rows:
            module = row["function"].rsplit(".", 1)[0]
            if not module.startswith("mortar1d3d."):
                module = "Numba's own implementations"
            for key, table in [(module, by_module)] + [
                    (name, by_group) for name, patterns in groups if _matches(row["function"], patterns)]:
                table[key][0] += row["own_cpu_seconds"]
                table[key][1] += row["own_llvm_seconds"]
                table[key][2] += 1
        total = [sum(r["own_cpu_seconds"] for r in rows), sum(r["own_llvm_seconds"] for r in rows), len(rows)]
        tables.append((by_module, by_group, total))
    header = " | ".join(Path(d).name for d in dumps)
    print(f"own compile CPU s (LLVM part, compilations) per dump: {header}")
    modules = sorted({m for t in tables for m in t[0]}, key=lambda m: -max(t[0][m][0] for t in tables))
    for label, rows in [("all", [t[2] for t in tables])] + \
            [(f"group {name}", [t[1][name] for t in tables]) for name, _ in groups] + \
            [(m, [t[0][m] for t in tables]) for m in modules]:
        cells = " | ".join(f"{cpu:6.2f} ({llvm:5.2f}, {n:3d})" for cpu, llvm, n in rows)
        print(f"  {cells}  {label}")


#: --split's columns: which stages of a compilation (``--dump``'s ``stages``) count as what
SPLIT = (("typing", ("type_inference",)), ("lowering", ("lowering",)), ("LLVM", ("LLVM: ",)))


def split(dumps, patterns):
    """Per function whose dotted name contains one of ``patterns`` (all functions with ``all``), from
    each ``--dump`` file: its compilations, own compile CPU s split into typing, lowering, LLVM and the
    rest (Numba's other passes, the dispatcher), and how often it was inlined at Numba IR level
    (``inline="always"``: sites, and the distinct functions it was inlined into, each of which types
    and lowers the copy again); largest first."""
    import collections
    import json

    for dump in dumps:
        rows = json.loads(Path(dump).read_text())
        if rows and "stages" not in rows[0]:
            raise SystemExit(f"{dump}: written by an older cold_start.py (no stages per compilation)")
        table = collections.defaultdict(lambda: collections.Counter())
        sites = collections.Counter()
        callers = collections.defaultdict(set)
        for row in rows:
            for callee, n in row["inlined"].items():
                sites[callee] += n
                callers[callee].add(row["function"])
            if not _matches(row["function"], patterns):
                continue
            entry = table[row["function"]]
            entry["compilations"] += 1
            entry["own"] += row["own_cpu_seconds"]
            rest = row["own_cpu_seconds"]
            for column, keys in SPLIT:
                t = sum(v for k, v in row["stages"].items() if any(key in k for key in keys))
                entry[column] += t
                rest -= t
            entry["rest"] += rest
        for name in sites:
            if _matches(name, patterns) and name not in table:
                table[name]["compilations"] += 0     # inlined only: never compiled on its own
        print(f"{Path(dump).name}: own compile CPU s per function (typing, lowering, LLVM, rest; x compilations; "
              f"inlined at IR level: sites in callers)")
        for name, e in sorted(table.items(), key=lambda kv: -kv[1]["own"]):
            inl = f"  inlined {sites[name]} in {len(callers[name])}" if sites[name] else ""
            print(f"  {e['own']:6.2f}  ({e['typing']:5.2f}, {e['lowering']:5.2f}, {e['LLVM']:5.2f}, {e['rest']:5.2f}) "
                  f"x{e['compilations']}{inl}  {name}")


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--package", default=str(Path(__file__).resolve().parents[1]), metavar="CHECKOUT",
                        help="directory holding the mortar1d3d package to start (default: this checkout)")
    parser.add_argument("--what", choices=("first", "element", "warmup", "demo"), default="first")
    parser.add_argument("--elements", nargs="+", metavar="NAME",
                        help="with --what demo: warm up these solid element types (meshio names) instead of hex8")
    parser.add_argument("--kernels", type=int, default=0, metavar="N",
                        help="list the N functions with the largest own compile time")
    parser.add_argument("--warm", type=int, nargs="?", const=1, default=0, metavar="N",
                        help="then run the same code N (default 1) more times, each in a new process with the "
                             "populated cache")
    parser.add_argument("--cache", metavar="DIR",
                        help="use (and keep) DIR as the kernel cache instead of a new empty directory: with a "
                             "populated one, every run is a warm start")
    parser.add_argument("--dump", metavar="JSON",
                        help="with --kernels: write every compilation (function, own time, argument types) to JSON")
    parser.add_argument("--summarise", nargs="+", metavar="JSON",
                        help="print the own compile time by module of earlier --dump files (side by side) and exit")
    parser.add_argument("--group", action="append", default=[], metavar="NAME=PATTERN[,PATTERN]",
                        help="with --summarise: also the total of the functions whose name contains a pattern "
                             "(ending in $: ends with it)")
    parser.add_argument("--split", nargs="+", metavar="PATTERN",
                        help="with --summarise: per function whose name contains a pattern ('all': every "
                             "function), its own time split into typing, lowering, LLVM and the rest, its "
                             "compilations and how often it was inlined at IR level")
    args = parser.parse_args(argv)
    if args.summarise and args.split:
        split(args.summarise, args.split)
        return
    if args.summarise:
        summarise(args.summarise, [(g.split("=", 1)[0], g.split("=", 1)[1].split(",")) for g in args.group])
        return
    root = Path(args.package).resolve()
    if not (root / "mortar1d3d" / "__init__.py").is_file():
        parser.error(f"--package: no mortar1d3d package in {root}")
    if args.elements and args.what != "demo":
        parser.error("--elements: only with --what demo")
    demo = DEMO_CODE.replace("['hexahedron']", repr(list(args.elements))) if args.elements else DEMO_CODE
    code = {"first": STARTUP_CODE, "element": ELEMENT_CODE, "warmup": WARMUP_CODE, "demo": demo}[args.what]
    if args.kernels > 0:
        dump = repr(str(Path(args.dump).resolve())) if args.dump else "None"
        code = RECORDER_CODE.replace("KERNELS", str(args.kernels)).replace("DUMP", dump) + "\n" + code
    check = f"; import mortar1d3d as _m; assert _m.__file__.startswith({str(root)!r}), _m.__file__"
    cache = str(Path(args.cache).resolve()) if args.cache else tempfile.mkdtemp(prefix="m13-cold-")
    try:
        env = dict(os.environ, NUMBA_CACHE_DIR=cache,
                   PYTHONPATH=os.pathsep.join([str(root)] + [p for p in [os.environ.get("PYTHONPATH")] if p]))
        runs = []
        for run in range(1 + args.warm):
            cold = not any(Path(cache).rglob("*.nbi"))
            if run > 0 and args.kernels > 0:   # its compile events are listed; the dump is the cold run's
                code = code.replace(dump, "None")
            child = _child(code + check, env, root, show=args.kernels > 0)
            runs.append(dict(child, cold=cold))
            inside = "" if child["in_process_s"] is None else f" ({child['in_process_s']:.2f} s in the process)"
            where = "from an empty cache" if cold else "with a populated cache (warm start)"
            print(f"{args.what} {where}, package {root}: {child['wall_s']:.1f} s wall{inside}, "
                  f"{child['cpu_s']:.2f} CPU s", flush=True)
        record("cold_start", what=args.what, elements=args.elements, package=str(root),
               cold=next((r for r in runs if r["cold"]), None), warm=[r for r in runs if not r["cold"]])
    finally:
        if not args.cache:
            shutil.rmtree(cache, ignore_errors=True)


if __name__ == "__main__":
    main()
