"""Running the study: every variant on every scene, the reference checks, the benchmark scene.

:func:`run_study` measures everything a :class:`~mortar1d3d.study.config.StudyConfig` asks for and
returns a plain dict of numbers; :func:`make_report` runs a preset and writes the report.
"""
import datetime
import os
import platform
import statistics
import subprocess
import time
from dataclasses import asdict, replace
from pathlib import Path

import numba
import numpy as np

from .. import generate
from ..mortar.assemble import assemble_mortar
from .accuracy import operator_errors
from .config import INTEGRATIONS, preset
from .monitor import MonitorProblem, monitor_error, solution_monitor
from .reference import pair_reference_check
from .report import write_report
from .scenes import MONITOR_KINDS, build_scene
from .timing import STAGES, scaling, stage_times, startup, time_assembly


def _set_threads(threads):
    default = numba.get_num_threads()
    numba.set_num_threads(max(1, min(int(threads), numba.config.NUMBA_NUM_THREADS)))
    return default


def study_scene(beams, solid, config, progress=None, monitor=False, clamped=None):
    """All variants of ``config`` on one scene: list of records (timing + errors vs the reference).

    With ``monitor``, every variant's operators are also solved with the scene's
    :class:`MonitorProblem` (``clamped``: a :class:`ClampedSolid` of the same mesh to reuse):
    each record gets ``u_err`` (:func:`monitor_error` against the reference operators' solution;
    None without ``monitor``) and ``u_free`` (the variant left a fibre a free rigid motion,
    :meth:`MonitorProblem.free_motions`).

    Returns
    -------
    records : list of dict
    info : dict
        Reference and scene sizes; ``monitor``: the monitor point, reference displacement and
        the monitor's cost (``setup_s``, ``solve_s``: wall time of the set-up and of all the
        solves), or None.
    problem : MonitorProblem or None
    """
    reference = assemble_mortar(beams, solid, integration="segment", n_gauss=config.reference_gauss, lm=config.lm)
    coarser = assemble_mortar(beams, solid, integration="segment", n_gauss=config.reference_gauss - 4, lm=config.lm)
    problem, u_ref, solve_s, monitor_info = None, None, 0.0, None
    if monitor:
        t0 = time.perf_counter()
        problem = MonitorProblem(beams, solid, reference, clamped=clamped)
        setup_s = time.perf_counter() - t0
        t0 = time.perf_counter()
        u_ref = solution_monitor(problem, reference.D, reference.M, reference.kappa)
        reference_free = not problem.held
        solve_s += time.perf_counter() - t0
    records = []
    for integration in INTEGRATIONS:
        for n in config.gauss.get(integration, ()):
            rec, ops = time_assembly(beams, solid, integration, n, config.lm, config.repeats, config.memory)
            rec.update(integration=integration, n_gauss=n, **operator_errors(ops, reference), u_err=None)
            if problem is not None:
                t0 = time.perf_counter()
                rec["u_err"] = monitor_error(solution_monitor(problem, ops.D, ops.M, ops.kappa), u_ref)
                rec["u_free"] = not problem.held
                solve_s += time.perf_counter() - t0
            records.append(rec)
            if progress:
                u = "" if rec["u_err"] is None else f"  u {rec['u_err']:.1e}"
                progress(f"    {integration:8s} n={n:2d}: {rec['time_s'] * 1e3:8.2f} ms  "
                         f"D {rec['D_fro']:.1e}  M {rec['M_fro']:.1e}{u}")
    if problem is not None:
        monitor_info = {"beam_node": problem.beam_node, "solid_node": problem.solid_node,
                        "u_ref": [float(x) for x in u_ref], "reference_free": reference_free,
                        "setup_s": setup_s, "solve_s": solve_s,
                        "solves": problem.n_solves, "solid_columns": problem.clamped.n_columns_solved,
                        "solid_dofs": 3 * solid.n_nodes}
    self_check = operator_errors(coarser, reference)
    return records, {"reference_gauss": config.reference_gauss,
                     "reference_vs_coarser": max(self_check["D_fro"], self_check["M_fro"]),
                     "points": reference.n_integration_points, "segments": len(reference.segments),
                     "beam_elements": beams.n_elements, "solid_elements": solid.n_elements,
                     "embedded_length": reference.embedded_length, "beam_length": reference.beam_length,
                     "monitor": monitor_info}, problem


def reference_checks(config, progress=None):
    """Adaptive-quadrature checks of the reference rule on a few beam elements per scene kind."""
    out = {}
    for kind in config.kinds:
        beams, solid = build_scene(kind, 1.0, "partly outside", config.cells, config.fibres, config.fibre_length,
                                   config.seed)
        ops = assemble_mortar(beams, solid, integration="segment", n_gauss=config.reference_gauss, lm=config.lm)
        # the beam elements cut most often: the hardest ones for the reference rule
        cuts = np.bincount(ops.segments["beam_element"], minlength=beams.n_elements)
        chosen = np.argsort(-cuts, kind="stable")[: config.reference_pairs]
        t0 = time.perf_counter()
        out[kind] = pair_reference_check(beams, solid, chosen, config.reference_gauss, config.lm)
        if progress:
            r = out[kind]
            progress(f"  reference check {kind}: {r['segments']} segments, D {r['D']:.1e} M {r['M']:.1e} "
                     f"kappa {r['kappa']:.1e} ({time.perf_counter() - t0:.1f} s)")
    return out


