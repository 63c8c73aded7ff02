"""Total Lagrangian solid element kernels of every solid type: internal forces, tangent, energy.

For a displacement field ``u`` on the reference mesh (``dof = 3*node + i``), per Gauss point
with reference derivatives ``∂N_a/∂X`` and weight ``w det J``
(:mod:`~mortar1d3d.physics.solid_reference`):

    F = I + Σ_a u_a ⊗ ∂N_a/∂X          P = F S          W = W(F)
    f_int[a, i]        = Σ_gp w detJ  P_iJ ∂N_a/∂X_J
    K[(a, i), (b, k)]  = Σ_gp w detJ  ∂N_a/∂X_J  A_iJkL  ∂N_b/∂X_L
    A_iJkL = ∂P_iJ/∂F_kL = δ_ik S_JL + F_iI F_kK C_IJKL

(``S``, ``C`` from :func:`~mortar1d3d.physics.materials.stress_tangent`, plus the fibres of
:func:`~mortar1d3d.physics.fibre_material.add_fibres`). With linear kinematics the strain is
``ε = sym(∇u)``, the stress Hooke's ``σ = C₀ : ε`` with ``C₀ = λ I⊗I + 2μ 𝕀`` for every material
(the linearisation of every material at F = I), and ``A = C₀``.

:func:`assemble_kernel` adds the element vectors and matrices into the global vector and CSR
data in the race-free order of :mod:`~mortar1d3d.physics.assembly_graph`; work buffers are
allocated per block of elements, never for all elements. :func:`cell_fields_kernel` averages
strain and Cauchy stress over each element's Gauss points.
"""
import numpy as np

from .._config import CHUNK, njit, njit_inline
from .._parallel import in_parallel
from .._schedule import n_chunks
from .._unlinked import unlinked
from ..elements.solid.dispatch import N_NODES
from .fibre_material import add_fibres
from .kinematics import det3, green_lagrange, small_strain
from .materials import VOIGT_INDEX, hooke, hooke_stress, stress_tangent

STATUS_OK = 0
STATUS_INVERTED = 1      # det F <= 0 (or not finite) at a Gauss point


@njit
def _expand_voigt(Cv, F, S, w, linear, A):
    """Write ``A[(3i+J)*9 + 3k+L] = w (δ_ik S_JL + F_iI F_kK C_IJKL)`` (linear: ``w C_iJkL``)."""
    if linear:
        for i in range(3):
            for J in range(3):
                p = VOIGT_INDEX[i, J]
                for k in range(3):
                    for L in range(3):
                        A[(3 * i + J) * 9 + 3 * k + L] = w * Cv[p, VOIGT_INDEX[k, L]]
        return
    # T[i, J, q] = Σ_I F_iI C[(I, J), q], then A = Σ_K T[i, J, (K, L)] F_kK
    T = A[81:]                      # scratch space behind A (the caller allocates 81 + 54)
    for i in range(3):
        for J in range(3):
            for q in range(6):
                T[(3 * i + J) * 6 + q] = (F[i, 0] * Cv[VOIGT_INDEX[0, J], q] + F[i, 1] * Cv[VOIGT_INDEX[1, J], q]
                                          + F[i, 2] * Cv[VOIGT_INDEX[2, J], q])
    for i in range(3):
        for J in range(3):
            base = (3 * i + J) * 6
            for k in range(3):
                for L in range(3):
                    value = (T[base + VOIGT_INDEX[0, L]] * F[k, 0] + T[base + VOIGT_INDEX[1, L]] * F[k, 1]
                             + T[base + VOIGT_INDEX[2, L]] * F[k, 2])
                    if i == k:
                        value += S[J, L]
                    A[(3 * i + J) * 9 + 3 * k + L] = w * value


