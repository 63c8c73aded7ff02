"""Figures of the Simo–Reissner beam (issue 18): cost per evaluation, tangent checks, Gauss rules.

    .venv/bin/python benchmarks/simo_reissner.py [--part cost|tangent|gauss|all] [--repeats 15]

- ``cost``: one ``evaluate`` with tangent of 100 Hermite elements (a helix), the Simo–Reissner beam
  (default rule and the 2-point force rule) next to the torsion-free ``BeamModel.evaluate`` of the
  same mesh made straight (it refuses curved ones), medians of ``--repeats`` calls with 1 thread
  and with the default thread count, and their ratios. The same block also times the force alone.
- ``tangent``: the complex-step tangent and the residual against central differences (h = 1e-6)
  of the residual and of the energy, with multiplicative perturbations of the triads.
- ``gauss``: zero eigenvalues of a free beam per rule (spurious modes), the linear tip displacement
  of a slender quarter arc against a 256-element solution, and the end-moment roll-up of a slender
  straight cantilever into a full circle (tip distance from the root), for several rules.
"""
import argparse
import statistics
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))     # measure this checkout's package
sys.path.insert(1, str(Path(__file__).resolve().parents[1] / "tests"))     # the tests' beam geometries

import numba                                                        # noqa: E402
import numpy as np                                                  # noqa: E402
import scipy.sparse.linalg as spla                                  # noqa: E402

from mortar1d3d.physics.beam import BeamModel                       # noqa: E402
from mortar1d3d.physics.simo_reissner import Section, SimoReissnerBeam  # noqa: E402
from test_simo_reissner import arc_beam as arc, helix_beam, straight_beam as straight  # noqa: E402


def helix(n, turns=2.0):
    return helix_beam(n, turns=turns)


def median_time(fun, repeats):
    fun()
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fun()
        times.append(time.perf_counter() - t0)
    return statistics.median(times)


# -- cost --------------------------------------------------------------------------------------------

def cost(repeats):
    n = 100
    section = Section.circular(1.0, 0.01, nu=0.3)
    rng = np.random.default_rng(0)
    models = {"SR (3, 3)": SimoReissnerBeam(helix(n), section),
              "SR force 2": SimoReissnerBeam(helix(n), section, force_gauss=2)}
    tf = BeamModel(straight(n), section.EA, section.EI2)
    d_tf = 1e-3 * rng.normal(size=tf.n_dofs)
    states = {k: (1e-3 * rng.normal(size=m.n_centreline_dofs), 0.01 * rng.normal(size=(m.n_rotation_nodes, 3)))
              for k, m in models.items()}
    default = numba.get_num_threads()
    print(f"cost of one evaluate, {n} Hermite elements (medians of {repeats}; load {_load()})")
    for threads in sorted({1, default}):
        numba.set_num_threads(threads)
        t_tf = median_time(lambda: tf.evaluate(d_tf), repeats)
        t_tf_f = median_time(lambda: tf.evaluate(d_tf, tangent=False), repeats)
        print(f"  {threads} thread(s): BeamModel (torsion-free) f+K {t_tf * 1e3:8.3f} ms, f {t_tf_f * 1e3:8.3f} ms")
        for name, model in models.items():
            d, psi = states[name]
            t = median_time(lambda: model.evaluate(d, psi), repeats)
            t_f = median_time(lambda: model.evaluate(d, psi, tangent=False), repeats)
            print(f"  {threads} thread(s): {name:<10} f+K {t * 1e3:8.3f} ms ({t / t_tf:5.1f}x), "
                  f"f {t_f * 1e3:8.3f} ms ({t_f / t_tf_f:5.1f}x); tangent/force {t / t_f:5.1f}")
    numba.set_num_threads(default)


def _load():
    try:
        return " ".join(Path("/proc/loadavg").read_text().split()[:3])
    except OSError:
        return "?"


# -- tangent ----------------------------------------------------------------------------------------

def perturbed(model, d, psi, x):
    nc = model.n_centreline_dofs
    return d + x[:nc], model.update(psi, x[nc:].reshape(-1, 3))


def tangent():
    section = Section(EA=10.0, GA2=4.0, GA3=3.0, GI_T=0.5, EI2=0.7, EI3=0.9)
    rng = np.random.default_rng(1)
    h = 1e-6
    print("tangent and residual against central differences (h = 1e-6), 3-element helix, random state")
    for rules in (dict(), dict(force_gauss=2)):
        model = SimoReissnerBeam(helix(3, turns=0.35), section, **rules)
        d, psi = 0.05 * rng.normal(size=model.n_centreline_dofs), 0.3 * rng.normal(size=(model.n_rotation_nodes, 3))
        f, K = model.evaluate(d, psi)
        K = K.toarray()
        Kfd = np.empty_like(K)
        gfd = np.empty(model.n_dofs)
        for j in range(model.n_dofs):
            x = np.zeros(model.n_dofs)
            x[j] = h
            Kfd[:, j] = (model.evaluate(*perturbed(model, d, psi, x), tangent=False)[0]
                         - model.evaluate(*perturbed(model, d, psi, -x), tangent=False)[0]) / (2 * h)
            gfd[j] = (model.energy(*perturbed(model, d, psi, x))
                      - model.energy(*perturbed(model, d, psi, -x))) / (2 * h)
        print(f"  rules {rules or 'default'}: max|K - K_fd| / max|K| = {np.abs(K - Kfd).max() / np.abs(K).max():.2e}; "
              f"max|f - dΠ_fd| / max|f| = {np.abs(f - gfd).max() / np.abs(f).max():.2e}; "
              f"asymmetry max|K - Kᵀ| / max|K| = {np.abs(K - K.T).max() / np.abs(K).max():.2e}")


