"""The parameter domains of element faces: the square [-1, 1]² and the triangle u, v >= 0, u + v <= 1.

A family's face is the image of one of these under ``ξ = origin + u a + v b``; its shape gives the
corners (in the order of the family's ``face_nodes``), the centroid and the quadrature rule, so
that the tables built from faces (surface loads, crossing starts) need no per-family branch.
"""
import numpy as np

from ...quadrature import quadrilateral_rule, triangle_rule
from ..descriptor import FaceShape

QUADRILATERAL = FaceShape("quadrilateral", corners=np.array([[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]]),
                          centre=np.zeros(2), rule=quadrilateral_rule)
TRIANGLE = FaceShape("triangle", corners=np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]]),
                     centre=np.full(2, 1.0 / 3.0), rule=triangle_rule)
