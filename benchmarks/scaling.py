"""How cost grows with problem size: assembly per integration point, Newton iteration per unknown.

    .venv/bin/python benchmarks/scaling.py [--part assembly newton] [--rounds 3]
                                           [--points 1e4 1e5 1e6 1e7] [--unknowns 1e4 1e5 1e6]
                                           [--profile TOP] [--package CHECKOUT]
                                           [--enforcement penalty|lagrange] [--stages]
                                           [--order generated|morton]

Issue 22, item 4. One thread throughout; every timed call is paired with the control loop of
``control.py`` (1 thread) in the same round, and the figure kept per size is the median over the
rounds of ``time / control``, so that the machine's speed of the moment cancels. The slope of
log(time) over log(size) is fitted by least squares; 1 means cost proportional to size.

- ``assembly``: ``assemble_mortar`` (element- and segment-based, 4 Gauss points) on
  ``fibre_cube(n, fibres, n)``, the whole scene grown together at the benchmark scene's density
  (about ten element-based integration points per solid element; each fibre is 0.3 long, the cube
  1, so its n elements are 0.3 times as long as the solid elements): n = (points / 10)^(1/3),
  fibres = points / (4 n). Prints the time per call, per
  integration point and per control, for each size, and the slope. ``--stages`` also prints, per
  size, the wall time per point of each stage (the call's ``timings``), the scene's work per point
  (candidate pairs, groups of points, entries of M and D, solid and beam elements: if these stay
  level, a growth of the cost per point is a growth of the cost of the same work), the pooled
  blocks of ``carve`` after the call (in use, unused), and per stage (medians over the rounds) the
  user and system CPU seconds, the minor page faults and the bytes of new (not reused) carved
  blocks, each per point: the stage boundaries are the call's own clock readings, which the
  benchmark records with ``getrusage`` as well.
- ``newton``: one Newton iteration's evaluation ``Model.residual(z, t, tangent=True)`` (residual
  and tangent of the solid, the beams and the penalty coupling, in the basis of the unknowns) of a
  Saint Venant–Kirchhoff cube ``fibre_cube(n, fibres, elements)`` with torsion-free fibres,
  nonlinear kinematics, at a displacement state z of small random numbers (so nothing is
  evaluated at the reference only). n is chosen so that the unknowns approach each requested
  count; the fibres grow with n² and their elements with n (constant density per solid element).
  Prints the time per iteration and per unknown, and the slope. The coupling operators (the
  mortar assembly) are built once in ``Model.prepare`` and are not part of the iteration.
  ``--profile TOP`` profiles one more call per size (cProfile) and prints the TOP functions by
  their own time. ``--stages`` also prints, per size, the work per unknown (solid elements,
  tangent entries: a cube of n³ elements has (n+1)³ nodes, so the elements per unknown rise with
  n) and the CPU seconds (user + system, medians over the rounds; steadier than wall seconds on a
  shared machine) of the call, of the solid's element kernel alone (into a tangent-sized array
  already in use) per element, of the rest per unknown, and of the first touch of a new
  tangent-sized array, then the slopes of each over its own size. ``--enforcement lagrange`` runs the same scene with Lagrange multipliers (the
  unknowns then include them, and the Jacobian is the saddle-point matrix).

Peak memory (``ru_maxrss`` of the process) is printed at the end. On this shared machine the
largest sizes take minutes; choose the sizes with ``--points`` / ``--unknowns``.
"""
import argparse
import os
import resource
import sys
import time
import warnings
from pathlib import Path

import numba
import numpy as np

# throughput puts the measured checkout (``--package CHECKOUT``, default this one) first on the path
from throughput import _timed  # noqa: E402,I100

from _record import record  # noqa: E402
import mortar1d3d as m13  # noqa: E402
from control import control_times  # noqa: E402
from mortar1d3d.model import Model  # noqa: E402
from mortar1d3d.model.build import build  # noqa: E402

N_GAUSS = 4


def slope(sizes, times):
    """Least-squares slope of log(times) over log(sizes)."""
    return float(np.polyfit(np.log(np.asarray(sizes, float)), np.log(np.asarray(times, float)), 1)[0])


