"""The speed targets of issue 22, each with its figure, its ratio to the target and the command behind it.

    .venv/bin/python benchmarks/targets.py [--quick] [--large] [--items 1 2 3 4] [--rounds 2]
                                           [--package CHECKOUT] [--out FILE]
    make bench-targets            # the same; QUICK=1 for --quick

``--package CHECKOUT`` measures another checkout's package with this checkout's scripts (passed on to
``throughput.py``, ``newton_path.py``, ``cold_start.py`` and ``scaling.py``; the solves of item 3 take
no ``--package``): run it alternately for two checkouts, each with its own ``--out``, to compare them.

Runs the project's own benchmark scripts, one child process each (the commands are printed as
they start, with their time when they end, and each child's output is kept in
``benchmarks/results/targets/<step>.log``), collects the figures they hand on through
``benchmarks/_record.py`` and prints one table: the item of the issue, what is measured, the
figure, the target, figure / target, whether it is met, and the script that measured it. The
table and every record go to ``benchmarks/results/targets.json`` (git-ignored).

The four items and what measures them:

1. **The Newton path.** ``throughput.py --distort 0.1``: the distorted hex8 benchmark cube
   (``fibre_cube(20, 1000, 20)``, interior nodes moved by up to 0.1 cells, q = 4), Gauss points
   per second of one thread (median over the rounds), element- and segment-based, with the
   1-thread time of ``control.py``'s compute loop in the same rounds (about 255 ms on this
   project's VM when undisturbed: a larger figure means the machine was busy and every rate is
   low by about that factor). ``newton_path.py --scene S`` for S = hex8 (the same distorted cube),
   hex27, tet10 and nurbs27, each in its own process, the four scenes run in turn ``--rounds``
   times: the curved types' rates over the distorted hex8 rate of the same round (median over the
   rounds), against 0.5.
2. **The first run.** ``cold_start.py --what warmup|demo|element|first --warm``: a new process with
   an empty kernel cache (``mortar1d3d.warmup()``; the demo's warm-up, the hex8 engine's kernels
   for both integrations; the first element-based assembly of a tiny hex8
   scene; the first segment- and element-based assembly), then the same code in a second process
   on the filled cache (three times; the median). Compiling runs on one thread, so on a busy machine its CPU seconds are
   what an idle machine's wall clock would show: the cold rows are judged on CPU seconds (the wall
   seconds are in the JSON). The warm start is the second process's own time from before
   ``import mortar1d3d`` to the end.
3. **The coupled solve.** ``penalty_solve.py --n 20 40`` (``--large``: also 66, about a million
   unknowns, about 4 CPU minutes, a quarter of an hour of wall time on a busy machine, 12 GB): CPU seconds and CG iterations of the coupled penalty
   solve over those of the solid alone in the same run (targets 2 and 1.5).
   ``lagrange_solve.py --cases 15:155``: the block solver for Lagrange multipliers over the
   penalty solve of the same cube (target 1.5).
4. **Scaling.** ``scaling.py``: the log-log slope of the assembly time per control over the
   integration points (1e4 to 1e6; ``--large`` to 1e7) and of one Newton iteration's residual and
   tangent over the unknowns (1e4 to 1e6); linear is a slope of 1, reported against 1.05.
   ``throughput.py`` on the straight benchmark cube: two threads' speed-up over the speed-up of
   the control whose chunks are claimed as in the engine's kernels, same rounds (target 0.9).

``--quick`` runs fewer rounds and sizes (about a third of the time: the slopes then span 1e4 to
1e5 and the row says so; n = 20 only; no full warm-up). No figure is ever asserted: this prints
what the machine of the moment gives. Timing never goes into ``make test``.
"""
import argparse
import datetime
import json
import os
import platform
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

from _record import ENV, read  # noqa: E402

RESULTS = HERE / "results"

