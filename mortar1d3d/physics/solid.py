"""Total Lagrangian solid elements of every solid type: internal forces, tangent, energy.

For a displacement field ``u`` on the reference mesh (``dof = 3*node + i``), per Gauss point
with reference derivatives ``∂N_a/∂X`` and weight ``w det J``:

    F = I + Σ_a u_a ⊗ ∂N_a/∂X          P = F S          W = W(F)
    f_int[a, i]        = Σ_gp w detJ  P_iJ ∂N_a/∂X_J
    K[(a, i), (b, k)]  = Σ_gp w detJ  ∂N_a/∂X_J  A_iJkL  ∂N_b/∂X_L
    A_iJkL = ∂P_iJ/∂F_kL = δ_ik S_JL + F_iI F_kK C_IJKL

(``S``, ``C`` from :func:`~mortar1d3d.physics.materials.stress_tangent``). With
``kinematics="linear"`` the strain is ``ε = sym(∇u)``, the stress Hooke's ``σ = C₀ : ε`` with
``C₀ = λ I⊗I + 2μ 𝕀`` for every material (the linearisation of every material at F = I), and
``A = C₀``: K is constant, assembled once, and ``f_int = K u``.

Full Gauss rules: hexahedron 2×2×2, hexahedron20 and hexahedron27 3×3×3, tetra 1 point,
tetra10 4 points (degree 2).

Parallel assembly without races, bit-identical for any number of threads: the elements are cut
into blocks of ``assembly_block`` (64) consecutive elements, and the blocks are greedily
coloured once (no two blocks of a colour share a node). Colours are processed in order, the
blocks of one colour in parallel, the elements of a block in order, each adding its element
vector and matrix directly into ``f_int`` and the CSR data of its nodes' rows. Every entry thus
receives its contributions in the same order whatever the thread count. Blocks rather than
single elements keep the writes local: consecutive elements share nodes, so the matrix rows
they touch stay in cache (colouring single elements made each colour sweep the whole matrix).
Locality thus follows the element numbering (mesh generators number elements locally).

The CSR pattern (node graph expanded to 3×3 blocks) and, per element, the column slot of every
node pair in the block row are computed once; work buffers are allocated per block of elements,
never for all elements.
"""
import numpy as np
import scipy.sparse as sp
from numba import prange

from .._config import CHUNK, njit, njit_parallel
from .._schedule import n_chunks
from ..elements.solid.dispatch import BY_CODE, MAX_NODES, N_NODES, SOLID_MODULES, deriv
from ..errors import MeshError, format_ids
from ..mesh import SolidMesh
from .fibre_material import FibreField, add_fibres
from .materials import VOIGT_INDEX, Material, hooke, stress_tangent

KINEMATICS = ("nonlinear", "linear")

#: consecutive elements per block of the coloured assembly (module docstring)
ASSEMBLY_BLOCK = 64

STATUS_OK = 0
STATUS_INVERTED = 1      # det F <= 0 (or not finite) at a Gauss point


class InvertedElementsError(FloatingPointError):
    """``det F <= 0`` at a Gauss point of the listed elements (``.elements``, int64 array).

    A Newton solver catches this to cut its step: the deformation is not admissible.
    """

    def __init__(self, elements):
        self.elements = np.asarray(elements, dtype=np.int64)
        super().__init__(f"det F <= 0 (or not finite) at a Gauss point of {len(self.elements)} solid "
                         f"elements: {format_ids(self.elements)}")


#: volume rule per element code (from the element descriptors): (points (n_gp, 3), weights (n_gp,))
RULES = {code: d.quadrature for code, d in BY_CODE.items()}
_N_CODES = len(BY_CODE)
N_GAUSS = np.array([len(RULES[c][1]) for c in range(_N_CODES)], dtype=np.int64)
RULE_PTR = np.concatenate([[0], np.cumsum(N_GAUSS)]).astype(np.int64)
RULE_XI = np.ascontiguousarray(np.vstack([RULES[c][0] for c in range(_N_CODES)]))
RULE_W = np.concatenate([RULES[c][1] for c in range(_N_CODES)])


