"""Several NURBS patches in one scene (``solid.mesh = { patches = [...] }``, issue 19): joined where
their control points coincide, so a closed pipe built from three 120° patches is the one-patch closed
pipe renumbered; patches of a degree above 3 or meeting non-conformingly are errors naming the key."""
import numpy as np
import pytest
import scipy.sparse as sp

import mortar1d3d as m13
from mortar1d3d.generate import helical_fibres
from mortar1d3d.nurbs.scene import patches_mesh, validate_patches
from mortar1d3d.scene import SceneError

RI, RO, L = 0.1, 0.2, 0.1


def pipe(**extra):
    return {"pipe": dict({"r_inner": RI, "r_outer": RO, "length": L}, **extra)}


ONE = [pipe(elements=[1, 3, 2])]
THREE = [pipe(elements=[1, 1, 2], angle=120.0, start=120.0 * k) for k in range(3)]


def permutation(a, b):
    """``p`` with ``b[p] == a`` to 1e-14 (a node of mesh a is node p of mesh b)."""
    d = np.linalg.norm(a[:, None, :] - b[None, :, :], axis=2)
    p = d.argmin(axis=1)
    assert d.min(axis=1).max() < 1e-14 and len(np.unique(p)) == len(p)
    return p


def scene(patches, fibres):
    return m13.Scene(
        solid={"mesh": {"patches": patches}, "material": {"model": "saint_venant_kirchhoff", "E": 1000.0, "nu": 0.3}},
        beams=[{"mesh": f, "model": "simo_reissner", "section": {"E": 1e5, "nu": 0.3, "radius": 0.004}}
               for f in fibres],
        dirichlet=[{"on": "solid:start", "components": ["x", "y", "z"]},
                   {"on": "beam:0:start", "rotation": [0.0, 0.0, 0.0]}],
        load=[{"type": "pressure", "on": "solid:inner", "value": 5.0},
              {"type": "point", "on": "beam:0:end", "value": [0.0, 0.5, 0.2]}],
        analysis={"kinematics": "nonlinear", "steps": 2})


def test_three_120_degree_patches_are_the_closed_pipe_renumbered():
    one, _ = patches_mesh(validate_patches(ONE))
    three, bezier = patches_mesh(validate_patches(THREE))
    assert (one.n_nodes, one.n_elements) == (three.n_nodes, three.n_elements) == (3 * 6 * 5, 6)
    assert bezier.nurbs.n_control == 3 * 6 * 4                   # the three seams joined (C¹ along z: 4 control planes)
    p = permutation(one.points, three.points)
    assert np.array_equal(one.weights, three.weights[p])
    # the named sets are the same nodes; the seams are inside, so no cut sets
    for name in ("inner", "outer", "start", "end"):
        assert np.array_equal(np.sort(p[one.point_sets[name]]), three.point_sets[name])
    assert not any(n.startswith("cut") for n in three.point_sets)
    assert len(three.point_sets["inner_1"]) == 3 * 5           # one patch's inner face
    fibre = helical_fibres(0.15, L, 55.0, count=1, elements=6)
    a = m13.assemble_mortar(fibre, one, lm="line3")
    b = m13.assemble_mortar(fibre, three, lm="line3")
    cols = (3 * p[:, None] + np.arange(3)).ravel()
    assert abs(a.D - b.D).max() < 1e-14 * abs(a.D).max()
    assert abs(a.M - b.M[:, cols]).max() < 1e-14 * abs(a.M).max()
    assert np.abs(a.kappa - b.kappa).max() < 1e-14 * a.kappa.max()


def test_three_patch_pipe_solves_as_the_one_patch_pipe():
    fibres = [helical_fibres(0.15, L, 55.0, count=1, elements=4)]
    a = m13.solve(scene(ONE, fibres))
    b = m13.solve(scene(THREE, fibres))
    p = permutation(a.model.solid_mesh.points, b.model.solid_mesh.points)
    scale = np.abs(a.solid_displacement).max()
    assert scale > 1e-3
    assert np.abs(a.solid_displacement - b.solid_displacement[p]).max() < 1e-11 * scale
    assert np.abs(a.beam_displacement - b.beam_displacement).max() < 1e-11 * np.abs(a.beam_displacement).max()


@pytest.mark.parametrize("patches, key, match", [
    ([pipe(elements=[1, 1, 1], angle=120.0), pipe(elements=[1, 1, 1], angle=120.0, start=120.0, degree=[2, 5, 2])],
     r"solid.mesh.patches\[1\].pipe.degree\[1\]", "above what the element registry has; supported are degrees 2 to 4"),
    # the same interface, cut into two elements along z on one side and one on the other
    ([pipe(elements=[1, 1, 1], angle=120.0), pipe(elements=[1, 1, 2], angle=120.0, start=120.0)],
     r"solid.mesh.patches\[\d\]", "meets patches"),
    ([{"brick": {"lower": [0, 0, 0], "upper": [1, 1, 1], "elements": [1, 1, 1]}},
      {"brick": {"lower": [1, 0, 0], "upper": [2, 1, 1], "elements": [1, 2, 1]}}],
     r"solid.mesh.patches\[\d\]", "non-conforming"),
    ([{"pipe": {"r_inner": RI}}], r"solid.mesh.patches\[0\].pipe", "missing"),
    ([{"cube": {}}], r"solid.mesh.patches\[0\]", r"expected \{ pipe"),
    ([], r"solid.mesh.patches", "at least one patch"),
])
def test_patch_errors_name_the_key(patches, key, match):
    with pytest.raises(SceneError, match=key + ".*" + match):
        s = m13.Scene(solid={"mesh": {"patches": patches}, "material": {"model": "linear_elastic", "E": 1.0, "nu": 0.3}},
                      dirichlet=[{"on": "solid:start" if "pipe" in patches[0] else "solid:x_min",
                                  "components": ["x", "y", "z"]}] if patches else [])
        m13.plan(s)


def test_bricks_side_by_side_join_and_keep_their_sets():
    patches = [{"brick": {"lower": [0, 0, 0], "upper": [1, 1, 1], "elements": [1, 1, 1]}},
               {"brick": {"lower": [1, 0, 0], "upper": [2, 1, 1], "elements": [1, 1, 1]}}]
    mesh, _ = patches_mesh(validate_patches(patches))
    assert mesh.n_nodes == 5 * 3 * 3                           # the shared face's 9 nodes once
    assert len(mesh.point_sets["x_min"]) == 9 and "x_max_0" not in mesh.point_sets   # joined: inside
    assert len(mesh.point_sets["y_min"]) == 15 and len(mesh.point_sets["y_min_1"]) == 9
