"""Generators: the §5 fibre cube rebuilt independently, structured boxes, distortion, random beams.

Reference values are computed from the specification (docs/conventions.md §5), not with the library's
helpers: splitmix64 with Python integers (tests/naive.py), fibre axes and helix frames from
scratch, volumes from the element modules' derivatives and Gauss rules.
"""
import math

import numpy as np
import pytest

from mortar1d3d import generate
from mortar1d3d.elements.solid.dispatch import SOLID_MODULES

from naive import domain_rule, reference_splitmix64

MODULES = SOLID_MODULES
TYPES = [n for n in MODULES if not MODULES[n].DESCRIPTOR.rational]     # nurbs27: from mortar1d3d.nurbs
L, R = 0.3, 0.03


# -- independent reference of docs/conventions.md §5 -----------------------------------------------------

def reference_fibres(fibres, curved, seed=12345):
    """Per fibre: centre c, axis d, frame e1, e2 and phase, one fibre at a time (plain Python)."""
    u = [x / 2.0 ** 53 for x in (z >> 11 for z in reference_splitmix64(seed, 6 * fibres))]
    out = []
    for f in range(fibres):
        u0, u1, u2, u3, u4, u5 = u[6 * f: 6 * f + 6]
        a = L / 2 + 0.02 + (R if curved else 0.0)
        c = np.array([a + (1 - 2 * a) * uk for uk in (u0, u1, u2)])
        z = 2 * u3 - 1
        phi = 2 * math.pi * u4
        d = np.array([math.sqrt(1 - z * z) * math.cos(phi), math.sqrt(1 - z * z) * math.sin(phi), z])
        helper = np.array([1.0, 0, 0]) if abs(d[0]) < 0.9 else np.array([0, 1.0, 0])
        e1 = np.cross(d, helper)
        e1 /= np.linalg.norm(e1)
        out.append((c, d, e1, np.cross(d, e1), 2 * math.pi * u5))
    return out


# -- splitmix64 ----------------------------------------------------------------------------------

def test_reference_splitmix64_matches_published_values():
    # Vigna's splitmix64.c from state 0 (guards the test's own reference implementation)
    assert reference_splitmix64(0, 3) == [0xE220A8397B1DCDAF, 0x6E789E6AA1B965F4, 0x06C45D188009454F]


@pytest.mark.parametrize("seed", [12345, 0, 1, 2 ** 64 - 1, 2 ** 63 + 17])
def test_splitmix64_bit_exact(seed):
    got = generate.splitmix64(seed, 50)
    assert got.dtype == np.uint64
    assert [int(z) for z in got] == reference_splitmix64(seed, 50)


def test_splitmix64_seed_12345_first_outputs_and_uniforms():
    ref = reference_splitmix64(12345, 6)
    assert [int(z) for z in generate.splitmix64(12345, 6)] == ref
    u = generate.splitmix64_uniforms(12345, 6)
    assert u.tolist() == [(z >> 11) * 2.0 ** -53 for z in ref]    # exact, not approximately
    assert ((u >= 0) & (u < 1)).all()


# -- fibre cube --------------------------------------------------------------------------------

