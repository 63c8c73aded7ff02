"""Scenes on a NURBS pipe (``solid.mesh = { pipe = {...} }``, issue 19 item 4): closed-end Lamé,
named face sets, fibres coupled by the mortar method, VTU output, and the errors for what rational
elements do not support."""
import numpy as np
import pytest

import mortar1d3d as m13
from mortar1d3d.generate import helical_fibres
from mortar1d3d.nurbs.mesh import element_values

RI, RO, L, E, NU, P = 0.1, 0.2, 0.1, 1000.0, 0.3, 1.0
SIGMA_Z = P * RI * RI / (RO * RO - RI * RI)          # closed ends: the axial stress of the cap force


def pipe_scene(elements=(2, 8, 1), beams=(), kinematics="linear", **pipe):
    """Closed pipe, inner pressure P, the cap force on the end as an axial traction; the start end held
    axially, rigid motions in x, y and about z removed by the nodes on the x and y axes there."""
    spec = dict({"r_inner": RI, "r_outer": RO, "length": L, "elements": list(elements)}, **pipe)
    return m13.Scene(
        solid={"mesh": {"pipe": spec}, "material": {"model": "linear_elastic", "E": E, "nu": NU}},
        beams=list(beams),
        dirichlet=[{"on": "solid:start", "components": ["z"]},
                   {"on": {"inside": [[RI, 0, 0], [RO, 0, 0]]}, "components": ["y"]},
                   {"on": {"inside": [[0, RI, 0], [0, RO, 0]]}, "components": ["x"]}],
        load=[{"type": "pressure", "on": "solid:inner", "value": P},
              {"type": "traction", "on": "solid:end", "value": [0, 0, SIGMA_Z]}],
        analysis={"kinematics": kinematics})


def sampled(result, points=5):
    mesh = result.model.solid_mesh
    s = np.linspace(-1, 1, points)
    xi = np.stack(np.meshgrid(s, s, s, indexing="ij"), -1).reshape(-1, 3)
    X = element_values(mesh, xi, mesh.points).reshape(-1, 3)
    U = element_values(mesh, xi, result.solid_displacement).reshape(-1, 3)
    return X, U


def lame_closed(r):
    """u_r of the closed-end thick pipe (σ_z = SIGMA_Z = c): u_r = r/E (c (1 - 2ν) + (1 + ν) d / r²)."""
    d = P * RI * RI * RO * RO / (RO * RO - RI * RI)
    return r / E * (SIGMA_Z * (1 - 2 * NU) + (1 + NU) * d / r ** 2)


def test_closed_pipe_scene_against_lame():
    result = m13.solve(pipe_scene())
    X, U = sampled(result)
    r = np.hypot(X[:, 0], X[:, 1])
    ur = (U[:, 0] * X[:, 0] + U[:, 1] * X[:, 1]) / r
    error = np.abs(ur - lame_closed(r)).max() / lame_closed(RI)
    assert error < 5e-3, error                        # measured 3.1e-3 (2 × 8 × 1 spans of 45°)
    # uniform axial strain c (1 - 2ν) / E: its mean to 1 % (measured 0.6 %), the displacement error
    # of the end face on the scale of the radial one
    uz = U[np.abs(X[:, 2] - L) < 1e-12, 2]
    exact = SIGMA_Z * (1 - 2 * NU) / E * L
    assert abs(uz.mean() / exact - 1) < 1e-2
    assert np.abs(uz - exact).max() < 5e-3 * lame_closed(RI)
    twist = (U[:, 1] * X[:, 0] - U[:, 0] * X[:, 1]) / r
    assert np.abs(twist).max() < 2e-4 * lame_closed(RI)          # measured 8e-5 (quadrature of rational spans)
    # the axial support carries the cap force (to the quadrature of the rational end face: 4e-9 measured)
    cap = SIGMA_Z * np.pi * (RO * RO - RI * RI)
    assert abs(result.reactions[0][2] + cap) < 1e-7 * cap