def _control():
    return control_times((1,))[1]


def _faults():
    """Minor page faults of this process so far (the kernel's count: unlike seconds, it does not
    depend on the load)."""
    return resource.getrusage(resource.RUSAGE_SELF).ru_minflt


def _morton(points, bits=10):
    """Morton (Z-order) code of points in the unit cube, ``bits`` per axis."""
    q = np.clip((np.asarray(points) * (1 << bits)).astype(np.int64), 0, (1 << bits) - 1)
    code = np.zeros(len(q), dtype=np.int64)
    for b in range(bits):
        for axis in range(3):
            code |= ((q[:, axis] >> b) & 1) << (3 * b + axis)
    return code


def spatially_ordered(beams, fibres):
    """The fibres of ``fibre_cube`` renumbered in the Morton order of their midpoints (same
    centrelines, same elements per fibre): beam elements that follow each other in memory then
    lie near each other in the solid."""
    m = beams.n_nodes // fibres - 1
    positions = beams.positions.reshape(fibres, m + 1, 3)
    tangents = beams.tangents.reshape(fibres, m + 1, 3)
    order = np.argsort(_morton(positions.mean(axis=1)), kind="stable")
    return m13.BeamMesh.hermite(positions[order].reshape(-1, 3), tangents[order].reshape(-1, 3), beams.elements)


class _StageClock:
    """Stands in for the ``time`` module of ``mortar1d3d.mortar.assemble`` during one call: each
    ``perf_counter()`` reading (the call's stage boundaries, which fill its ``timings``) also
    records the process's user and system CPU seconds and minor page faults at that moment."""

    def __init__(self):
        self.marks = []

    def perf_counter(self):
        usage = resource.getrusage(resource.RUSAGE_SELF)
        t = time.perf_counter()
        self.marks.append((t, usage.ru_utime, usage.ru_stime, usage.ru_minflt, _new_bytes()))
        return t


def _stage_call(call):
    """``call()`` (an ``assemble_mortar``) with its stages' CPU seconds: the result and a dict
    stage -> (wall, user, system seconds, minor faults). Each interval between two of the call's
    clock readings is named by the ``timings`` entry with the same wall time (the same subtraction);
    the interval from the last stage to the end of the call (the constraint residual and the
    segments table) is "rest"."""
    clock = _StageClock()
    module = sys.modules["mortar1d3d.mortar.assemble"]
    module.time = clock
    try:
        ops = call()
    finally:
        module.time = time
    marks = clock.marks
    names = {seconds: name for name, seconds in ops.timings.items() if name != "total"}
    out = {}
    for i in range(1, len(marks)):
        name = names.get(marks[i][0] - marks[i - 1][0], "rest" if i == len(marks) - 1 else f"interval {i}")
        out[name] = tuple(b - a for a, b in zip(marks[i - 1], marks[i]))
    out["call"] = tuple(b - a for a, b in zip(marks[0], marks[-1]))
    return ops, out


def _new_bytes():
    """Bytes of the new (not reused) blocks ``carve`` has made so far; NaN for a checkout without the count."""
    from mortar1d3d import _memory
    return getattr(_memory, "new_bytes", float("nan"))


def _pool_bytes():
    """GB of ``carve``'s pooled blocks (in use, unused); NaN for a checkout without ``pool_bytes``."""
    from mortar1d3d import _memory
    if not hasattr(_memory, "pool_bytes"):
        return float("nan"), float("nan")
    return tuple(b / 2**30 for b in _memory.pool_bytes())


def _work(ops, n, fibres):
    """The scene's own work per integration point (the same per point at every size if the cost
    per point is to stay level)."""
    count = ops.n_integration_points
    return {"candidate pairs": ops.diagnostics["candidate_pairs"] / count, "groups": len(ops.segments) / count,
            "M entries": ops.M.nnz / count, "D entries": ops.D.nnz / count, "solid elements": n ** 3 / count,
            "beam elements": fibres * n / count}


