"""The solid model on NURBS patches, with control-point DOFs.

:class:`NurbsSolidModel` runs :class:`~mortar1d3d.physics.solid.SolidModel` (total Lagrangian, every
material, or linear kinematics) on the ``nurbs27`` mesh of the patches
(:func:`~mortar1d3d.nurbs.bezier_mesh`) and maps everything to the global control points with
T (mesh node values = T · control values): internal forces Tᵀ f, stiffness Tᵀ K T, since the NURBS
space is the image of T. Surface loads act on patch faces (:meth:`NurbsSolidModel.pressure`),
Dirichlet conditions on the control points of patch faces (:meth:`NurbsSolid.face_control`: a
control net face carries exactly the face's functions, so fixing them fixes the face).
"""
import numpy as np
import scipy.sparse as sp

from ..elements.solid import nurbs27
from ..physics.solid import SolidModel
from ..quadrature import gauss_legendre
from .mesh import bezier_mesh

#: the faces of a patch by parameter direction and side, as the element faces of :mod:`.hex_family`:
#: (fixed direction, value of ξ there, the two free directions in right-handed order with the outward normal)
_FACES = {(0, -1.0): (2, 1), (0, 1.0): (1, 2), (1, -1.0): (0, 2), (1, 1.0): (2, 0), (2, -1.0): (1, 0), (2, 1.0): (0, 1)}


class NurbsSolidModel:
    """Internal forces and stiffness of a quadratic :class:`~mortar1d3d.nurbs.NurbsSolid` on its control points.

    Parameters
    ----------
    nurbs : NurbsSolid
    material : Material
    kinematics : {"nonlinear", "linear"}

    Attributes
    ----------
    mesh : BezierMesh
    solid : SolidModel
        On the Bézier mesh's nodes.
    n_dofs : int
        ``3 n_control`` (dof = 3 control point + i).
    """

    def __init__(self, nurbs, material, kinematics="nonlinear"):
        self.mesh = bezier_mesh(nurbs)
        self.nurbs = nurbs
        self.solid = SolidModel(self.mesh.solid, material, kinematics)
        self.T3 = sp.kron(self.mesh.T, sp.identity(3), format="csr")
        self.n_dofs = 3 * nurbs.n_control

    def node_displacement(self, u):
        """Bézier-mesh node displacements (3 n_nodes,) of control-point displacements ``u`` (3 n_control,)."""
        return self.T3 @ np.asarray(u, dtype=np.float64)

    def evaluate(self, u, tangent=True):
        """Internal forces (n_dofs,) and the tangent (csr, or None) at control-point displacements ``u``."""
        f, K = self.solid.evaluate(self.node_displacement(u), tangent)
        return self.T3.T @ f, (sp.csr_matrix(self.T3.T @ K @ self.T3) if tangent else None)

    def pressure(self, patch, face, p, n_gauss=4):
        """Consistent control-point forces of a pressure ``p`` (force per reference area, pushing into the
        body) on face ``face`` (``"u0_min"``, ...) of patch ``patch``, dead load on the reference surface:
        f_i = -∫ p R_i n dA with n the outward normal. Returns (n_dofs,)."""
        axis, side = int(face[1]), (-1.0 if face.endswith("min") else 1.0)
        patch_obj = self.nurbs.patches[patch]
        last = {-1.0: 0, 1.0: patch_obj.element_shape[axis] - 1}[side]
        elements = np.flatnonzero((self.mesh.element_patch == patch) & (self.mesh.element_span[:, axis] == last))
        t, w = gauss_legendre(n_gauss)
        a, b = _FACES[(axis, side)]
        xi = np.zeros((n_gauss * n_gauss, 3))
        xi[:, axis] = side
        xi[:, a] = np.repeat(t, n_gauss)
        xi[:, b] = np.tile(t, n_gauss)
        weight = np.outer(w, w).ravel()
        B, dB = nurbs27.bernstein_values(xi)
        solid = self.mesh.solid
        f = np.zeros(3 * solid.n_nodes)
        for e in elements:
            nodes = solid.connectivity[e, :27]
            X, wts = solid.points[nodes], solid.weights[nodes]
            wB = B * wts
            W = wB.sum(axis=1)
            R = wB / W[:, None]
            dR = (dB * wts[None, :, None] - R[:, :, None] * (dB * wts[None, :, None]).sum(axis=1)[:, None, :]) / W[:, None, None]
            ta = np.einsum("qa,ai->qi", dR[:, :, a], X)
            tb = np.einsum("qa,ai->qi", dR[:, :, b], X)
            n_dA = np.cross(ta, tb) * weight[:, None]          # outward normal times area element
            np.add.at(f.reshape(-1, 3), nodes, -p * np.einsum("qa,qi->ai", R, n_dA))
        return self.T3.T @ f

    def sample(self, u=None, points=3):
        """Points of every element on a ``points``³ lattice of [-1, 1]³ (n_elements, points³, 3), displaced by
        the control-point displacements ``u`` if given (output, error measures)."""
        s = np.linspace(-1.0, 1.0, points)
        xi = np.stack(np.meshgrid(s, s, s, indexing="ij"), axis=-1).reshape(-1, 3)
        B, _ = nurbs27.bernstein_values(xi)
        solid = self.mesh.solid
        nodes = solid.connectivity[:, :27]
        wB = B[None] * solid.weights[nodes][:, None, :]
        R = wB / wB.sum(axis=2, keepdims=True)
        X = solid.points if u is None else solid.points + self.node_displacement(u).reshape(-1, 3)
        return np.einsum("mqa,mai->mqi", R, X[nodes])

    def write_vtu(self, path, u=None):
        """The solid as sampled spans: every element's points at the 27 hexahedron27 lattice parameters
        (exact points of the NURBS geometry; ParaView interpolates between them), with the
        ``displacement`` of the control-point displacements ``u`` as point data. Returns the path."""
        import meshio

        from ..elements.solid.hex_family import QUADRATIC_NODES

        B, _ = nurbs27.bernstein_values(QUADRATIC_NODES)
        solid = self.mesh.solid
        nodes = solid.connectivity[:, :27]
        wB = B[None] * solid.weights[nodes][:, None, :]
        R = wB / wB.sum(axis=2, keepdims=True)
        x = np.einsum("mqa,mai->mqi", R, solid.points[nodes]).reshape(-1, 3)
        d = np.zeros(x.shape) if u is None else \
            np.einsum("mqa,mai->mqi", R, self.node_displacement(u).reshape(-1, 3)[nodes]).reshape(-1, 3)
        cells = np.arange(len(x)).reshape(-1, 27)
        meshio.write(path, meshio.Mesh(x, [("hexahedron27", cells)], point_data={"displacement": d}))
        return path


__all__ = ["NurbsSolidModel"]
