"""Issue 16.3: curved torsion-free beams are refused; zero-energy modes of beams are found before any solve."""
import numpy as np
import pytest

import mortar1d3d as m13
from mortar1d3d import BeamMesh, SceneError
from mortar1d3d.mechanisms import MECHANISM_TOLERANCE, _element_projectors, _node_scale, find_mechanisms
from mortar1d3d.model import Model
from mortar1d3d.physics.beam import BeamModel

SOLID = {"mesh": {"box": [[0, 0, 0], [1, 1, 1]], "cells": [3, 3, 3]},
         "material": {"model": "linear_elastic", "E": 1e9, "nu": 0.3}}


def rod_scene(model, end=1.5, enforcement="penalty", integration="segment", n_gauss=6, elements=8,
              start=(0.2, 0.45, 0.55), constraint="mortar"):
    """A straight beam from inside the unit cube to x = ``end`` (outside for end > 1)."""
    return m13.Scene(solid=SOLID,
                     beams=[{"curve": {"line": [list(start), [end, 0.5, 0.5]]}, "elements": elements, "model": model,
                             "section": {"E": 2e11, "radius": 0.01}}],
                     coupling={"enforcement": enforcement, "integration": integration, "n_gauss": n_gauss,
                               "constraint": constraint},
                     dirichlet=[{"on": "solid:x_min"}],
                     load=[{"type": "traction", "on": "solid:x_max", "value": [0, 0, -1e6]}],
                     analysis={"kinematics": "linear"})


def arc(radius=0.3, elements=12):
    """The issue's half circle of radius 0.3 in the middle of the unit cube."""
    c = np.array([0.5, 0.5, 0.5])
    return BeamMesh.from_curve(lambda t: c + radius * np.array([np.cos(t), np.sin(t), 0.0]),
                               lambda t: radius * np.array([-np.sin(t), np.cos(t), 0.0]), 0.0, np.pi, elements)


# -- curved torsion-free beams -------------------------------------------------------------------

def test_curved_torsion_free_beam_is_a_scene_error_and_the_truss_follows_the_solid():
    """Before: the tied arc moved 0.65 m where the solid moved 0.036 m (penalty; Lagrange 473 m)."""
    beam = arc()
    scene = dict(solid=SOLID, dirichlet=[{"on": "solid:x_min"}],
                 load=[{"type": "traction", "on": "solid:x_max", "value": [0, 0, -5e6]}],
                 analysis={"kinematics": "linear"})
    straight = {"curve": {"line": [[0.1, 0.2, 0.2], [0.9, 0.2, 0.2]]}, "elements": 4,
                "section": {"E": 2e11, "radius": 0.005}}
    bad = m13.Scene(beams=[straight, {"mesh": beam, "model": "torsion_free", "section": {"E": 2e11, "radius": 0.005}}],
                    **scene)
    message = r"^beams\[1\]\.model: .*initially straight.*12 of its 12 elements.*model = \"simo_reissner\".*model = \"truss\""
    with pytest.raises(SceneError, match=message):
        m13.plan(bad)
    helix = {"curve": {"helix": {"centre": [0.5, 0.5, 0.5], "axis": [1, 0, 0], "radius": 0.1, "length": 0.6,
                                 "turns": 1.0}}, "elements": 8, "section": {"E": 2e11, "radius": 0.005}}
    with pytest.raises(SceneError, match=r"^beams\[0\]\.model: .*initially straight"):
        m13.solve(m13.Scene(beams=[helix], **scene))
    kinked = {"curve": {"polyline": [[0.1, 0.5, 0.5], [0.5, 0.5, 0.5], [0.9, 0.6, 0.5]]},
              "section": {"E": 2e11, "radius": 0.005}}
    with pytest.raises(SceneError, match=r"^beams\[0\]\.model: .*2 of its 2 elements"):
        m13.plan(m13.Scene(beams=[kinked], **scene))
    collinear = dict(kinked, curve={"polyline": [[0.1, 0.5, 0.5], [0.5, 0.5, 0.5], [0.9, 0.5, 0.5]]})
    m13.plan(m13.Scene(beams=[collinear], **scene))
    # the same arc as a truss: tied to the solid, it moves with it
    truss = BeamMesh.lagrange(beam.positions, beam.elements)
    for enforcement in ("penalty", "lagrange"):
        result = m13.solve(m13.Scene(beams=[{"mesh": truss, "model": "truss", "section": {"E": 2e11, "radius": 0.005}}],
                                     coupling={"enforcement": enforcement}, **scene))
        u_beam = np.linalg.norm(result.beam_displacement, axis=1).max()
        u_solid = np.linalg.norm(result.solid_displacement, axis=1).max()
        # measured 0.0236 m in a solid that moves at most 0.0358 m
        assert 0.5 * u_solid < u_beam < u_solid


