"""The solid model on NURBS patches, with control-point DOFs.

:class:`NurbsSolidModel` runs :class:`~mortar1d3d.physics.solid.SolidModel` (total Lagrangian, every
material, or linear kinematics) on the ``nurbs27``, ``nurbs64`` or ``nurbs125`` mesh of the patches (any degree 1 … 4
per direction, elevated to the common degree there: :func:`~mortar1d3d.nurbs.bezier_mesh`) and maps everything to the global control points with
T (mesh node values = T · control values): internal forces Tᵀ f, stiffness Tᵀ K T, since the NURBS
space is the image of T. Surface loads act on patch faces: follower pressure on the current
surface (:meth:`NurbsSolidModel.pressure_load`, with its load stiffness) or dead pressure on the
reference surface (:meth:`NurbsSolidModel.pressure`), both by the surface kernels of
:mod:`mortar1d3d.physics.surface` with rational face tables. Dirichlet conditions act
on the control points of patch faces (:meth:`NurbsSolid.face_control`: a
control net face carries exactly the face's functions, so fixing them fixes the face).
"""
import numpy as np
import scipy.sparse as sp

from ..physics.solid import SolidModel
from ..physics.surface import FACE_DTYPE, Pressure
from .mesh import bezier_mesh, element_values


class NurbsSolidModel:
    """Internal forces and stiffness of a :class:`~mortar1d3d.nurbs.NurbsSolid` (degrees 1 … 4 per direction) on its
    control points.

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

    def face_set(self, patch, face):
        """The Bézier mesh's element faces on face ``face`` (``"u0_min"``, ...) of patch ``patch``: a
        structured array of :data:`~mortar1d3d.physics.surface.FACE_DTYPE` (surface loads)."""
        return patch_face_set(self.mesh, patch, face)

    def pressure_load(self, patch, face, p, n_gauss=None):
        """Follower pressure ``p`` (force per current area, pushing into the body) on face ``face`` of
        patch ``patch``, on control points: a :class:`ControlPointLoad` whose ``evaluate(u, tangent)``
        gives Tᵀ f(T u) and its derivative Tᵀ K T (``n_gauss`` points per direction on each span face; None:
        the rule of the face's degree, :func:`~mortar1d3d.physics.rational_surface.rational_face_points`)."""
        return ControlPointLoad(Pressure(self.mesh.solid, self.face_set(patch, face), p, n_gauss), self.T3)

    def pressure(self, patch, face, p, n_gauss=None):
        """Consistent control-point forces of a pressure ``p`` (force per reference area, pushing into the
        body) on face ``face`` (``"u0_min"``, ...) of patch ``patch``, dead load on the reference surface:
        f_i = -∫ p R_i n dA with n the outward normal. Returns (n_dofs,)."""
        return self.pressure_load(patch, face, p, n_gauss).evaluate(None, tangent=False)[0]

    def sample(self, u=None, points=3):
        """Points of every element on a ``points``³ lattice of [-1, 1]³ (n_elements, points³, 3), displaced by
        the control-point displacements ``u`` if given (output, error measures)."""
        s = np.linspace(-1.0, 1.0, points)
        xi = np.stack(np.meshgrid(s, s, s, indexing="ij"), axis=-1).reshape(-1, 3)
        solid = self.mesh.solid
        X = solid.points if u is None else solid.points + self.node_displacement(u).reshape(-1, 3)
        return element_values(solid, xi, X)

    def write_vtu(self, path, u=None):
        """The solid as sampled spans (:func:`mortar1d3d.io.vtu.write_solid`: every element's exact points
        at the hexahedron27 lattice parameters of (p-1)³ sub-boxes; ParaView interpolates between them), with the
        ``displacement`` of the control-point displacements ``u`` as point data. Returns the path."""
        from ..io.vtu import write_solid

        solid = self.mesh.solid
        d = np.zeros((solid.n_nodes, 3)) if u is None else self.node_displacement(u).reshape(-1, 3)
        return write_solid(path, solid, point_data={"displacement": d})


def _parse_face(face):
    """(axis, side) of a patch face name ``"u0_min"`` ... ``"u2_max"``; ValueError otherwise."""
    if not (isinstance(face, str) and len(face) == 6 and face[0] == "u" and face[1] in "012"
            and face[2:] in ("_min", "_max")):
        raise ValueError(f"face {face!r}: expected 'u0_min', 'u0_max', 'u1_min', ..., 'u2_max'")
    return int(face[1]), (-1.0 if face.endswith("min") else 1.0)


def patch_face_set(mesh, patch, face):
    """Element faces (:data:`~mortar1d3d.physics.surface.FACE_DTYPE`) of a :class:`BezierMesh` that lie on
    face ``face`` of patch ``patch``: the elements of the first or last span in that direction, with the
    local face whose outward normal is ± the parameter direction."""
    axis, side = _parse_face(face)
    if not 0 <= patch < len(mesh.nurbs.patches):
        raise ValueError(f"patch {patch}: the solid has {len(mesh.nurbs.patches)} patch(es)")
    last = {-1.0: 0, 1.0: mesh.nurbs.patches[patch].element_shape[axis] - 1}[side]
    elements = np.flatnonzero((mesh.element_patch == patch) & (mesh.element_span[:, axis] == last))
    d = mesh.solid.blocks[0][0]
    normal = np.zeros(3)
    normal[axis] = side
    local = [f for f in range(d.n_faces) if np.allclose(d.faces[f][3], normal)]
    out = np.empty(len(elements), dtype=FACE_DTYPE)
    out["element"], out["face"], out["code"] = elements, local[0], d.code
    return out


class ControlPointLoad:
    """A displacement-dependent load on the Bézier mesh (``evaluate(u_nodes, tangent)``) seen on control
    points: f_c(u) = Tᵀ f(T u), K_c = Tᵀ K T (T: node values from control values, per component)."""

    def __init__(self, load, T3):
        self.load, self.T3 = load, T3

    def evaluate(self, u=None, tangent=True):
        """External force (n_dofs,) and its derivative (csr, or None) at control-point displacements ``u``."""
        f, K = self.load.evaluate(None if u is None else self.T3 @ np.asarray(u, dtype=np.float64), tangent)
        return self.T3.T @ f, (sp.csr_matrix(self.T3.T @ K @ self.T3) if tangent else None)


__all__ = ["NurbsSolidModel", "ControlPointLoad", "patch_face_set"]
