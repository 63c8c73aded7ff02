"""Fibre-reinforced pipe under internal pressure: an exact NURBS wall with two helical fibre families.

A closed pipe section (inner radius r_i, outer r_o, length L, about the z axis) of a soft matrix,
meshed as one quadratic NURBS patch (``solid.mesh = { pipe = ... }``: the circles are exact), with
two families of helical fibres at ±α from the axis on the mid-wall cylinder (``n`` fibres each,
:func:`mortar1d3d.generate.helical_fibres`: Hermite ``simo_reissner`` beams, exact nodes and
tangents), tied to the wall by the mortar penalty coupling. Loads: internal pressure p on the inner
face and the closed-end cap force as an axial traction σ_z = p r_i² / (r_o² − r_i²) on the end
face z = L.

Supports (the same in every case): the start face z = 0 is held axially (a symmetry plane), and the
nodes on the x axis (y = 0) and on the y axis (x = 0) of that face are held in y and in x. That
removes the rigid motions and nothing else: the wall swells, lengthens or shortens and twists
freely. The fibres end free at both end faces (their force builds up over a load-introduction
length), so strain and twist are measured in the middle half of the pipe (L/4 ≤ z ≤ 3L/4) and the
radial expansion at mid-length; the fibre force is the mean over the fibre nodes in the middle half.

Three studies:

(a) **Unreinforced pipe against Lamé** (closed ends, generalised plane strain: u_r = r/E (c (1 − 2ν)
    + (1 + ν) d / r²), c = σ_z, d = p r_i² r_o² / (r_o² − r_i²)): the error of u_r on the inner and
    outer surface per refinement level, for the scene's C⁰ space of the Bézier spans and for the
    patch's own C^(p-1) NURBS space (:class:`~mortar1d3d.nurbs.NurbsSolidModel`), and the rates: in h
    (n × 4n × 1 spans, n = 1, 2, 4, 8) and in p (degree 2, the exact geometry, then 3 and 4, the same
    geometry degree-elevated: ``pipe.degree = 3`` or ``4``, ``nurbs64`` or ``nurbs125`` spans).
(b) **Winding sweep** α = 15° … 85° for several fibre/matrix stiffness ratios E_f / E_m: radial
    expansion, axial strain, twist and fibre force against α. Netting theory (fibres alone carry
    the load: hoop σ_θ = p r / t = N sin²α, axial σ_z = p r / (2t) = N cos²α) balances the two at
    tan²α = 2, α = arctan √2 ≈ 54.74°: below it the pipe swells and shortens, above it lengthens.
    For this wall, with the pressure on r_i and the fibres on R_f, the same balance reads
    tan²α = 2 R_f / r_i, α ≈ 56.01°. The zero crossing of the axial strain (from shortening to
    lengthening) is found by linear interpolation between sweep angles and moves up towards the
    netting angle as the fibres get stiffer: the matrix alone lengthens the pipe
    (ε_z = σ_z (1 − 2ν) / E > 0), so with softer fibres the crossing lies lower.
(c) Plots ``reinforced_pipe.png`` (radial expansion against pressure for several α, nonlinear
    kinematics with follower pressure; axial strain against α with the netting angle marked), a VTU
    series per case of the sweep's stiffest ratio, and the run time of every case.

    python examples/reinforced_pipe.py --out results/reinforced_pipe
    python examples/reinforced_pipe.py --quick          # the reduced run of tests/test_reinforced_pipe.py
    python examples/reinforced_pipe.py --lame           # study (a) only, levels 1, 2, 4, 8, degrees 2, 3 and 4

The scene file ``examples/scenes/reinforced_pipe.toml`` is the case α = 54.74°, E_f / E_m = 1000.
Measured figures: see the module's section in docs/validation.md.
"""
import argparse
import math
import os
import time

import numpy as np

import mortar1d3d as m13
from mortar1d3d.generate import helical_fibres
from mortar1d3d.nurbs.mesh import element_values

# geometry (m) and materials (Pa): a thick-ish wall of a soft matrix
R_INNER, R_OUTER, LENGTH = 0.10, 0.12, 0.24
R_FIBRE = 0.5 * (R_INNER + R_OUTER)
E_MATRIX, NU_MATRIX = 1e6, 0.3
FIBRE_RADIUS = 0.002
PRESSURE = 1e3
SIGMA_Z = PRESSURE * R_INNER ** 2 / (R_OUTER ** 2 - R_INNER ** 2)     # closed end: cap force / wall area
NETTING_ANGLE = math.degrees(math.atan(math.sqrt(2.0)))
# netting theory with this wall: the pressure on r_i gives the hoop force p r_i per length, the cap
# force p π r_i² spread over the fibre cylinder's circumference p r_i² / (2 R_f): tan²α = 2 R_f / r_i
NETTING_ANGLE_WALL = math.degrees(math.atan(math.sqrt(2.0 * R_FIBRE / R_INNER)))

