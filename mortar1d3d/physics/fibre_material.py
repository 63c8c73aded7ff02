"""Fibre-reinforced hyperelastic solid: matrix material plus axial stiffness along fibre families.

The continuum counterpart of embedded axial fibres (torsion-free beams or trusses coupled to a
solid): every fibre family ``f`` adds, at every Gauss point of the elements it reinforces,

    W_f = ½ k_f (a_f · E a_f)²            k_f = E_f V_f   (fibre modulus × volume fraction)

to the matrix energy, with ``E`` the Green–Lagrange strain and ``a_f`` the unit fibre direction
in the reference configuration. ``a·E a = ½(λ_a² - 1)`` is the Green–Lagrange strain of a fibre
of stretch ``λ_a``. With a Saint Venant–Kirchhoff matrix this is the *fibre-reinforced SVK*
material (matrix and fibres share the strain: a Voigt mixture, the matrix is not cut away, as
for embedded beams, which add their stiffness to the solid's).

A :class:`FibreField` stores the families of every element compactly: a table of fibre *sets*
(CSR ``set_ptr``, rows ``[a_x, a_y, a_z, k]``) and, per element, the index of its set (set 0 is
the empty set). Elements of one layer of a laminate share one set.

The kernel :func:`add_fibres` adds the fibre stress and tangent to a matrix material's ``S``
and Voigt ``C`` (conventions of :mod:`~mortar1d3d.physics.materials`); the solid element
kernels call it after :func:`~mortar1d3d.physics.materials.stress_tangent` when an element's
set is not empty.
"""
import math

import numpy as np

from .._config import njit
from .kinematics import green_lagrange, small_strain
from .materials import stress_tangent


@njit
def add_fibres(data, lo, hi, H, linear, S, C):
    """Add fibre families ``data[lo:hi]`` to a stress ``S`` and tangent ``C``; return their energy.

    Parameters
    ----------
    data : (n, 4) float64
        Fibre families ``[a_x, a_y, a_z, k]``, ``|a| = 1``, ``k = E_f V_f``.
    lo, hi : int
        Rows of ``data`` to add (the element's fibre set).
    H : (3, 3) float64
        Displacement gradient ``H = F - I``.
    linear : bool
        True: small strain ``ε = sym(H)`` instead of ``E`` (then ``S`` stands for σ).
    S : (3, 3) float64, in/out
        2nd Piola–Kirchhoff stress (σ if linear), incremented.
    C : (6, 6) float64, in/out
        ``dS/dE`` in Voigt form (engineering shear), incremented.

    Returns
    -------
    W : float
        ``Σ_f ½ k_f (a_f·E a_f)²``.

    Notes
    -----
    With ``ε_a = a·E a`` and ``A = a⊗a``:

        W = ½ k ε_a²        S = ∂W/∂E = k ε_a A        C = ∂S/∂E = k A⊗A

    In Voigt form ``C[p, q] += k A_p A_q`` with ``A_p = a_I a_J`` for ``p = (I, J)``: the
    engineering shear strain ``2E_IJ`` of column q then meets ``a_I a_J`` once, which is
    ``a_I a_J E_IJ + a_J a_I E_JI`` of the tensor product.
    """
    if linear:
        e00, e11, e22, e01, e12, e02 = small_strain(H)
    else:
        e00, e11, e22, e01, e12, e02 = green_lagrange(H)
    W = 0.0
    A = np.empty(6)
    for f in range(lo, hi):
        a0 = data[f, 0]
        a1 = data[f, 1]
        a2 = data[f, 2]
        k = data[f, 3]
        A[0] = a0 * a0
        A[1] = a1 * a1
        A[2] = a2 * a2
        A[3] = a0 * a1
        A[4] = a1 * a2
        A[5] = a0 * a2
        ea = A[0] * e00 + A[1] * e11 + A[2] * e22 + 2.0 * (A[3] * e01 + A[4] * e12 + A[5] * e02)
        W += 0.5 * k * ea * ea
        s = k * ea
        S[0, 0] += s * A[0]
        S[1, 1] += s * A[1]
        S[2, 2] += s * A[2]
        S[0, 1] += s * A[3]
        S[1, 0] += s * A[3]
        S[1, 2] += s * A[4]
        S[2, 1] += s * A[4]
        S[0, 2] += s * A[5]
        S[2, 0] += s * A[5]
        for p in range(6):
            kp = k * A[p]
            for q in range(6):
                C[p, q] += kp * A[q]
    return W


@njit
def fibre_stress_tangent(code, lam, mu, data, lo, hi, H, S, C):
    """Matrix material (``code``, λ, μ) plus fibres ``data[lo:hi]``: energy, ``S``, ``C`` at ``H``.

    The combined material kernel (for tests and users outside the element loops); arguments as
    :func:`~mortar1d3d.physics.materials.stress_tangent` and :func:`add_fibres`.
    """
    W = stress_tangent(code, lam, mu, H, S, C)
    return W + add_fibres(data, lo, hi, H, False, S, C)