def test_fibre_cube_straight_matches_specification():
    n, fibres, m = 3, 7, 5
    beams, solid = generate.fibre_cube(n, fibres, m)
    assert beams.element_type.name == "hermite"
    assert (beams.n_nodes, beams.n_elements) == (fibres * (m + 1), fibres * m)
    assert (solid.n_nodes, solid.n_elements) == ((n + 1) ** 3, n ** 3)
    assert list(solid.cells) == ["hexahedron"]
    # fibre f uses nodes f(m+1) .. f(m+1)+m, elements in fibre order
    f, i = np.divmod(np.arange(fibres * m), m)
    np.testing.assert_array_equal(beams.elements, np.column_stack([f * (m + 1) + i, f * (m + 1) + i + 1]))

    X = beams.positions.reshape(fibres, m + 1, 3)
    T = beams.tangents.reshape(fibres, m + 1, 3)
    for k, (c, d, _, _, _) in enumerate(reference_fibres(fibres, curved=False)):
        expected = np.array([c + (j / m - 0.5) * L * d for j in range(m + 1)])
        np.testing.assert_allclose(X[k], expected, rtol=0, atol=1e-15)
        np.testing.assert_allclose(T[k], np.tile(d, (m + 1, 1)), rtol=0, atol=1e-15)
    assert (beams.positions > 0.02 - 1e-15).all() and (beams.positions < 0.98 + 1e-15).all()
    chord = np.linalg.norm(X[:, -1] - X[:, 0], axis=1)
    np.testing.assert_allclose(chord, L, rtol=0, atol=1e-12)
    np.testing.assert_allclose(beams.lengths.reshape(fibres, m).sum(axis=1), L, rtol=0, atol=1e-12)


def test_fibre_cube_curved_is_the_specified_helix():
    fibres, m = 5, 30
    beams, solid = generate.fibre_cube(2, fibres, m, curved=True)
    assert (beams.n_nodes, beams.n_elements, solid.n_elements) == (fibres * (m + 1), fibres * m, 8)
    X = beams.positions.reshape(fibres, m + 1, 3)
    T = beams.tangents.reshape(fibres, m + 1, 3)
    arc = math.sqrt(L ** 2 + (2 * math.pi * R * 2) ** 2)
    for k, (c, d, e1, e2, phase) in enumerate(reference_fibres(fibres, curved=True)):
        s = np.arange(m + 1) / m
        theta = phase + 2 * math.pi * 2 * s
        expected = (c + ((s - 0.5) * L)[:, None] * d
                    + R * (np.cos(theta)[:, None] * e1 + np.sin(theta)[:, None] * e2))
        np.testing.assert_allclose(X[k], expected, rtol=0, atol=1e-15)
        rel = X[k] - c
        axial = rel @ d
        radial = np.linalg.norm(rel - axial[:, None] * d, axis=1)
        np.testing.assert_allclose(radial, R, rtol=0, atol=1e-12)
        np.testing.assert_allclose(axial, (s - 0.5) * L, rtol=0, atol=1e-12)
        # tangent = normalised derivative: its axial part is L / |x'(s)| = L / arc
        np.testing.assert_allclose(T[k] @ d, L / arc, rtol=1e-12)
    assert (beams.positions > 0.02).all() and (beams.positions < 0.98).all()
    lengths = beams.lengths.reshape(fibres, m).sum(axis=1)
    np.testing.assert_allclose(lengths, arc, rtol=1e-4)


def test_fibre_cube_straight_and_curved_share_the_random_stream():
    # u5 is drawn for straight fibres too: fibre 2 of both scenes has the same axis
    straight, _ = generate.fibre_cube(1, 3, 4)
    curved, _ = generate.fibre_cube(1, 3, 4, curved=True)
    d = reference_fibres(3, curved=False)[2][1]
    np.testing.assert_allclose(straight.tangents[10], d, atol=1e-15)
    chord = curved.positions[14] - curved.positions[10]
    np.testing.assert_allclose(chord / np.linalg.norm(chord), d, atol=1e-12)   # two full turns


def test_fibre_cube_hermite_centrelines_stay_inside_even_with_one_element():
    beams, _ = generate.fibre_cube(1, 40, 1, curved=True)
    eta = np.linspace(-1, 1, 21)
    pts = np.vstack([beams.evaluate(e, eta) for e in range(beams.n_elements)])
    assert (pts > 0.0).all() and (pts < 1.0).all()


def test_fibre_cube_benchmark_size_and_determinism():
    beams, solid = generate.fibre_cube(4, 1000, 20)
    assert (beams.n_nodes, beams.n_elements, solid.n_elements) == (21000, 20000, 64)
    np.testing.assert_allclose(beams.length, 300.0, rtol=1e-12)
    again, _ = generate.fibre_cube(4, 1000, 20)
    assert np.array_equal(again.positions, beams.positions)
    other, _ = generate.fibre_cube(4, 1000, 20, seed=1)
    assert not np.array_equal(other.positions, beams.positions)


