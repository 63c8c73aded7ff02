"""The report: sentences generated from the measured numbers, the Markdown tables, the JSON.

:func:`sentences` and :func:`monitor_sentences` read a results dict (:func:`~mortar1d3d.study.run.run_study`);
:func:`write_report` writes ``accuracy_vs_time.md``, the plots (:mod:`mortar1d3d.study.plots`) and
``results.json``.
"""
import json
import statistics
from pathlib import Path

import numpy as np

from .accuracy import dm_error, u_error
from .config import INTEGRATIONS
from .plots import write_plots
from .scenes import MONITOR_KINDS
from .timing import STAGES


def _cheapest(records, integration, threshold, error=dm_error):
    """Record with the fewest Gauss points of one integration whose error (default: of D and M)
    is <= threshold (or None).

    Fewest points rather than least time: the error of a rule does not depend on the machine load.
    """
    ok = [r for r in records if r["integration"] == integration and error(r) is not None and error(r) <= threshold]
    return min(ok, key=lambda r: r["n_gauss"]) if ok else None


#: how the sentences name the integrations
_LABEL = {"element": "element-based integration", "segment": "segment-based", "auto": "auto"}


def _headline_scene(scenes, kind):
    """The scene of ``kind`` the threshold sentences quote: h_B/h_S = 1 if there is one (or None)."""
    sel = [s for s in scenes if s["kind"] == kind]
    return next((s for s in sel if s["ratio"] == 1.0), sel[0] if sel else None)


def _reach(records, integration, threshold, error):
    """(cheapest record of ``integration`` with ``error`` <= threshold or None, its most accurate record)."""
    recs = [r for r in records if r["integration"] == integration and error(r) is not None]
    if not recs:
        return None, None
    return _cheapest(records, integration, threshold, error), min(recs, key=error)


def _clauses(records, threshold, error, reached, missed):
    """One clause per integration on reaching ``threshold`` in ``error``.

    ``reached(integration, best)`` words the cheapest record that reaches it,
    ``missed(integration, closest)`` the most accurate one where none does; integrations without
    records are left out.
    """
    out = []
    for integration in INTEGRATIONS:
        best, closest = _reach(records, integration, threshold, error)
        if closest is not None:
            out.append(missed(integration, closest) if best is None else reached(integration, best))
    return out


def _fmt_e(x):
    return "0" if x == 0 else f"{x:.1e}"


def sentences(results):
    """Plain sentences generated from the measured numbers."""
    out = []
    cfg = results["config"]
    for kind in cfg["kinds"]:
        scene = _headline_scene(results["scenes"], kind)
        if scene is None:
            continue
        for threshold in cfg["thresholds"]:
            parts = _clauses(
                scene["records"], threshold, dm_error,
                reached=lambda i, best: f"{_LABEL[i]} needs n = {best['n_gauss']} ({best['points']} points, "
                                        f"{best['time_s'] * 1e3:.2f} ms)",
                missed=lambda i, closest: f"{_LABEL[i]} does not reach it with up to {max(cfg['gauss'][i])} points "
                                          f"per {'beam element' if i == 'element' else 'segment'} "
                                          f"(best {_fmt_e(dm_error(closest))} with n = {closest['n_gauss']})")
            out.append(f"To reach a D/M error of {threshold:.0e} on {kind} (h_B/h_S = {scene['ratio']:g}, "
                       f"{scene['embedding']}), " + "; ".join(parts) + ".")
    for kinds, label in ((["straight fibres, hex8"], "straight fibres in hex8"),
                         ([k for k in cfg["kinds"] if k != "straight fibres, hex8"], "curved fibres in curved elements")):
        ratios = []
        for scene in results["scenes"]:
            if scene["kind"] not in kinds:
                continue
            seg = {r["n_gauss"]: r["time_s"] for r in scene["records"] if r["integration"] == "segment"}
            ratios += [r["time_s"] / seg[r["n_gauss"]] for r in scene["records"]
                       if r["integration"] == "auto" and r["n_gauss"] in seg]
        if ratios:
            out.append(f"On {label}, \"auto\" takes a median {statistics.median(ratios):.2f}x the time of "
                       f"segment-based integration with the same n (range {min(ratios):.2f}-{max(ratios):.2f} over "
                       f"{len(ratios)} scene/n pairs)" + (", with the exact rule at any n" if "straight" in label else
                                                         ", with the same points (no affine elements to exploit)")
                       + ".")
    out += monitor_sentences(results)
    t = results["auto_target"]
    verdict = "meets" if t["auto_over_element"] <= 1.3 else "misses"
    out.append(f"On the benchmark scene fibre_cube{tuple(t['scene'])} with n_gauss = 4, \"auto\" takes "
               f"{t['auto']['time_s'] * 1e3:.0f} ms, {t['auto_over_element']:.2f}x the element-based "
               f"{t['element']['time_s'] * 1e3:.0f} ms (segment-based: {t['segment_over_element']:.2f}x), with a "
               f"D/M error of {_fmt_e(dm_error(t['auto']))} against segment-based with 8 points (element-based: "
               f"{_fmt_e(dm_error(t['element']))}); it {verdict} the target of 1.3x.")
    fit = results["scaling"]["fit"]
    rows = results["scaling"]["rows"]
    if fit.get("time_slope") is not None:
        out.append(f"From {rows[0]['points']:.1e} to {rows[-1]['points']:.1e} integration points the "
                   f"segment-based assembly time grows with slope {fit['time_slope']:.2f} on a log-log scale"
                   + (f" ({fit['time_slope_from_1e4']:.2f} from 1e4 points on)" if "time_slope_from_1e4" in fit
                      else "") + ".")
    st = results["startup"]
    if "cold" in st:
        out.append(f"A fresh process needs {st['cold']['in_process_s']:.1f} s to import and assemble a tiny "
                   f"scene with an empty kernel cache (compilation), {st['warm']['in_process_s']:.2f} s with the "
                   "cache filled.")
    else:
        out.append(f"A fresh process with a filled kernel cache imports and assembles a tiny scene in "
                   f"{st['warm']['in_process_s']:.2f} s (cold start: run the full report).")
    return out