FULL = {"elements": (1, 16, 8), "fibres": 8, "angles": (15, 25, 35, 45, 50, 52.5, 55, 57.5, 60, 65, 75, 85),
        "ratios": (100, 1000, 10000), "lame_levels": (1, 2, 4, 8), "lame_degrees": (2, 3, 4), "pressure_steps": 5,
        "pressure_angles": (35, 55, 75)}
QUICK = {"elements": (1, 8, 4), "fibres": 4, "angles": (35, 55, 75), "ratios": (1000,), "lame_levels": (1, 2),
         "lame_degrees": (2, 3), "pressure_steps": 0, "pressure_angles": ()}


def fibre_elements(angle, elements):
    """Beam elements per fibre: about one per 22.5° of arc (and at least one per axial span)."""
    turns = LENGTH * math.tan(math.radians(abs(angle))) / (2 * math.pi * R_FIBRE)
    return max(elements[2], int(math.ceil(16 * turns)))


def pipe_scene(angle=None, ratio=1000.0, fibres=8, elements=(1, 16, 8), kinematics="linear", pressure=PRESSURE,
               steps=1, degree=2):
    """The reinforced pipe (module docstring) with fibres at ±``angle`` degrees, or without fibres; the wall
    of NURBS ``degree`` 2 (the exact geometry) or 3 (degree-elevated)."""
    beams = []
    if angle is not None:
        section = {"E": ratio * E_MATRIX, "nu": 0.3, "radius": FIBRE_RADIUS}
        m = fibre_elements(angle, elements)
        for sign, phase in ((1.0, 0.0), (-1.0, math.pi / fibres)):
            beams.append({"mesh": helical_fibres(R_FIBRE, LENGTH, sign * angle, fibres, m, phase=phase),
                          "model": "simo_reissner", "section": section})
    extra = {"coupling": {"penalty": 1e3 * E_MATRIX}} if beams else {}
    return m13.Scene(
        solid={"mesh": {"pipe": {"r_inner": R_INNER, "r_outer": R_OUTER, "length": LENGTH, "elements": list(elements),
                                 "degree": degree}},
               "material": {"model": "linear_elastic" if kinematics == "linear" else "neo_hooke", "E": E_MATRIX,
                            "nu": NU_MATRIX}},
        beams=beams,
        dirichlet=[{"on": "solid:start", "components": ["z"]},
                   {"on": {"inside": [[R_INNER, 0, 0], [R_OUTER, 0, 0]]}, "components": ["y"]},
                   {"on": {"inside": [[0, R_INNER, 0], [0, R_OUTER, 0]]}, "components": ["x"]}],
        load=[{"type": "pressure", "on": "solid:inner", "value": pressure},
              {"type": "traction", "on": "solid:end", "value": [0, 0, pressure * R_INNER ** 2 / (R_OUTER ** 2 - R_INNER ** 2)]}],
        analysis={"kinematics": kinematics, "steps": steps, "solver": "direct"}, **extra)


def lame_radial(r):
    """u_r(r) of the closed-end thick-walled pipe (generalised plane strain)."""
    d = PRESSURE * R_INNER ** 2 * R_OUTER ** 2 / (R_OUTER ** 2 - R_INNER ** 2)
    return r / E_MATRIX * (SIGMA_Z * (1 - 2 * NU_MATRIX) + (1 + NU_MATRIX) * d / r ** 2)


def sample(mesh, u, points=5):
    """Exact points X and displacements U on a ``points``³ lattice of every span: (k, 3) each."""
    s = np.linspace(-1.0, 1.0, points)
    xi = np.stack(np.meshgrid(s, s, s, indexing="ij"), -1).reshape(-1, 3)
    return element_values(mesh, xi, mesh.points).reshape(-1, 3), element_values(mesh, xi, u).reshape(-1, 3)


