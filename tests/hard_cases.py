"""Hard geometric scenes and the independent checks shared by test_hard_cases.py and test_fuzz.py.

Everything a check compares against is computed without the library's kernels:

- centrelines from the formulas of docs/conventions.md §2 (Hermite H1..H4 with the mesh's L, Lagrange) and
  solid shape functions from the descriptors' reference nodes and a monomial basis (Vandermonde
  inverse), both in tests/naive.py;
- point-in-element by a vectorised numpy Newton from the element centre;
- the embedded η-set of every beam element by dense sampling of the centreline, point-in-solid
  at every sample and bisection of every in/out change to 1e-13 in η.

A *case* is a named scene (beams, solid) plus what the checks need to know about its
conditioning: ``conditioning`` = 1/sin θ for a beam meeting the solid's outer boundary at a
small angle θ (a crossing there is only determined to ``tol·h / sin θ``), 1 otherwise.
"""
from dataclasses import dataclass, replace

import numpy as np

import mortar1d3d as m13
from mortar1d3d import BeamMesh, SolidMesh, generate
from mortar1d3d.elements.solid.dispatch import BY_CODE
from naive import arc_length, centreline, outside_distance, reference_samples, shape_values

# --------------------------------------------------------------------------------------------
# point location (numpy Newton) on the shape functions of tests/naive.py
# --------------------------------------------------------------------------------------------


def element_nodes(solid, s):
    d = BY_CODE[int(solid.element_codes[s])]
    return d, solid.points[solid.connectivity[s, : d.n_nodes]]


def _newton(name, X, P, xi, h, iterations):
    """Vectorised Newton on x(ξ) = P from ``xi`` (modified), one element per row; converged flags."""
    active = np.arange(len(P))
    for _ in range(iterations):
        N, dN = shape_values(name, xi[active])
        r = P[active] - np.einsum("ka,kai->ki", N, X[active])
        # done: converged, or far outside (|ξ| > 5: such a point is in no danger of being inside)
        keep = (np.linalg.norm(r, axis=1) > 1e-15 * h[active]) & (np.abs(xi[active]).max(axis=1) < 5.0)
        active, r, dN = active[keep], r[keep], dN[keep]
        if not len(active):
            break
        J = np.einsum("kai,kaj->kij", X[active], dN)
        ok = np.abs(np.linalg.det(J)) > 0
        active, J, r = active[ok], J[ok], r[ok]
        xi[active] += np.linalg.solve(J, r[:, :, None])[:, :, 0]
    N, _ = shape_values(name, xi)
    res = np.linalg.norm(P - np.einsum("ka,kai->ki", N, X), axis=1)
    return res <= 1e-13 * h


def _starts(d):
    """Newton starts spread over the reference element: the points of the 3-per-direction lattice
    in it (hex: 3x3x3; tet: the 10 lattice points of a quadratic tet) pulled towards the centre."""
    return d.centre + 0.75 * (reference_samples(d.family, 3) - d.centre)


def locate_points(name, X, P, iterations=40):
    """ξ (k, 3) of the points P (k, 3) in the elements with nodes X (k, n_nodes, 3), one pair per row,
    and whether Newton converged (|x - p| <= 1e-13 h).

    Computed in each element's local frame (nodes minus its first node), like the library, so
    that far-from-origin meshes keep their digits. Vectorised over all pairs at once. Newton runs
    from the element centre; a point not found inside that way is tried again from starts spread
    over the element (a curved element's map folds outside it, so Newton can converge to a second
    solution outside while the point lies inside), and a solution inside wins.
    """
    d = next(d for d in BY_CODE.values() if d.name == name)
    origin = X[:, :1, :]
    X = X - origin
    P = P - origin[:, 0, :]
    h = np.linalg.norm(X.max(axis=1) - X.min(axis=1), axis=1)
    xi = np.tile(d.centre, (len(P), 1)).astype(float)
    converged = _newton(name, X, P, xi, h, iterations)
    if d.degree > 1 or name == "hexahedron":
        retry = np.flatnonzero(~converged | (outside_distance(d.family, xi) > 0.0))
        for start in _starts(d):
            if not len(retry):
                break
            trial = np.tile(start, (len(retry), 1))
            ok = _newton(name, X[retry], P[retry], trial, h[retry], iterations)
            better = ok & (~converged[retry] | (outside_distance(d.family, trial) < outside_distance(d.family,
                                                                                                   xi[retry])))
            xi[retry[better]] = trial[better]
            converged[retry[better]] = True
            retry = retry[~(ok & (outside_distance(d.family, trial) <= 0.0))]
        # a strongly curved element can hide the preimage inside from every fixed start (make fuzz: a
        # tet10 near a vertex): start also from the lattice points whose images lie nearest to p
        if len(retry):
            lattice = _lattice(d)
            N, _ = shape_values(name, lattice)
            images = np.matmul(N[None], X[retry])                      # (k, lattice points, 3)
            nearest = np.argsort(np.linalg.norm(images - P[retry][:, None, :], axis=2), axis=1)[:, :4]
            for j in range(nearest.shape[1]):
                trial = lattice[nearest[:, j]].copy()
                ok = _newton(name, X[retry], P[retry], trial, h[retry], iterations)
                inside = ok & (outside_distance(d.family, trial) <= 0.0)
                xi[retry[inside]] = trial[inside]
                converged[retry[inside]] = True
                retry, nearest = retry[~inside], nearest[~inside]
                if not len(retry):
                    break
    return xi, converged


