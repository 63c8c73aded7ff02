"""Element types: solid interpolations, beam centrelines and Lagrange-multiplier functions.

Each type is one module with a descriptor holding all its data (:mod:`.descriptor`);
:mod:`.solid.registry` lists the solid element types and families, and :mod:`.solid.dispatch`
derives the per-code tables and the kernels' dispatch from that list. Beam centreline and
multiplier types live in ``beam`` and ``multiplier``; :mod:`.validity` proves det J > 0.
"""
from .solid.dispatch import SOLID_ELEMENTS, solid_element
from .beam import BEAM_ELEMENTS, beam_element
from .multiplier import MULTIPLIERS, multiplier

__all__ = ["SOLID_ELEMENTS", "solid_element", "BEAM_ELEMENTS", "beam_element", "MULTIPLIERS", "multiplier"]