def auto_target(config, progress=None):
    """Auto vs element- and segment-based on the benchmark scene (interleaved repeats, n_gauss 4)."""
    beams, solid = generate.fibre_cube(*config.benchmark_scene)
    times = {k: [] for k in INTEGRATIONS}
    stages = {k: [] for k in INTEGRATIONS}
    ops = {}
    for k in INTEGRATIONS:           # untimed: JIT / cache
        assemble_mortar(beams, solid, integration=k, n_gauss=4)
    for _ in range(max(1, config.benchmark_repeats)):
        for k in INTEGRATIONS:
            t0 = time.perf_counter()
            ops[k] = assemble_mortar(beams, solid, integration=k, n_gauss=4)
            times[k].append(time.perf_counter() - t0)
            stages[k].append(stage_times(ops[k].timings))
    reference = assemble_mortar(beams, solid, integration="segment", n_gauss=8)
    out = {"scene": list(config.benchmark_scene), "n_gauss": 4, "repeats": config.benchmark_repeats}
    for k in INTEGRATIONS:
        out[k] = {"time_s": statistics.median(times[k]), "points": ops[k].n_integration_points,
                  "stages_s": {s: statistics.median(t[s] for t in stages[k]) for s in STAGES},
                  **operator_errors(ops[k], reference)}
    out["auto_over_element"] = out["auto"]["time_s"] / out["element"]["time_s"]
    out["segment_over_element"] = out["segment"]["time_s"] / out["element"]["time_s"]
    out["auto_diagnostics"] = {k: int(v) for k, v in ops["auto"].diagnostics.items()}
    if progress:
        progress(f"  auto/element time {out['auto_over_element']:.2f}, segment/element "
                 f"{out['segment_over_element']:.2f}; auto M error {out['auto']['M_fro']:.1e}")
    return out


def run_study(config, progress=print):
    """Run every part of the study; a JSON-able dict of all measured numbers."""
    progress = progress or (lambda *_: None)
    t_start = time.perf_counter()
    default = _set_threads(config.threads)
    try:
        progress(f"study '{config.name}': {len(config.kinds)} kinds x {len(config.ratios)} ratios x "
                 f"{len(config.embeddings)} embeddings, {config.threads} thread(s)")
        scenes = []
        for kind in config.kinds:
            clamped = None      # one factorised solid per kind: the scenes of a kind share the mesh
            for ratio in config.ratios:
                for embedding in config.embeddings:
                    progress(f"  {kind}, h_B/h_S = {ratio:g}, {embedding}")
                    beams, solid = build_scene(kind, ratio, embedding, config.cells, config.fibres,
                                               config.fibre_length, config.seed)
                    monitor = config.monitor and kind in MONITOR_KINDS and (
                        config.monitor_max_solid_dofs is None or 3 * solid.n_nodes <= config.monitor_max_solid_dofs)
                    records, info, problem = study_scene(beams, solid, config, monitor=monitor, clamped=clamped)
                    if problem is not None:
                        clamped = problem.clamped
                        m = info["monitor"]
                        progress(f"    monitor: set-up {m['setup_s']:.2f} s, {m['solves']} solves "
                                 f"{m['solve_s']:.2f} s")
                    scenes.append({"kind": kind, "ratio": ratio, "embedding": embedding, **info,
                                   "records": records})
        progress("reference rule against adaptive quadrature")
        checks = reference_checks(config, progress)
        progress(f"auto target on fibre_cube{tuple(config.benchmark_scene)}")
        target = auto_target(config, progress)
        progress("scaling")
        scale = scaling(config, progress)
        progress("start-up in fresh processes" + (" (cold + warm)" if config.startup_cold else " (warm)"))
        start = startup(cold=config.startup_cold)
        threads_used = numba.get_num_threads()
    finally:
        numba.set_num_threads(default)
    return {"config": asdict(config), "scenes": scenes, "reference_checks": checks, "auto_target": target,
            "scaling": scale, "startup": start,
            "machine": _machine(threads_used), "study_s": time.perf_counter() - t_start}


def _machine(threads):
    try:
        load = os.getloadavg()
    except OSError:
        load = None
    try:
        commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True, timeout=10,
                                cwd=str(Path(__file__).resolve().parent)).stdout.strip() or None
    except (OSError, subprocess.SubprocessError):
        commit = None
    return {"date": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
            "python": platform.python_version(), "numba": numba.__version__, "numpy": np.__version__,
            "platform": platform.platform(), "cpus": os.cpu_count(), "threads": threads,
            "load_average": list(load) if load else None, "commit": commit}


def make_report(preset_name="full", out="report", progress=print, **overrides):
    """Run the study with a preset (plus field overrides) and write the report; returns its path."""
    config = replace(preset(preset_name), **overrides)
    results = run_study(config, progress=progress)
    path = write_report(results, out)
    if progress:
        progress(f"wrote {path}")
    return path
