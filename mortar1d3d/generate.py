"""Model generators: structured boxes, distorted meshes, fibre cubes and random curved beams.

Everything here is deterministic (a seed in, the same arrays out) and vectorised with numpy:
no Python loop over elements, fibres or nodes, so benchmark scenes build in well under a second.

- :func:`box`: structured mesh of an axis-aligned box for every solid element type, with the
  six face node sets ``x_min`` ... ``z_max``.
- :func:`distort`: a copy of a solid mesh with its interior nodes moved by a smooth field.
- :func:`fibre_cube`: the benchmark scene of docs/conventions.md §5 (the unit cube, straight or helical
  fibres drawn with splitmix64 so that other codes can rebuild the same curves).
- :func:`random_curved_beams`: random helix pieces and arcs inside a box, for tests.
- :func:`fibres_in_box`: straight fibres in any box with length and orientation distributions and
  a minimum spacing; :func:`helices_on_cylinder`: a family of helices on one cylinder;
  :func:`straight_beams`, :func:`helix_beams`: their Hermite meshes (``[[fibres]]`` of a scene
  uses the same generators, one beam per fibre).
- :func:`splitmix64`, :func:`splitmix64_uniforms`: the random stream of docs/conventions.md §5.
"""
import numpy as np

from .elements.solid.dispatch import NODAL_ELEMENTS as SOLID_ELEMENTS
from .elements.solid.dispatch import SOLID_MODULES
from .mesh import BeamMesh, SolidMesh

__all__ = ["box", "distort", "fibre_cube", "random_curved_beams", "splitmix64", "splitmix64_uniforms",
           "fibres_in_box", "helices_on_cylinder", "straight_beams", "helix_beams", "helical_fibres",
           "segment_distances",
           "FIBRE_LENGTH", "FIBRE_MARGIN", "HELIX_RADIUS", "HELIX_TURNS", "FACE_SETS"]

# docs/conventions.md §5: fixed so that every code builds the same scene from (n, fibres, m, curved, seed)
FIBRE_LENGTH = 0.3      # L: axial length of every fibre
FIBRE_MARGIN = 0.02     # gap between a fibre's bounding box and the cube faces
HELIX_RADIUS = 0.03     # R of the curved fibres
HELIX_TURNS = 2         # turns of the curved fibres

#: Names of the face node sets of :func:`box`, in the order (axis, side).
FACE_SETS = ("x_min", "x_max", "y_min", "y_max", "z_min", "z_max")

_MASK64 = (1 << 64) - 1
_SPLITMIX_GAMMA = np.uint64(0x9E3779B97F4A7C15)
_SPLITMIX_M1 = np.uint64(0xBF58476D1CE4E5B9)
_SPLITMIX_M2 = np.uint64(0x94D049BB133111EB)


# -- random stream (docs/conventions.md §5) ------------------------------------------------------------

def splitmix64(seed, count):
    """The first ``count`` outputs of splitmix64 started from ``state = seed``.

    Each draw does ``state += 0x9E3779B97F4A7C15; z = state; z = (z ^ z>>30) * 0xBF58476D1CE4E5B9;
    z = (z ^ z>>27) * 0x94D049BB133111EB; z ^= z>>31`` with 64-bit wrap-around. Since the state
    only ever grows by the constant, draw k (1-based) starts from ``seed + k * gamma mod 2^64``,
    which lets all draws be computed at once.

    Parameters
    ----------
    seed : int
        Any Python integer; taken modulo 2^64.
    count : int

    Returns
    -------
    (count,) uint64
    """
    state = np.uint64(int(seed) & _MASK64)
    # numpy uint64 array arithmetic wraps modulo 2^64 silently, which is exactly the C semantics
    z = state + np.arange(1, int(count) + 1, dtype=np.uint64) * _SPLITMIX_GAMMA
    z = (z ^ (z >> np.uint64(30))) * _SPLITMIX_M1
    z = (z ^ (z >> np.uint64(27))) * _SPLITMIX_M2
    return z ^ (z >> np.uint64(31))


def splitmix64_uniforms(seed, count):
    """Uniform values ``(z >> 11) * 2^-53`` in [0, 1) of the first ``count`` splitmix64 draws.

    Returns
    -------
    (count,) float64
        Exact: ``z >> 11`` has 53 bits, so the conversion to float64 does not round.
    """
    return (splitmix64(seed, count) >> np.uint64(11)).astype(np.float64) * 2.0 ** -53


# -- curves ------------------------------------------------------------------------------------

