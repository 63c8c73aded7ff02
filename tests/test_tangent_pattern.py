"""The model's tangent summed on one cached pattern (model.tangent) equals scipy's sum bit for bit."""
import numpy as np
import pytest
import scipy.sparse as sp

import mortar1d3d as m13
from mortar1d3d.model import Model
from mortar1d3d.model.build import build
from mortar1d3d.model.tangent import FilledBlock, TangentPattern


def _random_block(rng, size, density=0.3):
    A = sp.random(size, size, density=density, random_state=rng, format="csr")
    return (A + A.T).tocsr()


def _scipy_sum(n, blocks, constant):
    """The reference: every block placed by a COO matrix, summed with scipy's addition."""
    K = sp.csr_matrix((n, n)) if constant is None else constant.copy()
    for B, index in blocks:
        B = B.tocoo()
        index = np.arange(B.shape[0]) + index if np.isscalar(index) else index
        K = K + sp.csr_matrix((B.data, (index[B.row], index[B.col])), shape=(n, n))
    return K.tocsr()


def _assert_same(K, ref):
    ref = ref.copy()
    ref.sort_indices()
    assert K.shape == ref.shape
    assert np.array_equal(K.indptr, ref.indptr)
    assert np.array_equal(K.indices, ref.indices)
    assert np.array_equal(K.data.view(np.int64), ref.data.view(np.int64))      # every bit


def _scene_blocks(rng, n=40):
    """A solid block at 0..19, a beam block at 20..27 and a scattered block (a beam with rotations)
    on 28..39 in shuffled order, plus a sparse constant over everything."""
    index = rng.permutation(np.arange(28, n))
    blocks = [(_random_block(rng, 20), 0), (_random_block(rng, 8), 20), (_random_block(rng, 12), index)]
    constant = _random_block(rng, n, density=0.05)
    return n, blocks, constant


def test_sum_equals_scipy_bitwise_and_pattern_is_reused():
    rng = np.random.default_rng(3)
    n, blocks, constant = _scene_blocks(rng)
    pattern = TangentPattern(n)
    for call in range(3):
        blocks = [(B.copy() if call else B, i) for B, i in blocks]       # new arrays, same patterns
        for B, _ in blocks:
            B.data[:] = rng.standard_normal(B.nnz)
        _assert_same(pattern.assemble(blocks, constant), _scipy_sum(n, blocks, constant))
    assert pattern.n_builds == 1


def test_changed_pattern_rebuilds_changed_values_do_not():
    rng = np.random.default_rng(4)
    n, blocks, constant = _scene_blocks(rng)
    pattern = TangentPattern(n)
    pattern.assemble(blocks, constant)
    blocks[0] = (_random_block(rng, 20, density=0.5), 0)
    _assert_same(pattern.assemble(blocks, constant), _scipy_sum(n, blocks, constant))
    assert pattern.n_builds == 2
    constant = 2.0 * constant                                        # new values, same pattern: no rebuild
    _assert_same(pattern.assemble(blocks, constant), _scipy_sum(n, blocks, constant))
    assert pattern.n_builds == 2
    _assert_same(pattern.assemble(blocks, None), _scipy_sum(n, blocks, None))
    assert pattern.n_builds == 3
    constant = constant.tolil()
    constant[0, n - 1] = 7.0                                         # a new entry in the constant
    constant = constant.tocsr()
    _assert_same(pattern.assemble(blocks, constant), _scipy_sum(n, blocks, constant))
    assert pattern.n_builds == 4


def test_cancelled_entries_are_removed_as_scipy_removes_them():
    n = 6
    constant = sp.csr_matrix(np.diag(np.arange(1.0, 7.0)))
    block = sp.csr_matrix(-np.diag([1.0, 2.0]) + np.array([[0.0, 5.0], [5.0, 0.0]]))
    K = TangentPattern(n).assemble([(block, 0)], constant)
    assert K.nnz == 6                                                 # (0,0) and (1,1) cancel; (0,1), (1,0) added
    assert K[0, 0] == 0.0 and K[0, 1] == 5.0
    _assert_same(K, _scipy_sum(n, [(block, 0)], constant))