def _shape_table(code):
    """(n_gp, n_nodes) shape function values at the Gauss points (pure Python: no compilation)."""
    d = BY_CODE[code]
    shape = SOLID_MODULES[d.name].shape.py_func
    points = RULES[code][0]
    table = np.empty((len(points), d.n_nodes))
    for q, xi in enumerate(points):
        shape(xi, table[q])
    return table


# ----------------------------------------------------------------------------- kernels

@njit_parallel
def _reference_kernel(points, connectivity, codes, gp_ptr, dn_ptr, rule_ptr, rule_xi, rule_w, dNdX, wJ, status):
    """∂N_a/∂X and w det J at every Gauss point (reference configuration); status 1 if det J <= 0.

    Gauss point q of element e (n nodes) keeps ``∂N_a/∂X_j`` at ``dNdX[dn_ptr[e] + 3nq + jn + a]``:
    node index fastest, so that the loops over nodes in the element kernel vectorise.
    """
    n_el = codes.shape[0]
    for c in prange(n_chunks(n_el, CHUNK)):
        dN = np.empty((MAX_NODES, 3))
        for e in range(c * CHUNK, min(n_el, (c + 1) * CHUNK)):
            code = codes[e]
            n = N_NODES[code]
            status[e] = 0
            for q in range(gp_ptr[e + 1] - gp_ptr[e]):
                r = rule_ptr[code] + q
                deriv(code, rule_xi[r], dN)
                j00 = j01 = j02 = j10 = j11 = j12 = j20 = j21 = j22 = 0.0
                for a in range(n):
                    x = points[connectivity[e, a]]
                    j00 += x[0] * dN[a, 0]
                    j01 += x[0] * dN[a, 1]
                    j02 += x[0] * dN[a, 2]
                    j10 += x[1] * dN[a, 0]
                    j11 += x[1] * dN[a, 1]
                    j12 += x[1] * dN[a, 2]
                    j20 += x[2] * dN[a, 0]
                    j21 += x[2] * dN[a, 1]
                    j22 += x[2] * dN[a, 2]
                c00 = j11 * j22 - j12 * j21
                c01 = j12 * j20 - j10 * j22
                c02 = j10 * j21 - j11 * j20
                det = j00 * c00 + j01 * c01 + j02 * c02
                if not det > 0.0:
                    status[e] = 1
                    det = 1.0
                inv = 1.0 / det
                # J⁻¹ (row i = ∂ξ_i/∂X); ∂N/∂X_j = Σ_i ∂N/∂ξ_i (J⁻¹)_ij
                i00 = c00 * inv
                i01 = (j02 * j21 - j01 * j22) * inv
                i02 = (j01 * j12 - j02 * j11) * inv
                i10 = c01 * inv
                i11 = (j00 * j22 - j02 * j20) * inv
                i12 = (j02 * j10 - j00 * j12) * inv
                i20 = c02 * inv
                i21 = (j01 * j20 - j00 * j21) * inv
                i22 = (j00 * j11 - j01 * j10) * inv
                base = dn_ptr[e] + 3 * n * q
                for a in range(n):
                    d0 = dN[a, 0]
                    d1 = dN[a, 1]
                    d2 = dN[a, 2]
                    dNdX[base + a] = d0 * i00 + d1 * i10 + d2 * i20
                    dNdX[base + n + a] = d0 * i01 + d1 * i11 + d2 * i21
                    dNdX[base + 2 * n + a] = d0 * i02 + d1 * i12 + d2 * i22
                wJ[gp_ptr[e] + q] = rule_w[r] * det