def _helix_frame(d):
    """Unit vectors e1, e2 normal to the unit axes ``d`` (k, 3), as docs/conventions.md §5 defines them.

    ``e1 = normalize(d × e*)`` with ``e* = e_x`` if ``|d_x| < 0.9`` else ``e_y`` (far from
    parallel to d, so the cross product is well conditioned); ``e2 = d × e1``.
    """
    helper = np.zeros_like(d)
    use_x = np.abs(d[:, 0]) < 0.9
    helper[use_x, 0] = 1.0
    helper[~use_x, 1] = 1.0
    e1 = np.cross(d, helper)
    e1 /= np.linalg.norm(e1, axis=1)[:, None]
    return e1, np.cross(d, e1)


def _helices(centres, axes, length, radius, turns, phase, n_elements):
    """Nodes and unit tangents of helices sampled at ``s = i / n_elements``, i = 0..n_elements.

    Helix k: ``c + (s - 1/2) length d + radius (cos θ e1 + sin θ e2)``, ``θ = phase + 2π turns s``,
    s ∈ [0, 1]. Per-helix parameters are arrays of shape (k,) (``centres``, ``axes``: (k, 3));
    ``radius = 0`` gives a straight segment with tangent d.

    Returns
    -------
    positions, tangents : (k * (n_elements + 1), 3) float64
        Helix k owns rows ``k (n_elements + 1)`` ... ``k (n_elements + 1) + n_elements``.
    """
    k = len(centres)
    s = np.arange(n_elements + 1) / n_elements                                  # (p,)
    length, radius, turns, phase = (np.broadcast_to(np.asarray(v, dtype=np.float64), (k,))[:, None]
                                    for v in (length, radius, turns, phase))     # (k, 1)
    e1, e2 = _helix_frame(axes)
    theta = phase + 2.0 * np.pi * turns * s                                      # (k, p)
    cos, sin = np.cos(theta)[..., None], np.sin(theta)[..., None]
    r = radius[..., None]
    positions = (centres[:, None, :] + ((s - 0.5) * length)[..., None] * axes[:, None, :]
                 + r * (cos * e1[:, None, :] + sin * e2[:, None, :]))
    tangents = (length[..., None] * axes[:, None, :]
                + (2.0 * np.pi * turns)[..., None] * r * (cos * e2[:, None, :] - sin * e1[:, None, :]))
    tangents /= np.linalg.norm(tangents, axis=2)[..., None]
    return positions.reshape(-1, 3), tangents.reshape(-1, 3)


def _chain_elements(n_curves, n_elements):
    """(n_curves * n_elements, 2) node ids: curve f uses nodes f (m+1) ... f (m+1) + m, in order."""
    first = (np.arange(n_curves)[:, None] * (n_elements + 1) + np.arange(n_elements)[None, :]).ravel()
    return np.column_stack([first, first + 1])