#: (item, key, what, target, larger is better)
TARGETS = [
    (1, "hex8_element", "distorted hex8, element-based, GP/s at 1 thread", 2.0e6, True),
    (1, "hex8_segment", "distorted hex8, segment-based, GP/s at 1 thread", 1.0e6, True),
    *[(1, f"{scene}_{integration}", f"{scene} / distorted hex8, {integration}-based (same round)", 0.5, True)
      for scene in ("hex27", "tet10", "nurbs27") for integration in ("element", "segment")],
    (2, "warmup_cold", "warmup() from an empty cache, CPU s", 25.0, False),
    (2, "demo_cold", "the demo's warm-up (hex8 engine, both integrations) from an empty cache, CPU s", 25.0, False),
    (2, "element_cold", "first element-based hex8 call from an empty cache, CPU s", 8.0, False),
    (2, "first_warm", "warm start (import + segment + element call), s in process", 1.5, False),
    *[(3, f"penalty_{n}_{kind}", f"fibre_cube({n}, 1000, 20) coupled / solid alone, {label}", target, False)
      for n in (20, 40, 66) for kind, label, target in (("cpu", "CPU s", 2.0), ("its", "CG iterations", 1.5))],
    (3, "lagrange_cpu", "Lagrange (block GMRES) / penalty, 15^3 cube with 155 fibres, CPU s", 1.5, False),
    (4, "slope_element", "assembly time over integration points, element-based, log-log slope", 1.05, False),
    (4, "slope_segment", "assembly time over integration points, segment-based, log-log slope", 1.05, False),
    (4, "slope_newton", "Newton iteration (residual + tangent) over unknowns, log-log slope", 1.05, False),
    (4, "threads_element", "2-thread speed-up / the claimed control's, straight cube, element-based", 0.9, True),
    (4, "threads_segment", "2-thread speed-up / the claimed control's, straight cube, segment-based", 0.9, True),
]


#: the child scripts that measure another checkout's package with ``--package CHECKOUT``
TAKES_PACKAGE = ("throughput.py", "newton_path.py", "cold_start.py", "scaling.py")


def steps(items, quick=False, large=False, rounds=2, package=None):
    """The child commands to run: (name, item, script, arguments, extra environment); with ``package``
    (a checkout), ``--package package`` in the arguments of the scripts that take it."""
    repeats = "3" if quick else "5"
    out = []
    if 1 in items:
        out.append(("throughput_distorted", 1, "throughput.py", ["--distort", "0.1", "--repeats", repeats], {}))
        for r in range(1 if quick else rounds):
            for scene in ("hex8", "hex27", "tet10", "nurbs27"):
                out.append((f"newton_path_{scene}_{r}", 1, "newton_path.py",
                            ["--scene", scene, "--repeats", "3", "--no-counts"], {}))
    if 2 in items:
        if not quick:
            out.append(("cold_warmup", 2, "cold_start.py", ["--what", "warmup"], {}))
        out.append(("cold_demo", 2, "cold_start.py", ["--what", "demo"], {}))
        out.append(("cold_element", 2, "cold_start.py", ["--what", "element"], {}))
        out.append(("cold_first", 2, "cold_start.py", ["--what", "first", "--warm", "3"], {}))
    if 3 in items:
        sizes = ["20"] if quick else ["20", "40"] + (["66"] if large else [])
        out.append(("penalty_solve", 3, "penalty_solve.py", ["--n", *sizes], {}))
        out.append(("lagrange_solve", 3, "lagrange_solve.py",
                    ["--cases", "15:155", "--direct", "--krylov", "gmres"], {}))
    if 4 in items:
        points = ["1e4", "1e5"] if quick else ["1e4", "1e5", "1e6"] + (["1e7"] if large else [])
        unknowns = ["1e4", "1e5"] if quick else ["1e4", "1e5", "1e6"]
        out.append(("scaling", 4, "scaling.py", ["--points", *points, "--unknowns", *unknowns], {}))
        out.append(("throughput_straight", 4, "throughput.py", ["--repeats", repeats], {}))
    if package:
        out = [(name, item, script, [*arguments, "--package", package] if script in TAKES_PACKAGE else arguments, extra)
               for name, item, script, arguments, extra in out]
    return out


def _median_ratio(rounds, key):
    values = [r[key] for r in rounds if r.get(key) is not None]
    return float(np.median(values)) if values else None


