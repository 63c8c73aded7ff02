"""Beam centreline interpolations: cubic Hermite (positions + unit tangents) and Lagrange.

Every centreline is ``r(η) = Σ_k H_k(η; L) q_k`` with vector coefficients ``q_k``:

=========  ====  ==========================================  =========================
type       code  coefficients q_k                            centreline DOFs per node
=========  ====  ==========================================  =========================
hermite    0     r1, t1, r2, t2 (t: unit tangents)           6: [r, t]
line       1     r1, r2                                      3
line3      2     r1, r2, r_mid (meshio ``line3`` order)      3
=========  ====  ==========================================  =========================

Only the Hermite functions depend on the element length ``L``.
"""
from dataclasses import dataclass

import numpy as np

from ..._config import njit
from . import hermite, lagrange


@dataclass(frozen=True)
class BeamElementType:
    """Descriptor of a beam centreline interpolation.

    ``n_nodes`` nodes per element, ``n_functions`` vector coefficients, ``dofs_per_node``
    centreline DOFs per node; coefficient k belongs to local node ``function_node[k]`` and
    starts at DOF offset ``function_offset[k]`` within that node's block.
    """

    name: str
    code: int
    n_nodes: int
    n_functions: int
    dofs_per_node: int
    function_node: tuple
    function_offset: tuple

    @property
    def has_tangents(self):
        """True when some coefficients are nodal tangents (DOF offset 3 in their node's block)."""
        return any(offset > 0 for offset in self.function_offset)


BEAM_ELEMENTS = {
    "hermite": BeamElementType("hermite", 0, 2, 4, 6, (0, 0, 1, 1), (0, 3, 0, 3)),
    "line": BeamElementType("line", 1, 2, 2, 3, (0, 1), (0, 0)),
    "line3": BeamElementType("line3", 2, 3, 3, 3, (0, 1, 2), (0, 0, 0)),
}
MAX_FUNCTIONS = 4


def beam_element(name):
    try:
        return BEAM_ELEMENTS[name]
    except KeyError:
        raise ValueError(f"unknown beam element type {name!r}; known types: "
                         f"{', '.join(BEAM_ELEMENTS)}") from None


@njit
def shape(code, eta, length, H):
    """Centreline functions of type ``code`` at ``eta`` into ``H``."""
    if code == 0:
        hermite.shape(eta, length, H)
    elif code == 1:
        lagrange.line2_shape(eta, H)
    else:
        lagrange.line3_shape(eta, H)


@njit
def deriv(code, eta, length, dH):
    """d/dη of the centreline functions of type ``code`` at ``eta`` into ``dH``."""
    if code == 0:
        hermite.deriv(eta, length, dH)
    elif code == 1:
        lagrange.line2_deriv(eta, dH)
    else:
        lagrange.line3_deriv(eta, dH)


def evaluate(element, eta, length=1.0, derivative=False):
    """Centreline functions (or their η-derivatives) of ``element`` at every ``eta``, in numpy.

    The vectorised counterpart of :func:`shape` and :func:`deriv` for code outside kernels (VTU
    sampling, arc lengths): it runs the kernels' own Python functions on arrays, whose
    arithmetic is elementwise, so every value has the bits a kernel computes at that point.

    Parameters
    ----------
    element : BeamElementType
    eta : array_like of float, any shape
    length : float
        Element length (enters the Hermite tangent functions only).
    derivative : bool
        d/dη instead of the functions.

    Returns
    -------
    eta.shape + (MAX_FUNCTIONS,) float64
        Zero beyond the element's ``n_functions``.
    """
    e = np.asarray(eta, dtype=np.float64)
    H = np.zeros((MAX_FUNCTIONS,) + e.shape)
    if element.code == 0:
        (hermite.deriv if derivative else hermite.shape).py_func(e, length, H)
    elif element.code == 1:
        (lagrange.line2_deriv if derivative else lagrange.line2_shape).py_func(e, H)
    else:
        (lagrange.line3_deriv if derivative else lagrange.line3_shape).py_func(e, H)
    return np.ascontiguousarray(np.moveaxis(H, 0, -1))


@njit
def n_functions(code):
    if code == 0:
        return 4
    if code == 1:
        return 2
    return 3
