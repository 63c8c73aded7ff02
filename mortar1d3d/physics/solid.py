"""The solid body of a model: internal forces, tangent stiffness, energy, loads and cell fields.

:class:`SolidModel` validates its inputs and owns the per-mesh data; the work is done by the
modules it is made of:

- :mod:`~mortar1d3d.physics.solid_reference`: volume rules, ``∂N/∂X`` and ``w det J`` at every
  Gauss point (once per mesh);
- :mod:`~mortar1d3d.physics.assembly_graph`: the CSR pattern and the colouring of element blocks
  for the race-free parallel assembly (once per mesh);
- :mod:`~mortar1d3d.physics.solid_kernels`: the Total Lagrangian (or small strain) element
  kernels and their assembly (every evaluation);
- :mod:`~mortar1d3d.physics.materials`, :mod:`~mortar1d3d.physics.fibre_material`: the
  constitutive laws the kernels call at every Gauss point.

With ``kinematics="linear"`` K is constant: it is assembled once, and ``f_int = K u``.
"""
import numpy as np
import scipy.sparse as sp

from ..errors import InvertedElementsError  # noqa: F401 (raised here; importable from here as before)
from ..mesh import SolidMesh
from .assembly_graph import assembly_graph
from .fibre_material import FibreField
from .materials import Material
from .solid_kernels import assemble_kernel, cell_fields_kernel
from .solid_reference import RULES, reference_gauss_points, shape_table

KINEMATICS = ("nonlinear", "linear")

#: consecutive elements per block of the coloured assembly (:mod:`~mortar1d3d.physics.assembly_graph`)
ASSEMBLY_BLOCK = 64


#: ``data_map`` of :func:`assemble_kernel` meaning "the mesh's own CSR pattern"
_OWN_PATTERN = np.empty(0, dtype=np.int32)


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
        Consecutive elements per block of the coloured parallel assembly
        (:mod:`~mortar1d3d.physics.assembly_graph`).
        Results do not depend on the thread count; they may differ in the last bits between
        block sizes (another summation order).

    Attributes
    ----------
    n_dofs : int
        ``3 * n_nodes``; ``dof = 3*node + i``.
    n_colours : int
        Colours of the element-block colouring (:mod:`~mortar1d3d.physics.assembly_graph`).
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
        self._gp_ptr, self._dn_ptr, self._dNdX, self._wJ = reference_gauss_points(mesh.kernel_points,
                                                                                  self._connectivity, self._codes)
        graph = assembly_graph(self._connectivity, self._codes, mesh.n_nodes, self.assembly_block)
        self._node_ptr, self._slot_ptr, self._slots = graph.node_ptr, graph.slot_ptr, graph.slots
        self._colour_ptr, self._colour_blocks = graph.colour_ptr, graph.colour_blocks
        index_type = np.int32 if max(len(graph.indices), self.n_dofs) < np.iinfo(np.int32).max else np.int64
        self._indptr = graph.indptr.astype(index_type)
        self._indices = graph.indices.astype(index_type)
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

    def _assemble(self, u, want_tangent, linear, data=None, data_map=_OWN_PATTERN):
        f = np.zeros(self.n_dofs)
        own = data is None
        if own:
            data = np.zeros(len(self._indices) if want_tangent else 0)
        energy = np.empty(self.mesh.n_elements)
        status = np.empty(self.mesh.n_elements, dtype=np.int64)
        assemble_kernel(u, self._connectivity, self._codes, self._gp_ptr, self._dn_ptr, self._dNdX, self._wJ,
                        self._colour_ptr, self._colour_blocks, self.assembly_block, self._node_ptr, self._slot_ptr,
                        self._slots, self.material.code, self._lam, self._mu, linear, want_tangent,
                        self.fibres.set_ptr, self.fibres.data, self.fibres.element_set, f, data, data_map, energy,
                        status)
        bad = np.flatnonzero(status)
        if bad.size:
            raise InvertedElementsError(bad)
        K = None
        if want_tangent and own:
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

    @property
    def pattern(self):
        """``(shape, indptr, indices)`` of the tangent's CSR pattern: fixed for the mesh, read-only."""
        return (self.n_dofs, self.n_dofs), self._indptr, self._indices

    def add_tangent_into(self, u, data, data_map):
        """Internal force at ``u``, with the tangent's entries added into a larger matrix's data.

        Nonlinear kinematics only (linear: :meth:`evaluate` returns the cached matrix). Entry k of
        :attr:`pattern` is added at ``data[data_map[k]]``, element by element in the same order as
        :meth:`evaluate` sums them, so each entry's value equals that of :meth:`evaluate`'s ``K``
        when ``data`` starts at zero there; the model's tangent is filled this way without a
        separate solid matrix (see :mod:`mortar1d3d.model.tangent`).

        Parameters
        ----------
        u : (n_dofs,) array_like of float
        data : (nnz,) float64, modified in place
        data_map : (len(pattern indices),) int32 or int64
            Positions in ``data`` of the entries of :attr:`pattern`, each a node's three columns
            adjacent (true of any sorted CSR pattern holding this one).

        Returns
        -------
        f_int : (n_dofs,) float64
        """
        if self._linear:
            raise ValueError("SolidModel.add_tangent_into: linear kinematics keep one cached matrix; use evaluate")
        u = self._displacement(u)
        if data_map.shape != self._indices.shape:
            raise ValueError(f"SolidModel.add_tangent_into: data_map must have {len(self._indices)} entries, "
                             f"got {data_map.shape}")
        self.n_evaluations += 1
        f, _, _ = self._assemble(u, True, False, data=data, data_map=data_map)
        self.n_tangents += 1
        return f

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
                if descriptor.rational:
                    # R_a = w_a B_a / W differs from element to element
                    B = shape_table(descriptor.code)[None] * self.mesh.weights[conn][:, None, :]
                    np.add.at(volume, conn, np.einsum("mq,mqa->ma", wJ, B / B.sum(axis=2, keepdims=True)))
                else:
                    np.add.at(volume, conn, wJ @ shape_table(descriptor.code))
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
        cell_fields_kernel(u, self._connectivity, self._codes, self._gp_ptr, self._dn_ptr, self._dNdX, self._wJ,
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
