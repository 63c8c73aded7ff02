"""The plan of effects: what :func:`~mortar1d3d.model.solve` will compute for a scene, in order.

:func:`plan` builds the scene and its :class:`~mortar1d3d.model.Model` (meshes, sets, supports:
everything that can be wrong with a scene is reported here, as ``solve`` would) and lists the
:class:`Effect` s that ``solve`` runs; it assembles nothing. The names are those that
``Model.counts`` (and ``Result.counts``) record when the effect runs.
"""
from dataclasses import dataclass

from .build import build
from .model import Model


@dataclass(frozen=True)
class Effect:
    """One thing :func:`solve` will compute: a stable ``name`` and how often/what exactly."""

    name: str
    when: str
    detail: str = ""

    def __str__(self):
        return f"{self.name:<28} {self.when:<22} {self.detail}"


class Plan(list):
    """The list of :class:`Effect` returned by :func:`plan`; ``print(plan(scene))`` shows a table.

    A plain list otherwise (indexing, ``==`` with a list of effects, ``[e.name for e in ...]``).
    """

    HEADER = ("effect", "when", "detail")

    def __str__(self):
        rows = [self.HEADER] + [(e.name, e.when, e.detail) for e in self]
        widths = [max(len(r[k]) for r in rows) for k in range(2)]
        lines = [f"{a:<{widths[0]}}  {b:<{widths[1]}}  {c}".rstrip() for a, b, c in rows]
        lines.insert(1, f"{'-' * widths[0]}  {'-' * widths[1]}  {'-' * max(len(r[2]) for r in rows)}")
        return "\n".join(lines)


def plan(scene):
    """The effects :func:`solve` will run for ``scene`` (Scene or TOML file), in order (a
    :class:`Plan`: a list of :class:`Effect` that prints as a table).

    Builds the meshes and resolves every set (supports, loads, fibre regions: a set that is
    unknown or selects nothing is reported here, as :func:`solve` would), assembles nothing.
    """
    return effects(Model(build(scene)))


