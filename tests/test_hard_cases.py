"""Issue 6, part 1: the named catalogue of hard geometric cases (scenes in tests/hard_cases.py).

Every case, as built (``plain``): no exception, warning, NaN or Inf; the segments of every beam
element tile its embedded part exactly once (compared with an independent dense point-in-solid
sampling + bisection); every segment lies in its owner and no lower-index element contains it;
the certificates hold (‖D q_B - M X_S‖ at round-off, Σκ = the analytic embedded length and = the
Gauss rule of |r'| on the segments); κ, D and M are invariant under renumbering of solid elements
and nodes; moving the beam by ±1e-12 h changes D, M, κ by O(1e-12) (times the conditioning the
case has by nature: 1/sin θ at a small angle to the outer boundary, sqrt at a tangential touch,
h/t for the shape functions of a sliver of thickness t).

The same cases at an offset of 1e6 and at scales 1e-6 and 1e6: the same segments (η to the
tolerance the round-off allows), κ and M scaled by the length scale, D by its columns' scale,
certificates and continuity again.

Regression cases found while building this (see also test_fuzz.py) are at the end.
"""
import warnings

import numpy as np
import pytest

import mortar1d3d as m13
from mortar1d3d import generate

import hard_cases as hc

CASES = hc.catalogue()


@pytest.fixture(scope="module")
def plain_results():
    """Operators of the plain cases, computed once (the transformed variants compare with them)."""
    return {}


def _plain(name, cache):
    if name not in cache:
        case = CASES[name]
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            cache[name] = hc.assemble(case)
    return cache[name]


@pytest.mark.parametrize("name", list(CASES))
def test_hard_case(name, plain_results):
    case = CASES[name]
    with warnings.catch_warnings():
        warnings.simplefilter("error")          # no missed-crossing or non-convergence warnings
        ops = _plain(name, plain_results)
        hc.check_finite(ops)
        hc.check_tiling(ops, case)
        hc.check_certificates(ops, case)
        hc.check_renumbering(ops, case)
        hc.check_continuity(ops, case)
    assert ops.diagnostics["segmentation_fallbacks"] == 0


def _column_scale(beams, scale):
    """D's columns scale like the length (positions) or its square (Hermite tangent functions ∝ L)."""
    per_node = beams.element_type.dofs_per_node
    factor = np.full((beams.n_nodes, per_node), scale)
    if per_node == 6:
        factor[:, 3:] = scale * scale
    return factor.ravel()


@pytest.mark.parametrize("transform", [t for t in hc.TRANSFORMS if t != "plain"])
@pytest.mark.parametrize("name", list(CASES))
def test_hard_case_moved_and_scaled(name, transform, plain_results):
    case = hc.transformed(CASES[name], transform)
    offset, scale = hc.TRANSFORMS[transform]
    ref = _plain(name, plain_results)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        ops = hc.assemble(case)
        hc.check_finite(ops)
        hc.check_certificates(ops, case)
        hc.check_continuity(ops, case)
    # the same pieces: cut positions to what the round-off allows
    tol = hc.eta_tolerance(case)
    for e in range(case.beams.n_elements):
        got, want = hc.segment_union(ops, e), hc.segment_union(ref, e)
        got = [g for g in got if g[1] - g[0] > 2 * tol]
        want = [w for w in want if w[1] - w[0] > 2 * tol]
        assert len(got) == len(want), (case.name, e, got, want)
        assert not got or np.allclose(got, want, rtol=0, atol=tol), (case.name, e, got, want)
    # operators scale with the length; round-off of the moved coordinates is ~ulp(offset)/h
    rel = 1e-12 + 1e3 * hc.coordinate_round_off(case.beams, case.solid)
    rel = rel * case.conditioning if not case.touch else max(rel, 1e2 * np.sqrt(rel))
    full = hc.full_operators(CASES[name])
    assert hc.relative_change(ref.kappa, ops.kappa / scale, np.linalg.norm(full.kappa)) <= rel
    assert hc.relative_change(ref.M, ops.M / scale, np.linalg.norm(full.M.toarray())) <= rel * case.gradient
    D = ops.D.multiply(1.0 / _column_scale(CASES[name].beams, scale)[None, :]).tocsr()
    assert hc.relative_change(ref.D, D, np.linalg.norm(full.D.toarray())) <= rel


# --------------------------------------------------------------------------------------------
# regression cases and the fallback of issue 6 part 3
# --------------------------------------------------------------------------------------------