# -- zero-energy modes -----------------------------------------------------------------------------

@pytest.mark.parametrize("enforcement, constraint", [("penalty", "mortar"), ("lagrange", "mortar"),
                                                     ("penalty", "gauss_point")])
def test_truss_half_outside_the_solid_is_a_mechanism(enforcement, constraint):
    """Nodes 6-8 of the truss lie beyond the element that enters the solid: they swing freely."""
    model = Model(rod_scene("truss", 1.5, enforcement, constraint=constraint))
    with pytest.raises(SceneError, match=r"^beams\[0\]: zero-energy mode .*nodes 6, 7, 8 move .*not coupled to the "
                                         r"solid.*truss has no bending stiffness"):
        model.prepare()
    (group, mechanism), = model.zero_energy_modes
    assert mechanism.sigma < 1e-14                     # measured 2e-16
    v = mechanism.mode
    moving = np.abs(v.reshape(-1, 3)).max(axis=1) > 1e-12
    assert np.flatnonzero(moving).tolist() == [6, 7, 8]
    # a true zero-energy mode of the assembled reference tangent, solid at rest
    z = np.zeros(model.n_displacement_dofs)
    z[group.dof_offset: group.dof_offset + len(v)] = v
    _, K = model.internal(np.zeros(model.n_displacement_dofs))      # penalty: coupling included
    assert np.abs(K @ z).max() < 1e-12 * abs(K).max()
    if enforcement == "lagrange":
        assert np.abs(model.constraint_matrix @ z).max() < 1e-12 * abs(model.constraint_matrix).max()
    # inside the solid the same truss is held
    Model(rod_scene("truss", 0.9, enforcement, constraint=constraint)).prepare()


@pytest.mark.parametrize("enforcement, constraint", [("penalty", "mortar"), ("lagrange", "mortar"),
                                                     ("penalty", "gauss_point")])
def test_torsion_free_beam_partly_outside_is_held_by_its_bending_stiffness(enforcement, constraint):
    model = Model(rod_scene("torsion_free", 1.5, enforcement, constraint=constraint)).prepare()
    assert model.zero_energy_modes == [] and model.counts["check.zero_energy_modes"] == 1
    g = model.groups[0]
    rows = g.operators.D.tocsr()[g.coupling.coupled_rows]
    (found,) = find_mechanisms(g.mesh, rows, tolerance=np.inf)
    assert found.sigma > 1e-2                          # measured 0.095: far from a mechanism
    # the reduced reference tangent is regular (penalty: Jacobi-scaled, smallest eigenvalue)
    if enforcement == "penalty":
        _, K = model.internal(np.zeros(model.n_displacement_dofs))
        A = K[model.free][:, model.free].toarray()
        d = 1.0 / np.sqrt(np.diag(A))
        assert np.linalg.eigvalsh(d[:, None] * A * d[None, :]).min() > 1e-10


def test_long_free_part_of_a_torsion_free_beam_is_soft_not_free():
    """σ of the chain falls like 1/n² with the n elements outside: 400 elements are far from the tolerance."""
    model = Model(rod_scene("torsion_free", 30.0, elements=400)).prepare()
    g = model.groups[0]
    (found,) = find_mechanisms(g.mesh, g.operators.D.tocsr()[g.coupling.coupled_rows], tolerance=np.inf)
    assert 1e3 * MECHANISM_TOLERANCE < found.sigma < 1e-4          # measured 1.6e-5


def test_fibre_tied_at_one_point_is_a_mechanism():
    """Element-based, one Gauss point per element: only element 0's centre (x = 0.9) is inside."""
    scene = rod_scene("torsion_free", 2.1, integration="element", n_gauss=1, elements=2, start=(0.5, 0.5, 0.5))
    model = Model(scene)
    with pytest.raises(SceneError, match=r"^beams\[0\]: zero-energy mode .*the coupling holds this beam at too few "
                                         r"places.*integration = \"segment\""):
        model.prepare()
    # segment-based integration couples the whole part inside: held
    Model(rod_scene("torsion_free", 2.1, elements=2, start=(0.5, 0.5, 0.5))).prepare()


