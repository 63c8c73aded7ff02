"""The beam centreline element types, in code order.

A new centreline interpolation is its module (``shape``, ``deriv``, ``deriv2`` with the signature
``(eta, length, out)``, ``coefficients(positions, tangents, nodes, origin, Qe)``,
``control_points(Qe, length, ctrl)`` and a ``DESCRIPTOR``) plus one line below; :mod:`mortar1d3d.elements.beam`
derives the tables and the kernels' dispatch from this list. The loops over a beam's points are
compiled per type, when a scene first uses the type (``unlinked(..., cases=CODES)`` in
:mod:`mortar1d3d.integration.points` and :mod:`mortar1d3d.geometry.search`): a new type needs no
other line.
"""
from . import hermite, line2, line3

BEAM_TYPES = (hermite, line2, line3)