def figures(records):
    """key -> (figure, where it came from, the step that measured it), from the records of the children."""
    out = {}

    def put(key, value, note, record):
        out[key] = (value, note, record.get("step"))

    for r in records:
        kind = r["kind"]
        if kind == "throughput" and r["distort"] > 0:
            put(f"hex8_{r['integration']}", r["gp_per_s_1thread"],
                f"median of the rounds; control {1e3 * r['control_1thread_s']:.0f} ms", r)
        elif kind == "throughput":
            put(f"threads_{r['integration']}", r["of_claimed"],
                f"claimed control's speed-up {r['claimed_speedup']:.2f}x", r)
        elif kind == "cold_start":
            if r["what"] in ("warmup", "demo", "element") and r.get("cold"):      # none with a filled --cache
                put(f"{r['what']}_cold", r["cold"]["cpu_s"], f"wall {r['cold']['wall_s']:.0f} s", r)
            warm = [w for w in r.get("warm") or [] if w.get("in_process_s") is not None]
            if warm:
                put(f"{r['what']}_warm", float(np.median([w["in_process_s"] for w in warm])),
                    f"median of {len(warm)} warm start(s), wall {np.median([w['wall_s'] for w in warm]):.1f} s", r)
        elif kind == "penalty_solve" and r["solver"].startswith("aux"):
            put(f"penalty_{r['n']}_cpu", r["cpu_per_solid"],
                f"{r['cpu_s']:.1f} CPU s, {r['unknowns']} unknowns, peak {r['peak_memory_gb']:.1f} GB", r)
            put(f"penalty_{r['n']}_its", r["iterations_per_solid"], f"{r['iterations']} iterations", r)
        elif kind == "lagrange_solve" and r["path"] == "lagrange gmres":
            put("lagrange_cpu", r["cpu_per_penalty"], f"{r['cpu_s']:.1f} CPU s, {r['iterations']} iterations", r)
        elif kind == "scaling_assembly":
            put(f"slope_{r['integration']}", r["slope"], f"{r['points'][0]:.0e} to {r['points'][-1]:.0e} points", r)
        elif kind == "scaling_newton":
            put("slope_newton", r["slope"], f"{r['unknowns'][0]:.0e} to {r['unknowns'][-1]:.0e} unknowns", r)
    # the curved types against the distorted hex8 of the same round
    rounds = {}
    for r in records:
        if r["kind"] == "newton_path":
            rounds.setdefault(r["round"], {})[r["scene"]] = r
    per_round, first = [], {}
    for found in rounds.values():
        base = found.get("hex8")
        if base is None:
            continue
        for scene in ("hex27", "tet10", "nurbs27"):
            if scene in found:
                first.setdefault(scene, found[scene])
        per_round.append({f"{scene}_{i}": found[scene][f"{i}_gp_per_s"] / base[f"{i}_gp_per_s"]
                          for scene in ("hex27", "tet10", "nurbs27") if scene in found
                          for i in ("element", "segment")})
    for scene in ("hex27", "tet10", "nurbs27"):
        for i in ("element", "segment"):
            value = _median_ratio(per_round, f"{scene}_{i}")
            if value is not None:
                put(f"{scene}_{i}", value, f"median of {len(per_round)} round(s), each over its hex8", first[scene])
    return out


def table(found, commands):
    """Rows (item, what, figure, target, ratio, met, note, command) for every target measured;
    ``commands``: the command line of each step by its name."""
    rows = []
    for item, key, what, target, larger in TARGETS:
        if key not in found:
            continue
        value, note, step = found[key]
        ratio = value / target
        met = ratio >= 1.0 if larger else ratio <= 1.0
        rows.append(dict(item=item, key=key, what=what, figure=value, target=target,
                         direction=">=" if larger else "<=", ratio=ratio, met=bool(met), note=note,
                         command=commands.get(step, "")))
    return rows


def _fmt(x):
    return f"{x:.3g}" if abs(x) < 1e4 else f"{x:.2e}"


