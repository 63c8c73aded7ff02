"""Physics on top of the meshes: materials (``materials``) and finite-deformation solids (``solid``).

Import the submodules directly; nothing here compiles or imports a kernel.
"""
