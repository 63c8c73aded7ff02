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
    dim: int = 3

    @property
    def n_faces(self):
        return self.faces.shape[0]