def _lattice(d, n=12):
    """Reference points of element type ``d``: an n+1 lattice of its parameter box, those inside it."""
    from mortar1d3d.elements.solid.dispatch import PARAMETER_BOX
    lo, hi = PARAMETER_BOX[d.code]
    axes = [np.linspace(lo[i], hi[i], n + 1) for i in range(3)]
    pts = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)
    return pts[outside_distance(d.family, pts) <= 1e-12]


def containment(solid, P):
    """(m, n_elements) outside distance of every point in every element (inf: not near / not found)."""
    P = np.atleast_2d(np.asarray(P, float))
    out = np.full((len(P), solid.n_elements), np.inf)
    start = 0
    for d, conn in solid.blocks:
        X = solid.points[conn]                                   # (n_el, n_nodes, 3)
        lo, hi = X.min(axis=1), X.max(axis=1)
        pad = 0.5 * (hi - lo).max(axis=1)[:, None]               # quadratic elements bulge beyond their nodes
        near = np.all((P[:, None, :] >= (lo - pad)[None]) & (P[:, None, :] <= (hi + pad)[None]), axis=2)
        ip, ie = np.nonzero(near)
        if len(ip):
            xi, ok = locate_points(d.name, X[ie], P[ip])
            out[ip[ok], start + ie[ok]] = outside_distance(d.family, xi[ok])
        start += len(conn)
    return out


# --------------------------------------------------------------------------------------------
# independent embedded set: dense sampling + bisection
# --------------------------------------------------------------------------------------------
INSIDE_TOL = 1e-12     # sharp boundary (the library's 1e-9 would move cuts by 1e-9 h / sin θ)
DEPTH = 1e-7           # an interval never deeper inside than this is a touch: coupling it is optional


def _inside(solid, P):
    return containment(solid, P).min(axis=1) <= INSIDE_TOL


def embedded_intervals(beams, solid, e, samples=257, bisections=45, extra=()):
    """Sorted disjoint η-intervals [(a, b, required), ...] of beam element e inside the solid.

    ``required`` is False for intervals whose centreline never gets deeper than ``DEPTH`` inside
    (tangential touches, pieces lying on the outer boundary): the library may couple them or not.
    ``extra``: more η to sample (the checks add the midpoints of the library's pieces and gaps,
    so that an excursion narrower than the sampling is looked at; in or out is decided here).
    """
    eta = np.unique(np.concatenate([np.linspace(-1.0, 1.0, samples), np.asarray(extra, float)]))
    r, _ = centreline(beams, e, eta)
    depth = containment(solid, r).min(axis=1)
    inside = depth <= INSIDE_TOL
    change = np.flatnonzero(inside[1:] != inside[:-1])
    lo, hi = eta[change].copy(), eta[change + 1].copy()
    lo_in = inside[change]
    for _ in range(bisections):
        if not len(lo):
            break
        mid = 0.5 * (lo + hi)
        m_in = _inside(solid, centreline(beams, e, mid)[0])
        same = m_in == lo_in
        lo = np.where(same, mid, lo)
        hi = np.where(same, hi, mid)
    cuts = 0.5 * (lo + hi)
    bounds = np.concatenate([[-1.0], cuts, [1.0]])
    states = np.concatenate([[inside[0]], ~lo_in]) if len(cuts) else np.array([inside[0]])
    out = []
    for i in range(len(bounds) - 1):
        if states[i]:
            a, b = bounds[i], bounds[i + 1]
            within = (eta > a) & (eta < b)
            mid = containment(solid, centreline(beams, e, [0.5 * (a + b)])[0]).min()
            deepest = min(depth[within].min() if within.any() else np.inf, mid)
            out.append((a, b, bool(deepest < -DEPTH)))
    return out


def segment_union(ops, e):
    """The segments of beam element e, sorted, with touching neighbours merged: [(a, b), ...]."""
    s = ops.segments[ops.segments["beam_element"] == e]
    s = np.sort(s, order="eta_start")
    out = []
    for a, b in zip(s["eta_start"], s["eta_end"]):
        if out and a <= out[-1][1]:
            out[-1] = (out[-1][0], max(out[-1][1], b))
        else:
            out.append((float(a), float(b)))
    return out


# --------------------------------------------------------------------------------------------
# cases
# --------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class Case:
    name: str
    beams: BeamMesh
    solid: SolidMesh
    conditioning: float = 1.0          # 1/sin θ at outer-boundary crossings (ill-conditioned cut)
    n_gauss: int = 10
    expected_length: float = None      # analytic embedded length when known
    eta_tol: float = 1e-9              # agreement of the tiling with the sampled embedded set
    touch: bool = False                # tangent to a face: coupled length ~ sqrt(shift) (Hölder 1/2)
    gradient: float = 1.0              # h / thinnest element: sensitivity of N(ξ(x)) to a shift


def unit(v):
    v = np.asarray(v, float)
    return v / np.linalg.norm(v)


def straight(a, b, elements=1):
    """Straight Hermite beam a→b in ``elements`` equal elements (unit chord tangents)."""
    a, b = np.asarray(a, float), np.asarray(b, float)
    t = np.linspace(0.0, 1.0, elements + 1)[:, None]
    pos = a + t * (b - a)
    d = unit(b - a)
    el = np.column_stack([np.arange(elements), np.arange(1, elements + 1)])
    return BeamMesh.hermite(pos, np.tile(d, (elements + 1, 1)), el)


def curve(f, df, t0, t1, elements):
    return BeamMesh.from_curve(f, df, t0, t1, elements)


def cube(cells=(2, 2, 2), element="hexahedron", upper=(2.0, 2.0, 2.0)):
    return generate.box((0.0, 0.0, 0.0), upper, cells, element)