def test_fibre_cube_rejects_empty_scenes():
    with pytest.raises(ValueError):
        generate.fibre_cube(2, 0, 3)
    with pytest.raises(ValueError):
        generate.fibre_cube(2, 3, 0)


# -- box -----------------------------------------------------------------------------------------

LOWER, UPPER, CELLS = np.array([-1.0, 0.5, 2.0]), np.array([0.5, 1.5, 2.25]), (2, 3, 1)
BOX_VOLUME = 1.5 * 1.0 * 0.25


def jacobian_determinants(solid, rule):
    """det J (elements, points) of the single block of ``solid`` at the points of ``rule``."""
    (name, conn), = solid.cells.items()
    pts, _ = rule
    deriv = MODULES[name].deriv.py_func
    dN = np.empty((len(pts), conn.shape[1], 3))
    for q, xi in enumerate(pts):
        deriv(xi, dN[q])
    J = np.einsum("mak,qai->mqki", solid.points[conn], dN)
    return np.linalg.det(J)


def volume(solid, n_points=2):
    """Σ w det J over the single block of ``solid`` with :func:`naive.domain_rule` (exact for det J
    of total degree 2 n_points - 3)."""
    (name, _), = solid.cells.items()
    rule = domain_rule(MODULES[name].DESCRIPTOR.family, n_points)
    det = jacobian_determinants(solid, rule)
    assert (det > 0).all()                   # positive orientation at every integration point
    return float((det @ rule[1]).sum())


def expected_counts(name, nx, ny, nz):
    corners = (nx + 1) * (ny + 1) * (nz + 1)
    edges = nx * (ny + 1) * (nz + 1) + (nx + 1) * ny * (nz + 1) + (nx + 1) * (ny + 1) * nz
    lattice = (2 * nx + 1) * (2 * ny + 1) * (2 * nz + 1)
    cells = nx * ny * nz
    return {"hexahedron": (corners, cells), "hexahedron20": (corners + edges, cells),
            "hexahedron27": (lattice, cells), "tetra": (corners, 6 * cells),
            # the Kuhn split uses one diagonal per grid face and the body diagonal of every cell:
            # its mid-edge nodes fill the whole half-cell lattice
            "tetra10": (lattice, 6 * cells),
            # two wedges per cell over the halves of its bottom square
            "wedge": (corners, 2 * cells)}[name]


@pytest.mark.parametrize("name", TYPES)
def test_box_volume_counts_and_uniqueness(name):
    solid = generate.box(LOWER, UPPER, CELLS, element=name)
    assert list(solid.cells) == [name]
    assert (solid.n_nodes, solid.n_elements) == expected_counts(name, *CELLS)
    assert abs(volume(solid) - BOX_VOLUME) <= 1e-12            # exact for affine elements
    assert len(np.unique(solid.points, axis=0)) == solid.n_nodes          # no duplicate nodes
    conn = solid.cells[name]
    assert np.array_equal(np.unique(conn), np.arange(solid.n_nodes))      # no orphan nodes
    assert (solid.points >= LOWER).all() and (solid.points <= UPPER).all()


@pytest.mark.parametrize("name", TYPES)
def test_box_higher_order_nodes_sit_where_the_reference_element_puts_them(name):
    solid = generate.box(LOWER, UPPER, CELLS, element=name)
    conn = solid.cells[name]
    ref = MODULES[name].REFERENCE_NODES
    family = MODULES[name].DESCRIPTOR.family_type
    linear = next(m for m in MODULES.values() if m.DESCRIPTOR.family_type is family and m.DESCRIPTOR.degree == 1)
    n_corners = len(linear.REFERENCE_NODES)
    N = np.empty((len(ref), n_corners))
    for a, xi in enumerate(ref):
        linear.shape.py_func(xi, N[a])
    corners = solid.points[conn[:, :n_corners]]
    np.testing.assert_allclose(solid.points[conn], np.einsum("ac,mck->mak", N, corners), rtol=0, atol=1e-15)


