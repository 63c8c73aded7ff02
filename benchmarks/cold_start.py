"""Cold start of a checkout's package: a fresh process, an empty kernel cache, one compile.

    .venv/bin/python benchmarks/cold_start.py [--package CHECKOUT] [--what warmup|first]

``--what first`` (default): ``import mortar1d3d`` and the first segment- and element-based
assembly of a tiny hex8 scene (``STARTUP_CODE`` of ``test_startup.py``); ``--what warmup``:
``mortar1d3d.warmup()``, every kernel. The child runs with ``NUMBA_CACHE_DIR`` pointing to a new
empty directory (removed afterwards) and the package of ``CHECKOUT`` (default: this one) first
on its path; its wall time is printed and it is an error if the package came from elsewhere.

To compare two versions, pair whole runs of this script so that both see the machine of the same
minutes, e.g. with an A/B timer that alternates the two commands::

    farm-bench -n 3 --warmup 0 --vs ".venv/bin/python benchmarks/cold_start.py --package OLD" \\
        -- .venv/bin/python benchmarks/cold_start.py --package .
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


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--package", default=str(Path(__file__).resolve().parents[1]), metavar="CHECKOUT",
                        help="directory holding the mortar1d3d package to start (default: this checkout)")
    parser.add_argument("--what", choices=("first", "warmup"), default="first")
    args = parser.parse_args(argv)
    root = Path(args.package).resolve()
    if not (root / "mortar1d3d" / "__init__.py").is_file():
        parser.error(f"--package: no mortar1d3d package in {root}")
    code = (STARTUP_CODE if args.what == "first" else WARMUP_CODE)
    check = f"; import mortar1d3d as _m; assert _m.__file__.startswith({str(root)!r}), _m.__file__"
    cache = tempfile.mkdtemp(prefix="m13-cold-")
    try:
        env = dict(os.environ, NUMBA_CACHE_DIR=cache,
                   PYTHONPATH=os.pathsep.join([str(root)] + [p for p in [os.environ.get("PYTHONPATH")] if p]))
        t0 = time.perf_counter()
        subprocess.run([sys.executable, "-c", code + check], env=env, cwd=root, check=True,
                       stdout=subprocess.DEVNULL)
        print(f"{args.what} from an empty cache, package {root}: {time.perf_counter() - t0:.1f} s")
    finally:
        shutil.rmtree(cache, ignore_errors=True)


if __name__ == "__main__":
    main()
