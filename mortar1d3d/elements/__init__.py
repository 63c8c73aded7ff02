"""Element types: solid interpolations, beam centrelines and Lagrange-multiplier functions.

``mortar1d3d.elements.solid.dispatch`` is the registry of solid element types (the only place
that knows all of them); beam centreline and multiplier types live in ``beam`` and
``multiplier``.
"""
from .solid.dispatch import SOLID_ELEMENTS, solid_element
from .beam import BEAM_ELEMENTS, beam_element
from .multiplier import MULTIPLIERS, multiplier

__all__ = ["SOLID_ELEMENTS", "solid_element", "BEAM_ELEMENTS", "beam_element", "MULTIPLIERS", "multiplier"]
