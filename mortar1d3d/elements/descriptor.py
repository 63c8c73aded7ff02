"""Frozen descriptors of element types and families: all a type's data, in one object per type.

An element family (:class:`ElementFamily`: hexahedra, tetrahedra, wedges) fixes the parameter
domain, its faces (each with its :class:`FaceShape`) and the cells of the validity check; an element
type (:class:`SolidElementType`) adds its nodes, shape function space, bounds and volume rule. The
registry (:mod:`mortar1d3d.elements.solid.registry`) lists the types and families;
:mod:`mortar1d3d.elements.solid.dispatch` derives every per-code table and the kernels' dispatch
from these descriptors, so a new type of a known family is one module and one registry line, and
a new family its module, its types' modules and registry lines.
"""
from dataclasses import dataclass, field

import numpy as np


@dataclass(frozen=True, eq=False)
class FaceShape:
    """The parameter domain of a face, ``(u, v)``: a square or a triangle
    (:mod:`~mortar1d3d.elements.solid.face_shapes`). A family's face ``f`` is the image of its shape
    under ``ξ = origin + u a + v b``.

    Attributes
    ----------
    name : str
        ``"quadrilateral"`` or ``"triangle"``.
    corners : (k, 2) float64
        Corners in cyclic order (the order of the family's ``face_nodes``).
    centre : (2,) float64
        Centroid (Newton start of a crossing search on the face).
    rule : callable ``() -> (points (q, 2), weights (q,))``
        Quadrature on the shape (surface loads).
    """

    name: str
    corners: np.ndarray = field(repr=False)
    centre: np.ndarray = field(repr=False)
    rule: object = field(repr=False)

    @property
    def n_corners(self):
        return len(self.corners)


@dataclass(frozen=True, eq=False)
class ElementFamily:
    """A parameter domain shared by several element types (one module per family, e.g.
    :mod:`~mortar1d3d.elements.solid.hex_family`).

    Attributes
    ----------
    name : str
        ``"hex"``, ``"tet"``, ... (what :attr:`SolidElementType.family` says).
    code : int
        Integer code used for dispatch inside kernels (position in the registry's family list).
    faces : (n_faces, 4, 3) float64
        Faces as affine maps of the parameter space: rows ``origin, a, b, outward_normal``;
        the face is ``ξ = origin + u a + v b`` and ``normal·(ξ - origin) > 0`` is outside.
    face_nodes : tuple of tuples
        Corner node ids of each face (VTK order; for output and tests), same order as ``faces``.
    corners : (n_corners, 3) float64
        Vertices of the parameter domain in VTK order (the nodes of the family's linear element).
    centre : (3,) float64
        Centre of the parameter domain (Newton start, expansion point of the bounds).
    outside_distance : numba dispatcher ``(xi) -> float``
        How far ξ lies outside the domain (<= 0 inside), in parameter units.
    box_meets : numba dispatcher ``(m0, m1, m2, r, tol) -> bool``
        Whether the box ``|ξ - m|∞ <= r`` meets ``{ξ : outside_distance(ξ) <= tol}`` (it may say
        True for a box that misses, never False for one that meets).
    face_shapes : tuple of FaceShape
        The (u, v) domain of each face, same order as ``faces``: its corners, centroid and
        quadrature rule (faces of one family may differ, e.g. a wedge's triangles and squares).
    cells : object
        Cells of the validity check (:mod:`mortar1d3d.elements.validity`): ``jacobian_degree``
        (an int, or a tuple of degrees per factor of a product domain: whatever ``lattice`` takes),
        ``lattice``, ``corner_rows``, ``whole``, ``points``, ``take``, ``children`` with
        ``n_children`` children per cell and, where the Bernstein coefficients can be subdivided
        exactly, ``child_coefficients``.
    cube_split : (n, n_corners, 3) int64
        Corner offsets (lattice units) of the n elements that fill a unit cube of a structured
        mesh (:func:`mortar1d3d.generate.box`).
    """

    name: str
    code: int
    faces: np.ndarray = field(repr=False)
    face_nodes: tuple = field(repr=False)
    corners: np.ndarray = field(repr=False)
    centre: np.ndarray = field(repr=False)
    outside_distance: object = field(repr=False)
    box_meets: object = field(repr=False)
    face_shapes: tuple = field(repr=False)
    cells: object = field(repr=False)
    cube_split: np.ndarray = field(repr=False)

    def __post_init__(self):
        counts = [s.n_corners for s in self.face_shapes]
        if not len(self.faces) == len(self.face_nodes) == len(self.face_shapes) or \
                counts != [len(nodes) for nodes in self.face_nodes]:
            raise ValueError(f"{self.name}: faces, face_nodes and face_shapes must agree face by face")

    @property
    def n_faces(self):
        return self.faces.shape[0]

    @property
    def face_centroids(self):
        """(n_faces, 3) parameter coordinates of each face's centroid (its shape's centre mapped)."""
        # the offset first, then the origin: u (a + b) for the equal parameters of a centroid, as
        # the crossing search has always started (the last bit of a Newton start can change a result)
        return np.array([origin + (s.centre[0] * a + s.centre[1] * b)
                         for (origin, a, b, _normal), s in zip(self.faces, self.face_shapes)])