@pytest.mark.parametrize("name", TYPES)
def test_box_is_conforming(name):
    # every element face is shared by exactly two elements, or lies on the box boundary
    solid = generate.box(LOWER, UPPER, CELLS, element=name)
    conn = solid.cells[name]
    face_nodes = MODULES[name].DESCRIPTOR.face_nodes
    width = max(len(f) for f in face_nodes)
    # corners of every face in their cyclic order, padded with -1; sorted, they key the face
    ordered = np.vstack([np.pad(conn[:, list(f)], ((0, 0), (0, width - len(f))), constant_values=-1)
                         for f in face_nodes])
    keys = np.sort(np.where(ordered < 0, np.iinfo(np.int64).max, ordered), axis=1)
    _, first, counts = np.unique(keys, axis=0, return_index=True, return_counts=True)
    assert counts.max() == 2
    area = 0.0
    for face in ordered[first[counts == 1]]:
        X = solid.points[face[face >= 0]]                                # (corners, 3)
        assert ((X == LOWER).all(axis=0) | (X == UPPER).all(axis=0)).any()
        # boundary area = box surface (a mismatched split would leave holes or extra faces)
        area += sum(0.5 * np.linalg.norm(np.cross(X[k] - X[0], X[k + 1] - X[0])) for k in range(1, len(X) - 1))
    size = UPPER - LOWER
    assert abs(area - 2 * (size[0] * size[1] + size[1] * size[2] + size[0] * size[2])) <= 1e-12


@pytest.mark.parametrize("name", TYPES)
def test_box_point_sets_select_exactly_the_face_nodes(name):
    solid = generate.box(LOWER, UPPER, CELLS, element=name)
    assert tuple(solid.point_sets) == generate.FACE_SETS == ("x_min", "x_max", "y_min", "y_max", "z_min", "z_max")
    for k, axis in enumerate("xyz"):
        np.testing.assert_array_equal(solid.point_sets[f"{axis}_min"], np.flatnonzero(solid.points[:, k] == LOWER[k]))
        np.testing.assert_array_equal(solid.point_sets[f"{axis}_max"], np.flatnonzero(solid.points[:, k] == UPPER[k]))
    nx, ny, nz = CELLS
    if name == "hexahedron":
        assert len(solid.point_sets["x_min"]) == (ny + 1) * (nz + 1)
    if name == "hexahedron27":
        assert len(solid.point_sets["z_max"]) == (2 * nx + 1) * (2 * ny + 1)


def test_box_numbering_is_x_fastest():
    solid = generate.box((0, 0, 0), (3, 2, 1), (3, 2, 1))
    np.testing.assert_array_equal(solid.points[:5], [[0, 0, 0], [1, 0, 0], [2, 0, 0], [3, 0, 0], [0, 1, 0]])
    centres = solid.points[solid.cells["hexahedron"]].mean(axis=1)
    np.testing.assert_allclose(centres[:4], [[0.5, 0.5, 0.5], [1.5, 0.5, 0.5], [2.5, 0.5, 0.5], [0.5, 1.5, 0.5]])


def test_box_single_cell_and_large_grid():
    solid = generate.box((0, 0, 0), (1, 1, 1), (1, 1, 1), element="tetra")
    assert (solid.n_nodes, solid.n_elements) == (8, 6)
    assert abs(volume(solid) - 1.0) <= 1e-15
    big = generate.box((0, 0, 0), (1, 1, 1), (40, 40, 40))
    assert (big.n_nodes, big.n_elements) == (41 ** 3, 40 ** 3)