def effects(model):
    """The :class:`Plan` (list of :class:`Effect`) that :func:`solve` will run for ``model`` (a Model)."""
    sc, nonlinear = model.scene, not model.linear
    every = "every iteration" if nonlinear else "once"
    out = Plan()
    if model.solid_mesh is not None:
        m = model.solid_mesh
        kinds = ", ".join(f"{len(c)} {d.name}" for d, c in m.blocks)
        out.append(Effect("solid.mesh", "once", f"{kinds}; {m.n_nodes} nodes"))
    for g in model.groups:
        out.append(Effect("beams.mesh", "once", f"{g.model}: {len(g.entries)} beam(s), {g.mesh.n_elements} "
                                                f"{g.mesh.element_type.name} elements"))
    if sc.coupled:
        c = sc.coupling
        out.append(Effect("mortar.search", "once", "broad phase, reference configuration"))
        if c["integration"] == "segment":
            out.append(Effect("mortar.segmentation", "once", f"beam–face intersections, {c['search_points']} "
                                                             "search points"))
        elif c["integration"] == "auto":
            out.append(Effect("mortar.segmentation", "once", "only beam elements that cross element faces "
                                                             f"({c['search_points']} search points)"))
        elif c["integration"] == "element_boundary":
            out.append(Effect("mortar.segmentation", "once", "only beam elements that cross the solid's boundary "
                                                             f"({c['search_points']} search points)"))
        out.append(Effect("mortar.integration_points", "once", f"{c['integration']}-based, n_gauss={c['n_gauss']}"))
        out.append(Effect("mortar.assembly", "once", f"D, M, kappa (lm={c['lm']})"))
        if c["enforcement"] == "lagrange":
            out.append(Effect("coupling.lagrange", "once", f"constraint rows B = [-M, D] ({c['constraint']})"))
        else:
            out.append(Effect(f"coupling.{c['constraint']}_penalty", "once",
                              f"constant stiffness, penalty {model.penalty:.4g}"))
    if sc.coupled and sc.coupling["rotational"] is not None:
        r = sc.coupling["rotational"]
        penalty = f"{r['penalty']:.4g}" if r["penalty"] is not None else "1e3 GI_T / h² (default)"
        if r["enforcement"] == "lagrange":
            out.append(Effect("coupling.rotational_lagrange", every, f"{r['triad']} solid triad, lm={r['lm']}, "
                                                                      "multipliers (nonlinear constraint rows)"))
        else:
            out.append(Effect("coupling.rotational_penalty", every, f"{r['triad']} solid triad, lm={r['lm']}, "
                                                                     f"penalty {penalty}"))
    out.append(Effect("check.rigid_body_modes", "once", "before any solve"))
    if model.groups:
        out.append(Effect("check.zero_energy_modes", "once", "beam mechanisms, before any solve"))
    if model.solid_mesh is not None:
        mat = sc.solid["material"]["model"]
        if sc.solid["material"].get("fibres"):
            mat += f" + {len(sc.solid['material']['fibres'])} fibre families"
        if nonlinear:
            out.append(Effect("solid.internal_force", every, f"total Lagrangian, {mat}"))
            out.append(Effect("solid.tangent", every, "consistent tangent"))
        else:
            out.append(Effect("solid.stiffness", "once", f"small strain, {mat}"))
    if model.groups:
        if nonlinear:
            out.append(Effect("beam.internal_force", every, ", ".join(g.model for g in model.groups)))
            out.append(Effect("beam.tangent", every, "consistent tangent"))
        else:
            out.append(Effect("beam.stiffness", "once", "linearised at the reference configuration"))
        framed = [g for g in model.groups if g.rotations.size]
        if framed:
            nodes = sum(g.rotations.size // 3 for g in framed)
            out.append(Effect("beam.rotations", "once", f"{', '.join(g.model for g in framed)}: {nodes} rotation "
                                                        "nodes (mesh nodes + element middles), reference triads"))
            if nonlinear:
                out.append(Effect("beam.rotation_update", every, "multiplicative: ψ ← log(exp(Δθ) exp(ψ))"))
    kinds = {item["type"] for item in sc.loads}
    for kind, when, detail in (("point", "once", "dead nodal forces"),
                               ("traction", "once", "dead surface traction"),
                               ("body", "once", "dead body force"),
                               ("line", "once", "dead line load per reference length on beams"),
                               ("line_moment", "once", "dead moment per reference length on beams with rotations")):
        if kind in kinds:
            out.append(Effect(f"load.{kind}", when, detail))
    if "pressure" in kinds:
        if nonlinear:
            out.append(Effect("load.pressure", every, "follower pressure on the current surface"))
            out.append(Effect("load.pressure_tangent", every, "load stiffness of the follower pressure"))
        else:
            out.append(Effect("load.pressure", "once", "pressure on the reference surface (linear kinematics)"))
    if "moment" in kinds:
        on_spins = [sel[1].rotations.size > 0 for item, (sel, _) in zip(sc.loads, model.load_sets)
                    if item["type"] == "moment"]
        if all(on_spins):
            out.append(Effect("load.moment", "once", "dead moments on rotation nodes (virtual work M·δθ)"))
        else:
            out.append(Effect("load.moment", every, "beam end moment"))
    if nonlinear:
        a = sc.analysis
        out.append(Effect("solver.newton", "every load step", f"{a['steps']} load steps, rtol {a['rtol']:g}, "
                                                              f"at most {a['max_iterations']} iterations"))
    else:
        out.append(Effect("solver.linear", "once", "one linear solve, no Newton loop"))
    method = model.linear_solver_method()
    amg = ("CG + auxiliary-space preconditioner (AMG on the solid carrying its beams, beam blocks "
           "factorised)" if model._auxiliary_space() else "CG + smoothed aggregation AMG (rigid-body modes)")
    detail = {"direct": "sparse LU (scipy)", "amg": amg,
              "block": "GMRES + block-triangular preconditioner (auxiliary space on the augmented stiffness, "
                       "Schur from kappa)"}[method]
    out.append(Effect(f"linear_solver.{method}", every, detail))
    if (method == "amg" and model._auxiliary_space()) or (method == "block" and model._auxiliary_space(True)):
        out.append(Effect("linear_solver.follow_operator", "once", "beam DOFs following the solid "
                                                                    "(prolongation of the auxiliary space)"))
    return out