@njit
def _element(e, u, connectivity, codes, gp_ptr, dn_ptr, dNdX, wJ, mat_code, lam, mu, linear, want_tangent,
             C0, ue, fe, Ke, F, S, Cv, P, A, G, D, fibre_ptr, fibre_data, fibre_set):
    """Element vector and matrix of element e; returns (energy, status).

    Fibres (:mod:`~mortar1d3d.physics.fibre_material`): rows ``fibre_ptr[s]:fibre_ptr[s+1]`` of
    ``fibre_data`` with ``s = fibre_set[e]`` add their stress and tangent at every Gauss point.

    ``fe[a, i]`` (n, 3); ``Ke[9a + 3i + k, b]`` = K[(a, i), (b, k)] (node b fastest, so that the
    loops over b vectorise), exactly symmetric. Buffers are the caller's (one set per chunk).
    """
    code = codes[e]
    n = N_NODES[code]
    for a in range(n):
        v = connectivity[e, a]
        for i in range(3):
            ue[a, i] = u[3 * v + i]
            fe[a, i] = 0.0
    if want_tangent:
        for r in range(9 * n):
            for b in range(n):
                Ke[r, b] = 0.0
    energy = 0.0
    status = STATUS_OK
    fibre_lo = fibre_ptr[fibre_set[e]]
    fibre_hi = fibre_ptr[fibre_set[e] + 1]
    for q in range(gp_ptr[e + 1] - gp_ptr[e]):
        x = dn_ptr[e] + 3 * n * q          # ∂N_a/∂X_j at dNdX[x + j*n + a]
        y = x + n
        z = x + 2 * n
        w = wJ[gp_ptr[e] + q]
        h00 = h01 = h02 = h10 = h11 = h12 = h20 = h21 = h22 = 0.0
        for a in range(n):
            d0 = dNdX[x + a]
            d1 = dNdX[y + a]
            d2 = dNdX[z + a]
            h00 += ue[a, 0] * d0
            h01 += ue[a, 0] * d1
            h02 += ue[a, 0] * d2
            h10 += ue[a, 1] * d0
            h11 += ue[a, 1] * d1
            h12 += ue[a, 1] * d2
            h20 += ue[a, 2] * d0
            h21 += ue[a, 2] * d1
            h22 += ue[a, 2] * d2
        if linear:
            # small strain, Hooke: P stands for σ = C₀ : ε
            e00 = h00
            e11 = h11
            e22 = h22
            g01 = h01 + h10          # engineering shear strains
            g12 = h12 + h21
            g02 = h02 + h20
            s0 = C0[0, 0] * e00 + C0[0, 1] * e11 + C0[0, 2] * e22
            s1 = C0[1, 0] * e00 + C0[1, 1] * e11 + C0[1, 2] * e22
            s2 = C0[2, 0] * e00 + C0[2, 1] * e11 + C0[2, 2] * e22
            P[0, 0] = s0
            P[1, 1] = s1
            P[2, 2] = s2
            P[0, 1] = P[1, 0] = C0[3, 3] * g01
            P[1, 2] = P[2, 1] = C0[4, 4] * g12
            P[0, 2] = P[2, 0] = C0[5, 5] * g02
            W = 0.5 * (s0 * e00 + s1 * e11 + s2 * e22 + P[0, 1] * g01 + P[1, 2] * g12 + P[0, 2] * g02)
            if fibre_hi > fibre_lo:
                # fibres: σ += k (a·ε a) a⊗a, tangent C₀ + Σ k A⊗A (in Cv; F is free here)
                F[0, 0], F[0, 1], F[0, 2] = h00, h01, h02
                F[1, 0], F[1, 1], F[1, 2] = h10, h11, h12
                F[2, 0], F[2, 1], F[2, 2] = h20, h21, h22
                for i in range(6):      # element by element: an array assignment compiles Numba's
                    for j in range(6):  # shape-mismatch message
                        Cv[i, j] = C0[i, j]
                W += add_fibres(fibre_data, fibre_lo, fibre_hi, F, True, P, Cv)
        else:
            F[0, 0] = 1.0 + h00
            F[0, 1] = h01
            F[0, 2] = h02
            F[1, 0] = h10
            F[1, 1] = 1.0 + h11
            F[1, 2] = h12
            F[2, 0] = h20
            F[2, 1] = h21
            F[2, 2] = 1.0 + h22
            if not det3(F) > 0.0:
                status = STATUS_INVERTED
            # the material takes H = F - I (P is free until P = F S below)
            P[0, 0], P[0, 1], P[0, 2] = h00, h01, h02
            P[1, 0], P[1, 1], P[1, 2] = h10, h11, h12
            P[2, 0], P[2, 1], P[2, 2] = h20, h21, h22
            W = stress_tangent(mat_code, lam, mu, P, S, Cv)
            if fibre_hi > fibre_lo:
                W += add_fibres(fibre_data, fibre_lo, fibre_hi, P, False, S, Cv)
            for i in range(3):
                for J in range(3):
                    P[i, J] = F[i, 0] * S[0, J] + F[i, 1] * S[1, J] + F[i, 2] * S[2, J]
        energy += w * W
        for i in range(3):
            p0 = w * P[i, 0]
            p1 = w * P[i, 1]
            p2 = w * P[i, 2]
            for a in range(n):
                fe[a, i] += p0 * dNdX[x + a] + p1 * dNdX[y + a] + p2 * dNdX[z + a]
        if not want_tangent:
            continue
        if linear:
            _expand_voigt(Cv if fibre_hi > fibre_lo else C0, F, S, w, True, A)
        else:
            _expand_voigt(Cv, F, S, w, False, A)
        # this Gauss point's ∂N/∂X in a small contiguous buffer: the loops over b below vectorise
        for b in range(n):
            D[0, b] = dNdX[x + b]
            D[1, b] = dNdX[y + b]
            D[2, b] = dNdX[z + b]
        # G[(i, J, k), b] = Σ_L A[iJ, kL] ∂N_b/∂X_L
        for t in range(27):
            a0 = A[3 * t]
            a1 = A[3 * t + 1]
            a2 = A[3 * t + 2]
            for b in range(n):
                G[t, b] = a0 * D[0, b] + a1 * D[1, b] + a2 * D[2, b]
        # K[(a, i), (b, k)] += Σ_J ∂N_a/∂X_J G[(i, J, k), b]; all b (a full, vectorised row is
        # faster than the upper triangle alone), the lower triangle is overwritten below
        for a in range(n):
            d0 = D[0, a]
            d1 = D[1, a]
            d2 = D[2, a]
            for i in range(3):
                for k in range(3):
                    t = 9 * i + k
                    r = 9 * a + 3 * i + k
                    for b in range(n):
                        Ke[r, b] += d0 * G[t, b] + d1 * G[t + 3, b] + d2 * G[t + 6, b]
    if want_tangent:
        # K is symmetric for hyperelastic materials: copy the upper triangle (row (a, i) < column
        # (b, k)) onto the lower one, so that the assembled matrix is exactly symmetric
        for a in range(n):
            for i in range(3):
                for b in range(a, n):
                    for k in range(3):
                        if b > a or k > i:
                            Ke[9 * b + 3 * k + i, a] = Ke[9 * a + 3 * i + k, b]
    return energy, status


