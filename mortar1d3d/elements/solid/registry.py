"""The solid element types and families, in code order.

This is the list to extend: a new element type of a known family is its module (shape functions,
derivatives and a ``DESCRIPTOR``) plus one line below; a new family is its module (an
:class:`~mortar1d3d.elements.descriptor.ElementFamily` with its kernels and validity cells, like
:mod:`.hex_family`) plus one line in ``FAMILIES``. :mod:`~mortar1d3d.elements.solid.dispatch`
derives every table and the kernels' dispatch from here, and ``tests/test_elements.py`` checks
that codes are the positions in these lists.
"""
from . import hex8, hex20, hex27, nurbs27, nurbs64, nurbs125, tet4, tet10, wedge6
from .hex_family import HEXAHEDRON
from .tet_family import TETRAHEDRON
from .wedge_family import WEDGE

FAMILIES = (HEXAHEDRON, TETRAHEDRON, WEDGE)
SOLID_TYPES = (hex8, hex20, hex27, tet4, tet10, wedge6, nurbs27, nurbs64, nurbs125)

#: the types whose kernels are compiled into every kernel that dispatches over the registry (so that
#: LLVM can inline them: the hot type); every other type's kernels are compiled once on their own,
#: when a scene first evaluates an element of that type, and called through a symbol
#: (:func:`mortar1d3d.elements.selector.kernel_selector`, lazily): a scene's first run compiles only
#: its own types' kernels, and a new type needs no line beyond its entry in ``SOLID_TYPES``
LINKED_TYPES = (hex8,)