def test_box_rejects_bad_input():
    for args in [((0, 0, 0), (1, 1, 1), (0, 1, 1)), ((0, 0, 0), (1, 0, 1), (1, 1, 1)),
                 ((0, 0, 0), (1, 1, 1), (1.5, 1, 1))]:
        with pytest.raises(ValueError):
            generate.box(*args)
    with pytest.raises(ValueError, match="pyramid"):
        generate.box((0, 0, 0), (1, 1, 1), (1, 1, 1), element="pyramid")


# -- distort -------------------------------------------------------------------------------------

@pytest.mark.parametrize("name", TYPES)
def test_distort_moves_interior_nodes_only_and_keeps_a_valid_conforming_mesh(name):
    solid = generate.box(LOWER, UPPER, (3, 3, 3), element=name)
    moved = generate.distort(solid, 0.2, seed=7)          # SolidMesh raises on inverted elements
    h = (UPPER - LOWER) / 3
    shift = moved.points - solid.points
    boundary = np.unique(np.concatenate(list(solid.point_sets.values())))
    assert np.abs(shift[boundary]).max() == 0.0
    interior = np.setdiff1d(np.arange(solid.n_nodes), boundary)
    assert (np.abs(shift[interior]).max(axis=0) > 0.01 * h).all()
    assert (np.abs(shift) <= 0.2 * h + 1e-15).all()
    assert {k: v.tolist() for k, v in moved.point_sets.items()} == {k: v.tolist() for k, v in solid.point_sets.items()}
    # fixed boundary + conforming elements: the volume is still the box's. det J of a distorted
    # element has total degree <= 15 (hex27: 5 per parameter): the rule is exact
    assert abs(volume(moved, 9) - BOX_VOLUME) <= 1e-12
    again = generate.distort(solid, 0.2, seed=7)
    assert np.array_equal(again.points, moved.points)
    assert not np.array_equal(generate.distort(solid, 0.2, seed=8).points, moved.points)


def test_distort_is_smooth():
    # neighbouring nodes move alike: the displacement gradient stays well below one
    solid = generate.box((0, 0, 0), (1, 1, 1), (8, 8, 8))
    moved = generate.distort(solid, 0.2, seed=3)
    conn = solid.cells["hexahedron"]
    du = (moved.points - solid.points)[conn[:, 1]] - (moved.points - solid.points)[conn[:, 0]]
    assert np.abs(du).max() <= 2 * 0.2 * (1 / 8)


# -- random curved beams -----------------------------------------------------------------------

def test_random_curved_beams_inside_box_and_deterministic():
    lower, upper = np.array([0.0, -1.0, 2.0]), np.array([1.0, 1.0, 2.5])
    count, m = 6, 4
    beams = generate.random_curved_beams(count, m, seed=11, lower=lower, upper=upper)
    assert beams.element_type.name == "hermite"
    assert (beams.n_nodes, beams.n_elements) == (count * (m + 1), count * m)
    f, i = np.divmod(np.arange(count * m), m)
    np.testing.assert_array_equal(beams.elements, np.column_stack([f * (m + 1) + i, f * (m + 1) + i + 1]))
    eta = np.linspace(-1, 1, 11)
    pts = np.vstack([beams.evaluate(e, eta) for e in range(beams.n_elements)])
    assert (pts > lower).all() and (pts < upper).all()
    # curved, C1 at the nodes inside a curve (tangents shared), not straight
    chord = np.linalg.norm(beams.positions[beams.elements[:, 1]] - beams.positions[beams.elements[:, 0]], axis=1)
    assert (beams.lengths > chord * (1 + 1e-6)).all()
    again = generate.random_curved_beams(count, m, seed=11, lower=lower, upper=upper)
    assert np.array_equal(again.positions, beams.positions) and np.array_equal(again.tangents, beams.tangents)
    other = generate.random_curved_beams(count, m, seed=12, lower=lower, upper=upper)
    assert not np.array_equal(other.positions, beams.positions)