def format_table(rows):
    lines = [f"{'item':<5}{'what':<82}{'figure':>10}  {'target':>10}  {'fig/target':>10}  {'met':>4}  note"]
    for r in rows:
        lines.append(f"{r['item']:<5}{r['what']:<82}{_fmt(r['figure']):>10}  "
                     f"{r['direction'] + ' ' + _fmt(r['target']):>10}  {r['ratio']:>10.2f}  "
                     f"{'yes' if r['met'] else 'no':>4}  {r['note']}")
    return lines


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--items", type=int, nargs="+", default=[1, 2, 3, 4], choices=[1, 2, 3, 4])
    parser.add_argument("--quick", action="store_true", help="fewer rounds and sizes (about a third of the time)")
    parser.add_argument("--large", action="store_true",
                        help="also the 1M-unknown penalty solve and assembly at 1e7 points (~30 min more, 11 GB)")
    parser.add_argument("--rounds", type=int, default=2, help="rounds of the four newton_path scenes")
    parser.add_argument("--out", default=str(RESULTS / "targets.json"))
    parser.add_argument("--package", metavar="CHECKOUT",
                        help="measure the package of this checkout (with this checkout's scripts; the steps whose "
                             "script takes no --package, items 3, measure this checkout's package and say so)")
    args = parser.parse_args(argv)

    logs = RESULTS / "targets"
    logs.mkdir(parents=True, exist_ok=True)
    plan = steps(set(args.items), args.quick, args.large, args.rounds,
                 str(Path(args.package).resolve()) if args.package else None)
    records = []
    load = [os.getloadavg()[0]]
    t_all = time.perf_counter()
    for k, (name, item, script, child_args, extra) in enumerate(plan, 1):
        if args.package and script not in TAKES_PACKAGE:
            print(f"(benchmarks/{script} takes no --package: it measures this checkout's package)")
        command = [sys.executable, str(HERE / script), *child_args]
        print(f"[{k}/{len(plan)}] item {item}: benchmarks/{script} {' '.join(child_args)} ...", end=" ", flush=True)
        with tempfile.NamedTemporaryFile(prefix="m13-targets-", suffix=".jsonl", delete=False) as f:
            record_file = f.name
        env = dict(os.environ, **extra, **{ENV: record_file})
        env.setdefault("NUMBA_NUM_THREADS", "2")
        t0 = time.perf_counter()
        with open(logs / f"{name}.log", "w", encoding="utf-8") as log:
            proc = subprocess.run(command, stdout=log, stderr=subprocess.STDOUT, env=env, cwd=HERE.parent)
        got = read(record_file)
        os.unlink(record_file)
        for r in got:
            r["step"] = name
            if r["kind"] == "newton_path":
                r["round"] = int(name.rsplit("_", 1)[1])
        records.extend(got)
        load.append(os.getloadavg()[0])
        status = "" if proc.returncode == 0 else f"; FAILED with exit code {proc.returncode}, see {logs / name}.log"
        print(f"{time.perf_counter() - t0:.0f} s, {len(got)} figure(s), load {load[-1]:.1f}{status}", flush=True)

    found = figures(records)
    rows = table(found, {name: "benchmarks/" + " ".join([script, *child_args])
                         for name, _, script, child_args, _ in plan})
    print()
    print(f"issue 22 targets ({'quick' if args.quick else 'full'} run, {time.perf_counter() - t_all:.0f} s; "
          f"1-minute load average {min(load):.1f}-{max(load):.1f}; figures are the machine's of the moment)")
    for line in format_table(rows):
        print(line)
    missing = [key for _, key, *_ in TARGETS if key not in found]
    if missing:
        print(f"not measured in this run: {', '.join(missing)}")
    print("commands: " + "; ".join(sorted({r['command'] for r in rows if r['command']})))
    Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    with open(args.out, "w", encoding="utf-8") as f:
        json.dump({"date": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
                   "machine": {"python": platform.python_version(), "cpus": os.cpu_count(), "load": load},
                   "quick": args.quick, "large": args.large, "rows": rows, "records": records}, f, indent=1)
    print(f"written: {args.out}")


if __name__ == "__main__":
    main()