def monitor_sentences(results):
    """Sentences on the solution monitor: how the displacement error follows the D/M error."""
    cfg = results["config"]
    scenes = [sc for sc in results["scenes"] if sc.get("monitor")]
    if not scenes:
        return ["The solution monitor did not run on any scene of this study (see Method)."]
    out = []
    threshold = cfg["thresholds"][0]
    for kind in cfg["kinds"]:
        scene = _headline_scene(scenes, kind)
        if scene is None:
            continue
        parts = _clauses(
            scene["records"], threshold, u_error,
            reached=lambda i, best: f"{_LABEL[i]} needs n = {best['n_gauss']} (D/M error there "
                                    f"{_fmt_e(dm_error(best))})",
            missed=lambda i, closest: f"{_LABEL[i]} does not reach it (best {_fmt_e(closest['u_err'])} with "
                                      f"n = {closest['n_gauss']})")
        out.append(f"To reach a monitor displacement error of {threshold:.0e} on {kind} (h_B/h_S = "
                   f"{scene['ratio']:g}, {scene['embedding']}), " + "; ".join(parts) + ".")
    pairs = [(r["u_err"], dm_error(r)) for sc in scenes for r in sc["records"] if r["u_err"] is not None
             and dm_error(r) > 1e-12]
    if pairs:
        ratios = [u / e for u, e in pairs]
        below = sum(x <= 1.0 for x in ratios)
        u_log, e_log = np.log10([u for u, _ in pairs]), np.log10([e for _, e in pairs])
        slope = float(np.polyfit(e_log, u_log, 1)[0]) if len(pairs) > 2 and np.ptp(e_log) > 0 else None
        text = (f"Where the operators are inexact (D/M error > 1e-12: {len(pairs)} variant/scene pairs on "
                f"{len(scenes)} scenes), the monitor displacement error is a median {statistics.median(ratios):.2g}x "
                f"the D/M error (range {min(ratios):.2g}-{max(ratios):.2g}x); it is below the D/M error in {below} "
                f"of the {len(pairs)} pairs")
        if slope is not None:
            text += (f", and a log-log fit over all pairs gives u err ~ (D/M error)^{slope:.2f} "
                     "(1 would mean: proportional)")
        out.append(text + ".")
    exact = [r["u_err"] for sc in scenes for r in sc["records"] if r["u_err"] is not None and dm_error(r) <= 1e-12]
    if exact:
        out.append(f"Variants with operators exact to round-off (D/M error <= 1e-12, {len(exact)} pairs) give "
                   f"displacements within {_fmt_e(max(exact))} of the reference solution.")
    free = [(sc, r) for sc in scenes for r in sc["records"] if r.get("u_free")]
    ref_free = [sc for sc in scenes if sc["monitor"].get("reference_free")]
    if free or ref_free:
        counts = {}
        for _, r in free:
            counts.setdefault(r["integration"], set()).add(int(r["n_gauss"]))
        which = [f"{name}-based n ∈ {{{', '.join(str(n) for n in sorted(ns))}}}" for name, ns in sorted(counts.items())]
        out.append(f"In {len(free)} variant/scene pair(s) on "
                   f"{len({id(sc) for sc, _ in free})} scene(s)" + (f" ({'; '.join(which)})" if which else "")
                   + (f" and in the reference solution of {len(ref_free)} scene(s)" if ref_free else "")
                   + " the coupling leaves some fibre a free rigid motion (held at one point, which it can turn "
                   "about); the fibre's free motion is set to zero there (`*` in the tables).")
    n_all = len(results["scenes"])
    straight = [sc for sc in results["scenes"] if sc["kind"] in MONITOR_KINDS]
    if len(scenes) < n_all:
        why = ["straight fibres only: the torsion-free beam needs initially straight centrelines, and curved "
               "fibres wait for a beam with a material frame (see Method)"]
        if len(scenes) < len(straight):
            cost = [sc["monitor"]["setup_s"] for sc in scenes]
            why.append(f"solids with at most {cfg['monitor_max_solid_dofs']} DOFs; its set-up took "
                       f"{min(cost):.2f}-{max(cost):.2f} s per scene there, the larger solids cost a factorisation "
                       "and a flexibility column per coupled solid DOF each")
        out.append(f"The monitor ran on {len(scenes)} of {n_all} scenes ({'; '.join(why)}).")
    return out


