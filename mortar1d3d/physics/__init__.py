"""Physics on top of the mortar engine: solids, beams, materials, loads, coupling enforcement.

Solid, from the material point up:

- :mod:`.kinematics`: strain measures (Green–Lagrange, small strain) and det of a displacement gradient;
- :mod:`.materials`, :mod:`.fibre_material`: stress and tangent of the matrix material and its fibres;
- :mod:`.solid_reference`: volume rules, ∂N/∂X and w det J at the Gauss points of a mesh;
- :mod:`.assembly_graph`: CSR pattern and block colouring of the race-free parallel assembly;
- :mod:`.solid_kernels`: element forces, tangents, energies and cell fields, and their assembly;
- :mod:`.solid`: :class:`~mortar1d3d.physics.solid.SolidModel`, the validating API over them;
- :mod:`.surface`: boundary faces, dead traction and follower pressure.

Beams and coupling: :mod:`.beam` (beam models), :mod:`.coupling` (penalty and Lagrange
enforcement of the mortar operators).
"""