@dataclass(frozen=True, eq=False)
class SolidElementType:
    """Descriptor of a solid (3D) element type.

    Attributes
    ----------
    name : str
        meshio cell type name (``"hexahedron"``, ``"tetra10"``, ...).
    code : int
        Integer code used for dispatch inside kernels.
    n_nodes : int
        Nodes per element (VTK/meshio order).
    degree : int
        Polynomial degree of the interpolation (1 or 2).
    family_type : ElementFamily
        Parameter domain, faces and their shapes (also as the properties ``family`` (its name),
        ``centre``, ``faces``, ``face_nodes``, ``n_faces``).
    reference_nodes : (n_nodes, 3) float64
        Parameter coordinates of the nodes, in VTK/meshio order.
    bounding_matrix : (m, n_nodes) float64
        Maps element nodes to points whose convex hull contains the element
        (Bernstein control points for quadratic elements; identity for linear ones).
    monomials : (n_nodes, 3) int64
        Exponents α of the monomials ξ^α that span the element's shape functions (the same space
        as the shape functions, one monomial per node). The geometry kernels bound the map's
        derivatives with them (point location, :mod:`mortar1d3d.geometry.projection`) and the
        mesh check bounds det J (:mod:`mortar1d3d.mesh`).
    quadrature : tuple of (points (q, 3), weights (q,))
        The volume rule of the solid model (:mod:`mortar1d3d.physics.solid_reference`), from
        :mod:`mortar1d3d.quadrature`.
    rational : bool
        True for rational Bernstein (Bézier) elements: ``shape``/``deriv`` give the polynomial
        Bernstein basis B_a and every node carries a weight w_a; the element's functions are
        R_a = w_a B_a / Σ_b w_b B_b (:func:`mortar1d3d.elements.solid.dispatch.rational_shape`). Their
        nodes are control points, not points of the element.
    hull_test : bool
        Whether the geometry kernels bound this type's elements by planes along their faces
        (:func:`mortar1d3d.geometry.search.solid_hulls`) besides their boxes, to drop candidate pairs and
        skip Newton projections. True unless the planes cost more than they save (hex8: its box is
        tight for a brick-like element, and the planes dropped 6 % of the pairs of the distorted
        benchmark cube while adding 9 % to its kernels' instructions).
    bernstein_error : bool
        Whether the segmentation bounds how far the element's map linearised at its centre strays
        from the map by the Bernstein coefficients of the remainder on the element (``bounding_matrix``
        applied to its monomials, :data:`mortar1d3d.elements.solid.dispatch.BERNSTEIN_MONOMIALS`)
        rather than by its monomial terms summed over the box about the centre
        (:func:`mortar1d3d.geometry.segmentation._linear_error`). True where the box is much larger than
        the element (tet10: the box |ξ - ξ_c|∞ <= 3/4 has 20 times the simplex's volume); the types
        left False keep their bounds, and their counts, unchanged.
    """

    name: str
    code: int
    n_nodes: int
    degree: int
    family_type: ElementFamily
    reference_nodes: np.ndarray = field(repr=False)
    bounding_matrix: np.ndarray = field(repr=False)
    monomials: np.ndarray = field(repr=False)
    quadrature: tuple = field(repr=False)
    dim: int = 3
    rational: bool = False
    hull_test: bool = True
    bernstein_error: bool = False

    def __post_init__(self):
        exps = np.asarray(self.monomials, dtype=np.int64)
        if exps.shape != (self.n_nodes, 3):
            raise ValueError(f"{self.name}: monomials must have shape ({self.n_nodes}, 3), got {exps.shape}")
        object.__setattr__(self, "monomials", exps)

    @property
    def family(self):
        """Name of the element's family (``"hex"``, ``"tet"``, ...)."""
        return self.family_type.name

    @property
    def centre(self):
        return self.family_type.centre

    @property
    def faces(self):
        return self.family_type.faces

    @property
    def face_nodes(self):
        return self.family_type.face_nodes

    @property
    def line_degree(self):
        """Degree in η of N_a(ξ(η)) along a straight line (ξ affine in η): the largest total degree
        of the element's monomials (e.g. hex8 3, hex27 6, tet4 1, tet10 2)."""
        return int(self.monomials.sum(axis=1).max())

    @property
    def parameter_box(self):
        """(2, 3) lower and upper corner of the box spanned by the reference nodes."""
        return np.stack([self.reference_nodes.min(axis=0), self.reference_nodes.max(axis=0)])

    @property
    def jacobian_degree(self):
        """Polynomial degree of det J for this element's shape functions, as the family's validity
        cells count it: per direction on a box (det J ∈ Q_p), total on a simplex (P_p), one degree
        per factor on a product of such domains. A rational element's check uses W⁴ det J, the
        determinant of the homogeneous Jacobian [[W, ∇W], [X̃, ∇X̃]]: degree 4p - 1 per direction
        for tensor degree p."""
        if self.rational:
            return 4 * int(self.monomials.max()) - 1
        return self.family_type.cells.jacobian_degree(self.monomials)

    @property
    def n_faces(self):
        return self.faces.shape[0]


