"""Property-based fuzzing of the mortar engine (hypothesis; issue 6, extended by issue 16).

Random valid solid meshes of every element type (structured boxes distorted by
``generate.distort``, and unstructured Delaunay tets of random points) and random beams
(straight, random cubic Hermite, helices; any of them may leave the solid) must satisfy the
properties of the catalogue (tests/hard_cases.py): no exception, warning, NaN or Inf; the segments
tile the independently sampled embedded set exactly once, owners by the lowest-index rule; the
certificates; invariance under renumbering; continuity under a 1e-12 h shift. Clamped scenes
(solid, rebar, supports, loads) under random rigid motions give the rotated results.

Issue 16 adds three classes: curved quadratic elements up to the limit of their validity (every
point inside is located inside, whole beams are coupled exactly where they are inside), and beams
cutting an edge or a corner of an element at every depth, from 1e-14 to 1e-1 of the element size,
inside and just outside.

Profiles (registered in tests/conftest.py, chosen by ``MORTAR1D3D_HYPOTHESIS``): ``bounded``
(default, ``make test``: few examples, ``derandomize=True``: the same examples on every run) and
``fuzz`` (``make fuzz``: many random examples). Every failure found becomes a named case in
test_hard_cases.py.
"""
import warnings

import numpy as np
from hypothesis import given
from hypothesis import strategies as st
from scipy.spatial import Delaunay
from scipy.spatial.transform import Rotation

import mortar1d3d as m13
from mortar1d3d import BeamMesh, SolidMesh, generate
from mortar1d3d.errors import MeshError

import hard_cases as hc
from clamped_scenes import clamped_scene, rotation_error

ELEMENTS = list(m13.elements.SOLID_ELEMENTS)
SIZE = 2.0        # the solid is the box [0, SIZE]^3 in every scene


@st.composite
def structured_solids(draw):
    element = draw(st.sampled_from(ELEMENTS))
    cells = tuple(draw(st.integers(1, 2)) for _ in range(3))
    amplitude = draw(st.sampled_from([0.0, 0.1, 0.2]))
    seed = draw(st.integers(0, 2 ** 16))
    solid = generate.box((0, 0, 0), (SIZE,) * 3, cells, element)
    return generate.distort(solid, amplitude, seed=seed) if amplitude and max(cells) > 1 else solid


@st.composite
def delaunay_tets(draw):
    """Delaunay tets of the box corners and random interior points (no slivers below 1e-3 h³)."""
    seed = draw(st.integers(0, 2 ** 16))
    n = draw(st.integers(1, 12))
    rng = np.random.default_rng(seed)
    corners = np.array([[i, j, k] for i in (0, 1) for j in (0, 1) for k in (0, 1)], float) * SIZE
    points = np.vstack([corners, rng.uniform(0.1, SIZE - 0.1, (n, 3))])
    tets = Delaunay(points).simplices.copy()
    X = points[tets]
    det = np.linalg.det(np.stack([X[:, 1] - X[:, 0], X[:, 2] - X[:, 0], X[:, 3] - X[:, 0]], axis=1))
    tets[det < 0] = tets[det < 0][:, [0, 1, 3, 2]]
    h = np.ptp(X, axis=1).max(axis=1)
    if (np.abs(det) < 1e-3 * h ** 3).any():
        tets = tets[np.abs(det) >= 1e-3 * h ** 3]
    try:
        return SolidMesh(points, {"tetra": tets})
    except MeshError:
        return SolidMesh(corners, {"tetra": hc._orient(corners, [[0, 1, 3, 7], [0, 1, 5, 7], [0, 2, 3, 7],
                                                                  [0, 2, 6, 7], [0, 4, 5, 7], [0, 4, 6, 7]])})


coordinate = st.floats(-0.4, SIZE + 0.4, allow_nan=False)
point = st.tuples(coordinate, coordinate, coordinate).map(np.array)
direction = st.tuples(*[st.floats(-1, 1, allow_nan=False)] * 3).filter(lambda v: np.linalg.norm(v) > 0.1).map(hc.unit)