def assembly(points, rounds, stages=False, order="generated"):
    print(f"assembly: assemble_mortar on fibre_cube(n, fibres, n), {N_GAUSS} Gauss points, 1 thread; "
          f"median over {rounds} rounds")
    print(f"{'integration':<12}{'n':>5}{'fibres':>8}{'points':>11}{'time s':>9}{'ns/point':>10}{'/control':>10}")
    m13.assemble_mortar(*m13.generate.fibre_cube(2, 2, 2), integration="element")     # compile before timing
    m13.assemble_mortar(*m13.generate.fibre_cube(2, 2, 2), integration="segment")
    for integration in ("element", "segment"):
        sizes, ratios, cpu_calls = [], [], []
        for target in points:
            n = max(2, int(round((target / 10) ** (1 / 3))))
            fibres = max(1, int(round(target / (N_GAUSS * n))))
            beams, solid = m13.generate.fibre_cube(n, fibres, n)
            if order == "morton":
                beams = spatially_ordered(beams, fibres)
            m13.assemble_mortar(beams, solid, integration=integration, n_gauss=N_GAUSS)      # first touch
            times, per_control, stage_cpu = [], [], []
            for _ in range(rounds):
                c = _control()
                faults = _faults()
                if stages:
                    t0 = time.perf_counter()
                    ops, cpu = _stage_call(lambda: m13.assemble_mortar(beams, solid, integration=integration,
                                                                       n_gauss=N_GAUSS))
                    t = time.perf_counter() - t0
                    stage_cpu.append(cpu)
                    pooled = _pool_bytes()
                else:
                    t, ops = _timed(lambda: m13.assemble_mortar(beams, solid, integration=integration,
                                                                n_gauss=N_GAUSS))
                faults = _faults() - faults
                times.append(t)
                per_control.append(t / c)
                count = ops.n_integration_points
                timings = dict(ops.timings)
                work = _work(ops, n, fibres) if stages else None
                del ops
            t, r = float(np.median(times)), float(np.median(per_control))
            sizes.append(count)
            ratios.append(r)
            print(f"{integration:<12}{n:>5}{fibres:>8}{count:>11.3g}{t:>9.3f}{1e9 * t / count:>10.1f}{r:>10.3g}",
                  flush=True)
            if stages:
                print("      ns per point by stage (last round): " + ", ".join(
                    f"{name} {1e9 * seconds / count:.0f}" for name, seconds in timings.items() if name != "total")
                    + f"; page faults per 1000 points {1e3 * faults / count:.2f}", flush=True)
                print("      work per point: " + ", ".join(f"{name} {value:.4g}" for name, value in work.items())
                      + "; pooled blocks after the call (GiB): in use {:.2f}, unused {:.2f}".format(*pooled),
                      flush=True)
                print(f"      CPU ns per point by stage, user + system (medians over {rounds} rounds), "
                      "minor faults per 1000 points, new carved blocks in bytes per point:", flush=True)
                for name in stage_cpu[-1]:
                    user, system, minflt, fresh = (float(np.median([c[name][k] for c in stage_cpu]))
                                                   for k in (1, 2, 3, 4))
                    print(f"        {name:<20}{1e9 * user / count:>8.0f} +{1e9 * system / count:>6.0f}"
                          f"{1e3 * minflt / count:>10.2f}{fresh / count:>10.1f}", flush=True)
                cpu_calls.append(float(np.median([c["call"][1] + c["call"][2] for c in stage_cpu])))
            del beams, solid
        print(f"{integration:<12}slope of log(time/control) over log(points): {slope(sizes, ratios):.3f}")
        if stages and len(sizes) > 1:
            print(f"{integration:<12}slope of log(CPU seconds, user + system) over log(points): "
                  f"{slope(sizes, cpu_calls):.3f}")
        record("scaling_assembly", integration=integration, points=[int(p) for p in sizes],
               per_control=ratios, slope=slope(sizes, ratios))