def write_report(results, out="report"):
    """Write ``accuracy_vs_time.md``, the PNG plots and ``results.json`` into ``out``; the report's path."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    files = write_plots(results, out)
    cfg = results["config"]
    mach = results["machine"]
    L = []
    L.append("# Accuracy vs time of the coupling integration\n")
    L.append(f"Generated by `mortar1d3d bench report{' --quick' if cfg['name'] == 'quick' else ''}` "
             f"(preset `{cfg['name']}`) on {mach['date']}, commit {mach['commit']}; Python {mach['python']}, "
             f"Numba {mach['numba']}, {mach['cpus']} CPUs, {mach['threads']} Numba thread(s) for all timings, "
             f"load average {', '.join(f'{x:.2f}' for x in mach['load_average']) if mach['load_average'] else '?'}. "
             f"The study took {results['study_s']:.0f} s. Timings on a shared machine are noisy; errors are not.\n")
    L.append("## Findings\n")
    for s in sentences(results):
        L.append(f"- {s}")
    L.append("")
    L.append("## Method\n")
    L.append(f"- Scenes: the unit cube with {cfg['cells']}³ cells; {cfg['fibres']} Hermite fibres of length "
             f"{cfg['fibre_length']} (straight, or half a helix turn of radius {0.1 * cfg['fibre_length']:g}); "
             "hex27 and tet10 meshes distorted (amplitude 0.1 of the cell size: curved faces). Beam element length "
             f"h_B over solid element size h_S in {list(cfg['ratios'])}; fibres fully embedded or centred on a face "
             f"of the cube (partly outside). LM interpolation `{cfg['lm']}`.")
    L.append(f"- Cost: median of {cfg['repeats']} calls of `assemble_mortar` after one untimed call (JIT "
             "excluded), stages from `ops.timings`; peak memory: `tracemalloc` peak of one more call (NumPy "
             "allocations, counted in full even where pages are never touched, e.g. the segmentation's "
             "crossing buffer; scratch buffers inside the kernels are not seen).")
    L.append(f"- Accuracy: relative Frobenius error and worst entry (over the largest entry) of D and M against "
             f"segment-based integration with {cfg['reference_gauss']} points per segment. `auto` uses the minimal "
             "exact Gauss rule on segments where the integrand is a polynomial (straight beams in affine "
             "elements), so its error there does not depend on n.")
    mon_scope = "the straight-fibre scenes" + ("" if cfg.get("monitor_max_solid_dofs") is None else
                                               f" whose solid has at most {cfg['monitor_max_solid_dofs']} DOFs")
    L.append("- Solution error (`u err`): a linear solve with each variant's operators "
             "(`mortar1d3d.study.MonitorProblem`): the cube, small-strain linear elastic (E = 1, ν = 0.3), "
             "clamped on x = 0 and bent by its own weight (body force (0, 0, -1)); the fibres torsion-free "
             "Hermite beams with E = 1000 and radius 0.02 (EA ≈ 1.26, as stiff axially as the cube, so the "
             "coupling carries real force), tied by penalty mortar coupling (ε = 1e3 E, the library default; "
             "with Lagrange multipliers the saddle point is singular for variants with fewer integration "
             "points than LM nodes, e.g. element-based n = 1). The monitor point is the beam node with the "
             "largest reference κ and the free solid node nearest to it; `u err` = |u - u_ref| / |u_ref| over "
             "both nodes' displacements, u_ref from the reference operators. The solid is factorised once per "
             "mesh and condensed onto the DOFs the coupling reaches, so each variant costs one small dense "
             "solve. `*`: the variant's coupling leaves some fibre a free rigid motion (a single coupling "
             "point): the unloaded free motion is set to zero. "
             f"Measured on {mon_scope}. Not on curved fibres: the torsion-free beam holds for initially straight "
             "centrelines only (a curved one could change its bending plane at no cost), and a truss would need "
             "the operators of a line centreline, not the Hermite ones measured here, and has no stiffness against "
             "sideways motion where a fibre leaves the cube; curved fibres wait for a beam with a material frame"
             + ("." if cfg.get("monitor", True) else " (switched off in this run).")
             + "\n")
    L.append("## The reference\n")
    L.append("Segment-based integration with the reference Gauss count, compared entry by entry with an "
             "independent adaptive quadrature (`scipy.integrate.quad_vec`, relative tolerance 1e-13, own "
             "Hermite formulas and Newton projection) on the most-cut beam elements of each kind "
             "(h_B/h_S = 1, partly outside); `face` is the largest distance of an interior segment end from "
             "its element's boundary in parameter units.\n")
    L.append("| scene | segments | D | M | κ | face |")
    L.append("|---|---|---|---|---|---|")
    for kind, r in results["reference_checks"].items():
        L.append(f"| {kind} | {r['segments']} | {_fmt_e(r['D'])} | {_fmt_e(r['M'])} | {_fmt_e(r['kappa'])} | "
                 f"{_fmt_e(r['face'])} |")
    L.append("")
    L.append("Per scene, the reference also differs from segment-based integration with 4 fewer points per "
             "segment by `ref vs n-4` in the tables below (an estimate of its own error).\n")
    if "pareto" in files:
        L.append(f"![error vs time]({files['pareto']})\n")
    if "monitor" in files:
        L.append(f"![solution error vs time]({files['monitor']})\n")
    L.append("## Tables\n")
    L.append("Times in ms (median); stages: search / segmentation / integration points / assembly / CSR / "
             "other (certificates, point records). "
             "Errors: relative Frobenius norm (fro) and worst entry (max); `u err`: monitor displacement "
             "error (— where the monitor did not run; `*`: a fibre had a free rigid motion, see Method).\n")
    for scene in results["scenes"]:
        L.append(f"### {scene['kind']}, h_B/h_S = {scene['ratio']:g}, {scene['embedding']}\n")
        L.append(f"{scene['beam_elements']} beam elements, {scene['solid_elements']} solid elements; embedded length "
                 f"{scene['embedded_length']:.4f} of {scene['beam_length']:.4f}; reference: "
                 f"{scene['points']} points on {scene['segments']} segments; ref vs n-4: "
                 f"{_fmt_e(scene['reference_vs_coarser'])}.\n")
        mon = scene.get("monitor")
        if mon:
            L.append(f"Monitor: beam node {mon['beam_node']}, solid node {mon['solid_node']}; |u_ref| = "
                     f"{np.linalg.norm(mon['u_ref']):.4g}" + ("*" if mon.get("reference_free") else "")
                     + f"; set-up {mon['setup_s']:.2f} s, {mon['solves']} solves {mon['solve_s']:.2f} s.\n")
        mem_head = " peak MiB |" if cfg["memory"] else ""
        L.append(f"| integration | n | points | time | stages |{mem_head} D fro | M fro | D max | M max | u err |")
        L.append("|---|---|---|---|---|" + ("---|" if cfg["memory"] else "") + "---|---|---|---|---|")
        for r in scene["records"]:
            st = " / ".join(f"{r['stages_s'][k] * 1e3:.2f}" for k in STAGES)
            mem = f" {r['peak_bytes'] / 2**20:.2f} |" if cfg["memory"] else ""
            u = "—" if not mon or r.get("u_err") is None else _fmt_e(r["u_err"]) + ("*" if r.get("u_free") else "")
            L.append(f"| {r['integration']} | {r['n_gauss']} | {r['points']} | {r['time_s'] * 1e3:.2f} | {st} |"
                     f"{mem} {_fmt_e(r['D_fro'])} | {_fmt_e(r['M_fro'])} | {_fmt_e(r['D_max'])} | "
                     f"{_fmt_e(r['M_max'])} | {u} |")
        L.append("")
    t = results["auto_target"]
    L.append(f"## \"auto\" on the benchmark scene fibre_cube{tuple(t['scene'])}\n")
    L.append(f"n_gauss = 4, medians of {t['repeats']} interleaved calls per variant; errors against "
             "segment-based with 8 points per segment.\n")
    L.append("| integration | points | time ms | " + " | ".join(STAGES) + " | D fro | M fro |")
    L.append("|---|---|---|" + "---|" * len(STAGES) + "---|---|")
    for k in INTEGRATIONS:
        r = t[k]
        L.append(f"| {k} | {r['points']} | {r['time_s'] * 1e3:.1f} | "
                 + " | ".join(f"{r['stages_s'][s] * 1e3:.1f}" for s in STAGES)
                 + f" | {_fmt_e(r['D_fro'])} | {_fmt_e(r['M_fro'])} |")
    L.append("")
    L.append(f"auto / element-based time: **{t['auto_over_element']:.2f}** (target <= 1.3); "
             f"segment-based / element-based: {t['segment_over_element']:.2f}. Auto diagnostics: "
             + ", ".join(f"{k} {v}" for k, v in t["auto_diagnostics"].items()) + ".\n")
    if "stages" in files:
        L.append(f"![stages]({files['stages']})\n")
    L.append("## Scaling\n")
    L.append("Segment-based, n_gauss = 4, fibre_cube(20, F, 20) with F chosen for the target number of points; "
             "median of 3 calls (1 above 1e6 points).\n")
    mem_head = " tracemalloc peak MiB | bytes / point |" if cfg["memory"] else ""
    L.append(f"| fibres | points | time s | points / s |{mem_head}")
    L.append("|---|---|---|---|" + ("---|---|" if cfg["memory"] else ""))
    for r in results["scaling"]["rows"]:
        mem = (f" {r['peak_bytes'] / 2**20:.1f} | {r['peak_bytes'] / r['points']:.0f} |" if cfg["memory"] else "")
        L.append(f"| {r['fibres']} | {r['points']} | {r['time_s']:.4f} | {r['points'] / r['time_s']:.3g} |{mem}")
    fit = results["scaling"]["fit"]
    L.append("")
    L.append("Fitted log-log slopes: " + ", ".join(f"{k} {v:.3g}" for k, v in fit.items() if v is not None) + ".\n")
    if "scaling" in files:
        L.append(f"![scaling]({files['scaling']})\n")
    st = results["startup"]
    L.append("## Start-up\n")
    L.append("Fresh `python -c` process: import + assembly of fibre_cube(3, 2, 3) with segment, element and auto "
             "integration.\n")
    L.append("| cache | in process s | wall s (incl. interpreter) |")
    L.append("|---|---|---|")
    for k in ("cold", "warm"):
        if k in st:
            L.append(f"| {k} | {st[k]['in_process_s']:.2f} | {st[k]['wall_s']:.2f} |")
    if "cold" not in st:
        L.append("\nCold start (empty `NUMBA_CACHE_DIR`) is measured by the full report only.")
    L.append("")
    path = out / "accuracy_vs_time.md"
    path.write_text("\n".join(L) + "\n")
    (out / "results.json").write_text(json.dumps(results, indent=1, default=float) + "\n")
    return path