def _orient(points, tets):
    """Swap two nodes of negatively oriented tets (VTK order needs det > 0)."""
    tets = np.array(tets)
    for t in tets:
        X = points[t]
        if np.linalg.det(np.array([X[1] - X[0], X[2] - X[0], X[3] - X[0]])) < 0:
            t[[2, 3]] = t[[3, 2]]
    return tets


def sliver_mesh(eps):
    """Five tets: the sliver A B C D (diagonals AB at z = 0 and CD at z = eps cross at distance eps),
    a tet from the apex T above to each upper face, from S below to each lower face."""
    P = np.array([[0, 0, 0], [1, 1, 0], [1, 0, eps], [0, 1, eps], [0.5, 0.5, 1.0], [0.5, 0.5, -1.0]], float)
    A, B, C, D, T, S = range(6)
    tets = [[A, B, C, D], [A, C, D, T], [B, C, D, T], [A, B, C, S], [A, B, D, S]]
    return SolidMesh(P, {"tetra": _orient(P, tets)})


def distorted_hex8(amplitude=0.3, seed=3, element="hexahedron"):
    """2x2x2 hex8 (or the cells of another linear ``element``) on [0,2]^3 with *every* node moved
    (non-planar faces, also on the boundary)."""
    solid = cube(element=element)
    rng = np.random.default_rng(seed)
    P = solid.points + amplitude * rng.uniform(-1, 1, solid.points.shape)
    return SolidMesh(P, solid.cells)


def curved_hex27(c=0.3):
    """One hex27 on [-1,1]^3 whose top face is the cylinder z = 1 + c (1 - x²)."""
    solid = generate.box((-1, -1, -1), (1, 1, 1), (1, 1, 1), "hexahedron27")
    P = solid.points.copy()
    P[:, 2] = np.where(P[:, 2] > 0.5, 1 + c * (1 - P[:, 0] ** 2),
                       np.where(np.abs(P[:, 2]) < 0.5, 0.5 * c * (1 - P[:, 0] ** 2), P[:, 2]))
    return SolidMesh(P, solid.cells)


def curved_tet10(delta=0.1):
    """One tet10 (unit corner tet) whose face x+y+z=1 bulges out by 4δ/3 at its centroid."""
    solid = generate.box((0, 0, 0), (1, 1, 1), (1, 1, 1), "tetra10")
    # the single tet with corners (0,0,0),(1,0,0),(0,1,0),(0,0,1) is not in the Kuhn split: build it
    d = next(d for d in BY_CODE.values() if d.name == "tetra10")
    ref = d.reference_nodes                       # ξ of the 10 nodes; x = ξ for the unit corner tet
    P = ref.astype(float).copy()
    n = unit([1, 1, 1])
    on_face = np.isclose(P.sum(axis=1), 1.0) & (P.max(axis=1) < 1.0)    # the 3 mid-edge nodes of that face
    P[on_face] += delta * n
    del solid
    return SolidMesh(P, {"tetra10": np.arange(10)[None]})


def _arch_up(x_mid, z_top, half_width, rise, y=0.3, elements=1):
    """Hermite arch in the x-z plane: ends at (x_mid ∓ w, y, z_top - rise), symmetric apex at
    (x_mid, y, z(0)), z(η) = z_end + t_z L/4 (1 - η²) (docs/conventions.md §2 Hermite, symmetric data)."""
    t1 = unit([half_width, 0.0, 2 * rise])
    t2 = unit([half_width, 0.0, -2 * rise])
    a = [x_mid - half_width, y, z_top - rise]
    b = [x_mid + half_width, y, z_top - rise]
    beams = BeamMesh.hermite([a, b], [t1, t2], [[0, 1]])
    L = beams.lengths[0]
    apex = a[2] + t1[2] * L / 4
    return beams, apex