def newton_scene(n, enforcement="penalty"):
    fibres = max(4, n * n // 4)
    beams, solid = m13.generate.fibre_cube(n, fibres, max(2, n // 2))
    return m13.Scene(solid={"mesh": solid, "material": {"model": "saint_venant_kirchhoff", "E": 1e9, "nu": 0.3}},
                     beams=[{"mesh": beams, "section": {"E": 2e11, "radius": 0.2 / n}}],
                     coupling={"enforcement": enforcement, "lm": "line2"},
                     dirichlet=[{"on": "solid:x_min"}],
                     load=[{"type": "traction", "on": "solid:x_max", "value": [0, 0, -2e7]}],
                     analysis={"kinematics": "nonlinear", "steps": 1})


def _unknowns(n):
    fibres, elements = max(4, n * n // 4), max(2, n // 2)
    return 3 * (n + 1) ** 3 + 6 * fibres * (elements + 1)


def _profile(call, top):
    """cProfile of one ``call()``: the ``top`` functions by own time (seconds), printed."""
    import cProfile
    import pstats
    profile = cProfile.Profile()
    profile.enable()
    call()
    profile.disable()
    stats = pstats.Stats(profile).stats
    rows = sorted(((tt, f"{Path(f).name}:{name}") for (f, _, name), (_, _, tt, _, _) in stats.items()), reverse=True)
    total = sum(tt for tt, _ in rows)
    print(f"      profile of one call ({total:.3f} s): " + ", ".join(f"{label} {tt:.3f}" for tt, label in rows[:top]),
          flush=True)


def _cpu(call):
    """CPU seconds (user + system) of ``call()``, and its result."""
    t = time.process_time()
    out = call()
    return time.process_time() - t, out


def _newton_stages(model, z, rounds):
    """CPU seconds (medians over ``rounds``) of a call and of its parts that depend on the size
    of the tangent: the solid's element kernel adding into a tangent-sized array already in use
    (zeroed before, untimed), and the first touch of a new such array (allocation and the
    operating system's zeroing of its pages)."""
    pattern = model._tangent_pattern
    solid = model.solid_physics
    n_solid = 3 * model.n_solid_nodes
    d = model.basis.to_physical(z[:model.n_displacement_dofs])[:n_solid]
    positions = pattern._positions[0]             # the solid's block is the first one
    data = np.zeros(pattern._nnz)

    def pages():
        fresh = np.zeros(pattern._nnz)
        fresh[::512] = 0.0                        # one write per 4 KiB page
    cpu = {"call": [], "kernel": [], "pages": []}
    for _ in range(rounds):
        cpu["call"].append(_cpu(lambda: model.residual(z, 1.0, tangent=True))[0])
        data.fill(0.0)
        cpu["kernel"].append(_cpu(lambda: solid.add_tangent_into(d, data, positions))[0])
        cpu["pages"].append(_cpu(pages)[0])
    return {k: float(np.median(v)) for k, v in cpu.items()}, solid.mesh.n_elements, pattern._nnz


def newton(unknowns, rounds, profile=0, enforcement="penalty", stages=False):
    print(f"newton: Model.residual(z, t, tangent=True) of fibre_cube(n, n²/4, n/2), Saint Venant–Kirchhoff, "
          f"torsion-free fibres, {enforcement}; 1 thread; median over {rounds} rounds")
    print(f"{'n':>4}{'unknowns':>11}{'time s':>9}{'us/unknown':>12}{'/control':>10}{'nnz(K)':>12}")
    model = Model(build(newton_scene(2, enforcement)))       # compile before timing
    model.prepare()
    model.residual(np.zeros(model.n_unknowns), 1.0)
    sizes, ratios, work = [], [], []
    rng = np.random.default_rng(1)
    for target in unknowns:
        n = 2
        while _unknowns(n + 1) <= target:
            n += 1
        model = Model(build(newton_scene(n, enforcement)))
        model.prepare()
        size = model.n_unknowns
        z = 1e-6 * rng.standard_normal(size)
        model.residual(z, 1.0)                   # first touch
        times, per_control = [], []
        nnz = 0
        for _ in range(rounds):
            c = _control()
            t, (r, K) = _timed(lambda: model.residual(z, 1.0, tangent=True))
            nnz = K.nnz
            del r, K
            times.append(t)
            per_control.append(t / c)
        t, ratio = float(np.median(times)), float(np.median(per_control))
        sizes.append(size)
        ratios.append(ratio)
        print(f"{n:>4}{size:>11}{t:>9.3f}{1e6 * t / size:>12.2f}{ratio:>10.3g}{nnz:>12}", flush=True)
        if profile:
            _profile(lambda: model.residual(z, 1.0, tangent=True), profile)
        if stages:
            cpu, elements, entries = _newton_stages(model, z, rounds)
            work.append((size, elements, entries, cpu))
            print(f"      solid elements per unknown {elements / size:.4f}, tangent entries per unknown "
                  f"{entries / size:.1f}; CPU us per unknown: call {1e6 * cpu['call'] / size:.3f}, solid kernel "
                  f"{1e6 * cpu['kernel'] / size:.3f} ({1e6 * cpu['kernel'] / elements:.2f} per element, "
                  f"{1e9 * cpu['kernel'] / entries:.1f} ns per entry), rest {1e6 * (cpu['call'] - cpu['kernel']) / size:.3f}"
                  f"; fresh pages of the tangent {1e6 * cpu['pages'] / size:.3f}", flush=True)
        del model
    print(f"slope of log(time/control) over log(unknowns): {slope(sizes, ratios):.3f}")
    if stages and len(work) > 1:
        size, elements, entries = (np.array([w[i] for w in work], float) for i in range(3))
        call, kernel = (np.array([w[3][k] for w in work]) for k in ("call", "kernel"))
        print(f"slopes of CPU seconds: call over unknowns {slope(size, call):.3f}, solid elements over unknowns "
              f"{slope(size, elements):.3f}, tangent entries over unknowns {slope(size, entries):.3f}, solid kernel "
              f"over solid elements {slope(elements, kernel):.3f}, rest over unknowns {slope(size, call - kernel):.3f}")
    record("scaling_newton", enforcement=enforcement, unknowns=[int(u) for u in sizes], per_control=ratios,
           slope=slope(sizes, ratios))


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--part", nargs="+", default=["assembly", "newton"], choices=["assembly", "newton"])
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--points", nargs="+", type=float, default=[1e4, 1e5, 1e6, 1e7])
    parser.add_argument("--unknowns", nargs="+", type=float, default=[1e4, 1e5, 1e6])
    parser.add_argument("--package", metavar="CHECKOUT", help="measure the package of this checkout (default: "
                                                              "this one), to compare versions")
    parser.add_argument("--profile", type=int, default=0, metavar="TOP",
                        help="newton: after the timed rounds, profile one more call per size and print the TOP "
                             "functions by own time")
    parser.add_argument("--stages", action="store_true",
                        help="assembly: also print the time per integration point of each stage of the call "
                             "(search, segmentation, integration points, assembly, csr), the work per point and "
                             "each stage's user and system CPU, page faults and new carved bytes per point; "
                             "newton: also print the "
                             "work per unknown (solid elements, tangent entries) and the CPU seconds of the call, "
                             "of the solid's element kernel and of the tangent's fresh pages, with their slopes")
    parser.add_argument("--order", choices=["generated", "morton"], default="generated",
                        help="assembly: the fibres in fibre_cube's (random) order, or renumbered in the Morton "
                             "order of their midpoints (memory locality of the solid's data)")
    parser.add_argument("--enforcement", choices=["penalty", "lagrange"], default="penalty",
                        help="newton: the coupling of the scene (lagrange: the unknowns include the multipliers, "
                             "and the Jacobian is the saddle-point matrix)")
    args = parser.parse_args(argv)
    warnings.simplefilter("ignore")
    numba.set_num_threads(1)
    print(f"load average {os.getloadavg()[0]:.2f}")
    if "assembly" in args.part:
        assembly(args.points, args.rounds, args.stages, args.order)
    if "newton" in args.part:
        newton(args.unknowns, args.rounds, args.profile, args.enforcement, args.stages)
    print(f"peak memory {resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 2**20:.2f} GB; "
          f"load average {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
