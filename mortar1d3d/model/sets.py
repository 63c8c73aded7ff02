"""Named sets of a scene resolved to nodes: ``solid:x_min``, ``solid:<point set>``, boxes
``{inside = [...]}``, ``beam:<i>``, ``beam:<i>:start|end``.

Every set that selects nothing is a SceneError naming the key path that used it, raised when
the set is resolved (at model construction, so that :func:`~mortar1d3d.model.plan` reports
what :func:`~mortar1d3d.model.solve` would).
"""
import numpy as np

from ..scene import BOX_FACES, SceneError


class NamedSets:
    """Resolves set specs against the meshes of a built scene.

    Parameters
    ----------
    solid_mesh : SolidMesh or None
    entry_group : list of BeamGroup
        The group of every ``beams[i]`` entry, in scene order.
    """

    def __init__(self, solid_mesh, entry_group):
        self.solid_mesh = solid_mesh
        self.entry_group = entry_group

    def beam_nodes(self, entry, which, path):
        """``(group, node ids)`` of beam ``entry``: all its nodes, or its ``"start"``/``"end"`` node."""
        if entry >= len(self.entry_group):
            n = len(self.entry_group)
            raise SceneError(f"{path}: beam {entry} does not exist (the scene has {n} beam{'s' if n != 1 else ''})")
        g = self.entry_group[entry]
        k = g.entries.index(entry)
        start, stop = g.entry_elements[k]
        if which == "start":
            return g, g.mesh.elements[start, :1].copy()
        if which == "end":
            return g, g.mesh.elements[stop - 1, 1:2].copy()
        return g, np.unique(g.mesh.elements[start:stop])

    def select(self, spec, path):
        """Resolve a set spec to ``("solid", node ids)`` or ``("beam", group, node ids)``.

        Raises SceneError (naming ``path``) when the set selects nothing.
        """
        if isinstance(spec, dict):
            if self.solid_mesh is None:
                raise SceneError(f"{path}: 'inside' selects solid nodes, but the scene has no solid")
            lo, hi = np.asarray(spec["inside"], dtype=float)
            X = self.solid_mesh.points
            tol = 1e-9 * float(np.linalg.norm(np.ptp(X, axis=0)))
            nodes = self._at(lambda x: ((x >= lo - tol) & (x <= hi + tol)).all(axis=-1))
            if nodes.size == 0:
                raise SceneError(f"{path}: the box {lo.tolist()} – {hi.tolist()} contains no solid node")
            return ("solid", nodes)
        parts = spec.split(":")
        if parts[0] == "solid":
            if self.solid_mesh is None:
                raise SceneError(f"{path}: {spec!r} names a solid set, but the scene has no solid")
            name = parts[1]
            X = self.solid_mesh.points
            if name in BOX_FACES:
                axis = "xyz".index(name[0])
                if self._rational:
                    from ..nurbs.sets import body_extent       # the body's extent, not its control points'
                    lo, hi = body_extent(self.solid_mesh, axis)
                    target = lo if name.endswith("min") else hi
                else:
                    target = X[:, axis].min() if name.endswith("min") else X[:, axis].max()
                tol = 1e-9 * float(np.linalg.norm(np.ptp(X, axis=0)))
                nodes = self._at(lambda x: np.abs(x[..., axis] - target) <= tol)
            elif name in self.solid_mesh.point_sets:
                nodes = np.unique(np.asarray(self.solid_mesh.point_sets[name], dtype=np.int64))
            else:
                known = sorted(set(BOX_FACES) | set(self.solid_mesh.point_sets))
                raise SceneError(f"{path}: unknown solid set {name!r}; known: {', '.join(known)}")
            if nodes.size == 0:
                raise SceneError(f"{path}: {spec!r} selects no node")
            return ("solid", nodes)
        entry = int(parts[1])
        g, nodes = self.beam_nodes(entry, parts[2] if len(parts) == 3 else None, path)
        return ("beam", g, nodes)

    @property
    def _rational(self):
        return any(d.rational for d, _ in self.solid_mesh.blocks)

    def _at(self, inside):
        """Solid nodes where ``inside(x)`` (points (..., 3) → bool) holds: polynomial elements' nodes by their
        position; of rational (NURBS) elements the control points of the corners, edges, faces and elements
        whose body lies there (:func:`mortar1d3d.nurbs.sets.body_nodes`)."""
        X = self.solid_mesh.points
        if not self._rational:
            return np.flatnonzero(inside(X))
        from ..nurbs.sets import body_nodes
        polynomial = np.unique(np.concatenate([conn[:, : d.n_nodes].ravel() for d, conn in self.solid_mesh.blocks
                                               if not d.rational] or [np.zeros(0, np.int64)]))
        return np.union1d(polynomial[inside(X[polynomial])], body_nodes(self.solid_mesh, inside))

    def fibre_regions(self, families):
        """Per ``solid.material.fibres`` family: None (every element) or the mask of the elements
        whose node centroid lies in its ``inside`` box (of a rational element: its body point at the
        parameter centre, :func:`mortar1d3d.nurbs.sets.element_centres`)."""
        mesh = self.solid_mesh
        out = []
        for i, f in enumerate(families):
            elements = None
            if f["inside"] is not None:
                lo, hi = f["inside"]
                if self._rational:
                    from ..nurbs.sets import element_centres
                    centroid = element_centres(mesh)
                else:
                    conn = mesh.connectivity
                    valid = conn >= 0
                    centroid = (mesh.points[np.where(valid, conn, 0)] * valid[..., None]).sum(axis=1) / valid.sum(axis=1)[:, None]
                tol = 1e-9 * float(np.linalg.norm(np.ptp(mesh.points, axis=0)))
                elements = ((centroid >= lo - tol) & (centroid <= hi + tol)).all(axis=1)
                if not elements.any():
                    raise SceneError(f"solid.material.fibres[{i}].inside: no element centroid lies in "
                                     f"{lo.tolist()} – {hi.tolist()}")
            out.append(elements)
        return out