def catalogue():
    """{name: Case} of issue 6 part 1 (before offsets and scalings)."""
    cases = {}

    def add(case):
        cases[case.name] = case

    node = np.array([1.0, 1.0, 1.0])
    d = unit([1.0, 0.8, 0.6])
    add(Case("through_node_8_hexes", straight(node - 0.7 * d, node + 0.9 * d, 2), cube(),
             expected_length=1.6))
    add(Case("through_node_many_tets", straight(node - 0.7 * d, node + 0.9 * d, 2), cube(element="tetra"),
             expected_length=1.6))
    add(Case("through_node_tet10_diagonal", straight(node - 0.6 * unit([1, 1, 1]), node + 0.6 * unit([1, 1, 1])),
             cube(element="tetra10"), expected_length=1.2))
    add(Case("along_edge_4_hexes", straight((1.0, 1.0, 0.3), (1.0, 1.0, 1.8), 2), cube(), expected_length=1.5))
    add(Case("along_edge_hex27", straight((0.25, 1.0, 1.0), (1.9, 1.0, 1.0)), cube(element="hexahedron27"),
             expected_length=1.65))
    add(Case("in_face_2_elements", straight((1.0, 0.2, 0.3), (1.0, 1.7, 0.6), 2), cube(),
             expected_length=float(np.linalg.norm([0, 1.5, 0.3]))))
    add(Case("in_face_tets", straight((0.3, 1.4, 1.0), (1.6, 1.8, 1.0)), cube(element="tetra"),
             expected_length=float(np.linalg.norm([1.3, 0.4, 0]))))
    add(Case("on_outer_boundary", straight((0.2, 0.3, 0.0), (1.7, 0.4, 0.0), 2), cube(),
             expected_length=float(np.linalg.norm([1.5, 0.1, 0]))))
    add(Case("on_outer_edge", straight((0.1, 0.0, 0.0), (1.8, 0.0, 0.0)), cube(element="hexahedron20"),
             expected_length=1.7))
    # grazing: flat face from outside (no coupling) and from inside (all coupled)
    beams, apex = _arch_up(1.0, 2.0, 0.6, 0.4, y=0.7)
    shift = 2.0 - apex
    add(Case("grazing_flat_face_inside", BeamMesh.hermite(beams.positions + [0, 0, shift], beams.tangents,
                                                          beams.elements), cube(), n_gauss=20, touch=True))
    beams, apex = _arch_up(1.0, 2.0, 0.6, -0.4, y=0.7)          # a sagging arch touching z = 2 from above
    add(Case("grazing_flat_face_outside", BeamMesh.hermite(beams.positions + [0, 0, 2.0 - apex], beams.tangents,
                                                           beams.elements), cube(), expected_length=0.0, touch=True))
    add(Case("grazing_curved_hex27_outside", straight((-0.9, 0.3, 1.3), (0.8, 0.3, 1.3)), curved_hex27(0.3),
             expected_length=0.0, touch=True))
    beams, apex = _arch_up(0.0, 1.3, 0.7, 0.5)                    # curvature > the face's: touches from inside
    add(Case("grazing_curved_hex27_inside", BeamMesh.hermite(beams.positions + [0, 0, 1.3 - apex],
                                                             beams.tangents, beams.elements), curved_hex27(0.3),
             n_gauss=20, touch=True))
    n = unit([1, 1, 1])
    top = np.full(3, 1 / 3) + 4 * 0.1 / 3 * n
    e1 = unit([1, -1, 0])
    add(Case("grazing_curved_tet10_outside", straight(top - 0.4 * e1, top + 0.4 * e1), curved_tet10(0.1),
             expected_length=0.0, touch=True))
    # wedges (two per grid cell, split along the cell's diagonal plane x - y = const): through a node
    # of 12 wedges, along a vertical edge of 6, in a slanted face, across the triangles, partly outside
    add(Case("through_node_wedges", straight(node - 0.7 * d, node + 0.9 * d, 2), cube(element="wedge"),
             expected_length=1.6))
    add(Case("along_edge_6_wedges", straight((1.0, 1.0, 0.3), (1.0, 1.0, 1.8), 2), cube(element="wedge"),
             expected_length=1.5))
    add(Case("in_slanted_face_wedges", straight((0.2, 0.2, 0.3), (1.7, 1.7, 1.6), 2), cube(element="wedge"),
             expected_length=float(np.linalg.norm([1.5, 1.5, 1.3]))))
    add(Case("across_triangle_faces_wedges", straight((0.7, 0.2, 0.1), (0.7, 0.2, 1.9), 2), cube(element="wedge"),
             expected_length=1.8))
    add(Case("both_ends_outside_wedges", straight((0.3, 1.2, -0.5), (1.4, 0.4, 2.5), 2), cube(element="wedge"),
             expected_length=2.0 / 3.0 * float(np.linalg.norm([1.1, -0.8, 3.0]))))
    # nearly parallel to a shared face (two hexes) and to the outer face, angle θ
    for k in (4, 8, 12):
        theta = 10.0 ** -k
        a = np.array([1.0 - 0.4 * np.sin(theta), 0.1, 0.5])
        b = np.array([1.0 + 0.4 * np.sin(theta), 0.1 + 0.8 * np.cos(theta), 0.5])
        add(Case(f"nearly_parallel_shared_face_1e-{k}", straight(a, b), cube((2, 1, 1), upper=(2, 1, 1)),
                 expected_length=float(np.linalg.norm(b - a))))
        a = np.array([0.3, 0.1, -0.4 * np.sin(theta)])
        b = np.array([0.3, 0.9, 0.4 * np.sin(theta)])
        add(Case(f"nearly_parallel_outer_face_1e-{k}", straight(a, b), cube((2, 1, 1), upper=(2, 1, 1)),
                 conditioning=1.0 / np.sin(theta), expected_length=0.5 * float(np.linalg.norm(b - a))))
    # end points exactly on a face, an edge, a node (from inside and from outside)
    add(Case("end_on_shared_face", straight((0.3, 0.4, 0.5), (1.0, 0.7, 0.6)), cube(),
             expected_length=float(np.linalg.norm([0.7, 0.3, 0.1]))))
    add(Case("end_on_edge", straight((0.3, 0.4, 0.5), (1.0, 1.0, 0.6)), cube(),
             expected_length=float(np.linalg.norm([0.7, 0.6, 0.1]))))
    add(Case("start_on_node", straight((1.0, 1.0, 1.0), (1.6, 0.3, 1.4), 2), cube(element="tetra10"),
             expected_length=float(np.linalg.norm([0.6, -0.7, 0.4]))))
    add(Case("end_on_outer_face_from_outside", straight((-0.5, 0.4, 0.5), (0.0, 0.7, 0.6)), cube(),
             expected_length=0.0))
    add(Case("end_on_outer_corner_from_outside", straight((-0.5, -0.4, -0.3), (0.0, 0.0, 0.0)), cube(),
             expected_length=0.0))
    # tiny and huge beam elements
    add(Case("tiny_beam_elements_across_a_node", straight(node - 2e-6 * d, node + 3e-6 * d, 5), cube(),
             expected_length=5e-6))
    add(Case("tiny_beam_element_across_a_face", straight((1.0 - 4e-7, 0.3, 0.4), (1.0 + 6e-7, 0.3, 0.4)), cube(),
             expected_length=1e-6))
    add(Case("one_beam_element_100_solids", straight((0.0, 0.3, 0.6), (100.0, 0.7, 0.2)),
             cube((100, 1, 1), upper=(100, 1, 1)), expected_length=float(np.linalg.norm([100, 0.4, -0.4]))))
    add(Case("one_beam_element_100_tets", straight((0.0, 0.3, 0.6), (17.0, 0.7, 0.2)),
             cube((17, 1, 1), element="tetra", upper=(17, 1, 1)), expected_length=float(np.linalg.norm([17, 0.4, -0.4]))))
    # leaves and re-enters element 0 three times (sine wave across x = 1), and leaves the solid
    w = 2 * np.pi * 3 / 1.8
    wave = curve(lambda t: (1.0 + 0.2 * np.sin(w * t), 0.5, 0.1 + t), lambda t: (0.2 * w * np.cos(w * t), 0.0, 1.0),
                 0.0, 1.8, 12)
    add(Case("leave_reenter_three_times_neighbour", wave, cube((2, 1, 2), upper=(2, 1, 2)), n_gauss=12))
    add(Case("leave_reenter_three_times_outside", wave, cube((1, 1, 2), upper=(1, 1, 2)), n_gauss=12))
    # one cubic element crossing x = 1 three times (S shape, one of them at η = 0 exactly)
    add(Case("cubic_crossing_one_face_three_times",
             curve(lambda t: (1 + 0.3 * (t ** 3 - 0.7 * t), 0.5 + 0.3 * t, 0.5 + 0.2 * t),
                   lambda t: (0.3 * (3 * t * t - 0.7), 0.3, 0.2), -1.0, 1.0, 1), cube(), n_gauss=12))
    # distorted hex8 with non-planar faces, and sliver tets
    helix = curve(lambda t: (1.0 + 0.5 * np.cos(t), 1.0 + 0.5 * np.sin(t), 0.3 + 0.12 * t),
                  lambda t: (-0.5 * np.sin(t), 0.5 * np.cos(t), 0.12), 0.0, 4 * np.pi, 10)
    add(Case("distorted_hex8_helix", helix, distorted_hex8(), n_gauss=12))
    add(Case("distorted_hex8_straight", straight((-0.4, 0.5, 0.6), (2.3, 1.4, 1.5), 3), distorted_hex8()))
    add(Case("distorted_wedge_helix", helix, distorted_hex8(element="wedge"), n_gauss=12))
    add(Case("distorted_wedge_straight", straight((-0.4, 0.5, 0.6), (2.3, 1.4, 1.5), 3),
             distorted_hex8(element="wedge")))
    for k in (4, 8):
        add(Case(f"sliver_tets_1e-{k}", straight((0.6, 0.3, -0.8), (0.6, 0.3, 0.8), 2), sliver_mesh(10.0 ** -k),
                 gradient=10.0 ** k))
        z = 0.25 * 10.0 ** -k                                      # a quarter of the sliver's height
        add(Case(f"along_sliver_1e-{k}", straight((0.2, 0.15, z), (0.9, 0.8, z)), sliver_mesh(10.0 ** -k),
                 gradient=10.0 ** k))
    # many fibres crossing at one node; beams starting or ending outside
    fibres = [straight(node - 0.5 * unit(v), node + 0.5 * unit(v)) for v in
              ([1, 0, 0], [0, 1, 0], [0, 0, 1], [1, 1, 0], [1, -1, 0], [1, 1, 1], [-1, 1, 1], [1, 2, 3])]
    add(Case("many_fibres_through_one_node", BeamMesh.join(fibres), cube(), expected_length=8.0))
    add(Case("start_outside", straight((-0.5, 0.3, 0.4), (1.5, 1.3, 1.4), 2), cube(element="hexahedron27"),
             expected_length=0.75 * float(np.linalg.norm([2, 1, 1]))))
    add(Case("both_ends_outside_helix", curve(lambda t: (-0.3 + 0.3 * t, 1.0 + 0.6 * np.cos(t), 1.0 + 0.6 * np.sin(t)),
                                              lambda t: (0.3, -0.6 * np.sin(t), 0.6 * np.cos(t)), 0.0, 9.0, 10),
             cube((1, 1, 1), element="tetra10"), n_gauss=12))
    return cases