@njit
def _graph_kernel(connectivity, codes, n_nodes, block):
    """Node graph, CSR pattern, per-element slots and a greedy colouring of element blocks.

    Returns
    -------
    node_ptr, neighbours : CSR of the sorted neighbour nodes (incl. itself) of every node
    slot_ptr, slots : per element, ``slots[slot_ptr[e] + a*n + b]`` = position of node b in
        the sorted neighbour list of node a
    indptr, indices : scalar CSR pattern, row ``3n+i`` holds ``3m+k`` for neighbours m, k < 3
    colour_ptr, colour_blocks : blocks (elements ``k*block`` to ``(k+1)*block - 1``) grouped by
        colour, ascending within a colour; blocks of one colour share no node
    """
    n_el = codes.shape[0]
    # node -> elements
    count = np.zeros(n_nodes + 1, dtype=np.int64)
    for e in range(n_el):
        for a in range(N_NODES[codes[e]]):
            count[connectivity[e, a] + 1] += 1
    el_ptr = np.cumsum(count)
    fill = el_ptr[:-1].copy()
    node_elements = np.empty(el_ptr[-1], dtype=np.int64)
    for e in range(n_el):
        for a in range(N_NODES[codes[e]]):
            v = connectivity[e, a]
            node_elements[fill[v]] = e
            fill[v] += 1
    # neighbour nodes: count, then fill and sort (short lists: insertion sort)
    stamp = np.full(n_nodes, -1, dtype=np.int64)
    degree = np.zeros(n_nodes + 1, dtype=np.int64)
    for v in range(n_nodes):
        for t in range(el_ptr[v], el_ptr[v + 1]):
            e = node_elements[t]
            for a in range(N_NODES[codes[e]]):
                m = connectivity[e, a]
                if stamp[m] != v:
                    stamp[m] = v
                    degree[v + 1] += 1
    node_ptr = np.cumsum(degree)
    neighbours = np.empty(node_ptr[-1], dtype=np.int64)
    stamp[:] = -1
    for v in range(n_nodes):
        k = node_ptr[v]
        for t in range(el_ptr[v], el_ptr[v + 1]):
            e = node_elements[t]
            for a in range(N_NODES[codes[e]]):
                m = connectivity[e, a]
                if stamp[m] != v:
                    stamp[m] = v
                    neighbours[k] = m
                    k += 1
        lo = node_ptr[v]
        for i in range(lo + 1, k):
            x = neighbours[i]
            j = i - 1
            while j >= lo and neighbours[j] > x:
                neighbours[j + 1] = neighbours[j]
                j -= 1
            neighbours[j + 1] = x
    # per element slots (binary search in the sorted neighbour lists)
    slot_ptr = np.zeros(n_el + 1, dtype=np.int64)
    for e in range(n_el):
        n = N_NODES[codes[e]]
        slot_ptr[e + 1] = slot_ptr[e] + n * n
    slots = np.empty(slot_ptr[-1], dtype=np.int32)
    for e in range(n_el):
        n = N_NODES[codes[e]]
        for a in range(n):
            v = connectivity[e, a]
            lo0 = node_ptr[v]
            for b in range(n):
                m = connectivity[e, b]
                lo = lo0
                hi = node_ptr[v + 1]
                while hi - lo > 1:
                    mid = (lo + hi) // 2
                    if neighbours[mid] <= m:
                        lo = mid
                    else:
                        hi = mid
                slots[slot_ptr[e] + a * n + b] = lo - lo0
    # scalar CSR pattern: the block row of node v expanded to rows 3v, 3v+1, 3v+2
    indptr = np.empty(3 * n_nodes + 1, dtype=np.int64)
    indptr[0] = 0
    indices = np.empty(9 * node_ptr[-1], dtype=np.int64)
    for v in range(n_nodes):
        deg = node_ptr[v + 1] - node_ptr[v]
        for i in range(3):
            start = 9 * node_ptr[v] + 3 * i * deg
            indptr[3 * v + i + 1] = start + 3 * deg
            for s in range(deg):
                for k in range(3):
                    indices[start + 3 * s + k] = 3 * neighbours[node_ptr[v] + s] + k
    # greedy colouring of blocks of `block` consecutive elements: the smallest colour that no
    # earlier block sharing a node has
    n_blocks = (n_el + block - 1) // block
    colour = np.full(n_blocks, -1, dtype=np.int64)
    forbidden = np.full(n_blocks + 1, -1, dtype=np.int64)
    n_colours = 0
    for k in range(n_blocks):
        for e in range(k * block, min(n_el, (k + 1) * block)):
            for a in range(N_NODES[codes[e]]):
                v = connectivity[e, a]
                for t in range(el_ptr[v], el_ptr[v + 1]):
                    other = node_elements[t] // block
                    if other != k and colour[other] >= 0:
                        forbidden[colour[other]] = k
        c = 0
        while forbidden[c] == k:
            c += 1
        colour[k] = c
        if c + 1 > n_colours:
            n_colours = c + 1
    colour_count = np.zeros(n_colours + 1, dtype=np.int64)
    for k in range(n_blocks):
        colour_count[colour[k] + 1] += 1
    colour_ptr = np.cumsum(colour_count)
    fill = colour_ptr[:-1].copy()
    colour_blocks = np.empty(n_blocks, dtype=np.int64)
    for k in range(n_blocks):
        colour_blocks[fill[colour[k]]] = k
        fill[colour[k]] += 1
    return node_ptr, neighbours, slot_ptr, slots, indptr, indices, colour_ptr, colour_blocks


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
                Cv[:, :] = C0
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
            det = (F[0, 0] * (F[1, 1] * F[2, 2] - F[1, 2] * F[2, 1])
                   - F[0, 1] * (F[1, 0] * F[2, 2] - F[1, 2] * F[2, 0])
                   + F[0, 2] * (F[1, 0] * F[2, 1] - F[1, 1] * F[2, 0]))
            if not det > 0.0:
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