def test_named_sets_of_a_pipe_section():
    spec = {"r_inner": RI, "r_outer": RO, "length": L, "elements": [1, 2, 2], "angle": 90.0, "start": 30.0}
    model = m13.Model(m13.Scene(solid={"mesh": {"pipe": spec}, "material": {"model": "linear_elastic", "E": E,
                                                                              "nu": NU}}))
    sets = model.solid_mesh.point_sets
    assert sorted(sets) == ["cut_end", "cut_start", "end", "inner", "outer", "start"]
    X = model.solid_mesh.points
    angle = np.degrees(np.arctan2(X[:, 1], X[:, 0]))
    assert np.abs(angle[sets["cut_start"]] - 30.0).max() < 1e-12
    assert np.abs(angle[sets["cut_end"]] - 120.0).max() < 1e-12
    assert np.abs(X[sets["end"], 2] - L).max() < 1e-15 and len(sets["end"]) == 3 * 5
    assert len(sets["inner"]) == 5 * 5                # 2 × 2 spans: 5 × 5 Bézier nodes on the face
    closed = m13.Model(pipe_scene()).solid_mesh.point_sets
    assert "cut_start" not in closed and "cut_end" not in closed


@pytest.mark.parametrize("spec, match", [
    ({"r_outer": 0.05}, r"solid\.mesh\.pipe\.r_outer: must be greater than r_inner"),
    ({"elements": [1, 2, 1]}, r"solid\.mesh\.pipe\.elements\[1\]: 2 element\(s\) cannot cover 360"),
    ({"angle": 400.0}, r"solid\.mesh\.pipe\.angle"),
    ({"degree": 5}, r"solid\.mesh\.pipe\.degree: degree 5 is above what the element registry has; supported are "
                    r"degrees 1 to 4 per direction, elevated exactly to nurbs27 \(degree 2\), nurbs64 \(degree 3\), "
                    r"nurbs125 \(degree 4\)"),
    ({"degree": [2, 1, 2]}, r"solid\.mesh\.pipe\.degree\[1\]: degree 1 in direction 1: must be at least 2"),
    ({"order": 3}, r"solid\.mesh\.pipe\.order: unknown key"),
])
def test_pipe_key_errors(spec, match):
    base = {"r_inner": RI, "r_outer": RO, "length": L, "elements": [1, 4, 1]}
    with pytest.raises(m13.SceneError, match=match):
        m13.Scene(solid={"mesh": {"pipe": dict(base, **spec)}, "material": {"model": "linear_elastic", "E": E,
                                                                             "nu": NU}})


def test_couplings_that_do_not_take_rational_elements_are_scene_errors():
    fibre = {"curve": {"line": [[0.15, 0.0, 0.02], [0.15, 0.0, 0.08]]}, "elements": 2, "model": "torsion_free",
             "section": {"EA": 1.0, "EI": 1.0}}
    s = pipe_scene(beams=[fibre])
    s.coupling["constraint"] = "gauss_point"
    with pytest.raises(m13.SceneError, match=r"coupling\.constraint: 'gauss_point' is not implemented for "
                                             r"rational elements \['nurbs27'\]"):
        m13.plan(s)


