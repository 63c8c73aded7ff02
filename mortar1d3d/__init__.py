"""mortar1d3d: mortar-type coupling of 1D beams embedded in 3D solid finite element meshes.

>>> import mortar1d3d as m13
>>> beams, solid = m13.generate.fibre_cube(4, 3, 5)
>>> ops = m13.assemble_mortar(beams, solid)          # doctest: +SKIP
"""
from . import generate
from .errors import MeshError
from .mesh import BeamMesh, SolidMesh

__version__ = "0.1.0"
__all__ = ["BeamMesh", "SolidMesh", "MeshError", "generate", "__version__"]
from .mortar.assemble import MortarOperators, assemble_mortar  # noqa: E402
from .geometry.projection import project_points  # noqa: E402

from .warmup import warmup  # noqa: E402
from .scene import Scene, SceneError  # noqa: E402
from .model import Effect, Model, plan, solve  # noqa: E402
from .result import Result  # noqa: E402
from .solvers.newton import ConvergenceError  # noqa: E402

__all__ += ["MortarOperators", "assemble_mortar", "project_points", "warmup", "Scene", "SceneError", "Effect",
            "Model", "plan", "solve", "Result", "ConvergenceError"]
