"""Beam centreline interpolations: cubic Hermite (positions + unit tangents) and Lagrange lines.

Every centreline is ``r(η) = Σ_k H_k(η; L) q_k`` with vector coefficients ``q_k``:

=========  ====  ==========================================  =========================
type       code  coefficients q_k                            centreline DOFs per node
=========  ====  ==========================================  =========================
hermite    0     r1, t1, r2, t2 (t: unit tangents)           6: [r, t]
line       1     r1, r2                                      3
line3      2     r1, r2, r_mid (meshio ``line3`` order)      3
=========  ====  ==========================================  =========================

Only the Hermite functions depend on the element length ``L``. Each type is one module with its
kernels (shape functions and derivatives, coefficients from node data, Bézier control points for
bounding boxes and inside certificates) and a :class:`~mortar1d3d.elements.descriptor.BeamElementType`; :mod:`.registry` lists
them, and everything here (tables by code, the kernels' dispatch, the vectorised evaluator) is
derived from that list.
"""
import numpy as np
from numba import literal_unroll

from ..._config import njit, njit_inline
from ..descriptor import BeamElementType
from ..selector import kernel_selector
from .registry import BEAM_TYPES

__all__ = ["BeamElementType", "BEAM_ELEMENTS", "BY_CODE", "MAX_FUNCTIONS", "beam_element", "shape", "deriv",
           "deriv2", "coefficients", "control_points", "n_functions", "evaluate"]

BEAM_ELEMENTS = {m.DESCRIPTOR.name: m.DESCRIPTOR for m in BEAM_TYPES}
BY_CODE = {d.code: d for d in BEAM_ELEMENTS.values()}
if sorted(BY_CODE) != list(range(len(BEAM_TYPES))):
    raise ImportError("beam element registry: codes must be 0, 1, 2, ... in registry order")
#: most coefficients of any centreline type (size of the kernels' scratch arrays)
MAX_FUNCTIONS = max(d.n_functions for d in BEAM_ELEMENTS.values())
#: per code: coefficients per element, polynomial degree in η
N_FUNCTIONS = np.array([BY_CODE[c].n_functions for c in range(len(BY_CODE))], dtype=np.int64)
DEGREE = np.array([BY_CODE[c].degree for c in range(len(BY_CODE))], dtype=np.int64)

#: the registry's codes, for ``literal_unroll`` over the types in njit code; import the name itself
#: (``from ..elements.beam import CODES``): read as ``module.CODES`` Numba types it as a tuple of
#: int64, not of literals, and ``select`` then finds no kernel
CODES = tuple(range(len(BEAM_TYPES)))
#: ``select(k, name)``: kernel ``name`` of type ``k`` (a literal) in njit code (see :mod:`..selector`);
#: lets a loop choose the type once and call its kernels directly inside
select = kernel_selector(BEAM_TYPES)


def beam_element(name):
    """Descriptor of the centreline type called ``name``."""
    try:
        return BEAM_ELEMENTS[name]
    except KeyError:
        raise ValueError(f"unknown beam element type {name!r}; known types: "
                         f"{', '.join(BEAM_ELEMENTS)}") from None


@njit
def shape(code, eta, length, H):
    """Centreline functions of type ``code`` at ``eta`` into ``H``."""
    for k in literal_unroll(CODES):
        if k == code:
            select(k, "shape")(eta, length, H)


@njit
def deriv(code, eta, length, dH):
    """d/dη of the centreline functions of type ``code`` at ``eta`` into ``dH``."""
    for k in literal_unroll(CODES):
        if k == code:
            select(k, "deriv")(eta, length, dH)


@njit
def deriv2(code, eta, length, ddH):
    """d²/dη² of the centreline functions of type ``code`` at ``eta`` into ``ddH``."""
    for k in literal_unroll(CODES):
        if k == code:
            select(k, "deriv2")(eta, length, ddH)


@njit
def coefficients(code, positions, tangents, nodes, origin, Qe):
    """Coefficients of the element with node ids ``nodes`` into ``Qe`` (MAX_FUNCTIONS, 3): positions
    minus ``origin`` (3,), tangents as they are, unused rows zero."""
    for k in literal_unroll(CODES):
        if k == code:
            select(k, "coefficients")(positions, tangents, nodes, origin, Qe)


@njit
def control_points(code, Qe, length, ctrl):
    """Bézier control points of coefficients ``Qe`` (in their frame) into ``ctrl`` (MAX_FUNCTIONS, 3);
    returns their number. The centreline lies in their convex hull."""
    n = 0
    for k in literal_unroll(CODES):
        if k == code:
            n = select(k, "control_points")(Qe, length, ctrl)
    return n


@njit_inline
def n_functions(code):
    return N_FUNCTIONS[code]


_KERNELS = ("shape", "deriv", "deriv2")


def evaluate(element, eta, length=1.0, derivative=0):
    """Centreline functions (or their η-derivatives) of ``element`` at every ``eta``, in numpy.

    The vectorised counterpart of :func:`shape`, :func:`deriv` and :func:`deriv2` for code outside
    kernels (VTU sampling, arc lengths, the beam model's reference geometry): it runs the kernels'
    own Python functions on arrays, whose arithmetic is elementwise, so every value has the bits a
    kernel computes at that point.

    Parameters
    ----------
    element : BeamElementType
    eta : array_like of float, any shape
    length : float or array_like
        Element length(s), broadcast against ``eta`` (it enters the Hermite tangent functions only).
    derivative : {0, 1, 2} (or bool)
        Order of the η-derivative.

    Returns
    -------
    broadcast(eta, length).shape + (MAX_FUNCTIONS,) float64
        Zero beyond the element's ``n_functions``.
    """
    e = np.asarray(eta, dtype=np.float64)
    L = np.asarray(length, dtype=np.float64)
    shape_ = np.broadcast_shapes(e.shape, L.shape)
    e = np.broadcast_to(e, shape_)
    H = np.zeros((MAX_FUNCTIONS,) + shape_)
    kernel = getattr(BEAM_TYPES[element.code], _KERNELS[int(derivative)])
    kernel.py_func(e, L, H)
    return np.ascontiguousarray(np.moveaxis(H, 0, -1))