def test_helical_fibres_coupled_to_the_pipe_and_written(tmp_path):
    """Two fibres at ±55° in the wall (simo_reissner, Hermite): their whole length is coupled, they
    stiffen the pipe (smaller radial expansion), and the result writes NURBS spans and fibres."""
    import meshio

    fibres = []
    for angle in (55.0, -55.0):
        mesh = helical_fibres(0.15, L, angle, count=1, elements=6)
        fibres.append({"mesh": mesh, "model": "simo_reissner",
                       "section": {"E": 100 * E, "nu": 0.3, "radius": 0.004}})
    plain = m13.solve(pipe_scene())
    result = m13.solve(pipe_scene(beams=fibres))
    beam_length = 2 * L / np.cos(np.radians(55.0))
    assert abs(sum(result.coupled_length) - beam_length) < 1e-3 * beam_length
    X, U = sampled(result)
    X0, U0 = sampled(plain)
    inner = np.abs(np.hypot(X[:, 0], X[:, 1]) - RI) < 1e-12
    ur = lambda X, U: ((U[:, 0] * X[:, 0] + U[:, 1] * X[:, 1]) / np.hypot(X[:, 0], X[:, 1]))[inner].mean()  # noqa
    assert ur(X, U) < 0.99 * ur(X0, U0)
    files = result.write(tmp_path)
    solid = meshio.read(next(f for f in files if "solid_0001" in str(f)))
    assert solid.cells_dict["hexahedron27"].shape == (16, 27)
    r = np.hypot(solid.points[:, 0], solid.points[:, 1])
    assert r.min() > RI - 1e-12 and r.max() < RO + 1e-12      # exact points, no control points
    assert any("beams" in str(f) for f in files)


@pytest.mark.parametrize("degree, p", [(2, 2), (3, 3), (1, 2), ([1, 3, 2], 3)])
def test_brick_in_uniaxial_tension_is_exact(degree, p):
    """``solid.mesh = { brick = ... }``: a NURBS block (weights 1) held on three faces by symmetry, a
    traction on x_max. The linear field u = σ/E (x, -ν y, -ν z) lies in the space, so the node
    displacements (Bézier control points of a linear field: the field at the nodes) are exact."""
    sigma = 2.0
    spec = {"lower": [0.0, 0.0, 0.0], "upper": [1.0, 0.5, 0.4], "elements": [2, 1, 2], "degree": degree}
    scene = m13.Scene(
        solid={"mesh": {"brick": spec}, "material": {"model": "linear_elastic", "E": E, "nu": NU}},
        dirichlet=[{"on": f"solid:{axis}_min", "components": [axis]} for axis in "xyz"],
        load=[{"type": "traction", "on": "solid:x_max", "value": [sigma, 0.0, 0.0]}],
        analysis={"kinematics": "linear"})
    result = m13.solve(scene)
    mesh = result.model.solid_mesh
    assert mesh.blocks[0][0].name == {2: "nurbs27", 3: "nurbs64"}[p] and mesh.n_elements == 4     # elevated to p
    X = mesh.points
    exact = sigma / E * X * [1.0, -NU, -NU]
    assert np.abs(result.solid_displacement - exact).max() < 1e-12 * sigma / E
    sets = mesh.point_sets
    assert sorted(sets) == ["x_max", "x_min", "y_max", "y_min", "z_max", "z_min"]
    assert len(sets["x_min"]) == (p + 1) * (2 * p + 1) and np.abs(X[sets["x_min"], 0]).max() == 0.0
    assert np.abs(X[sets["z_max"], 2] - 0.4).max() < 1e-15


@pytest.mark.parametrize("spec, match", [
    ({"upper": [1.0, 0.0, 1.0]}, r"solid\.mesh\.brick\.upper: must be greater than lower"),
    ({"degree": 0}, r"solid\.mesh\.brick\.degree: degree 0 in direction 0: must be at least 1"),
    ({"degree": [1, 2, 5]}, r"solid\.mesh\.brick\.degree\[2\]: degree 5 is above what the element registry has"),
    ({"degree": [1, 2]}, r"solid\.mesh\.brick\.degree"),
    ({"elements": [1, 0, 1]}, r"solid\.mesh\.brick\.elements\[1\]"),
    ({"cells": [1, 1, 1]}, r"solid\.mesh\.brick\.cells: unknown key"),
])
def test_brick_key_errors(spec, match):
    base = {"lower": [0.0, 0.0, 0.0], "upper": [1.0, 1.0, 1.0], "elements": [1, 1, 1]}
    with pytest.raises(m13.SceneError, match=match):
        m13.Scene(solid={"mesh": {"brick": dict(base, **spec)}, "material": {"model": "linear_elastic", "E": E,
                                                                              "nu": NU}})
