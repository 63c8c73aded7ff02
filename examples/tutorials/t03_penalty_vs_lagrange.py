"""Tutorial 3: penalty against Lagrange multipliers; the penalty error falls like 1/ε.

The coupling constraint D d_B − M d_S = 0 can be enforced exactly with Lagrange multipliers (a
saddle-point system with λ as extra unknowns) or approximately with a penalty ε (a stiff spring
energy ½ ε gᵀ diag(κ)⁻¹ g on the gap g; no extra unknowns, but the constraint holds only up to
an error that shrinks as ε grows).

The scene: a block 2 × 0.5 × 0.5 of 8 × 2 × 2 hex8, clamped at x = 0, with a stiff bar
(``torsion_free`` beam) along its axis that sticks out of the free end by 0.25 and is pulled
sideways there by a point load. Linear kinematics, so every solve is one linear solve. The tip of
the bar is solved once with Lagrange multipliers (the reference) and with penalties ε = c · E_solid
for c = 10² … 10⁵; the relative difference of the displacements falls like 1/ε (a slope of −1 in
``penalty_vs_lagrange.png``) until round-off.

Run it::

    python examples/tutorials/t03_penalty_vs_lagrange.py [--out results/tutorials] [--no-plot]
"""
from pathlib import Path

import numpy as np

import mortar1d3d as m13
from _tutorial import main, save_figure

E_SOLID = 1.0e4
FACTORS = (1e2, 1e3, 1e4, 1e5)


def scene(enforcement, penalty=None, cells=(8, 2, 2)):
    """The block with its bar as a Scene (the same keys as a TOML file)."""
    coupling = {"enforcement": enforcement, "integration": "segment", "lm": "line2"}
    if penalty is not None:
        coupling["penalty"] = penalty
    return m13.Scene(
        solid={"mesh": {"box": [[0, 0, 0], [2, 0.5, 0.5]], "cells": list(cells), "element": "hexahedron"},
               "material": {"model": "linear_elastic", "E": E_SOLID, "nu": 0.3}},
        beams=[{"curve": {"line": [[0, 0.25, 0.25], [2.25, 0.25, 0.25]]}, "elements": 9,
                "model": "torsion_free", "section": {"E": 100 * E_SOLID, "radius": 0.05}}],
        coupling=coupling,
        dirichlet=[{"on": "solid:x_min"}, {"on": "beam:0:start"}],
        load=[{"type": "point", "on": "beam:0:end", "value": [0.0, 0.0, -1.0]}],
        analysis={"kinematics": "linear"})


def displacement(result):
    return np.concatenate([result.solid_displacement.ravel(), result.beam_displacement.ravel()])


def run(factors=FACTORS, out=None, plot=True, verbose=True):
    reference = m13.solve(scene("lagrange"))
    u_ref = displacement(reference)
    errors = {}
    for c in factors:
        u = displacement(m13.solve(scene("penalty", penalty=c * E_SOLID)))
        errors[c] = np.linalg.norm(u - u_ref) / np.linalg.norm(u_ref)
    c = np.log10(list(errors))
    slope = np.polyfit(c, np.log10(list(errors.values())), 1)[0]
    result = {"tip_deflection": float(reference.beam_displacement[-1, 2]), "errors": errors, "slope": slope}
    if verbose:
        print(f"Lagrange multipliers: tip deflection of the bar {result['tip_deflection']:.6e}")
        for c, e in errors.items():
            print(f"  penalty ε = {c:7.0e} E_solid: relative difference {e:.3e}")
        print(f"log-log slope of the difference against ε: {slope:.3f} (1/ε gives -1)")
    if plot:
        _plot(errors, Path(out or "results/tutorials"))
    return result


def _plot(errors, out):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    c = np.array(list(errors))
    e = np.array(list(errors.values()))
    fig, ax = plt.subplots(figsize=(5.5, 4))
    ax.loglog(c, e, "o-", label="penalty against Lagrange")
    ax.loglog(c, e[0] * c[0] / c, "k--", lw=0.8, label="∝ 1/ε")
    ax.set_xlabel("penalty ε / E_solid")
    ax.set_ylabel("relative difference of the displacements")
    ax.legend()
    save_figure(fig, out, "penalty_vs_lagrange.png")


if __name__ == "__main__":
    main(run, __doc__)