# ----------------------------------------------------------------------------- fibre fields

def fibre_family(direction, E, volume_fraction, path="fibre"):
    """Validated ``[a_x, a_y, a_z, k]`` row: unit direction and ``k = E V_f``.

    Parameters
    ----------
    direction : (3,) array_like
        Fibre direction in the reference configuration (normalised here; must not be zero).
    E : float
        Fibre Young's modulus, > 0.
    volume_fraction : float
        0 < V_f <= 1 (the fraction of the reinforced elements' volume taken by these fibres).

    Raises
    ------
    ValueError
        Naming ``path`` and the offending value.
    """
    a = np.asarray(direction, dtype=np.float64).reshape(-1)
    if a.shape != (3,) or not np.isfinite(a).all():
        raise ValueError(f"{path}.direction: expected 3 finite numbers, got {direction!r}")
    norm = float(np.linalg.norm(a))
    if norm == 0.0:
        raise ValueError(f"{path}.direction: must not be zero")
    E = float(E)
    volume_fraction = float(volume_fraction)
    if not (math.isfinite(E) and E > 0.0):
        raise ValueError(f"{path}.E: fibre Young's modulus must be finite and > 0, got {E!r}")
    if not (math.isfinite(volume_fraction) and 0.0 < volume_fraction <= 1.0):
        raise ValueError(f"{path}.volume_fraction: expected 0 < V_f <= 1, got {volume_fraction!r}")
    return np.array([a[0] / norm, a[1] / norm, a[2] / norm, E * volume_fraction])


class FibreField:
    """Fibre families per element of a solid mesh (module docstring).

    Parameters
    ----------
    n_elements : int
        Elements of the mesh.
    families : sequence of (row, elements)
        ``row`` (4,) ``[a_x, a_y, a_z, k]`` from :func:`fibre_family`; ``elements`` the element
        ids it reinforces (int array or boolean mask (n_elements,)), or None for every element.

    Attributes
    ----------
    set_ptr : (n_sets + 1,) int64
        Rows ``set_ptr[s]:set_ptr[s+1]`` of ``data`` form set s; set 0 is empty.
    data : (n_rows, 4) float64
    element_set : (n_elements,) int64
        Set index of every element.
    """

    def __init__(self, n_elements, families=()):
        n_elements = int(n_elements)
        rows = []
        member = np.zeros((n_elements, len(families)), dtype=bool)
        for j, (row, elements) in enumerate(families):
            row = np.asarray(row, dtype=np.float64)
            if row.shape != (4,) or not np.isfinite(row).all() or row[3] <= 0.0:
                raise ValueError(f"FibreField: family {j} must be [a_x, a_y, a_z, k > 0], got {row!r}")
            if abs(np.linalg.norm(row[:3]) - 1.0) > 1e-12:
                raise ValueError(f"FibreField: family {j} direction must be a unit vector, got {row[:3]!r}")
            rows.append(row)
            if elements is None:
                member[:, j] = True
            else:
                elements = np.asarray(elements)
                if elements.dtype == bool:
                    if elements.shape != (n_elements,):
                        raise ValueError(f"FibreField: family {j} mask must have {n_elements} entries")
                    member[:, j] = elements
                else:
                    elements = elements.astype(np.int64).reshape(-1)
                    if elements.size and (elements.min() < 0 or elements.max() >= n_elements):
                        raise ValueError(f"FibreField: family {j} names elements outside 0..{n_elements - 1}")
                    member[elements, j] = True
        # one set per distinct combination of families (set 0: none)
        keys, element_set = np.unique(member, axis=0, return_inverse=True) if len(families) else (
            np.zeros((1, 0), dtype=bool), np.zeros(n_elements, dtype=np.int64))
        element_set = np.asarray(element_set, dtype=np.int64).reshape(-1)
        empty = np.zeros((1, len(families)), dtype=bool)
        if not (keys[0] == empty[0]).all():     # np.unique sorts: the all-False key comes first if present
            keys = np.vstack([empty, keys])
            element_set += 1
        ptr, data = [0], []
        for key in keys:
            chosen = [rows[j] for j in np.flatnonzero(key)]
            data.extend(chosen)
            ptr.append(ptr[-1] + len(chosen))
        self.set_ptr = np.array(ptr, dtype=np.int64)
        self.data = np.ascontiguousarray(np.array(data, dtype=np.float64).reshape(-1, 4))
        self.element_set = np.ascontiguousarray(element_set)
        self.n_families = len(families)

    @classmethod
    def empty(cls, n_elements):
        """No fibres anywhere."""
        return cls(n_elements, ())

    def element_families(self, e):
        """(m, 4) fibre rows of element ``e``."""
        s = self.element_set[e]
        return self.data[self.set_ptr[s]:self.set_ptr[s + 1]]

    def __repr__(self):
        return (f"FibreField({self.n_families} families, {len(self.set_ptr) - 1} sets, "
                f"{np.count_nonzero(self.element_set)} of {len(self.element_set)} elements reinforced)")