def test_repeated_entries_in_a_block_are_summed():
    block = sp.csr_matrix((np.array([1.0, 2.0, 4.0]), np.array([0, 0, 1]), np.array([0, 2, 3])), shape=(2, 2))
    K = TangentPattern(3).assemble([(block, 1)], None)
    assert K[1, 1] == 3.0 and K[2, 2] == 4.0 and K.nnz == 2


def test_shared_pattern_is_read_only():
    rng = np.random.default_rng(5)
    n, blocks, constant = _scene_blocks(rng)
    for B, _ in blocks:
        B.data[:] = 1.0 + rng.random(B.nnz)                           # no cancellation: pattern shared
    K = TangentPattern(n).assemble(blocks, sp.csr_matrix((n, n)) + sp.identity(n, format="csr"))
    with pytest.raises(ValueError):
        K.indices[0] = 1


def test_dropped_results_are_refilled_held_ones_are_never_touched():
    rng = np.random.default_rng(6)
    n, blocks, constant = _scene_blocks(rng)
    pattern = TangentPattern(n)

    def new_values():
        for B, _ in blocks:
            B.data[:] = 1.0 + rng.random(B.nnz)                       # no cancellation: the result shares data
        return pattern.assemble(blocks, constant), _scipy_sum(n, blocks, constant)

    K1, ref1 = new_values()
    K2, ref2 = new_values()                                           # K1 held: a new array, K1 unchanged
    assert pattern.n_recycled == 0 and K2.data is not K1.data
    _assert_same(K1, ref1)
    memory = K2.data.__array_interface__["data"][0]
    del K1, K2
    K3, ref3 = new_values()                                           # K2 dropped: its array refilled from zero
    assert pattern.n_recycled == 1 and K3.data.__array_interface__["data"][0] == memory
    _assert_same(K3, ref3)
    view = K3.data[:5]
    held = view.copy()
    del K3
    K4, ref4 = new_values()                                           # a view of K3's values still held
    assert pattern.n_recycled == 1
    assert np.array_equal(view, held)
    _assert_same(K4, ref4)


@pytest.mark.parametrize("beam_model", ["torsion_free", "simo_reissner"])
def test_model_tangent_equals_block_sum(beam_model):
    """Solid + beams + penalty coupling: the model's tangent is the blocks plus the coupling stiffness."""
    if beam_model == "torsion_free":
        beam = {"mesh": m13.generate.fibre_cube(2, 3, 2)[0], "section": {"E": 2e11, "radius": 0.05}}
    else:
        beam = {"curve": {"line": [[0.1, 0.5, 0.5], [0.9, 0.4, 0.6]]}, "elements": 3, "model": "simo_reissner",
                "section": {"E": 2e11, "nu": 0.3, "radius": 0.02}}
    scene = m13.Scene(solid={"mesh": {"box": [[0, 0, 0], [1, 1, 1]], "cells": [2, 2, 2]},
                             "material": {"model": "saint_venant_kirchhoff", "E": 1e9, "nu": 0.3}},
                      beams=[beam], coupling={"enforcement": "penalty", "lm": "line2"},
                      dirichlet=[{"on": "solid:x_min"}]
                      + ([{"on": "beam:0:start", "rotation": [0, 0, 0]}] if beam_model == "simo_reissner" else []),
                      analysis={"kinematics": "nonlinear", "steps": 1})
    model = Model(build(scene))
    model.prepare()
    n = model.n_displacement_dofs
    d = 1e-3 * np.random.default_rng(6).standard_normal(n)
    r, K = model.internal(d)
    nS = 3 * model.n_solid_nodes
    r_ref = np.zeros(n)
    r_ref[:nS], K_solid = model.solid_physics.evaluate(d[:nS])
    blocks = [(K_solid, 0)]
    for g in model.groups:
        if g.rotations.size:
            idx = np.concatenate([np.arange(g.dofs.start, g.dofs.stop), np.arange(g.rotations.start, g.rotations.stop)])
            r_ref[idx], Kb = g.physics.evaluate(d[g.dofs.slice], d[g.rotations.slice].reshape(-1, 3))
            blocks.append((Kb, idx))
        else:
            r_ref[g.dofs.slice], Kb = g.physics.evaluate(d[g.dofs.slice])
            blocks.append((Kb, g.dofs.start))
    r_ref += model.coupling_stiffness @ d
    _assert_same(K, _scipy_sum(n, blocks, model.coupling_stiffness))
    assert np.array_equal(r.view(np.int64), r_ref.view(np.int64))      # the solid's force added in the fill
    _, K2 = model.internal(2.0 * d)
    assert model._tangent_pattern.n_builds == 1 and not np.array_equal(K2.data, K.data)


