"""Cold start of a checkout's package: a fresh process, an empty kernel cache, one compile.

    .venv/bin/python benchmarks/cold_start.py [--package CHECKOUT] [--what warmup|first] [--kernels 25]

``--what first`` (default): ``import mortar1d3d`` and the first segment- and element-based
assembly of a tiny hex8 scene (``STARTUP_CODE`` of ``test_startup.py``); ``--what warmup``:
``mortar1d3d.warmup()``, every kernel. The child runs with ``NUMBA_CACHE_DIR`` pointing to a new
empty directory (removed afterwards) and the package of ``CHECKOUT`` (default: this one) first
on its path; its wall time is printed and it is an error if the package came from elsewhere.

``--kernels N`` also prints where the compile time goes: Numba's compile events are recorded in
the child and the N functions with the largest *own* compile time are listed (the time between
the start and end of a function's compilation minus that of the compilations nested in it: a
kernel compiles the functions it calls first), with the number of type signatures each was
compiled for, and the sum over all functions, which is the time spent compiling. Recording adds
a little to the wall time.

To compare two versions, pair whole runs of this script so that both see the machine of the same
minutes: alternate the two commands (A B A B ...) and compare their CPU seconds (user + system of
the whole process, e.g. from ``/usr/bin/time``) run by run::

    /usr/bin/time -f "%U %S" .venv/bin/python benchmarks/cold_start.py --package OLD
    /usr/bin/time -f "%U %S" .venv/bin/python benchmarks/cold_start.py --package .
"""
import argparse
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from test_startup import STARTUP_CODE

WARMUP_CODE = "import mortar1d3d as m; m.warmup()"

#: run in the child before the measured code when ``--kernels`` is given: records Numba's compile
#: events and prints the functions with the largest own compile time when the child exits
RECORDER_CODE = """
import atexit, collections, time
from numba.core import event as _event
_spans = []
class _Listener(_event.Listener):
    def __init__(self):
        self.stack = []
    def on_start(self, ev):
        self.stack.append([time.perf_counter(), 0.0])
    def on_end(self, ev):
        start, nested = self.stack.pop()
        total = time.perf_counter() - start
        if self.stack:
            self.stack[-1][1] += total
        d = ev.data.get("dispatcher")
        name = getattr(getattr(d, "py_func", None), "__qualname__", str(d))
        module = getattr(getattr(d, "py_func", None), "__module__", "?")
        _spans.append((module + "." + name, total - nested))
_event.register("numba:compile", _Listener())
def _report():
    own = collections.defaultdict(float)
    count = collections.Counter()
    for name, t in _spans:
        own[name] += t
        count[name] += 1
    top = sorted(own.items(), key=lambda kv: -kv[1])[:KERNELS]
    total = sum(own.values())
    print(f"compiling: {total:.1f} s in {len(_spans)} compilations of {len(own)} functions; "
          f"the {len(top)} largest (own time, signatures):", flush=True)
    for name, t in top:
        print(f"  {t:7.2f} s  {100 * t / total:5.1f} %  x{count[name]}  {name}", flush=True)
atexit.register(_report)
"""


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--package", default=str(Path(__file__).resolve().parents[1]), metavar="CHECKOUT",
                        help="directory holding the mortar1d3d package to start (default: this checkout)")
    parser.add_argument("--what", choices=("first", "warmup"), default="first")
    parser.add_argument("--kernels", type=int, default=0, metavar="N",
                        help="list the N functions with the largest own compile time")
    args = parser.parse_args(argv)
    root = Path(args.package).resolve()
    if not (root / "mortar1d3d" / "__init__.py").is_file():
        parser.error(f"--package: no mortar1d3d package in {root}")
    code = (STARTUP_CODE if args.what == "first" else WARMUP_CODE)
    if args.kernels > 0:
        code = RECORDER_CODE.replace("KERNELS", str(args.kernels)) + "\n" + code
    check = f"; import mortar1d3d as _m; assert _m.__file__.startswith({str(root)!r}), _m.__file__"
    cache = tempfile.mkdtemp(prefix="m13-cold-")
    try:
        env = dict(os.environ, NUMBA_CACHE_DIR=cache,
                   PYTHONPATH=os.pathsep.join([str(root)] + [p for p in [os.environ.get("PYTHONPATH")] if p]))
        t0 = time.perf_counter()
        subprocess.run([sys.executable, "-c", code + check], env=env, cwd=root, check=True,
                       stdout=None if args.kernels > 0 else subprocess.DEVNULL)
        print(f"{args.what} from an empty cache, package {root}: {time.perf_counter() - t0:.1f} s")
    finally:
        shutil.rmtree(cache, ignore_errors=True)


if __name__ == "__main__":
    main()
