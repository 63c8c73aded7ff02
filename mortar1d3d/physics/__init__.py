"""Physics on top of the mortar engine: solids, beams, materials, loads, coupling enforcement."""