def test_filled_block_equals_matrix_block():
    """A block that adds its own values at the given positions gives the same result as the matrix."""
    rng = np.random.default_rng(11)
    n, blocks, constant = _scene_blocks(rng)
    B, index = blocks[0]
    calls = []

    def fill(data, positions):
        calls.append(len(positions))
        np.add.at(data, positions, B.data)

    filled = [(FilledBlock(B.shape, B.indptr, B.indices, fill), index)] + blocks[1:]
    pattern = TangentPattern(n)
    _assert_same(pattern.assemble(filled, constant), _scipy_sum(n, blocks, constant))
    pattern.assemble(filled, constant)
    assert calls == [B.nnz, B.nnz] and pattern.n_builds == 1


def test_solid_add_tangent_into_checks_its_input():
    """Linear kinematics keep one cached matrix, and a map of the wrong length is refused."""
    from mortar1d3d.physics.materials import material
    from mortar1d3d.physics.solid import SolidModel
    mesh = m13.generate.box((0, 0, 0), (1, 1, 1), (1, 1, 1))
    mat = material("saint_venant_kirchhoff", 1e9, 0.3)
    solid = SolidModel(mesh, mat, kinematics="nonlinear")
    _, indptr, indices = solid.pattern
    data = np.zeros(len(indices))
    with pytest.raises(ValueError, match="data_map must have"):
        solid.add_tangent_into(np.zeros(solid.n_dofs), data, np.arange(3, dtype=np.int32))
    with pytest.raises(ValueError, match="linear kinematics"):
        SolidModel(mesh, mat, kinematics="linear").add_tangent_into(np.zeros(solid.n_dofs), data,
                                                                   np.arange(len(indices), dtype=np.int32))
    # the identity map gives the solid's own matrix, bit for bit
    u = 1e-3 * np.random.default_rng(2).standard_normal(solid.n_dofs)
    f = solid.add_tangent_into(u, data, np.arange(len(indices), dtype=np.int32))
    f_ref, K_ref = solid.evaluate(u)
    assert np.array_equal(f, f_ref) and np.array_equal(data.view(np.int64), K_ref.data.view(np.int64))


def _reference_jacobian(model, z, t):
    """The Jacobian as the model summed it before everything went on one pattern: scipy's
    ``block_diag`` (or its sum with the penalty stiffness), then each load's ``K − t Kp`` and
    ``K − Km``, then ``sp.bmat`` with the constraint matrix."""
    from mortar1d3d.physics.beam import end_moment
    n, nS = model.n_displacement_dofs, 3 * model.n_solid_nodes
    d = z[:n]
    blocks = [(model.solid_physics.evaluate(d[:nS])[1], 0)]
    blocks += [(g.physics.evaluate(d[g.dofs.slice])[1], g.dofs.start) for g in model.groups]
    penalty = model.scene.coupled and not model.lagrange
    if penalty:
        K = _scipy_sum(n, blocks, model.coupling_stiffness)
    else:
        K = sp.block_diag([B for B, _ in blocks], format="csr")
    for p in model.pressures:
        Kp = p.evaluate(d[:nS])[1].tocoo()
        K = K - t * sp.csr_matrix((Kp.data, (Kp.row, Kp.col)), shape=(n, n))
    q = model.reference() + d
    for dofs, moment in model.moments:
        Km = end_moment(q[dofs], t * moment)[1]
        K = K - sp.csr_matrix((Km.ravel(), (np.repeat(dofs, 3), np.tile(dofs, 3))), shape=K.shape)
    if model.lagrange:
        B = model.constraint_matrix
        K = sp.bmat([[K, B.T], [B, None]], format="csr")
    return K