@njit_parallel
def _assemble_kernel(u, connectivity, codes, gp_ptr, dn_ptr, dNdX, wJ, colour_ptr, colour_blocks, block, node_ptr,
                     slot_ptr, slots, mat_code, lam, mu, linear, want_tangent, fibre_ptr, fibre_data, fibre_set, f,
                     data, element_energy, status):
    """Add every element's f_e (and K_e) into ``f`` and the CSR ``data``, colour by colour."""
    C0 = np.empty((6, 6))
    hooke(lam, mu, C0)
    n_el = codes.shape[0]
    for colour in range(colour_ptr.shape[0] - 1):
        for c in prange(colour_ptr[colour], colour_ptr[colour + 1]):
            ue = np.empty((MAX_NODES, 3))
            fe = np.empty((MAX_NODES, 3))
            Ke = np.empty((9 * MAX_NODES, MAX_NODES))
            F = np.empty((3, 3))
            S = np.empty((3, 3))
            Cv = np.empty((6, 6))
            P = np.empty((3, 3))
            A = np.empty(81 + 54)
            G = np.empty((27, MAX_NODES))
            D = np.empty((3, MAX_NODES))
            k = colour_blocks[c]
            for e in range(k * block, min(n_el, (k + 1) * block)):
                energy, st = _element(e, u, connectivity, codes, gp_ptr, dn_ptr, dNdX, wJ, mat_code, lam, mu,
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
                            r = 9 * a + 3 * i
                            data[pos] += Ke[r, b]
                            data[pos + 1] += Ke[r + 1, b]
                            data[pos + 2] += Ke[r + 2, b]


@njit_parallel
def _cell_fields_kernel(u, connectivity, codes, gp_ptr, dn_ptr, dNdX, wJ, mat_code, lam, mu, linear,
                        fibre_ptr, fibre_data, fibre_set, strain, stress, status):
    """Per element, the w det J-weighted mean over its Gauss points of E (ε) and σ."""
    n_el = codes.shape[0]
    for c in prange(n_chunks(n_el, CHUNK)):
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
                    for i in range(3):
                        for j in range(3):
                            eps = 0.5 * (F[i, j] + F[j, i])
                            strain[e, i, j] += w * eps
                    # σ = λ tr ε I + 2μ ε (C₀ of :func:`hooke`)
                    trace = F[0, 0] + F[1, 1] + F[2, 2]
                    for i in range(3):
                        for j in range(3):
                            sigma = mu * (F[i, j] + F[j, i])
                            if i == j:
                                sigma += lam * trace
                            stress[e, i, j] += w * sigma
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
                for i in range(3):
                    for j in range(3):
                        # E = (H + Hᵀ + HᵀH) / 2, without the cancellation of (FᵀF - I) / 2
                        E = 0.5 * (F[i, j] + F[j, i] + F[0, i] * F[0, j] + F[1, i] * F[1, j] + F[2, i] * F[2, j])
                        strain[e, i, j] += w * E
                for i in range(3):
                    F[i, i] += 1.0
                det = (F[0, 0] * (F[1, 1] * F[2, 2] - F[1, 2] * F[2, 1])
                       - F[0, 1] * (F[1, 0] * F[2, 2] - F[1, 2] * F[2, 0])
                       + F[0, 2] * (F[1, 0] * F[2, 1] - F[1, 1] * F[2, 0]))
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


# ----------------------------------------------------------------------------- model

class SolidModel:
    """A solid body: internal forces, tangent stiffness and energy of a displacement field.

    Parameters
    ----------
    mesh : SolidMesh
        Any element types, mixed blocks allowed.
    material : Material
        From :func:`~mortar1d3d.physics.materials.material`.
    kinematics : {"nonlinear", "linear"}
        ``"nonlinear"``: Total Lagrangian finite deformation with the material's law.
        ``"linear"``: small strain, Hooke's law with the material's λ, μ (for every material).
    fibres : FibreField, optional
        Fibre families per element (:mod:`~mortar1d3d.physics.fibre_material`): their axial
        energy ``½ k (a·E a)²`` is added to the material's (with linear kinematics
        ``½ k (a·ε a)²``). None: no fibres.
    assembly_block : int
        Consecutive elements per block of the coloured parallel assembly (module docstring).
        Results do not depend on the thread count; they may differ in the last bits between
        block sizes (another summation order).

    Attributes
    ----------
    n_dofs : int
        ``3 * n_nodes``; ``dof = 3*node + i``.
    n_colours : int
        Colours of the element-block colouring (parallel assembly, module docstring).
    n_evaluations, n_tangents : int
        Calls of :meth:`evaluate`, and tangent matrices assembled (for linear kinematics the
        one cached K).

    Notes
    -----
    Memory per element: ∂N/∂X at every Gauss point, ``24 n_gp n_nodes`` bytes (hex8 1.5 KiB,
    hex27 17 KiB), plus ``4 n_nodes²`` bytes of CSR slots.
    """

    def __init__(self, mesh, material, kinematics="nonlinear", *, fibres=None, assembly_block=ASSEMBLY_BLOCK):
        if not isinstance(mesh, SolidMesh):
            raise TypeError(f"SolidModel: mesh must be a SolidMesh, got {type(mesh).__name__}")
        if not isinstance(material, Material):
            raise TypeError(f"SolidModel: material must be a Material (see physics.materials.material), "
                            f"got {type(material).__name__}")
        if kinematics not in KINEMATICS:
            raise ValueError(f"SolidModel: unknown kinematics {kinematics!r}; known: {', '.join(KINEMATICS)}")
        if fibres is None:
            fibres = FibreField.empty(mesh.n_elements)
        if not isinstance(fibres, FibreField) or len(fibres.element_set) != mesh.n_elements:
            raise TypeError(f"SolidModel: fibres must be a FibreField of the mesh's {mesh.n_elements} elements, "
                            f"got {fibres!r}")
        self.fibres = fibres
        if int(assembly_block) < 1:
            raise ValueError(f"SolidModel: assembly_block must be >= 1, got {assembly_block!r}")
        self.assembly_block = int(assembly_block)
        self.mesh = mesh
        self.material = material
        self.kinematics = kinematics
        self.n_dofs = 3 * mesh.n_nodes
        self.n_evaluations = 0
        self.n_tangents = 0
        self._linear = kinematics == "linear"
        self._lam = float(material.lam)
        self._mu = float(material.mu)

        self._codes = np.ascontiguousarray(mesh.element_codes, dtype=np.int64)
        self._connectivity = np.ascontiguousarray(mesh.connectivity, dtype=np.int64)
        n_gp = N_GAUSS[self._codes]
        self._gp_ptr = np.concatenate([[0], np.cumsum(n_gp)]).astype(np.int64)
        self._dn_ptr = np.concatenate([[0], np.cumsum(3 * n_gp * N_NODES[self._codes])]).astype(np.int64)
        self._dNdX = np.empty(self._dn_ptr[-1])
        self._wJ = np.empty(self._gp_ptr[-1])
        status = np.empty(mesh.n_elements, dtype=np.int64)
        _reference_kernel(mesh.points, self._connectivity, self._codes, self._gp_ptr, self._dn_ptr, RULE_PTR,
                          RULE_XI, RULE_W, self._dNdX, self._wJ, status)
        bad = np.flatnonzero(status)
        if bad.size:
            raise MeshError(f"solid elements with det J <= 0 at a Gauss point: {format_ids(bad)}")

        (self._node_ptr, _, self._slot_ptr, self._slots, indptr, indices, self._colour_ptr,
         self._colour_blocks) = _graph_kernel(self._connectivity, self._codes, mesh.n_nodes,
                                                   self.assembly_block)
        index_type = np.int32 if max(len(indices), self.n_dofs) < np.iinfo(np.int32).max else np.int64
        self._indptr = indptr.astype(index_type)
        self._indices = indices.astype(index_type)
        self._indptr.flags.writeable = False
        self._indices.flags.writeable = False
        self.n_colours = len(self._colour_ptr) - 1
        self._K_linear = None
        self._nodal_volume = None

    # -- evaluation ----------------------------------------------------------------------

    def _displacement(self, u):
        u = np.ascontiguousarray(u, dtype=np.float64).reshape(-1)
        if u.shape != (self.n_dofs,):
            raise ValueError(f"SolidModel: u must have {self.n_dofs} entries (3 per node), got {u.size}")
        return u

    def _assemble(self, u, want_tangent, linear):
        f = np.zeros(self.n_dofs)
        data = np.zeros(len(self._indices) if want_tangent else 0)
        energy = np.empty(self.mesh.n_elements)
        status = np.empty(self.mesh.n_elements, dtype=np.int64)
        _assemble_kernel(u, self._connectivity, self._codes, self._gp_ptr, self._dn_ptr, self._dNdX, self._wJ,
                         self._colour_ptr, self._colour_blocks, self.assembly_block, self._node_ptr, self._slot_ptr,
                         self._slots, self.material.code, self._lam, self._mu, linear, want_tangent,
                         self.fibres.set_ptr, self.fibres.data, self.fibres.element_set, f, data, energy, status)
        bad = np.flatnonzero(status)
        if bad.size:
            raise InvertedElementsError(bad)
        K = None
        if want_tangent:
            K = sp.csr_matrix((data, self._indices, self._indptr), shape=(self.n_dofs, self.n_dofs), copy=False)
            K.has_sorted_indices = True
            self.n_tangents += 1
        return f, K, energy

    def _linear_stiffness(self):
        if self._K_linear is None:
            _, self._K_linear, _ = self._assemble(np.zeros(self.n_dofs), True, True)
        return self._K_linear

    def evaluate(self, u, tangent=True):
        """Internal force vector and (optionally) the tangent stiffness at displacement ``u``.

        Parameters
        ----------
        u : (n_dofs,) array_like of float
            Nodal displacements, ``dof = 3*node + i``.
        tangent : bool
            Assemble ``K`` as well.

        Returns
        -------
        f_int : (n_dofs,) float64
        K : scipy.sparse.csr_matrix (n_dofs, n_dofs), symmetric, or None
            Linear kinematics: the same cached matrix on every call (do not modify it), and
            ``f_int = K u``.

        Raises
        ------
        InvertedElementsError
            det F <= 0 at a Gauss point (nonlinear kinematics), naming the elements.
        """
        u = self._displacement(u)
        self.n_evaluations += 1
        if self._linear:
            K = self._linear_stiffness()
            return K @ u, (K if tangent else None)
        f, K, _ = self._assemble(u, tangent, False)
        return f, K

    def energy(self, u):
        """Total strain energy ``Σ_gp w det J W`` at ``u`` (float).

        Raises :class:`InvertedElementsError` where the deformation is not admissible.
        """
        u = self._displacement(u)
        _, _, energy = self._assemble(u, False, self._linear)
        return float(np.sum(energy))

    # -- loads and output ------------------------------------------------------------------

    def nodal_volumes(self):
        """(n_nodes,) ``∫ N_a dV₀``: the consistent nodal share of the reference volume."""
        if self._nodal_volume is None:
            volume = np.zeros(self.mesh.n_nodes)
            start = 0
            for descriptor, conn in self.mesh.blocks:
                m = len(conn)
                n_gp = len(RULES[descriptor.code][1])
                g0 = self._gp_ptr[start]
                wJ = self._wJ[g0:g0 + m * n_gp].reshape(m, n_gp)
                np.add.at(volume, conn, wJ @ _shape_table(descriptor.code))
                start += m
            self._nodal_volume = volume
        return self._nodal_volume

    def body_force(self, b):
        """Consistent nodal forces ``∫ N_a b dV₀`` of a dead load ``b`` (3,) per reference volume.

        Returns (n_dofs,) float64.
        """
        b = np.asarray(b, dtype=np.float64)
        if b.shape != (3,) or not np.isfinite(b).all():
            raise ValueError(f"SolidModel.body_force: b must be 3 finite numbers, got {b!r}")
        return (self.nodal_volumes()[:, None] * b[None, :]).reshape(-1)

    def cell_fields(self, u):
        """Per-element strain and Cauchy stress, averaged over the Gauss points (weights w det J).

        Returns
        -------
        dict
            ``"green_lagrange_strain"`` (n_elements, 3, 3) and ``"cauchy_stress"``
            (n_elements, 3, 3) (σ = F S Fᵀ / J). Linear kinematics: the small strain
            ε = sym(∇u) and Hooke's σ under the same names.
        """
        u = self._displacement(u)
        n_el = self.mesh.n_elements
        strain = np.empty((n_el, 3, 3))
        stress = np.empty((n_el, 3, 3))
        status = np.empty(n_el, dtype=np.int64)
        _cell_fields_kernel(u, self._connectivity, self._codes, self._gp_ptr, self._dn_ptr, self._dNdX, self._wJ,
                            self.material.code, self._lam, self._mu, self._linear, self.fibres.set_ptr,
                            self.fibres.data, self.fibres.element_set, strain, stress, status)
        bad = np.flatnonzero(status)
        if bad.size:
            raise InvertedElementsError(bad)
        return {"green_lagrange_strain": strain, "cauchy_stress": stress}

    def volume(self):
        """Reference volume ``Σ_gp w det J`` (float)."""
        return float(np.sum(self._wJ))

    def __repr__(self):
        return (f"SolidModel({self.mesh!r}, {self.material.name}, {self.kinematics}; "
                f"{self.n_dofs} dofs, {self.n_colours} colours)")