@st.composite
def beams(draw):
    kind = draw(st.sampled_from(["straight", "hermite", "helix"]))
    if kind == "straight":
        a, b = draw(point), draw(point)
        if np.linalg.norm(b - a) < 0.05:
            b = a + 0.5
        return hc.straight(a, b, draw(st.integers(1, 3)))
    if kind == "hermite":
        a, b = draw(point), draw(point)
        if np.linalg.norm(b - a) < 0.05:
            b = a + 0.5
        return BeamMesh.hermite([a, b], [draw(direction), draw(direction)], [[0, 1]])
    centre, axis = draw(point), draw(direction)
    radius = draw(st.floats(0.1, 0.8))
    turns = draw(st.floats(0.3, 2.0))
    pitch = draw(st.floats(0.0, 0.6))
    e1 = hc.unit(np.cross(axis, [1.0, 0, 0] if abs(axis[0]) < 0.9 else [0, 1.0, 0]))
    e2 = np.cross(axis, e1)
    w = 2 * np.pi * turns

    def f(t):
        return centre + radius * (np.cos(w * t) * e1 + np.sin(w * t) * e2) + pitch * (t - 0.5) * axis

    def df(t):
        return radius * w * (-np.sin(w * t) * e1 + np.cos(w * t) * e2) + pitch * axis

    return BeamMesh.from_curve(f, df, 0.0, 1.0, draw(st.integers(max(2, int(4 * turns)), 8)))


def check_scene(beams, solid):
    # random curves meet the outer boundary at any angle: a cut at angle θ is only determined to
    # tol / sin θ (found by make fuzz: beams from a corner along an outer face at θ = 6e-8)
    case = hc.Case("fuzz", beams, solid, conditioning=4 * hc.estimated_conditioning(beams, solid))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        hc.check_all(case)


@given(solid=structured_solids(), beams=beams())
def test_fuzz_structured(solid, beams):
    check_scene(beams, solid)


@given(solid=delaunay_tets(), beams=beams())
def test_fuzz_delaunay_tets(solid, beams):
    check_scene(beams, solid)


# --------------------------------------------------------------------------------------------
# clamped scenes under rigid motions (issue 16): a clamp fixes the tangent's direction in any
# orientation, so a rigidly moved scene gives the rigidly rotated results
# --------------------------------------------------------------------------------------------
_UNMOVED = {}


def _unmoved(kinematics):
    if kinematics not in _UNMOVED:
        _UNMOVED[kinematics] = m13.solve(clamped_scene(kinematics=kinematics))
    return _UNMOVED[kinematics]


rotations = st.tuples(*[st.floats(-1, 1, allow_nan=False)] * 4).filter(lambda q: np.linalg.norm(q) > 0.1).map(
    lambda q: Rotation.from_quat(q).as_matrix())
translations = st.tuples(*[st.floats(-10, 10, allow_nan=False)] * 3).map(np.array)


@given(Q=rotations, shift=translations, kinematics=st.sampled_from(["linear", "nonlinear"]))
def test_fuzz_clamped_scene_under_rigid_motion(Q, shift, kinematics):
    moved = m13.solve(clamped_scene(Q, shift, kinematics=kinematics))
    # round-off of the moved coordinates grows with the translation (up to 10 sizes here): the
    # deviations measured stay below 1e-10 (tests/test_supports.py); a clamp that fixed the stretch
    # in some orientations gave 1e-3..1e-2
    errors = rotation_error(_unmoved(kinematics), moved, Q)
    assert max(errors.values()) <= 1e-8, errors


def test_profiles_are_registered():
    from hypothesis import settings
    assert settings.get_profile("bounded").derandomize
    assert settings.get_profile("fuzz").max_examples > settings.get_profile("bounded").max_examples


# --------------------------------------------------------------------------------------------
# issue 16: curved quadratic elements up to their validity limit
# --------------------------------------------------------------------------------------------
CURVED = ["hexahedron20", "hexahedron27", "tetra10"]


def _perturbed(name, direction, fraction):
    """Nodes of one element of type ``name`` on the unit cube / corner tet, its mid-side nodes moved by
    ``fraction`` of the largest multiple of ``direction`` that keeps det J > 0 throughout."""
    from mortar1d3d.elements.solid.dispatch import SOLID_ELEMENTS
    from mortar1d3d.elements.validity import VALID, jacobian_validity
    d = SOLID_ELEMENTS[name]
    base = d.reference_nodes * 0.5 + 0.5 if d.family == "hex" else d.reference_nodes.astype(float)
    first = 8 if d.family == "hex" else 4

    def nodes(t):
        X = base.copy()
        X[first:] += t * direction[: d.n_nodes - first]
        return X

    lo, hi = 0.0, 1.0
    while jacobian_validity(d, nodes(hi)[None], np.array([1.7]))[0] == VALID and hi < 64:
        lo, hi = hi, 2 * hi
    for _ in range(30):                 # bisection to the validity limit
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if jacobian_validity(d, nodes(mid)[None], np.array([1.7]))[0] == VALID else (lo, mid)
    return nodes(fraction * lo)