TRANSFORMS = {"plain": (0.0, 1.0), "offset_1e6": (1e6, 1.0), "scale_1e-6": (0.0, 1e-6), "scale_1e6": (0.0, 1e6)}


def transformed(case, kind):
    """The case moved by an offset of 1e6 (all coordinates) or scaled by 1e-6 / 1e6."""
    offset, scale = TRANSFORMS[kind]
    if kind == "plain":
        return case
    move = lambda x: scale * np.asarray(x) + offset   # noqa: E731
    b = case.beams
    beams = BeamMesh(b.element_type.name, move(b.positions), b.elements, tangents=b.tangents)
    solid = SolidMesh(move(case.solid.points), case.solid.cells)
    length = None if case.expected_length is None else scale * case.expected_length
    return replace(case, name=f"{case.name}[{kind}]", beams=beams, solid=solid, expected_length=length)


# --------------------------------------------------------------------------------------------
# checks
# --------------------------------------------------------------------------------------------
def element_size(solid):
    return float(np.median([np.ptp(element_nodes(solid, s)[1], axis=0).max() for s in range(solid.n_elements)]))


def coordinate_round_off(beams, solid):
    """Relative size of the coordinates' round-off compared with the element size."""
    big = max(np.abs(solid.points).max(), np.abs(beams.positions).max())
    return np.finfo(float).eps * big / element_size(solid)


def assemble(case, beams=None, solid=None, **kwargs):
    kwargs.setdefault("n_gauss", case.n_gauss)
    return m13.assemble_mortar(case.beams if beams is None else beams, case.solid if solid is None else solid,
                               **kwargs)