@pytest.mark.parametrize("case", ["lagrange", "lagrange_pressure", "penalty_loads", "uncoupled_pressure"])
def test_jacobian_with_loads_and_multipliers_equals_scipy(case):
    """Lagrange multipliers (the saddle point's border), follower pressure and end moments are summed
    on the cached pattern too: same entries, same stored zeros, same bits as scipy's operations."""
    loads = [{"type": "pressure", "on": "solid:z_max", "value": 0.7}] if "pressure" in case or case == "penalty_loads" \
        else [{"type": "traction", "on": "solid:x_max", "value": [0, 0, -0.1]}]
    if case == "penalty_loads":
        loads.append({"type": "moment", "on": "beam:0:end", "value": [0.0, 0.3, 0.1]})
    coupling = {"enforcement": "lagrange", "lm": "line2"} if case.startswith("lagrange") else \
        {"enforcement": "penalty", "penalty": 50.0} if case == "penalty_loads" else None
    scene = m13.Scene(solid={"mesh": {"box": [[0, 0, 0], [1, 0.3, 0.3]], "cells": [3, 1, 1]},
                             "material": {"model": "neo_hooke", "E": 10.0, "nu": 0.3}},
                      beams=[{"curve": {"line": [[0.1, 0.1, 0.12], [0.9, 0.2, 0.17]]}, "elements": 3,
                              "section": {"EA": 3.0, "EI": 0.2}}],
                      coupling=coupling, dirichlet=[{"on": "solid:x_min"}], load=loads,
                      analysis={"kinematics": "nonlinear", "steps": 1})
    model = Model(build(scene))
    model.prepare()
    z = 0.01 * np.random.default_rng(5).standard_normal(model.n_unknowns)
    r, K = model.residual(z, 0.8)
    ref = _reference_jacobian(model, z, 0.8)
    _assert_same(K, ref)
    _assert_same(model.residual(0.0 * z, 0.8)[1], _reference_jacobian(model, 0.0 * z, 0.8))   # the reference state
    # a second state reuses the pattern
    z2 = 1.5 * z
    _, K2 = model.residual(z2, 0.8)
    _assert_same(K2, _reference_jacobian(model, z2, 0.8))
    assert model._tangent_pattern.n_builds == 1


def test_zero_modes():
    """zeros = keep leaves every union entry (as bmat would), keep_constant removes all zeros but the
    constant's, eliminate removes all."""
    n = 4
    A = sp.csr_matrix(np.array([[1.0, 2.0], [2.0, 1.0]]))
    L = sp.csr_matrix(np.array([[1.0, 0.0], [0.0, 0.0]]))             # cancels A[0, 0]
    C = sp.csr_matrix((np.array([0.0, 3.0]), np.array([2, 3]), np.array([0, 1, 2, 2, 2])), shape=(n, n))   # a stored zero
    counts = {}
    for zeros in ("keep", "keep_constant", "eliminate"):
        K = TangentPattern(n).assemble([(A, 0)], C, [(L, 0, 1.0)], zeros=zeros)
        counts[zeros] = K.nnz
        assert K[0, 0] == 0.0 and K[0, 1] == 2.0 and K[1, 3] == 3.0
    assert counts == {"keep": 6, "keep_constant": 5, "eliminate": 4}
    with pytest.raises(ValueError, match="zeros must be"):
        TangentPattern(n).assemble([(A, 0)], zeros="drop")
