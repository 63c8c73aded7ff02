"""Frozen descriptors of element types (what Python code needs to know about an element)."""
from dataclasses import dataclass, field

import numpy as np


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
    family : str
        ``"hex"`` (parameter space [-1, 1]^3) or ``"tet"`` (ξ_i >= 0, Σξ_i <= 1).
    reference_nodes : (n_nodes, 3) float64
        Parameter coordinates of the nodes, in VTK/meshio order.
    centre : (3,) float64
        Start point of Newton iterations (element centre in parameter space).
    faces : (n_faces, 4, 3) float64
        Faces as affine maps of the parameter space: rows ``origin, a, b, outward_normal``;
        the face is ``ξ = origin + u a + v b`` and ``normal·(ξ - origin) > 0`` is outside.
    face_nodes : tuple of tuples
        Corner node ids of each face (for output and tests), same order as ``faces``.
    bounding_matrix : (m, n_nodes) float64
        Maps element nodes to points whose convex hull contains the element
        (Bernstein control points for quadratic elements; identity for linear ones).
    monomials : (n_nodes, 3) int64
        Exponents α of the monomials ξ^α that span the element's shape functions (the same space
        as the shape functions, one monomial per node). The geometry kernels bound the map's
        derivatives with them (point location, :mod:`mortar1d3d.geometry.projection`) and the
        mesh check bounds det J (:mod:`mortar1d3d.mesh`).
    """

    name: str
    code: int
    n_nodes: int
    degree: int
    family: str
    reference_nodes: np.ndarray = field(repr=False)
    centre: np.ndarray = field(repr=False)
    faces: np.ndarray = field(repr=False)
    face_nodes: tuple = field(repr=False)
    bounding_matrix: np.ndarray = field(repr=False)
    monomials: np.ndarray = field(repr=False, default=None)
    dim: int = 3

    def __post_init__(self):
        exps = np.asarray(self.monomials, dtype=np.int64)
        if exps.shape != (self.n_nodes, 3):
            raise ValueError(f"{self.name}: monomials must have shape ({self.n_nodes}, 3), got {exps.shape}")
        object.__setattr__(self, "monomials", exps)

    @property
    def parameter_box(self):
        """(2, 3) lower and upper corner of the box spanned by the reference nodes."""
        return np.stack([self.reference_nodes.min(axis=0), self.reference_nodes.max(axis=0)])

    @property
    def jacobian_degree(self):
        """Polynomial degree of det J: per direction for hexahedra (det J ∈ Q_p), total for tetrahedra (P_p).

        A column ∂x/∂ξ_j of J has the degree of the monomials differentiated by ξ_j; det J takes
        one factor from each column.
        """
        exps = self.monomials
        if self.family == "hex":
            # degree in ξ_i of column j: max of α_i - [i == j] over the monomials that ξ_j does not kill
            return max(sum(int(max(exps[exps[:, j] > 0, i] - (i == j), default=0)) for j in range(3))
                       for i in range(3))
        return 3 * max(int(exps.sum(axis=1).max()) - 1, 0)

    @property
    def n_faces(self):
        return self.faces.shape[0]