def fibre_cube(n, fibres, elements_per_fibre, curved=False, seed=12345):
    """The benchmark scene of docs/conventions.md §5: fibres in the unit cube meshed with n³ hex8.

    Every fibre draws six splitmix64 uniforms u0..u5 (in this order, fibre after fibre, from
    ``state = seed``): centre ``c_k = a + (1 - 2a) u_k`` (k = 0, 1, 2) with
    ``a = L/2 + 0.02`` (``+ R`` if curved), axis ``d = (√(1-z²) cos φ, √(1-z²) sin φ, z)`` with
    ``z = 2 u3 - 1``, ``φ = 2π u4``. A straight fibre has nodes ``c + (i/m - 1/2) L d``,
    i = 0..m, and tangents d. A curved fibre is a helix of radius R = 0.03 with two turns around
    the same axis (same axial extent L, centred at c), phase ``2π u5``:
    ``c + (s - 1/2) L d + R (cos θ e1 + sin θ e2)``, ``θ = 2π u5 + 4π s``, nodes at ``s = i/m``,
    tangents the normalised derivative; ``e1 = normalize(d × e*)`` (``e* = e_x`` if
    ``|d_x| < 0.9`` else ``e_y``), ``e2 = d × e1``. u5 is drawn for straight fibres as well, so
    the straight and curved scenes share their centres and axes.

    The fibres stay inside the cube: a point at axial distance t and radial distance r from the
    fibre's axis lies within ``sqrt(t² + r²)`` of c in every coordinate, which is at most
    ``L/2`` (straight) or ``sqrt(L²/4 + R²) < L/2 + R`` (helix); ``a`` adds 0.02 to that, so all
    nodes and the whole straight centrelines lie in ``[0.02, 0.98]³``. The Hermite interpolant
    of a helix leaves the helix's cylinder by its interpolation error only (at most 0.009 for
    ``elements_per_fibre = 1``, round-off from 3 elements on), which the margin covers: curved
    centrelines lie strictly inside the cube as well. The Hermite length of a helix converges
    like m⁻⁴: relative error 1.3e-4 at m = 20, below 1e-4 from m = 24 on. Fibres may cross
    each other; they do not interact.

    Parameters
    ----------
    n : int
        Hexahedra per cube edge (the solid is ``box((0, 0, 0), (1, 1, 1), (n, n, n))``).
    fibres : int
        Number of fibres, >= 1.
    elements_per_fibre : int
        Hermite elements per fibre (m), >= 1.
    curved : bool
        Helices instead of straight fibres.
    seed : int
        Initial splitmix64 state.

    Returns
    -------
    beams : BeamMesh
        One Hermite mesh of ``fibres * (m + 1)`` nodes and ``fibres * m`` elements; fibre f
        uses nodes ``f (m+1)`` ... ``f (m+1) + m``, elements are in fibre order.
    solid : SolidMesh
        n³ ``hexahedron`` elements with the face sets of :func:`box`.
    """
    n, fibres, m = int(n), int(fibres), int(elements_per_fibre)
    if fibres < 1 or m < 1:
        raise ValueError(f"fibre_cube: need fibres >= 1 and elements_per_fibre >= 1, got {fibres}, {m}")
    L, R = FIBRE_LENGTH, HELIX_RADIUS
    u = splitmix64_uniforms(seed, 6 * fibres).reshape(fibres, 6)
    a = L / 2 + FIBRE_MARGIN + (R if curved else 0.0)
    centres = a + (1.0 - 2.0 * a) * u[:, :3]
    z = 2.0 * u[:, 3] - 1.0
    phi = 2.0 * np.pi * u[:, 4]
    rho = np.sqrt(1.0 - z * z)
    axes = np.column_stack([rho * np.cos(phi), rho * np.sin(phi), z])
    if curved:
        positions, tangents = _helices(centres, axes, L, R, HELIX_TURNS, 2.0 * np.pi * u[:, 5], m)
    else:
        # the §5 formula itself (not the helix with R = 0), so other codes match to the last bit
        s = np.arange(m + 1) / m
        positions = (centres[:, None, :] + ((s - 0.5) * L)[None, :, None] * axes[:, None, :]).reshape(-1, 3)
        tangents = np.repeat(axes, m + 1, axis=0)
    beams = BeamMesh.hermite(positions, tangents, _chain_elements(fibres, m))
    return beams, box((0.0, 0.0, 0.0), (1.0, 1.0, 1.0), (n, n, n))


def random_curved_beams(count, elements, seed=0, lower=(0.0, 0.0, 0.0), upper=(1.0, 1.0, 1.0)):
    """Random smooth curves (helix pieces and circular arcs) inside a box, as Hermite beams.

    Curve k is a helix ``c + (s - 1/2) h d + R (cos θ e1 + sin θ e2)``, ``θ = θ0 + 2π t s``,
    s ∈ [0, 1], with a random unit axis d, radius ``R ∈ [0.05, 0.15] e``, axial length
    ``h ∈ [0, 0.5] e`` (small h: nearly planar arcs), ``t ∈ [0.25, 1.5]`` turns and phase θ0,
    where e is the shortest box edge; all drawn with ``numpy.random.default_rng(seed)``. The
    centre is drawn so that every point of the curve keeps ``0.05 e`` from the box faces (each
    coordinate stays within ``h/2 + R`` of c); the Hermite interpolant stays inside the box for
    ``elements >= 3``.

    Parameters
    ----------
    count : int
        Number of curves, >= 1.
    elements : int
        Hermite elements per curve (m), >= 1.
    seed : int
    lower, upper : (3,) array_like of float
        Box corners, ``upper > lower``.

    Returns
    -------
    BeamMesh
        Hermite mesh with ``count * (m + 1)`` nodes; curve k uses nodes ``k (m+1)`` ...
        ``k (m+1) + m`` (layout as in :func:`fibre_cube`).
    """
    count, m = int(count), int(elements)
    if count < 1 or m < 1:
        raise ValueError(f"random_curved_beams: need count >= 1 and elements >= 1, got {count}, {m}")
    lower, upper = _box_corners(lower, upper)
    e = float((upper - lower).min())
    rng = np.random.default_rng(seed)
    radius = e * rng.uniform(0.05, 0.15, count)
    height = e * rng.uniform(0.0, 0.5, count)
    turns = rng.uniform(0.25, 1.5, count)
    phase = rng.uniform(0.0, 2.0 * np.pi, count)
    axes = rng.normal(size=(count, 3))
    axes /= np.linalg.norm(axes, axis=1)[:, None]
    reach = 0.5 * height + radius + 0.05 * e                                     # (count,)
    centres = lower + reach[:, None] + (upper - lower - 2.0 * reach[:, None]) * rng.uniform(size=(count, 3))
    positions, tangents = _helices(centres, axes, height, radius, turns, phase, m)
    return BeamMesh.hermite(positions, tangents, _chain_elements(count, m))