def measures(result, EA=0.0):
    """Radial expansion u_r at mid-length on the mid-wall radius, axial strain and twist per length in the
    middle half, mean fibre axial force (axial stiffness ``EA``) in the middle half (0 without fibres)."""
    X, U = sample(result.model.solid_mesh, result.solid_displacement)
    r = np.hypot(X[:, 0], X[:, 1])
    tol = 1e-9 * LENGTH
    mid = (np.abs(X[:, 2] - LENGTH / 2) < tol) & (np.abs(r - R_FIBRE) < tol)
    ur = ((U[:, 0] * X[:, 0] + U[:, 1] * X[:, 1]) / r)
    ut = ((U[:, 1] * X[:, 0] - U[:, 0] * X[:, 1]) / r)
    lo, hi = np.abs(X[:, 2] - LENGTH / 4) < tol, np.abs(X[:, 2] - 3 * LENGTH / 4) < tol
    strain = (U[hi, 2].mean() - U[lo, 2].mean()) / (LENGTH / 2)
    twist = ((ut[hi] / r[hi]).mean() - (ut[lo] / r[lo]).mean()) / (LENGTH / 2)
    force = 0.0
    if result.scene.beams:
        # linear kinematics: the axial strain of a Hermite node is t0 · Δt (|t| is the local stretch)
        forces = []
        start = 0
        for entry in range(len(result.scene.beams)):
            g, nodes = result.model.sets.beam_nodes(entry, None, f"beams[{entry}]")   # the rows of the result
            X0, t0 = g.mesh.positions[nodes], g.mesh.tangents[nodes]
            dt = result.beam_tangent_displacement[start:start + len(nodes)]
            middle = np.abs(X0[:, 2] - LENGTH / 2) <= LENGTH / 4 + tol
            forces.append(EA * np.einsum("ij,ij->i", t0, dt)[middle])
            start += len(nodes)
        force = float(np.concatenate(forces).mean())
    return {"radial": float(ur[mid].mean()), "strain": float(strain), "twist": float(twist), "force": force}


def zero_crossing(angles, strains):
    """The angle where the axial strain turns from shortening to lengthening (the last sign change from
    negative to positive, linear interpolation between sweep angles), or None. A soft fibre family can
    give a second, low-angle change (nearly axial fibres too weak to stop the matrix's lengthening)."""
    found = None
    for a0, a1, s0, s1 in zip(angles[:-1], angles[1:], strains[:-1], strains[1:]):
        if s0 < 0.0 <= s1:
            found = float(a0 - s0 * (a1 - a0) / (s1 - s0))
    return found


def lame_study(levels, degree=2):
    """u_r errors (inner, outer; relative to u_r(r_i)) per level n: the scene on n × 4n × 1 spans of NURBS
    ``degree`` (C⁰ Bézier space) and NurbsSolidModel on the same patch (its C^(p-1) NURBS space). Rows
    ``(n, mesh nodes, scene inner, scene outer, control points, patch inner, patch outer)``."""
    import scipy.sparse.linalg as spla

    from mortar1d3d import nurbs
    from mortar1d3d.physics.materials import material

    rows = []
    for n in levels:
        elements = (n, 4 * n, 1)
        result = m13.solve(pipe_scene(None, elements=elements, degree=degree))
        X, U = sample(result.model.solid_mesh, result.solid_displacement)
        scene_err = _lame_errors(X, U)
        model = nurbs.NurbsSolidModel(nurbs.hollow_cylinder(R_INNER, R_OUTER, LENGTH, elements=elements, degree=degree),
                                      material("linear_elastic", E_MATRIX, NU_MATRIX), kinematics="linear")
        _, K = model.evaluate(np.zeros(model.n_dofs))
        f = model.pressure(0, "u0_min", PRESSURE) - model.pressure(0, "u2_max", SIGMA_Z)
        solid = model.nurbs
        fixed = np.zeros(model.n_dofs, dtype=bool)
        fixed[3 * solid.face_control(0, "u2_min") + 2] = True
        X0 = solid.control
        on_start = np.abs(X0[:, 2]) < 1e-12
        fixed[3 * np.flatnonzero(on_start & (np.abs(X0[:, 1]) < 1e-12) & (X0[:, 0] > 0)) + 1] = True
        fixed[3 * np.flatnonzero(on_start & (np.abs(X0[:, 0]) < 1e-12) & (X0[:, 1] > 0)) + 0] = True
        free = np.flatnonzero(~fixed)
        u = np.zeros(model.n_dofs)
        u[free] = spla.spsolve(K[free][:, free].tocsc(), f[free])
        Xn, Un = sample(model.mesh.solid, model.node_displacement(u).reshape(-1, 3))
        rows.append((n, model.mesh.solid.n_nodes, *scene_err, solid.n_control, *_lame_errors(Xn, Un)))
    return rows


