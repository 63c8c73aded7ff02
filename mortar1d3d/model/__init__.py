"""From a scene to a result, one way: build → Model → solve.

==============  ================================================================================
module          purpose
==============  ================================================================================
``readers``     mesh file readers, one plugin per format, in an explicit registry (meshio)
``curves``      beam meshes from curve specifications (line, polyline, helix, function)
``sets``        named sets (``solid:x_min``, boxes, ``beam:<i>:end``) resolved to nodes
``dofmap``      the DOF map: contiguous blocks of solid, centreline, rotation, multiplier unknowns
``build``       scene → meshes, beam groups, named sets, DOF map (:class:`BuiltScene`)
``model``       :class:`Model`: supports, loads, solid/beam physics, coupling, residual, solver choice
``checks``      supports (free rigid motions), zero-energy modes, the small-displacement warning
``effects``     the plan of effects: :class:`Effect`, :func:`plan`
``solve``       :func:`solve`: build, Model, solvers.newton, Result
==============  ================================================================================
"""
from .build import BeamGroup, BuiltScene, as_scene, build
from .checks import LINEAR_DISPLACEMENT_LIMIT, free_rigid_motions
from .curves import chord_tangents
from .dofmap import Block, DofMap
from .effects import Effect, plan
from .model import DEFAULT_PENALTY_FACTOR, PENALTY_ROUNDOFF_LIMIT, Model
from .readers import READERS, read_mesh_file
from .sets import NamedSets
from .solve import solve

_chord_tangents = chord_tangents        # the name before the split (tests use it)

__all__ = ["Effect", "Model", "plan", "solve", "build", "BuiltScene", "BeamGroup", "DofMap", "Block", "NamedSets",
           "READERS", "read_mesh_file", "as_scene", "chord_tangents", "free_rigid_motions",
           "DEFAULT_PENALTY_FACTOR", "PENALTY_ROUNDOFF_LIMIT", "LINEAR_DISPLACEMENT_LIMIT"]