def test_truss_chain_between_supports_without_a_solid():
    beams = [{"curve": {"polyline": [[0, 0, 0], [0.5, 0, 0], [1, 0, 0]]}, "model": "truss", "section": {"EA": 1.0}}]
    ends = [{"on": "beam:0:start"}, {"on": "beam:0:end"}]
    with pytest.raises(SceneError, match=r"^beams\[0\]: zero-energy mode .*node 1 moves.*nothing but the beam "
                                         r"itself holds.*support them sideways"):
        Model(m13.Scene(beams=beams, dirichlet=ends)).prepare()
    # holding the middle node sideways removes it
    Model(m13.Scene(beams=beams, dirichlet=ends + [{"on": "beam:0", "components": ["y", "z"]}])).prepare()


def test_chains_of_one_entry_are_named_and_numbering_does_not_matter():
    """Three fibres in one BeamMesh entry, the last one a truss half outside; then its nodes shuffled."""
    parts = []
    for k, end in enumerate((0.8, 0.85, 1.6)):
        x = np.linspace(0.2, end, 5)
        parts.append(BeamMesh.lagrange(np.column_stack([x, 0.3 + 0.2 * k + 0 * x, 0.5 + 0 * x]),
                                       np.column_stack([np.arange(4), np.arange(1, 5)])))
    beams = BeamMesh.join(parts)
    scene = m13.Scene(solid=SOLID, beams=[{"mesh": beams, "model": "truss", "section": {"EA": 1e6}}],
                      dirichlet=[{"on": "solid:x_min"}])
    with pytest.raises(SceneError, match=r"^beams\[0\] \(chain 2 of its 3 unconnected chains, nodes 10\.\.14\): "
                                         r"zero-energy mode .*node 14 moves \(y\)"):
        Model(scene).prepare()
    model = Model(scene)
    with pytest.raises(SceneError):
        model.prepare()
    g = model.groups[0]
    rows = g.operators.D.tocsr()[g.coupling.coupled_rows]
    natural = find_mechanisms(beams, rows)
    # the same beams with scrambled node numbers (a wide band: reordered before the factorisation)
    perm = np.random.default_rng(1).permutation(beams.n_nodes)
    inverse = np.argsort(perm)
    shuffled = BeamMesh.lagrange(beams.positions[perm], inverse[beams.elements])
    dof_perm = (3 * perm[:, None] + np.arange(3)).ravel()
    found = find_mechanisms(shuffled, rows[:, dof_perm])
    assert len(natural) == len(found) == 1
    # x = 0.2 ... 1.6 in four elements: node 13 (x = 1.25) ends the element that enters the solid
    assert natural[0].moving.tolist() == [14]
    assert perm[found[0].moving].tolist() == [14]
    assert found[0].sigma < 1e-14 and natural[0].sigma < 1e-14


@pytest.mark.parametrize("kind", ["torsion_free", "truss"])
def test_element_stiffness_vanishes_exactly_on_rigid_motions(kind):
    """The probe's premise: at the reference state an element's stiffness is zero on its rigid
    motions and on nothing else (straight Hermite elements, truss bars)."""
    rng = np.random.default_rng(4)
    d = rng.standard_normal(3)
    d /= np.linalg.norm(d)
    x = np.array([0.1, -0.3, 0.2]) + np.outer([0.0, 0.3, 0.8, 1.0], d)
    elements = np.column_stack([np.arange(3), np.arange(1, 4)])
    if kind == "torsion_free":
        beams = BeamMesh.hermite(x, np.tile(d, (4, 1)), elements)
        model = BeamModel(beams, 1.0, 0.05)
    else:
        beams = BeamMesh.lagrange(x, elements)
        model = BeamModel(beams, 1.0, None, model="truss")
    _, _, ke = model._run(np.zeros(model.n_dofs), 2)
    dofs, Pi = _element_projectors(beams, _node_scale(beams))
    node_scale = _node_scale(beams)
    for e in range(beams.n_elements):
        # Π is the projector in dimensionless DOFs w = S v; the element stiffness in those DOFs is S⁻¹ K S⁻¹
        cols = beams.function_columns()[e]
        cols = cols[cols >= 0]
        node = cols // 2 if kind == "torsion_free" else cols
        tangent = (cols % 2 == 1) if kind == "torsion_free" else np.zeros(len(cols), bool)
        s_inv = np.repeat(np.where(tangent, 1.0, node_scale[node]), 3)
        K = s_inv[:, None] * ke[e] * s_inv[None, :]
        P = Pi[e]
        assert np.abs(K - P @ K @ P).max() < 1e-12 * np.abs(K).max()        # zero on the rigid motions
        eig = np.linalg.eigvalsh(K)
        assert np.count_nonzero(eig > 1e-10 * eig.max()) == round(np.trace(P))   # and positive elsewhere
