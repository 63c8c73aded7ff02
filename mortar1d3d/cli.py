"""Command line: ``mortar1d3d run|plan scene.toml`` (or a 4C input file), ``mortar1d3d check input.4C.yaml``, ``mortar1d3d demo``, ``mortar1d3d warmup``,
``mortar1d3d bench report``."""
import argparse
import os
import runpy
import signal
import sys
import time
import warnings
from pathlib import Path


def _run(args):
    from .distributed import MissingPackageError
    from .errors import MeshError
    from .model import solve
    from .scene import SceneError
    from .solvers.newton import ConvergenceError
    try:
        scene = _read_scene(args.scene)
        if args.backend:
            scene.analysis = {**scene.analysis, "backend": args.backend}
        ranks = launched_ranks()
        if ranks > 1 and scene.analysis.get("backend") != "petsc":
            raise SceneError(f"analysis.backend = \"{scene.analysis.get('backend')}\" under an MPI launcher with "
                             f"{ranks} processes: each would solve the whole scene and write the same files; "
                             "set analysis.backend = \"petsc\" (or run --backend petsc), or run without mpiexec")
        if not args.quiet:
            print(f"mortar1d3d run {args.scene}: {scene!r}", flush=True)
        start = time.perf_counter()
        out = Path(args.out) if args.out else Path("results") / scene.name
        # a distributed run: every rank writes its elements under out/parallel, rank 0 the Result
        parallel = out / "parallel" if scene.analysis.get("backend") == "petsc" else None
        result = solve(scene, progress=not args.quiet, parallel_output=parallel)
        if result is None:          # a rank other than 0 of a distributed run: rank 0 writes
            return 0
        paths = result.write(out, samples_per_element=args.samples)
    except (SceneError, MeshError, ConvergenceError, MissingPackageError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2 if isinstance(exc, (SceneError, MeshError, MissingPackageError)) else 3
    if not args.quiet:
        print(f"{result!r}")
        for line in result.coupling_summary():
            print(f"  {line}")
        print(f"wrote {len(paths)} files to {out}/ (open {out / 'result.pvd'} in ParaView) "
              f"in {time.perf_counter() - start:.2f} s")
    return 0


#: environment variables in which MPI launchers give the number of processes started (Open MPI,
#: MPICH/Intel MPI and Slurm's PMI, MVAPICH)
LAUNCHER_SIZE_VARIABLES = ("OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "MV2_COMM_WORLD_SIZE")


def launched_ranks(environ=None):
    """The number of processes an MPI launcher (``mpiexec``, ``srun``) started with this one, 1 if
    none did, read from the launcher's environment without starting MPI."""
    environ = os.environ if environ is None else environ
    for name in LAUNCHER_SIZE_VARIABLES:
        value = environ.get(name, "")
        if value.isdigit() and int(value) > 0:
            return int(value)
    return 1


def _read_scene(path):
    """A TOML scene, or a 4C input file (``.yaml``/``.yml``, read by :mod:`mortar1d3d.io.fourc`)."""
    from .scene import Scene
    if str(path).endswith((".yaml", ".yml")):
        return Scene.from_4c(path)
    return Scene.from_toml(path)


def _check(args):
    """``mortar1d3d check input.4C.yaml``: run a 4C input file and compare its RESULT DESCRIPTION."""
    from .errors import MeshError
    from .io.fourc import check
    from .scene import SceneError
    from .solvers.newton import ConvergenceError
    try:
        report = check(args.input, progress=not args.quiet)
    except (SceneError, MeshError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    except ConvergenceError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 3
    print(f"mortar1d3d check {args.input}: {len(report.rows)} result entries, solved in {report.seconds:.2f} s")
    print(report.table())
    failed = sum(r.status == "FAIL" for r in report.rows)
    other = sum(r.status == "not comparable" for r in report.rows)
    print(f"{'FAILED' if failed else 'passed'}: {len(report.rows) - failed - other} pass, {failed} fail, "
          f"{other} not comparable; max deviation {report.max_deviation:.3g}")
    return 1 if failed else 0


def _plan(args):
    from .errors import MeshError
    from .model import plan
    from .scene import SceneError
    try:
        effects = plan(_read_scene(args.scene))
    except (SceneError, MeshError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    print(f"mortar1d3d plan {args.scene}: solve() will run")
    for line in str(effects).splitlines():
        print(f"  {line}")
    return 0


def _bench_report(args):
    """``mortar1d3d bench report``: the accuracy-vs-time study of issue 5 (mortar1d3d.study)."""
    from .study import make_report
    preset = "tiny" if args.tiny else "quick" if args.quick else "full"
    start = time.perf_counter()
    path = make_report(preset, args.out, progress=None if args.quiet else print)
    if not args.quiet:
        print(f"report written to {path} in {time.perf_counter() - start:.0f} s")
    return 0


def _format_warning(message, category, filename, lineno, line=None):
    """A warning on the command line: what it says, not where in the library it was raised."""
    return f"warning: {category.__name__}: {message}\n"


def main(argv=None):
    """Run the command line; returns the exit code.

    Warnings are printed as ``warning: <category>: <message>``. When the reader of stdout goes
    away (``mortar1d3d plan scene.toml | head``) the command stops quietly, as other command-line
    tools do, with the exit status of a process ended by SIGPIPE.
    """
    previous = warnings.formatwarning
    warnings.formatwarning = _format_warning
    try:
        return _main(argv)
    except BrokenPipeError:
        # the interpreter flushes stdout once more at exit: point it at /dev/null so that this
        # flush does not fail (and print) again
        try:
            os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        except (AttributeError, OSError, ValueError):    # stdout is not a file (embedded use)
            pass
        return 128 + getattr(signal, "SIGPIPE", 13)
    finally:
        warnings.formatwarning = previous


def _main(argv):
    parser = argparse.ArgumentParser(prog="mortar1d3d", description="Beams embedded in 3D solids (mortar coupling)")
    from . import __version__
    parser.add_argument("--version", action="version", version=f"mortar1d3d {__version__}")
    sub = parser.add_subparsers(dest="command", required=True)
    run = sub.add_parser("run", help="solve a scene file and write a ParaView series")
    run.add_argument("scene", help="TOML scene file, or a 4C input file (.4C.yaml)")
    run.add_argument("--out", help="output directory (default results/<scene name>)")
    run.add_argument("--samples", type=int, default=8, help="beam samples per element in the output")
    run.add_argument("--quiet", action="store_true", help="no progress output")
    run.add_argument("--backend", choices=("serial", "petsc"),
                     help="analysis.backend instead of the scene's (petsc: under mpiexec -n N, docs/distributed.md)")
    pl = sub.add_parser("plan", help="print what solving a scene file will compute")
    pl.add_argument("scene")
    chk = sub.add_parser("check", help="run a 4C input file (.4C.yaml) and compare with its RESULT DESCRIPTION")
    chk.add_argument("input", help="4C input file")
    chk.add_argument("--quiet", action="store_true", help="no progress output")
    demo = sub.add_parser("demo", help="assemble the benchmark scene, print certificates, write VTU and a plot")
    demo.add_argument("--out", default="results/demo")
    warm = sub.add_parser("warmup", help="compile (or load cached) kernels")
    warm.add_argument("--elements", nargs="+", metavar="TYPE",
                      help="only the engine's kernels for these solid element types (meshio names), e.g. hexahedron")
    warm.add_argument("--integration", nargs="+", choices=("segment", "element", "auto"),
                      help="with --elements: only these integrations (default: all three)")
    warm.add_argument("--no-physics", action="store_true", help="leave out the physics (solid, beams, coupling)")
    # -- bench report (issue 5): self-contained block
    bench = sub.add_parser("bench", help="measured studies")
    bench_sub = bench.add_subparsers(dest="bench_command", required=True)
    report = bench_sub.add_parser("report", help="accuracy vs time of the integration variants: writes "
                                  "<out>/accuracy_vs_time.md with tables and PNG plots")
    size = report.add_mutually_exclusive_group()
    size.add_argument("--quick", action="store_true", help="smaller study (under two minutes with a warm cache)")
    size.add_argument("--tiny", action="store_true", help="smoke-test size (used by the test suite)")
    report.add_argument("--out", default="report", help="output directory (default: report)")
    report.add_argument("--quiet", action="store_true", help="no progress output")
    args, rest = parser.parse_known_args(argv)
    if args.command == "bench":
        return _bench_report(args)
    if args.command == "run":
        return _run(args)
    if args.command == "plan":
        return _plan(args)
    if args.command == "check":
        return _check(args)
    if args.command == "warmup":
        from .warmup import INTEGRATIONS, warmup
        if args.integration and not args.elements:
            parser.error("warmup: --integration needs --elements")
        try:
            warmup(verbose=True, elements=args.elements, integrations=args.integration or INTEGRATIONS,
                   physics=not args.no_physics)
        except ValueError as error:
            print(f"mortar1d3d warmup: {error}", file=sys.stderr)
            return 2
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
