"""Nonlinear physics on top of the mortar engine: beams, solids, materials, coupling, loads."""