# -- structured solid meshes -------------------------------------------------------------------

def _box_corners(lower, upper):
    lower = np.asarray(lower, dtype=np.float64).reshape(3)
    upper = np.asarray(upper, dtype=np.float64).reshape(3)
    if not (np.isfinite(lower).all() and np.isfinite(upper).all() and (upper > lower).all()):
        raise ValueError(f"box: need finite corners with upper > lower, got {lower}, {upper}")
    return lower, upper


def _corner_weights(name):
    """(n_nodes, n_corners) linear shape functions of the family's corners at the nodes of ``name``.

    A node of a straight-sided element sits at this average of the corners; on the doubled
    lattice of quadratic elements the averages are integers (mid-edge, face and cell centres).
    The family's linear element (its type of degree 1) gives the functions.
    """
    descriptor = SOLID_ELEMENTS[name]
    linear = next(n for n, d in SOLID_ELEMENTS.items() if d.family_type is descriptor.family_type and d.degree == 1)
    shape = SOLID_MODULES[linear].shape.py_func      # pure Python: nothing compiles here
    W = np.empty((descriptor.n_nodes, SOLID_ELEMENTS[linear].n_nodes))
    for a, xi in enumerate(descriptor.reference_nodes):
        shape(xi, W[a])
    return W


def box(lower, upper, cells, element="hexahedron"):
    """Structured mesh of the box ``[lower, upper]`` with ``cells = (nx, ny, nz)`` grid cells.

    Every grid cell is filled by the elements of the family's ``cube_split``
    (:class:`~mortar1d3d.elements.descriptor.ElementFamily`), the same in every cell, so that
    neighbours conform: e.g. one hexahedron, or six tetrahedra (the Kuhn split along the cell
    diagonal from its lower to its upper corner). Nodes are shared, never duplicated. Quadratic
    elements take their nodes from the lattice of ``(2nx+1) x (2ny+1) x (2nz+1)`` points (half the
    cell size); lattice points no element uses (face and cell centres for ``hexahedron20``) are
    left out.

    Node numbering: lattice order, x fastest, then y, then z (compacted where points are left
    out). Element numbering: cells in the same order (x fastest), the elements of a cell
    consecutive. Node counts, e.g.: hex8 and tetra ``(nx+1)(ny+1)(nz+1)``; hex27 and tetra10
    ``(2nx+1)(2ny+1)(2nz+1)`` (the Kuhn split uses every lattice point: a face diagonal per
    face, the body diagonal per cell); hex20 ``(nx+1)(ny+1)(nz+1) + nx(ny+1)(nz+1) +
    (nx+1)ny(nz+1) + (nx+1)(ny+1)nz``.

    Parameters
    ----------
    lower, upper : (3,) array_like of float
        Box corners, ``upper > lower``.
    cells : (3,) sequence of int
        Grid cells per direction, each >= 1.
    element : str
        meshio name of the element type.

    Returns
    -------
    SolidMesh
        With ``point_sets`` ``x_min``, ``x_max``, ``y_min``, ``y_max``, ``z_min``, ``z_max``:
        sorted int64 ids of the nodes on each face of the box.
    """
    lower, upper = _box_corners(lower, upper)
    cells = np.asarray(cells).reshape(3)
    if not (np.issubdtype(cells.dtype, np.integer) and (cells >= 1).all()):
        raise ValueError(f"box: cells must be three integers >= 1, got {cells}")
    if element not in SOLID_ELEMENTS:
        raise ValueError(f"box: unknown element type {element!r}; known types: {', '.join(SOLID_ELEMENTS)}")
    nx, ny, nz = (int(c) for c in cells)
    descriptor = SOLID_ELEMENTS[element]
    scale = descriptor.degree            # lattice intervals per cell edge (1 linear, 2 quadratic)
    size = scale * np.array([nx, ny, nz]) + 1

    # Every cell is meshed alike, so the nodes' lattice offsets from the cell's lower corner are
    # computed once, for the elements of one cell (1 hex, 6 tets, ...): linear interpolation of
    # the element corners at the reference nodes. The weights are multiples of 1/8 (products of
    # at most three 1/2's), so integer arithmetic on 8 W is exact.
    family = descriptor.family_type
    corners = family.cube_split                            # (elements per cube, n_corners, 3)
    W = _corner_weights(element)
    W8 = np.rint(8 * W).astype(np.int64)
    offsets = (W8 @ (scale * corners)) // 8                                     # (per cell, n_nodes, 3)
    strides = np.array([1, size[0], size[0] * size[1]])
    # lower corner of every cell (x fastest) as a lattice id, plus the node offsets
    c = np.arange(nx * ny * nz)
    cell_base = scale * np.column_stack([c % nx, (c // nx) % ny, c // (nx * ny)]) @ strides
    ids = (cell_base[:, None, None] + (offsets @ strides)[None]).reshape(-1, descriptor.n_nodes)

    # keep only the lattice points in use, renumbered in lattice order
    used = np.zeros(int(np.prod(size)), dtype=bool)
    used[ids] = True
    kept = np.flatnonzero(used)
    new_id = np.cumsum(used) - 1
    connectivity = new_id[ids]
    I = np.column_stack([kept % size[0], (kept // size[0]) % size[1], kept // (size[0] * size[1])])

    # linspace hits both corners exactly, so the face nodes lie exactly on the face planes
    axes = [np.linspace(lower[k], upper[k], size[k]) for k in range(3)]
    points = np.column_stack([axes[k][I[:, k]] for k in range(3)])
    point_sets = {}
    for k, axis in enumerate("xyz"):
        point_sets[f"{axis}_min"] = np.flatnonzero(I[:, k] == 0)
        point_sets[f"{axis}_max"] = np.flatnonzero(I[:, k] == size[k] - 1)
    return SolidMesh(points, {element: connectivity}, point_sets=point_sets)


# -- distortion --------------------------------------------------------------------------------

def distort(solid, amplitude=0.1, seed=0):
    """A copy of ``solid`` with its interior nodes moved by a smooth deterministic field.

    Node x moves by ``amplitude * h ⊙ g(x) * ramp(x)``, where h (3,) is the cell size per
    direction (the smallest element extent along each axis), every component of g is a sum of
    three sines of random direction, phase and wavelength (6 to 12 cells; weights sum to one, so
    ``|g_i| <= 1``), and ``ramp = min(1, distance to the bounding box / h)`` (per direction)
    fades the motion out towards the boundary. Nodes on the bounding box faces do not move, so
    the box keeps its faces, volume and point sets. The displacement gradient stays below about
    ``2 * amplitude`` (in cell units), so the mesh remains valid up to ``amplitude ≈ 0.2``;
    inverted elements raise :class:`~mortar1d3d.errors.MeshError` as in :class:`SolidMesh`.

    Parameters
    ----------
    solid : SolidMesh
    amplitude : float
        Largest displacement per component, relative to the cell size.
    seed : int
        Seed of ``numpy.random.default_rng`` for the field's directions, phases, wavelengths.

    Returns
    -------
    SolidMesh
        Same cells and point sets, moved points.
    """
    X = solid.points
    lo, hi = X.min(axis=0), X.max(axis=0)
    h = np.full(3, np.inf)
    for d, conn in solid.blocks:
        P = X[conn]
        h = np.minimum(h, (P.max(axis=1) - P.min(axis=1)).min(axis=0))
    h = np.where(h > 0, h, hi - lo)            # a flat direction (no extent) has nothing to distort
    rng = np.random.default_rng(seed)
    n_waves = 3
    directions = rng.normal(size=(3, n_waves, 3))
    directions /= np.linalg.norm(directions, axis=2)[..., None]
    wavenumber = 2.0 * np.pi / rng.uniform(6.0, 12.0, size=(3, n_waves))     # radians per cell
    phase = rng.uniform(0.0, 2.0 * np.pi, size=(3, n_waves))
    weight = rng.uniform(0.5, 1.0, size=(3, n_waves))
    weight /= weight.sum(axis=1)[:, None]
    Y = (X - lo) / h                                                            # cell units
    arg = np.einsum("iwk,nk->niw", directions * wavenumber[..., None], Y) + phase
    g = np.einsum("niw,iw->ni", np.sin(arg), weight)                            # (n_nodes, 3)
    distance = np.minimum(X - lo, hi - X) / h                                   # cell units per axis
    ramp = np.clip(distance.min(axis=1), 0.0, 1.0)
    on_boundary = ((np.abs(X - lo) <= 1e-12 * (hi - lo)) | (np.abs(hi - X) <= 1e-12 * (hi - lo))).any(axis=1)
    ramp[on_boundary] = 0.0
    points = X + amplitude * h * g * ramp[:, None]
    return SolidMesh(points, solid.cells, point_sets=solid.point_sets)


# -- fibre families for scenes (random straight fibres in a box, helices on a cylinder) ---------

def _draw(spec, rng, count, what):
    """``count`` values of a length distribution: a number, ``{"uniform": [a, b]}`` or
    ``{"normal": [mean, std]}`` (redrawn until positive)."""
    if isinstance(spec, dict):
        if len(spec) != 1 or next(iter(spec)) not in ("uniform", "normal"):
            raise ValueError(f"{what}: expected a number, {{uniform = [a, b]}} or {{normal = [mean, std]}}, got {spec!r}")
        kind, (p, q) = next(iter(spec.items()))
        if kind == "uniform":
            if not 0.0 < p <= q:
                raise ValueError(f"{what}.uniform: expected 0 < a <= b, got [{p}, {q}]")
            return rng.uniform(p, q, count)
        if not (p > 0.0 and q >= 0.0):
            raise ValueError(f"{what}.normal: expected mean > 0 and std >= 0, got [{p}, {q}]")
        out = rng.normal(p, q, count)
        while (bad := out <= 0.0).any():
            out[bad] = rng.normal(p, q, int(bad.sum()))
        return out
    value = float(spec)
    if not value > 0.0:
        raise ValueError(f"{what}: expected a number > 0, got {spec!r}")
    return np.full(count, value)


def _directions(spec, rng, count):
    """``count`` unit vectors: ``"isotropic"`` (uniform on the sphere), a vector (all along it), or
    ``{"direction": d, "spread": degrees}`` (uniform over the cap of that half-angle around d)."""
    if isinstance(spec, str):
        if spec != "isotropic":
            raise ValueError(f"orientation: expected 'isotropic', a direction or {{direction, spread}}, got {spec!r}")
        axis, cos_min = np.array([0.0, 0.0, 1.0]), -1.0
    elif isinstance(spec, dict):
        axis, cos_min = np.asarray(spec["direction"], dtype=float), np.cos(np.radians(float(spec.get("spread", 0.0))))
    else:
        axis, cos_min = np.asarray(spec, dtype=float), 1.0
    norm = np.linalg.norm(axis)
    if axis.shape != (3,) or not norm > 0.0:
        raise ValueError(f"orientation: the direction must be a non-zero 3-vector, got {axis}")
    axis = axis / norm
    # uniform on a spherical cap: the cosine to the axis is uniform in [cos_min, 1]
    c = rng.uniform(cos_min, 1.0, count)
    phi = rng.uniform(0.0, 2.0 * np.pi, count)
    s = np.sqrt(np.maximum(1.0 - c * c, 0.0))
    e1, e2 = _helix_frame(axis[None, :])
    return c[:, None] * axis + s[:, None] * (np.cos(phi)[:, None] * e1 + np.sin(phi)[:, None] * e2)


def segment_distances(p, q, a, b):
    """Shortest distances between the segment [p, q] (3,) and each segment [a_k, b_k] (k, 3).

    Minimises ``|p + s (q - p) - a - t (b - a)|`` over s, t ∈ [0, 1] (both segments of non-zero
    length): s from the unconstrained optimum clamped to [0, 1] (0 for parallel segments), t
    optimal for that s; where t had to be clamped, s is re-optimised for the clamped t.
    """
    d1, d2, r = q - p, b - a, p[None, :] - a          # r: (k, 3)
    A, E = d1 @ d1, np.einsum("ki,ki->k", d2, d2)
    B, C, F = d2 @ d1, r @ d1, np.einsum("ki,ki->k", d2, r)
    den = A * E - B * B
    s = np.where(den > 1e-14 * A * E, np.clip((B * F - C * E) / np.where(den > 0, den, 1.0), 0.0, 1.0), 0.0)
    t_free = (B * s + F) / E
    t = np.clip(t_free, 0.0, 1.0)
    s = np.where(t != t_free, np.clip((B * t - C) / A, 0.0, 1.0), s)
    return np.linalg.norm(r + s[:, None] * d1[None, :] - t[:, None] * d2, axis=1)


def fibres_in_box(count, lower, upper, length=0.3, orientation="isotropic", min_spacing=0.0, seed=0,
                  max_attempts=1000):
    """Straight fibres placed at random inside a box, with length and orientation distributions and
    a minimum distance between any two fibres.

    Each candidate draws its length, its direction and then its centre, uniformly among the
    centres that keep the whole fibre inside ``[lower, upper]``; a candidate closer than
    ``min_spacing`` to an accepted fibre (shortest distance between the two segments) is
    rejected and drawn again (random sequential adsorption). Drawn with
    ``numpy.random.default_rng(seed)``: the same arguments give the same fibres.

    Parameters
    ----------
    count : int
        Number of fibres, >= 1.
    lower, upper : (3,) array_like of float
        Box corners, ``upper > lower`` (length units).
    length : float or dict
        A length, ``{"uniform": [a, b]}`` or ``{"normal": [mean, std]}`` (redrawn until > 0).
    orientation : str, (3,) array_like or dict
        ``"isotropic"`` (uniform on the sphere), a direction (all fibres parallel), or
        ``{"direction": d, "spread": degrees}`` (uniform within that angle of d).
    min_spacing : float
        Smallest distance between the centrelines of two fibres, >= 0.
    seed : int
    max_attempts : int
        Candidates drawn per fibre before giving up.

    Returns
    -------
    (count, 2, 3) float64
        Start and end point of every fibre.

    Raises
    ------
    ValueError
        A fibre longer than fits in the box, or fewer than ``count`` fibres placed within
        ``count * max_attempts`` candidates (the message says how many fitted).
    """
    count = int(count)
    if count < 1:
        raise ValueError(f"fibres_in_box: need count >= 1, got {count}")
    lower, upper = _box_corners(lower, upper)
    if not min_spacing >= 0.0:
        raise ValueError(f"fibres_in_box: min_spacing must be >= 0, got {min_spacing}")
    rng = np.random.default_rng(seed)
    size = upper - lower
    placed = np.empty((count, 2, 3))
    n, attempts, batch = 0, 0, max(count, 16)
    while n < count and attempts < count * max_attempts:
        L = _draw(length, rng, batch, "length")
        d = _directions(orientation, rng, batch)
        half = 0.5 * L[:, None] * np.abs(d)                              # half extent per axis
        room = size - 2.0 * half
        u = rng.uniform(size=(batch, 3))
        for k in range(batch):
            attempts += 1
            if (room[k] < 0.0).any():
                continue
            centre = lower + half[k] + room[k] * u[k]
            p, q = centre - 0.5 * L[k] * d[k], centre + 0.5 * L[k] * d[k]
            if min_spacing > 0.0 and n and segment_distances(p, q, placed[:n, 0], placed[:n, 1]).min() < min_spacing:
                continue
            placed[n] = p, q
            n += 1
            if n == count or attempts >= count * max_attempts:
                break
    if n < count:
        raise ValueError(f"fibres_in_box: placed {n} of {count} fibres in {attempts} attempts; lower min_spacing "
                         f"({min_spacing:g}), the count or the lengths, or enlarge the box")
    return placed


def helices_on_cylinder(count, centre, axis, radius, length, turns, phase=0.0):
    """A family of ``count`` helices wound on one cylinder, evenly shifted in phase (like the
    strands of a rope or the wires of a helical reinforcement).

    Helix k is the curve of :func:`fibre_cube`'s helices with phase ``phase + 2π k / count``:
    ``c + (s - 1/2) length d + radius (cos θ e1 + sin θ e2)``, ``θ = phase_k + 2π turns s``.

    Parameters
    ----------
    count : int
        Number of helices, >= 1.
    centre, axis : (3,) array_like of float
        Centre of the cylinder's axis segment and its direction (normalised here).
    radius, length : float
        Cylinder radius and axial length (> 0).
    turns : float
        Turns of every helix over ``length`` (negative: left-handed, the other family of a ±α
        winding; the winding angle from the axis is arctan(2π radius abs(turns) / length)).
    phase : float
        Phase of helix 0 in radians.

    Returns
    -------
    list of dict
        One ``{"centre", "axis", "radius", "length", "turns", "phase"}`` per helix: the
        ``helix`` curve of a scene beam (docs/scene_reference.md); :func:`helix_beams` meshes them.
    """
    count = int(count)
    if count < 1 or not (radius > 0 and length > 0 and np.isfinite(turns)):
        raise ValueError(f"helices_on_cylinder: need count >= 1, radius > 0, length > 0, finite turns, got "
                         f"{count}, {radius}, {length}, {turns}")
    axis = np.asarray(axis, dtype=float)
    axis = axis / np.linalg.norm(axis)
    centre = np.asarray(centre, dtype=float)
    return [{"centre": centre.copy(), "axis": axis.copy(), "radius": float(radius), "length": float(length),
             "turns": float(turns), "phase": float(phase) + 2.0 * np.pi * k / count} for k in range(count)]


def straight_beams(endpoints, elements):
    """Hermite beams along straight fibres (e.g. from :func:`fibres_in_box`).

    Parameters
    ----------
    endpoints : (k, 2, 3) array_like of float
    elements : int
        Elements per fibre (m), >= 1.

    Returns
    -------
    BeamMesh
        Fibre f uses nodes ``f (m+1)`` ... ``f (m+1) + m`` (layout as in :func:`fibre_cube`).
    """
    P = np.asarray(endpoints, dtype=float).reshape(-1, 2, 3)
    m = int(elements)
    s = np.arange(m + 1) / m
    positions = (P[:, :1] + s[None, :, None] * (P[:, 1:] - P[:, :1])).reshape(-1, 3)
    d = P[:, 1] - P[:, 0]
    tangents = np.repeat(d / np.linalg.norm(d, axis=1)[:, None], m + 1, axis=0)
    return BeamMesh.hermite(positions, tangents, _chain_elements(len(P), m))


def helix_beams(helices, elements):
    """Hermite beams along helices given as dicts (e.g. from :func:`helices_on_cylinder`).

    Returns
    -------
    BeamMesh
        Helix k uses nodes ``k (m+1)`` ... ``k (m+1) + m`` (layout as in :func:`fibre_cube`).
    """
    m = int(elements)
    get = lambda key: np.array([h[key] for h in helices], dtype=float)      # noqa: E731
    positions, tangents = _helices(get("centre"), get("axis"), get("length"), get("radius"), get("turns"),
                                   get("phase"), m)
    return BeamMesh.hermite(positions, tangents, _chain_elements(len(helices), m))


def helical_fibres(radius, length, angle, count, elements, phase=0.0, z0=0.0):
    """One family of helical fibres in a pipe wall about the z axis, as Hermite beams with exact nodes and
    tangents (a winding of a filament-wound pipe).

    Fibre k: ``x(z) = (radius cos φ, radius sin φ, z)``, ``φ = phase + 2π k / count + (z - z0) tan(angle) / radius``
    for ``z0 <= z <= z0 + length``: a helix at ``angle`` from the axis (the winding angle α;
    ``tan α = radius dφ/dz``). ``angle > 0`` winds counter-clockwise seen from +z as z grows
    (right-handed), ``angle < 0`` clockwise: the two families of a ±α winding.

    Parameters
    ----------
    radius, length : float
        Radius of the fibres' cylinder and axial length (m), both > 0.
    angle : float
        Winding angle α in degrees, 0 < abs(α) < 90.
    count : int
        Fibres of the family (>= 1), evenly spaced in phase.
    elements : int
        Hermite elements per fibre (>= 1), equal steps in z.
    phase : float
        Angle (radians, from the x axis) of fibre 0 at ``z0``.
    z0 : float
        Axial start of the fibres.

    Returns
    -------
    BeamMesh
        Fibre k uses nodes ``k (m+1)`` ... ``k (m+1) + m`` (m = ``elements``), starting at ``z0``. The
        nodes lie on the cylinder and the tangents make the angle α with the axis, both to
        round-off; between the nodes the cubic Hermite centreline approximates the helix.
    """
    radius, length, angle = float(radius), float(length), float(angle)
    count, m = int(count), int(elements)
    if not (radius > 0 and length > 0 and 0.0 < abs(angle) < 90.0 and count >= 1 and m >= 1):
        raise ValueError(f"helical_fibres: need radius > 0, length > 0, 0 < |angle| < 90 degrees, count >= 1, "
                         f"elements >= 1, got {radius}, {length}, {angle}, {count}, {m}")
    tan_a = np.tan(np.radians(angle))
    z = float(z0) + length * np.arange(m + 1) / m
    phi = float(phase) + 2.0 * np.pi * np.arange(count)[:, None] / count + ((z - float(z0)) * tan_a / radius)[None, :]
    cos, sin = np.cos(phi).ravel(), np.sin(phi).ravel()
    positions = np.column_stack([radius * cos, radius * sin, np.tile(z, count)])
    # dx/dz = (-tan α sin φ, tan α cos φ, 1), normalised: cos α (-tan α sin φ, tan α cos φ, 1)
    c, s_ = np.cos(np.radians(angle)), np.sin(np.radians(angle))
    tangents = np.column_stack([-s_ * sin, s_ * cos, np.full(len(cos), c)])
    return BeamMesh.hermite(positions, tangents, _chain_elements(count, m))