#: called once per element through a symbol: its code is optimised once, not again in the parallel
#: body and in the kernel (see mortar1d3d._unlinked)
_element_call = unlinked(_element)


@njit
def assemble_kernel(u, connectivity, codes, gp_ptr, dn_ptr, dNdX, wJ, colour_ptr, colour_blocks, block, node_ptr,
                    slot_ptr, slots, mat_code, lam, mu, linear, want_tangent, fibre_ptr, fibre_data, fibre_set, f,
                    data, data_map, element_energy, status):
    """Add every element's f_e (and K_e) into ``f`` and the CSR ``data``, colour by colour.

    The colouring and the CSR slots are those of :mod:`~mortar1d3d.physics.assembly_graph`:
    blocks of one colour share no node, so they add into ``f`` and ``data`` in parallel without
    races, and every entry receives its contributions in the same order for any thread count.

    ``data_map`` empty: ``data`` is the data of the mesh's own CSR pattern. Otherwise entry k of
    that pattern is added at ``data[data_map[k]]`` (a larger pattern holding the mesh's, e.g. the
    model's tangent with coupling and beams; its rows keep the three columns of a node together,
    so one look-up serves a node pair's row of three).
    """
    C0 = np.empty((6, 6))
    hooke(lam, mu, C0)
    n_el = codes.shape[0]
    mapped = data_map.shape[0] > 0
    # buffers as wide as the mesh's largest element (its connectivity's width), not the registry's:
    # a hex8 mesh's element matrix buffer stays 4.6 KB whatever types the registry holds
    w = connectivity.shape[1]
    for colour in range(colour_ptr.shape[0] - 1):
        _assemble_workers(colour_ptr[colour + 1] - colour_ptr[colour], colour_ptr[colour], u, connectivity, codes,
                          gp_ptr, dn_ptr, dNdX, wJ, colour_blocks, block, node_ptr, slot_ptr, slots, mat_code, lam,
                          mu, linear, want_tangent, fibre_ptr, fibre_data, fibre_set, f, data, data_map,
                          element_energy, status, C0, n_el, mapped, w)