@dataclass(frozen=True)
class BeamElementType:
    """Descriptor of a beam centreline interpolation ``r(η) = Σ_k H_k(η; L) q_k``, η ∈ [-1, 1].

    Attributes
    ----------
    name : str
        ``"hermite"``, ``"line"``, ``"line3"`` (meshio's names for the Lagrange lines).
    code : int
        Integer code used for dispatch inside kernels (position in
        :mod:`mortar1d3d.elements.beam.registry`).
    n_nodes : int
        Nodes per element.
    n_functions : int
        Vector coefficients q_k per element.
    dofs_per_node : int
        Centreline DOFs per node (3 per vector a node carries).
    function_node, function_offset : tuple of int
        Coefficient k belongs to local node ``function_node[k]`` and starts at DOF offset
        ``function_offset[k]`` within that node's block (offset 3: a tangent).
    degree : int
        Polynomial degree of the functions in η (exact Gauss counts of ``integration="auto"``).
    """

    name: str
    code: int
    n_nodes: int
    n_functions: int
    dofs_per_node: int
    function_node: tuple
    function_offset: tuple
    degree: int

    @property
    def has_tangents(self):
        """True when some coefficients are nodal tangents (DOF offset 3 in their node's block)."""
        return any(offset > 0 for offset in self.function_offset)