@st.composite
def curved_elements(draw):
    name = draw(st.sampled_from(CURVED))
    seed = draw(st.integers(0, 2 ** 16))
    fraction = draw(st.sampled_from([0.3, 0.7, 0.9, 0.98]))
    direction = np.random.default_rng(seed).uniform(-1, 1, (19, 3)) * 0.1
    X = _perturbed(name, direction, fraction)
    return name, X


@given(element=curved_elements(), seed=st.integers(0, 2 ** 16))
def test_fuzz_points_inside_curved_elements_are_found_inside(element, seed):
    from mortar1d3d.elements.solid.dispatch import SOLID_ELEMENTS, SOLID_MODULES
    from mortar1d3d.geometry.projection import INSIDE
    name, X = element
    d = SOLID_ELEMENTS[name]
    solid = SolidMesh(X, {name: np.arange(len(X))[None]})
    rng = np.random.default_rng(seed)
    if d.family == "hex":
        xi = rng.uniform(-1, 1, (300, 3))
        xi = np.sign(xi) * (1 - np.abs(xi) ** 4)                     # many near faces, edges, corners
    else:
        xi = rng.dirichlet(np.full(4, 0.3), 300)[:, 1:]
    N = np.empty(d.n_nodes)
    points = np.empty((len(xi), 3))
    for i, x in enumerate(xi):
        SOLID_MODULES[name].shape.py_func(np.ascontiguousarray(x), N)
        points[i] = N @ X
    found, status = m13_project(solid, points)
    assert np.all(status == INSIDE), xi[status != INSIDE][:3]
    np.testing.assert_allclose(found, xi, rtol=0, atol=1e-10)


def m13_project(solid, points):
    from mortar1d3d import project_points
    return project_points(solid, points, 0)


@given(element=curved_elements(), beams=beams())
def test_fuzz_beams_in_curved_elements(element, beams):
    """Whole beams (anywhere, partly outside) in a curved element near its validity limit: the segments tile
    the independently located embedded set and Σκ is its arc length (hard_cases.check_all)."""
    name, X = element
    solid = SolidMesh(2.0 * X, {name: np.arange(len(X))[None]})      # the box [0, 2]³ like the beams
    check_scene(beams, solid)


# --------------------------------------------------------------------------------------------
# issue 16: corner and edge cuts at every depth
# --------------------------------------------------------------------------------------------
@st.composite
def corner_cuts(draw):
    """A 2x2x2 mesh of [0, 2]³ and a straight beam passing a node (corner) or an edge of its elements at a
    signed distance 10^-k (k in 1..14; negative: outside the element whose corner it cuts, i.e. it cuts the
    neighbours' corners) in a random direction."""
    element = draw(st.sampled_from(ELEMENTS))
    solid = generate.box((0, 0, 0), (SIZE,) * 3, (2, 2, 2), element)
    rng = np.random.default_rng(draw(st.integers(0, 2 ** 16)))
    kind = draw(st.sampled_from(["corner", "edge"]))
    node = rng.integers(0, 3, 3).astype(float)                  # a lattice node of the 2x2x2 mesh
    depth = draw(st.sampled_from([-1.0, 1.0])) * 10.0 ** -draw(st.integers(1, 14))
    if kind == "corner":
        # the beam passes the node at distance |depth| along the diagonal of a random octant
        octant = rng.choice([-1.0, 1.0], 3)
        normal = octant / np.sqrt(3.0)
        direction = hc.unit(np.cross(normal, rng.normal(size=3)))
        point = node + depth * normal
    else:
        axis = rng.integers(0, 3)
        along = np.eye(3)[axis]
        others = [i for i in range(3) if i != axis]
        quadrant = rng.choice([-1.0, 1.0], 2)
        normal = (quadrant[0] * np.eye(3)[others[0]] + quadrant[1] * np.eye(3)[others[1]]) / np.sqrt(2.0)
        tangent = hc.unit(np.cross(along, normal))
        direction = hc.unit(tangent + rng.uniform(-0.5, 0.5) * along)
        point = node + rng.uniform(0.1, 0.9) * along + depth * normal
    half = rng.uniform(0.2, 0.8)
    beams = hc.straight(point - half * direction, point + half * direction, draw(st.integers(1, 2)))
    return beams, solid


@given(scene=corner_cuts())
def test_fuzz_corner_and_edge_cuts_at_every_depth(scene):
    beams, solid = scene
    check_scene(beams, solid)