# -- Gauss rules ------------------------------------------------------------------------------------

RULES = ((3, None), (4, None), (5, None), (2, 3), (3, 2), (2, 2), (3, (3, 2, 2)), (3, (2, 3, 3)))


def _label(rule):
    return f"n_gauss={rule[0]}, force_gauss={rule[1] if rule[1] is not None else rule[0]}"


def clamped_solve(model, fixed, F):
    _, K = model.evaluate(np.zeros(model.n_centreline_dofs), np.zeros((model.n_rotation_nodes, 3)))
    free = np.setdiff1d(np.arange(model.n_dofs), fixed)
    u = np.zeros(model.n_dofs)
    u[free] = spla.spsolve(K.tocsc()[free][:, free], F[free])
    return u


def arc_tip(n, section, rule, load):
    model = SimoReissnerBeam(arc(n), section, n_gauss=rule[0], force_gauss=rule[1])
    nc = model.n_centreline_dofs
    F = np.zeros(model.n_dofs)
    F[6 * n: 6 * n + 3] = load
    u = clamped_solve(model, [0, 1, 2, nc, nc + 1, nc + 2], F)
    return u[6 * n: 6 * n + 3]


def roll_up(n, section, rule, clamp_tangent, steps=40):
    model = SimoReissnerBeam(straight(n), section, n_gauss=rule[0], force_gauss=rule[1])
    nc = model.n_centreline_dofs
    fixed = [0, 1, 2, nc, nc + 1, nc + 2] + ([3, 4, 5] if clamp_tangent else [])
    free = np.setdiff1d(np.arange(model.n_dofs), fixed)
    d, psi = np.zeros(nc), np.zeros((model.n_rotation_nodes, 3))
    iterations = 0
    for step in range(1, steps + 1):
        F = np.zeros(model.n_dofs)
        F[nc + 3 * n + 2] = step / steps * 2 * np.pi * section.EI3
        for _ in range(30):
            f, K = model.evaluate(d, psi)
            iterations += 1
            x = np.zeros(model.n_dofs)
            x[free] = -spla.spsolve(K.tocsc()[free][:, free], (f - F)[free])
            if not np.isfinite(x).all():
                return float("nan"), iterations
            d, psi = d + x[:nc], model.update(psi, x[nc:].reshape(-1, 3))
            if np.abs(x).max() < 1e-12:
                break
        else:
            return float("nan"), iterations
    return float(np.linalg.norm(model.beams.positions[n] + d[6 * n: 6 * n + 3])), iterations


def gauss():
    import warnings
    warnings.simplefilter("ignore")         # singular matrices of the rules with zero-energy modes
    section = Section(EA=10.0, GA2=4.0, GA3=3.0, GI_T=0.5, EI2=0.7, EI3=0.9)
    print("zero eigenvalues of a free beam (6 = rigid motions only), 1 and 3 elements, straight / arc:")
    for rule in RULES:
        counts = []
        for beams in (straight(1), straight(3), arc(3)):
            model = SimoReissnerBeam(beams, section, n_gauss=rule[0], force_gauss=rule[1])
            _, K = model.evaluate(np.zeros(model.n_centreline_dofs), np.zeros((model.n_rotation_nodes, 3)))
            ev = np.linalg.eigvals(K.toarray())
            counts.append(int(np.sum(np.abs(ev) < 1e-10 * np.abs(ev).max())))
        print(f"  {_label(rule):<36} {counts}")
    print("quarter arc R = 1, circular section r, linear tip load, |u - u_ref| / |u_ref| (u_ref: 256 elements,"
          " 5 points), elements 4 / 8 / 16:")
    for r in (1e-2, 1e-3):
        section_r = Section.circular(1.0, r, nu=0.3)
        for name, load in (("in-plane", [0.0, 1.0, 0.0]), ("out-of-plane", [0.0, 0.0, 1.0])):
            load = np.array(load) * r ** 4
            ref = arc_tip(256, section_r, (5, None), load)
            for rule in RULES:
                errors = [np.linalg.norm(arc_tip(n, section_r, rule, load) - ref) / np.linalg.norm(ref)
                          for n in (4, 8, 16)]
                print(f"  r = {r:g} {name:<13} {_label(rule):<36} " + " ".join(f"{e:9.2e}" for e in errors))
    print("end-moment roll-up into a full circle, L = 1, circular section r, 40 load steps: tip distance from"
          " the root / L [Newton iterations], elements 4 / 8 / 16 (nan: singular or no convergence):")
    for r in (1e-2, 1e-3):
        section_r = Section.circular(1.0, r, nu=0.3)
        for rule in ((3, None), (4, None), (3, 2), (2, 2)):
            for clamp_tangent in (False, True):
                row = [roll_up(n, section_r, rule, clamp_tangent) for n in (4, 8, 16)]
                clamp = "r, t, Λ" if clamp_tangent else "r, Λ"
                print(f"  r = {r:g} clamp {clamp:<8} {_label(rule):<36} "
                      + " ".join(f"{e:9.2e} [{i}]" for e, i in row))


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--part", choices=("cost", "tangent", "gauss", "all"), default="all")
    parser.add_argument("--repeats", type=int, default=15)
    args = parser.parse_args()
    if args.part in ("tangent", "all"):
        tangent()
    if args.part in ("cost", "all"):
        cost(args.repeats)
    if args.part in ("gauss", "all"):
        gauss()