@njit
def _assemble_worker(j, first, u, connectivity, codes, gp_ptr, dn_ptr, dNdX, wJ, colour_blocks, block, node_ptr,
                     slot_ptr, slots, mat_code, lam, mu, linear, want_tangent, fibre_ptr, fibre_data, fibre_set, f,
                     data, data_map, element_energy, status, C0, n_el, mapped, w):
    # block colour_blocks[first + j] of the colour starting at first (see assemble_kernel)
    c = first + j
    ue = np.empty((w, 3))
    fe = np.empty((w, 3))
    Ke = np.empty((9 * w, w))
    F = np.empty((3, 3))
    S = np.empty((3, 3))
    Cv = np.empty((6, 6))
    P = np.empty((3, 3))
    A = np.empty(81 + 54)
    G = np.empty((27, w))
    D = np.empty((3, w))
    k = colour_blocks[c]
    for e in range(k * block, min(n_el, (k + 1) * block)):
        energy, st = _element_call(e, u, connectivity, codes, gp_ptr, dn_ptr, dNdX, wJ, mat_code, lam, mu,
                              linear, want_tangent, C0, ue, fe, Ke, F, S, Cv, P, A, G, D, fibre_ptr,
                              fibre_data, fibre_set)
        element_energy[e] = energy
        status[e] = st
        n = N_NODES[codes[e]]
        for a in range(n):
            v = connectivity[e, a]
            for i in range(3):
                f[3 * v + i] += fe[a, i]
        if not want_tangent:
            continue
        base_slot = slot_ptr[e]
        for a in range(n):
            v = connectivity[e, a]
            deg = node_ptr[v + 1] - node_ptr[v]
            row0 = 9 * node_ptr[v]
            for b in range(n):
                col = row0 + 3 * slots[base_slot + a * n + b]
                for i in range(3):
                    pos = col + 3 * i * deg
                    if mapped:
                        pos = data_map[pos]
                    r = 9 * a + 3 * i
                    data[pos] += Ke[r, b]
                    data[pos + 1] += Ke[r + 1, b]
                    data[pos + 2] += Ke[r + 2, b]


_assemble_workers = in_parallel(_assemble_worker)


@njit_inline
def _add_symmetric(out, e, w, s00, s11, s22, s01, s12, s02):
    """``out[e] += w s`` for a symmetric tensor ``s`` given by its six components."""
    out[e, 0, 0] += w * s00
    out[e, 1, 1] += w * s11
    out[e, 2, 2] += w * s22
    out[e, 0, 1] += w * s01
    out[e, 1, 0] += w * s01
    out[e, 1, 2] += w * s12
    out[e, 2, 1] += w * s12
    out[e, 0, 2] += w * s02
    out[e, 2, 0] += w * s02


