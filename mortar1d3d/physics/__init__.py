"""Physics of the nonlinear model: solids, beams, materials, coupling and loads."""