def _lame_errors(X, U):
    r = np.hypot(X[:, 0], X[:, 1])
    ur = (U[:, 0] * X[:, 0] + U[:, 1] * X[:, 1]) / r
    scale = lame_radial(R_INNER)
    return [float(np.abs(ur - lame_radial(r))[np.abs(r - radius) < 1e-12].max() / scale) for radius in (R_INNER, R_OUTER)]


def sweep(config, out=None):
    """Measures per (ratio, angle), the unreinforced pipe and the run time of each case."""
    rows = []
    for ratio in config["ratios"]:
        for angle in config["angles"]:
            t0 = time.perf_counter()
            result = m13.solve(pipe_scene(angle, ratio, config["fibres"], config["elements"]))
            seconds = time.perf_counter() - t0
            EA = ratio * E_MATRIX * math.pi * FIBRE_RADIUS ** 2
            rows.append(dict(measures(result, EA), ratio=ratio, angle=angle, seconds=seconds,
                             coupled=float(sum(result.coupled_length) / sum(result.beam_length))))
            if out is not None and ratio == max(config["ratios"]):
                result.write(os.path.join(out, f"vtu_alpha{angle:04.1f}"))
    t0 = time.perf_counter()
    plain = measures(m13.solve(pipe_scene(None, elements=config["elements"])))
    plain["seconds"] = time.perf_counter() - t0
    return rows, plain


def pressure_curves(config):
    """Radial expansion against pressure, nonlinear kinematics (neo-Hooke matrix, follower pressure),
    for the ``pressure_angles`` at the largest ratio below 1e4 (so Newton stays quick)."""
    ratio = min(config["ratios"][-1], 1000)
    curves = {}
    for angle in config["pressure_angles"]:
        result = m13.solve(pipe_scene(angle, ratio, config["fibres"], config["elements"], kinematics="nonlinear",
                                      pressure=20 * PRESSURE, steps=config["pressure_steps"]))
        mesh = result.model.solid_mesh
        n = 3 * mesh.n_nodes
        values = [0.0]
        for z in result.history[1:] if len(result.history) > config["pressure_steps"] else result.history:
            X, U = sample(mesh, np.asarray(z[:n]).reshape(-1, 3), points=3)
            r = np.hypot(X[:, 0], X[:, 1])
            mid = (np.abs(X[:, 2] - LENGTH / 2) < 1e-9) & (np.abs(r - R_FIBRE) < 1e-9)
            values.append(float(((U[:, 0] * X[:, 0] + U[:, 1] * X[:, 1]) / r)[mid].mean()))
        curves[angle] = (20 * PRESSURE * np.linspace(0, 1, len(values)), np.array(values))
    return curves


def lame_report(lame):
    """Study (a) as text: per degree, the errors per level and the rates log2(e_n / e_2n) (h), then the
    error ratio from each degree to the next at equal n (p); ``lame`` maps degree -> rows of :func:`lame_study`."""
    lines = ["(a) unreinforced closed pipe vs Lamé: max |u_r - Lamé| / u_r(r_i) on the inner | outer surface"]
    for degree, rows in lame.items():
        lines += [f"  degree {degree}:",
                  "    n   spans      C0 Bézier (scene)          C^(p-1) NURBS (patch)"]
        for i, (n, nodes, si, so, nc, ni, no) in enumerate(rows):
            rate = ""
            if i:
                rate = "   h-rate " + " ".join(f"{math.log2(a / b):.2f}" for a, b in zip(rows[i - 1][2:4] + rows[i - 1][5:7],
                                                                                       (si, so, ni, no)))
            lines.append(f"  {n:3d} {n}x{4 * n}x1   {si:.2e} | {so:.2e} ({nodes} nodes)   {ni:.2e} | {no:.2e} "
                         f"({nc} control points)" + rate)
    degrees = sorted(lame)
    for low, high in zip(degrees, degrees[1:]):
        lines.append(f"  p-refinement, degree {low} -> {high} at equal n: error ratio (scene inner | outer, "
                     f"patch inner | outer)")
        for a_row, b_row in zip(lame[low], lame[high]):
            ratios = [a / b for a, b in zip(a_row[2:4] + a_row[5:7], b_row[2:4] + b_row[5:7])]
            lines.append(f"  {a_row[0]:3d}   " + " | ".join(f"{r:7.1f}" for r in ratios))
    return lines


