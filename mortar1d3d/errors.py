"""Every exception and warning the library raises, in one place.

Errors (all raised at the API boundary or by the solvers, with messages that name the key path,
ids or values at fault and what to try):

- :class:`MeshError` (``ValueError``): invalid mesh input;
- :class:`SceneError` (``ValueError``): invalid scene; the message starts with the key path;
- :class:`LinearSolverError` (``RuntimeError``): a linear solve failed;
- :class:`ConvergenceError` (``RuntimeError``): Newton's method gave up;
- :class:`InvertedElementsError` (``FloatingPointError``): det F <= 0 in solid elements (a Newton
  solver catches it to cut its step);
- :class:`RotationRangeError` (``FloatingPointError``): Simo–Reissner beam elements whose triads are
  too far apart for the interpolation, or non-finite (likewise a reason to cut the step);
- :class:`MissingPackageError` (``ImportError``): an optional package of the distributed path
  (the ``mpi`` extra) is not installed.

Warnings (``UserWarning`` subclasses): :class:`AccuracyWarning`, :class:`CouplingWarning`,
:class:`LargeDeformationWarning`.

The modules that raise them re-export them under their old names (``mortar1d3d.scene.SceneError``,
``mortar1d3d.solvers.newton.ConvergenceError``, ...).
"""
import numpy as np

__all__ = ["MeshError", "SceneError", "FourCError", "LinearSolverError", "ConvergenceError", "InvertedElementsError",
           "RotationRangeError", "MissingPackageError", "AccuracyWarning", "CouplingWarning", "LargeDeformationWarning", "format_ids"]


def format_ids(ids, limit=10):
    """``"3, 17, 42 (and 5 more)"`` for error messages."""
    ids = [int(i) for i in ids]
    head = ", ".join(str(i) for i in ids[:limit])
    return head + (f" (and {len(ids) - limit} more)" if len(ids) > limit else "")


# ------------------------------------------------------------------------------------- errors
class MeshError(ValueError):
    """Invalid mesh input: the message names the problem and the offending ids."""


class SceneError(ValueError):
    """Invalid scene: the message starts with the key path of the offending entry."""


class LinearSolverError(RuntimeError):
    """A linear solve failed: the message says what was reached and what to try."""


class ConvergenceError(RuntimeError):
    """Newton's method gave up: the message says where, what was seen and what to try."""


class InvertedElementsError(FloatingPointError):
    """``det F <= 0`` at a Gauss point of the listed elements (``.elements``, int64 array).

    A Newton solver catches this to cut its step: the deformation is not admissible.
    """

    def __init__(self, elements):
        self.elements = np.asarray(elements, dtype=np.int64)
        super().__init__(f"det F <= 0 (or not finite) at a Gauss point of {len(self.elements)} solid "
                         f"elements: {format_ids(self.elements)}")


class RotationRangeError(FloatingPointError):
    """Simo–Reissner beam elements (``.elements``, int64 array) whose end triad is turned against the
    middle one by more than the triad interpolation takes, or whose energy or force is not finite.

    A Newton solver catches this (a FloatingPointError) to cut its step.
    """

    def __init__(self, elements, message):
        self.elements = np.asarray(elements, dtype=np.int64)
        super().__init__(message)


class FourCError(SceneError):
    """A 4C input file the library cannot run as it is (:mod:`mortar1d3d.io.fourc`): the message
    names the section, key and value."""


class MissingPackageError(ImportError):
    """An optional package of the distributed path (``pip install "mortar1d3d[mpi]"``) is not
    installed (:mod:`mortar1d3d.distributed`): the message names it and how to install it."""


# ----------------------------------------------------------------------------------- warnings
class AccuracyWarning(UserWarning):
    """The inputs are valid but round-off will cost accuracy (e.g. a penalty far above E_solid)."""


class CouplingWarning(UserWarning):
    """A beam of a coupled scene is not coupled to the solid (e.g. it lies outside it)."""


class LargeDeformationWarning(UserWarning):
    """A linear analysis moved a body by a sizeable fraction of its own size: linear kinematics is
    not valid there (often a unit slip, e.g. E in MPa in a scene in metres)."""