def estimated_conditioning(beams, solid, delta=1e-4):
    """1/sin θ of the worst boundary crossing of the embedded set, from the reference alone.

    At every cut of :func:`embedded_intervals` (and at beam ends lying within 1e-8 of the
    boundary) the slope of the outside distance along η is compared with that of a crossing
    at right angles; the ratio is the factor by which the cut moves per unit of tolerance.
    """
    h = element_size(solid)
    worst = 1.0
    for e in range(beams.n_elements):
        nominal = beams.lengths[e] / h               # |d dist / dη| at right angles (parameter units)
        ends = [x for a, b, _ in embedded_intervals(beams, solid, e) for x in (a, b)]
        for eta in ends:
            pts = np.clip([eta - delta, eta + delta], -1, 1)
            dist = containment(solid, centreline(beams, e, pts)[0]).min(axis=1)
            dist = np.where(np.isfinite(dist), dist, 1.0)
            slope = abs(dist[1] - dist[0]) / max(pts[1] - pts[0], 1e-300)
            worst = max(worst, min(nominal / max(slope, 1e-300), 1e12))
    return worst


def estimated_gradient(beams, solid, samples=33):
    """cond(J) = σ_max / σ_min of the solid's Jacobian where the beams are inside, at least 1.

    The local form of ``Case.gradient`` (h / thinnest element for a sliver): a shift δ of the beam
    moves ξ by J⁻¹ δ, so N(ξ(x)), and with it M, changes up to cond(J) times faster than in a
    well-shaped element of the same size. Curved elements near their validity limit have det J
    small somewhere; there this is large.
    """
    worst = 1.0
    etas = np.linspace(-1.0, 1.0, samples)
    for e in range(beams.n_elements):
        P = centreline(beams, e, etas)[0]
        for d, conn in solid.blocks:
            X = solid.points[conn]
            lo, hi = X.min(axis=1), X.max(axis=1)
            pad = 0.5 * (hi - lo).max(axis=1)[:, None]
            near = np.all((P[:, None, :] >= (lo - pad)[None]) & (P[:, None, :] <= (hi + pad)[None]), axis=2)
            ip, ie = np.nonzero(near)
            if len(ip):
                xi, ok = locate_points(d.name, X[ie], P[ip])
                inside = ok & (outside_distance(d.family, xi) <= 1e-9)
                if inside.any():
                    _, dN = shape_values(d.name, xi[inside])
                    J = np.einsum("kai,kaj->kij", X[ie[inside]], dN)
                    sv = np.linalg.svd(J, compute_uv=False)
                    worst = max(worst, float(np.max(sv[:, 0] / np.maximum(sv[:, -1], 1e-300))))
    return min(worst, 1e12)


def check_finite(ops):
    assert np.isfinite(ops.kappa).all()
    assert np.isfinite(ops.D.data).all() and np.isfinite(ops.M.data).all()
    assert np.isfinite(ops.points["xi"]).all() and np.isfinite(ops.points["weight"]).all()
    assert np.isfinite(ops.constraint_residual)
    assert ops.diagnostics["points_not_converged"] == 0
    assert ops.diagnostics["points_outside_element"] == 0


def eta_tolerance(case):
    """How well a cut η is determined: 1e-9, plus the face Newton's 1e-12 h (and the coordinates'
    round-off) turned into η by the beam element length, times the conditioning 1/sin θ; at a
    tangential touch a distance δ moves the cuts by ~sqrt(δ)."""
    h = element_size(case.solid)
    spread = 2.0 * (1e-11 + 64 * coordinate_round_off(case.beams, case.solid)) * h / case.beams.lengths.min()
    tol = case.conditioning * (case.eta_tol + spread)
    return tol + 10 * np.sqrt(spread) if case.touch else tol


def check_tiling(ops, case, reference=None):
    """Segments of every beam element: disjoint, inside [-1, 1], owners containing them, union = the
    independently sampled embedded set (cut positions to ``eta_tolerance``)."""
    beams, solid = case.beams, case.solid
    seg = ops.segments
    assert np.all(np.diff(seg["beam_element"]) >= 0)
    tol = eta_tolerance(case)
    for e in range(beams.n_elements):
        s = seg[seg["beam_element"] == e]
        if len(s):
            assert np.all(s["eta_end"] > s["eta_start"]), s
            assert s["eta_start"][0] >= -1.0 and s["eta_end"][-1] <= 1.0
            assert np.all(s["eta_end"][:-1] <= s["eta_start"][1:]), f"overlap in beam element {e}: {s}"
        got = segment_union(ops, e)
        bounds = np.array([-1.0] + [x for g in got for x in g] + [1.0])
        if reference is None:
            want = embedded_intervals(beams, solid, e, extra=0.5 * (bounds[1:] + bounds[:-1]))
        else:
            want = reference[e]
        msg = f"{case.name}: beam element {e}: segments {got}, embedded {want} (tol {tol:.1e})"
        # no segment outside the embedded set, except within the library's 1e-9 tolerance band
        for a, b in got:
            if any(w[0] - tol <= a and b <= w[1] + tol for w in want):
                continue
            excess = _excess(a, b, want)
            eta = np.concatenate([lo + (hi - lo) * np.linspace(0.05, 0.95, 7) for lo, hi in excess])
            dist = containment(solid, centreline(beams, e, eta)[0]).min(axis=1)
            band = 2 * INSIDE_TOL_LIBRARY + 64 * coordinate_round_off(beams, solid)
            assert dist.max() <= band, msg + f": coupled {dist.max():.1e} outside"
        # every clearly embedded interval is covered by one segment run (same ends, or the run
        # goes on through the tolerance band checked above)
        for a, b, required in want:
            if not required:
                continue
            match = [g for g in got if g[0] <= b and g[1] >= a]
            assert len(match) == 1, msg
            assert match[0][0] <= a + tol and match[0][1] >= b - tol, msg
            assert (abs(match[0][0] - a) <= tol or any(w[1] < a for w in want) or a == -1.0
                    or match[0][0] < a), msg
    check_owners(ops, case)