def report(lame, rows, plain, config):
    lines = lame_report(lame)
    lines.append("")
    lines.append(f"(b) winding sweep, {config['fibres']} fibres per family, p = {PRESSURE:g} Pa, closed ends "
                 f"(unreinforced: u_r = {plain['radial']:.4e} m, eps_z = {plain['strain']:.4e})")
    lines.append("  Ef/Em  alpha   u_r (m)     eps_z       twist (rad/m)  N_fibre (N)  coupled  time (s)")
    for row in rows:
        lines.append(f"  {row['ratio']:5g}  {row['angle']:5.1f}  {row['radial']:.4e}  {row['strain']:+.4e}  "
                     f"{row['twist']:+.3e}     {row['force']:+.3e}   {row['coupled']:.4f}  {row['seconds']:.1f}")
    lines.append("")
    lines.append(f"  zero crossing of eps_z, shortening to lengthening (netting theory: {NETTING_ANGLE:.2f}° thin wall, "
                 f"{NETTING_ANGLE_WALL:.2f}° for this wall):")
    crossings = {}
    for ratio in config["ratios"]:
        sel = [r for r in rows if r["ratio"] == ratio]
        crossings[ratio] = zero_crossing([r["angle"] for r in sel], [r["strain"] for r in sel])
        value = "none in the sweep" if crossings[ratio] is None else f"{crossings[ratio]:.2f}°"
        lines.append(f"    Ef/Em = {ratio:g}: {value}")
    return "\n".join(lines), crossings


def plot(rows, curves, config, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (left, right) = plt.subplots(1, 2, figsize=(11, 4.2))
    for angle, (p, ur) in curves.items():
        left.plot(p / 1e3, ur * 1e3, "o-", label=f"α = {angle}°")
    left.set_xlabel("internal pressure (kPa)")
    left.set_ylabel("radial expansion at mid-length (mm)")
    left.set_title("nonlinear, follower pressure" if curves else "(no pressure curves in this run)")
    if curves:
        left.legend()
    for ratio in config["ratios"]:
        sel = [r for r in rows if r["ratio"] == ratio]
        right.plot([r["angle"] for r in sel], [r["strain"] * 1e3 for r in sel], "o-", label=f"E_f / E_m = {ratio:g}")
    right.axhline(0.0, color="0.5", lw=0.8)
    right.axvline(NETTING_ANGLE, color="k", ls="--", lw=1.0, label=f"netting angle arctan √2 = {NETTING_ANGLE:.1f}°")
    right.axvline(NETTING_ANGLE_WALL, color="k", ls=":", lw=1.0,
                  label=f"netting, this wall: arctan √(2 R_f / r_i) = {NETTING_ANGLE_WALL:.1f}°")
    right.set_xlabel("winding angle α from the axis (°)")
    right.set_ylabel("axial strain (‰)")
    right.set_title("closed-end pressure: shortening below, lengthening above")
    right.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--out", default="results/reinforced_pipe", help="output directory")
    parser.add_argument("--quick", action="store_true", help="the reduced run (coarse, three angles, one ratio)")
    parser.add_argument("--no-plot", action="store_true")
    parser.add_argument("--no-vtu", action="store_true")
    parser.add_argument("--lame", action="store_true", help="study (a) only: the Lamé errors and rates, h and p")
    args = parser.parse_args(argv)
    config = QUICK if args.quick else FULL
    os.makedirs(args.out, exist_ok=True)
    t0 = time.perf_counter()
    lame = {degree: lame_study(config["lame_levels"], degree) for degree in config["lame_degrees"]}
    if args.lame:
        print("\n".join(lame_report(lame)))
        print(f"total {time.perf_counter() - t0:.1f} s")
        return {"lame": lame[2], "lame_by_degree": lame}
    rows, plain = sweep(config, None if args.no_vtu else args.out)
    curves = pressure_curves(config) if config["pressure_angles"] else {}
    text, crossings = report(lame, rows, plain, config)
    print(text)
    if not args.no_plot:
        print("wrote", plot(rows, curves, config, os.path.join(args.out, "reinforced_pipe.png")))
    print(f"total {time.perf_counter() - t0:.1f} s")
    return {"lame": lame[2], "lame_by_degree": lame, "rows": rows, "plain": plain, "crossings": crossings,
            "curves": curves}


if __name__ == "__main__":
    main()
