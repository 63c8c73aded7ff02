"""NURBS volumes: patches, Bézier extraction, rational basis kernels, exact generators, refinement,
the engine's mesh of rational Bézier elements and the solid model on control points.

A patch enters the engine as ``nurbs27``, ``nurbs64`` or ``nurbs125`` elements (one per non-empty knot
span, its Bézier control points and weights as nodes; degrees 1 … 4 per direction are elevated exactly
to 2, 3 or 4, the highest degree of any direction): :func:`bezier_mesh` gives the :class:`~mortar1d3d.SolidMesh`
that :func:`mortar1d3d.assemble_mortar` and :func:`mortar1d3d.project_points` take, and the sparse
map ``T`` from control points to its nodes (``M_control = M (T ⊗ I₃)``).

>>> from mortar1d3d import nurbs
>>> pipe = nurbs.hollow_cylinder(0.1, 0.2, 0.3, angle=90.0, elements=(1, 1, 1))
>>> pipe.n_elements
1
"""
from .generate import brick, hollow_cylinder
from .mesh import BezierMesh, bezier_mesh
from .patch import NurbsPatch, NurbsSolid
from .solid import NurbsSolidModel

__all__ = ["NurbsPatch", "NurbsSolid", "BezierMesh", "bezier_mesh", "NurbsSolidModel", "hollow_cylinder", "brick"]