INSIDE_TOL_LIBRARY = 1e-9


def _excess(a, b, want):
    """Parts of [a, b] outside the union of the ``want`` intervals."""
    pieces, start = [], a
    for lo, hi, _ in sorted(want):
        if hi <= start or lo >= b:
            continue
        if lo > start:
            pieces.append((start, lo))
        start = max(start, hi)
    if start < b:
        pieces.append((start, b))
    return pieces or [(a, b)]


def check_owners(ops, case, samples=3):
    """Every segment lies in its owner; no lower-index element contains it clearly (ownership rule)."""
    beams, solid = case.beams, case.solid
    seg = ops.segments
    if not len(seg):
        return
    frac = (np.arange(samples) + 0.5) / samples
    eta = seg["eta_start"][:, None] + frac[None] * (seg["eta_end"] - seg["eta_start"])[:, None]
    P = np.vstack([centreline(beams, int(row["beam_element"]), eta[i])[0] for i, row in enumerate(seg)])
    dist = containment(solid, P).reshape(len(seg), samples, solid.n_elements)
    loose = 1e-7          # parameter distance: not amplified by the conditioning of the cut
    for i, row in enumerate(seg):
        owner = int(row["solid_element"])
        assert np.all(dist[i, :, owner] <= loose), (case.name, row, dist[i, :, owner])
        mid = dist[i, samples // 2]
        lower = np.flatnonzero(mid[:owner] <= -1e-7)
        assert not len(lower), f"{case.name}: segment {row} owned by {owner}, but {lower} contain it"


def check_certificates(ops, case):
    beams, solid = case.beams, case.solid
    h = element_size(solid)
    # the library's ‖D q_B - M X_S‖ / ‖D q_B‖ is round-off, except when the coupled part lies near the
    # coordinate origin (‖D q_B‖ → 0 while ξ still carries round-off of h; found by make fuzz: a touch
    # at the corner (0,0,0), 6e-8): judged against κ h there
    scale = np.linalg.norm(ops.D @ beams.centreline_dofs())
    assert ops.constraint_residual * scale <= 1e-12 * max(scale, h * np.linalg.norm(ops.kappa)), \
        (case.name, ops.constraint_residual, scale)
    # translation-free form: |D q_B - M X_S| per LM node, relative to κ h (the offset would hide errors)
    r = (ops.D @ beams.centreline_dofs() - ops.M @ solid.points.ravel()).reshape(-1, 3)
    bound = (1e-12 + 64 * coordinate_round_off(beams, solid)) * h * max(ops.kappa.max(), 1e-300)
    assert np.abs(r).max() <= bound, (case.name, np.abs(r).max(), bound)
    # Σκ = coupled length: against the analytic value, and against the tiling's arc length
    # a cut is known to 1e-11 h / sin θ; far from the origin every node carries ulps of round-off
    # (and a touch turns a distance δ into a coupled length ~ sqrt(δ h))
    eps = np.finfo(float).eps
    big = max(np.abs(solid.points).max(), np.abs(beams.positions).max())
    tol = 1e-11 * case.conditioning * h + 1e-12 * beams.length + 8 * eps * big * (beams.n_elements + 1)
    if case.touch:
        tol += 10 * h * np.sqrt(1e-11 + 64 * coordinate_round_off(beams, solid))
    if case.expected_length is not None:
        assert abs(ops.embedded_length - case.expected_length) <= max(tol, 1e-12 * case.expected_length), \
            (case.name, ops.embedded_length, case.expected_length)
    # Σκ = the n_gauss rule of |r'| on the segments (numpy, independent centreline derivative)
    tiled = sum(arc_length(beams, int(r["beam_element"]), r["eta_start"], r["eta_end"], ops.n_gauss)
                for r in ops.segments)
    assert abs(ops.embedded_length - tiled) <= 1e-13 * max(tiled, h), (case.name, ops.embedded_length, tiled)
    # partition of unity: M 1 = κ per component
    MX = (ops.M @ np.ones(ops.M.shape[1])).reshape(-1, 3)
    np.testing.assert_allclose(MX, np.repeat(ops.kappa[:, None], 3, axis=1), rtol=0,
                               atol=1e-13 * max(ops.kappa.max(), 1e-300))


def relative_change(a, b, size=None):
    """‖a - b‖_F / max(‖a‖_F, size) for sparse or dense a, b."""
    a = a.toarray() if hasattr(a, "toarray") else np.asarray(a)
    b = b.toarray() if hasattr(b, "toarray") else np.asarray(b)
    scale = max(np.linalg.norm(a), size or 0.0)
    return float(np.linalg.norm(a - b) / scale) if scale > 0 else float(np.linalg.norm(b))


def band_ownership_change(ops, case, factor=10.0):
    """Relative change of M that renumbering may cause through pieces lying within the inside
    tolerance of a neighbouring element.

    Such a piece belongs to whichever of the two has the lower index. Its points lie outside the
    other element by at most its extent (a corner cut at depth s has a chord of about s) and never
    by more than the tolerance band, and there the two elements' shape functions differ by that
    distance over h. Summed with each piece's share of the coupled length; ``factor`` bounds |∇N| h.
    Pieces longer than the band are not affected: they cannot lie inside it.
    """
    seg = ops.segments
    if len(seg) == 0:
        return 0.0
    h = element_size(case.solid)
    length = 0.5 * (seg["eta_end"] - seg["eta_start"]) * case.beams.lengths[seg["beam_element"]]
    band = m13._config.PARAMETER_TOL * h
    total = length.sum()
    return float(factor * np.sum(length / total * np.minimum(length, band)) / h) if total > 0 else 0.0


def renumbered(solid, seed=0):
    """Solid with permuted elements (per block) and nodes; old element i -> new_elem[i], node k -> new_node[k]."""
    rng = np.random.default_rng(seed)
    new_node = rng.permutation(solid.n_nodes)
    points = np.empty_like(solid.points)
    points[new_node] = solid.points
    cells, new_elem, start = {}, np.empty(solid.n_elements, np.int64), 0
    for d, conn in solid.blocks:
        order = rng.permutation(len(conn))                    # new j = old order[j]
        cells[d.name] = new_node[conn[order]]
        new_elem[start + order] = start + np.arange(len(conn))
        start += len(conn)
    return SolidMesh(points, cells), new_elem, new_node


def check_renumbering(ops, case, seed=0):
    """κ, D and M (columns permuted) unchanged; the coupled η-set unchanged; segments whose midpoint is
    inside exactly one element keep that element (mapped); every owner follows the lowest-index rule
    of its own numbering (check_owners). On shared faces the owner may change, the operators may not."""
    solid2, new_elem, new_node = renumbered(case.solid, seed)
    ops2 = assemble(case, solid=solid2)
    tol = 1e-13 * case.conditioning
    assert relative_change(ops.kappa, ops2.kappa) <= tol, (case.name, relative_change(ops.kappa, ops2.kappa))
    assert relative_change(ops.D, ops2.D) <= tol
    cols = (3 * new_node[:, None] + np.arange(3)).ravel()
    change = relative_change(ops.M, ops2.M[:, cols])
    assert change <= 1e-12 * case.conditioning + band_ownership_change(ops, case), (case.name, change)
    case2 = replace(case, solid=solid2)
    check_owners(ops2, case2)
    for e in range(case.beams.n_elements):
        a, b = segment_union(ops, e), segment_union(ops2, e)
        assert len(a) == len(b)
        assert not a or np.allclose(a, b, rtol=0, atol=eta_tolerance(case))
    # interior segments: same pieces, owner mapped
    seg, seg2 = ops.segments, ops2.segments
    for row in seg:
        mid = 0.5 * (row["eta_start"] + row["eta_end"])
        p = centreline(case.beams, int(row["beam_element"]), [mid])[0]
        dist = containment(case.solid, p)[0]
        if np.count_nonzero(dist <= 1e-6) == 1 and dist[row["solid_element"]] < -1e-6:
            hit = seg2[(seg2["beam_element"] == row["beam_element"]) & (seg2["eta_start"] <= mid)
                       & (seg2["eta_end"] >= mid)]
            assert len(hit) == 1 and hit["solid_element"][0] == new_elem[row["solid_element"]], (case.name, row, hit)
    return ops2


def shifted_beams(beams, delta):
    return BeamMesh(beams.element_type.name, beams.positions + delta, beams.elements, tangents=beams.tangents)


SHIFT_DIRECTION = unit([0.48, -0.61, 0.63])


def full_operators(case):
    """The operators of the same beams fully inside one enclosing hex8: the size a change is measured
    against when the case itself couples little or nothing (a beam touching the solid from outside)."""
    lo, hi = case.beams.positions.min(axis=0), case.beams.positions.max(axis=0)
    pad = 0.5 * (hi - lo).max() + case.beams.lengths.max()
    return assemble(case, solid=generate.box(lo - pad, hi + pad, (1, 1, 1)))


def check_continuity(ops, case, factor=1e-12):
    """Moving the beam by ±factor·h changes D, M, κ by O(factor) (relative, Frobenius), not O(1).

    Bound: 1e3 · shift · conditioning (cuts at a small angle θ to the outer boundary move by
    shift / sin θ) · gradient for M (shape functions of a sliver of thickness t vary like h / t);
    at a tangential touch the coupled length itself grows like sqrt(shift): 1e2 · sqrt(shift).
    Far from the origin the shift is rounded to whole ulps: the bound uses the shift received.
    """
    h = element_size(case.solid)
    full = full_operators(case)
    worst = 0.0
    for sign in (1.0, -1.0):
        moved = shifted_beams(case.beams, sign * factor * h * SHIFT_DIRECTION)
        real = max(np.abs(moved.positions - case.beams.positions).max() / h, factor)
        ops2 = assemble(case, beams=moved)
        for name, a, b, f in (("D", ops.D, ops2.D, full.D), ("M", ops.M, ops2.M, full.M),
                              ("kappa", ops.kappa, ops2.kappa, full.kappa)):
            size = np.linalg.norm(f.toarray() if hasattr(f, "toarray") else f)
            change = relative_change(a, b, size)
            bound = 1e3 * real * case.conditioning * (case.gradient if name == "M" else 1.0) + 1e-13
            if case.touch:
                bound = max(bound, 1e2 * np.sqrt(real))
            worst = max(worst, change / bound)
            assert change <= bound, f"{case.name}: shift {sign * factor}·h changes {name} by {change:.2e} > {bound:.1e}"
    return worst


def check_all(case, renumber=True, continuity=True, reference=None):
    ops = assemble(case)
    check_finite(ops)
    check_tiling(ops, case, reference)
    check_certificates(ops, case)
    if renumber:
        check_renumbering(ops, case)
    if continuity:
        check_continuity(ops, case)
    return ops
