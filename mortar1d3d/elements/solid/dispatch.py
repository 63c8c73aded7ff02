"""Registry of solid element types and the kernels that dispatch on their integer code.

This is the only module that knows every solid element type. To add one: write its module
(``shape``, ``deriv``, ``DESCRIPTOR``), import it here, add it to ``SOLID_ELEMENTS`` and to the
``if`` chains below. ``tests/test_elements.py`` checks the chains against the registry.

Dispatching on an integer inside the kernels (rather than compiling one kernel per element
type) keeps one compiled version of every kernel, which Numba's on-disk cache can store.
"""
import numpy as np

from ..._config import njit
from . import hex8, hex20, hex27, tet4, tet10
from ._family import HEX, HEX_FACES, TET, TET_FACES, hex_outside_distance, tet_outside_distance

SOLID_MODULES = {m.DESCRIPTOR.name: m for m in (hex8, hex20, hex27, tet4, tet10)}
SOLID_ELEMENTS = {name: m.DESCRIPTOR for name, m in SOLID_MODULES.items()}
BY_CODE = {d.code: d for d in SOLID_ELEMENTS.values()}
MAX_NODES = max(d.n_nodes for d in SOLID_ELEMENTS.values())
MAX_FACES = 6

# per code: number of nodes, family
N_NODES = np.array([BY_CODE[c].n_nodes for c in range(len(BY_CODE))], dtype=np.int64)
FAMILY = np.array([HEX if BY_CODE[c].family == "hex" else TET for c in range(len(BY_CODE))], dtype=np.int64)


def solid_element(name):
    """Descriptor of the solid element type called ``name`` (meshio name)."""
    try:
        return SOLID_ELEMENTS[name]
    except KeyError:
        raise ValueError(f"unknown solid element type {name!r}; known types: "
                         f"{', '.join(SOLID_ELEMENTS)}") from None


@njit
def shape(code, xi, N):
    """Shape function values of element type ``code`` at ``xi`` into ``N[:n_nodes]``."""
    if code == 0:
        hex8.shape(xi, N)
    elif code == 1:
        hex20.shape(xi, N)
    elif code == 2:
        hex27.shape(xi, N)
    elif code == 3:
        tet4.shape(xi, N)
    else:
        tet10.shape(xi, N)


@njit
def deriv(code, xi, dN):
    """Shape function derivatives of element type ``code`` at ``xi`` into ``dN[:n_nodes, :]``."""
    if code == 0:
        hex8.deriv(xi, dN)
    elif code == 1:
        hex20.deriv(xi, dN)
    elif code == 2:
        hex27.deriv(xi, dN)
    elif code == 3:
        tet4.deriv(xi, dN)
    else:
        tet10.deriv(xi, dN)


@njit
def n_nodes(code):
    return N_NODES[code]


@njit
def outside_distance(code, xi):
    """How far ``xi`` lies outside the reference element (<= 0 inside, parameter units)."""
    if FAMILY[code] == HEX:
        return hex_outside_distance(xi)
    return tet_outside_distance(xi)


@njit
def is_inside(code, xi, tol):
    return outside_distance(code, xi) <= tol


@njit
def faces(code):
    """Face table (n_faces, 4, 3) of element type ``code``: origin, a, b, outward normal."""
    if FAMILY[code] == HEX:
        return HEX_FACES
    return TET_FACES


@njit
def centre(code, xi):
    """Write the parameter-space centre (Newton start) of type ``code`` into ``xi``."""
    if FAMILY[code] == HEX:
        xi[0] = xi[1] = xi[2] = 0.0
    else:
        xi[0] = xi[1] = xi[2] = 0.25
