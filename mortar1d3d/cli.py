"""Command line: ``mortar1d3d demo``, ``mortar1d3d warmup``."""
import argparse
import runpy
import sys
from pathlib import Path


def main(argv=None):
    parser = argparse.ArgumentParser(prog="mortar1d3d", description="Beams embedded in 3D solids (mortar coupling)")
    sub = parser.add_subparsers(dest="command", required=True)
    demo = sub.add_parser("demo", help="assemble the benchmark scene, print certificates, write VTU and a plot")
    demo.add_argument("--out", default="results/demo")
    sub.add_parser("warmup", help="compile (or load cached) kernels")
    args, rest = parser.parse_known_args(argv)
    if args.command == "warmup":
        from .warmup import warmup
        warmup(verbose=True)
        return 0
    example = Path(__file__).resolve().parent.parent / "examples" / "fibre_cube_demo.py"
    if not example.exists():
        print("the demo example is part of the source tree (examples/fibre_cube_demo.py); "
              "run it from a checkout", file=sys.stderr)
        return 1
    sys.argv = [str(example), "--out", args.out, *rest]
    runpy.run_path(str(example), run_name="__main__")
    return 0


if __name__ == "__main__":
    sys.exit(main())