@njit
def cell_fields_kernel(u, connectivity, codes, gp_ptr, dn_ptr, dNdX, wJ, mat_code, lam, mu, linear,
                       fibre_ptr, fibre_data, fibre_set, strain, stress, status):
    """Per element, the w det J-weighted mean over its Gauss points of E (ε) and σ."""
    n_el = codes.shape[0]
    _cell_fields_kernel_workers(n_chunks(n_el, CHUNK), u, connectivity, codes, gp_ptr, dn_ptr, dNdX, wJ, mat_code,
                               lam, mu, linear, fibre_ptr, fibre_data, fibre_set, strain, stress, status, n_el)


@njit
def _cell_fields_kernel_worker(c, u, connectivity, codes, gp_ptr, dn_ptr, dNdX, wJ, mat_code, lam, mu, linear,
                              fibre_ptr, fibre_data, fibre_set, strain, stress, status, n_el):
    F = np.empty((3, 3))
    S = np.empty((3, 3))
    Cv = np.empty((6, 6))
    for e in range(c * CHUNK, min(n_el, (c + 1) * CHUNK)):
        n = N_NODES[codes[e]]
        status[e] = STATUS_OK
        fibre_lo = fibre_ptr[fibre_set[e]]
        fibre_hi = fibre_ptr[fibre_set[e] + 1]
        volume = 0.0
        for i in range(3):
            for j in range(3):
                strain[e, i, j] = 0.0
                stress[e, i, j] = 0.0
        for q in range(gp_ptr[e + 1] - gp_ptr[e]):
            x = dn_ptr[e] + 3 * n * q
            w = wJ[gp_ptr[e] + q]
            volume += w
            for i in range(3):
                for j in range(3):
                    F[i, j] = 0.0
            for a in range(n):
                v = connectivity[e, a]
                for i in range(3):
                    for j in range(3):
                        F[i, j] += u[3 * v + i] * dNdX[x + j * n + a]      # ∇u for now
            if linear:
                e00, e11, e22, e01, e12, e02 = small_strain(F)
                _add_symmetric(strain, e, w, e00, e11, e22, e01, e12, e02)
                hooke_stress(lam, mu, e00, e11, e22, e01, e12, e02, S)      # σ = C₀ : ε
                for i in range(3):
                    for j in range(3):
                        stress[e, i, j] += w * S[i, j]
                if fibre_hi > fibre_lo:
                    S[:, :] = 0.0
                    add_fibres(fibre_data, fibre_lo, fibre_hi, F, True, S, Cv)
                    for i in range(3):
                        for j in range(3):
                            stress[e, i, j] += w * S[i, j]
                continue
            stress_tangent(mat_code, lam, mu, F, S, Cv)     # takes H = ∇u
            if fibre_hi > fibre_lo:
                add_fibres(fibre_data, fibre_lo, fibre_hi, F, False, S, Cv)
            e00, e11, e22, e01, e12, e02 = green_lagrange(F)
            _add_symmetric(strain, e, w, e00, e11, e22, e01, e12, e02)
            for i in range(3):
                F[i, i] += 1.0
            det = det3(F)
            if not det > 0.0:
                status[e] = STATUS_INVERTED
            for i in range(3):
                for j in range(3):
                    # σ = F S Fᵀ / J
                    sigma = 0.0
                    for I in range(3):
                        for J in range(3):
                            sigma += F[i, I] * S[I, J] * F[j, J]
                    stress[e, i, j] += w * sigma / det
        for i in range(3):
            for j in range(3):
                strain[e, i, j] /= volume
                stress[e, i, j] /= volume


_cell_fields_kernel_workers = in_parallel(_cell_fields_kernel_worker)
