"""NURBS volumes: patches, Bézier extraction, rational basis kernels, exact generators, refinement.

>>> from mortar1d3d import nurbs
>>> pipe = nurbs.hollow_cylinder(0.1, 0.2, 0.3, angle=90.0, elements=(1, 1, 1))
>>> pipe.n_elements
1
"""
from .generate import brick, hollow_cylinder
from .patch import NurbsPatch, NurbsSolid

__all__ = ["NurbsPatch", "NurbsSolid", "hollow_cylinder", "brick"]
