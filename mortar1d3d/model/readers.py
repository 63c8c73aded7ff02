"""Mesh file readers: one plugin per file format, in an explicit registry.

A reader turns a file named by a scene (``solid.mesh``, ``beams[i].mesh``) into a
:class:`~mortar1d3d.mesh.SolidMesh` or :class:`~mortar1d3d.mesh.BeamMesh`. :data:`READERS` lists
the plugins in the order they are asked; the first whose :meth:`accepts` is true reads the file.
Today there is one, meshio's (every format meshio knows, by the file's suffix); a reader for
another code's input files is one class with the three methods below and one line in
:data:`READERS`.
"""
from pathlib import Path

import numpy as np

from ..errors import MeshError
from ..mesh import BeamMesh, SolidMesh
from ..scene import SceneError
from .curves import chord_tangents


class MeshioReader:
    """Every format meshio reads (VTU, Gmsh, Abaqus, ...), chosen by meshio from the suffix."""

    name = "meshio"

    def accepts(self, path):
        return True

    @staticmethod
    def read(path, where):
        """``meshio.read(path)``; any failure becomes a SceneError that names ``where`` and the file."""
        import meshio
        try:
            return meshio.read(path)
        except SystemExit:      # meshio's XML readers call sys.exit on a malformed file
            raise SceneError(f"{where}: cannot read mesh file {str(path)!r} (malformed {Path(path).suffix} file)") \
                from None
        except Exception as exc:
            raise SceneError(f"{where}: cannot read mesh file {str(path)!r}: {type(exc).__name__}: {exc}") from None

    def read_solid(self, path, where):
        """SolidMesh of every volume cell block of the file (MeshError on bad cells)."""
        return SolidMesh.from_meshio(self.read(path, where))

    def read_beams(self, path, element, where):
        """BeamMesh of the file's ``line`` cells, interpolated by ``element`` (a BeamElementType).

        Elements with nodal tangents take them from the point data ``tangent``, or, when there
        is none, from the chords of the cells, which must then form one chain.
        """
        m = self.read(path, where)
        lines = [c.data for c in m.cells if c.type == "line"]
        if not lines:
            raise MeshError(f"{path}: no 'line' cells")
        elements = np.vstack(lines)
        if not element.has_tangents:
            return BeamMesh.lagrange(m.points, elements)
        if "tangent" in m.point_data:
            tangents = m.point_data["tangent"]
        else:
            order = np.concatenate([elements[:, 0], elements[-1:, 1]])
            if len(np.unique(order)) != len(order) or not (elements[1:, 0] == elements[:-1, 1]).all():
                raise MeshError(f"{path}: without point data 'tangent' the line cells must form one chain")
            tangents = np.zeros_like(m.points, dtype=float)
            tangents[order] = chord_tangents(m.points[order].astype(float))
        return BeamMesh.hermite(m.points, tangents, elements)


#: the mesh readers, asked in this order
READERS = (MeshioReader(),)


def reader(path):
    """The first reader of :data:`READERS` that accepts ``path``."""
    return next(r for r in READERS if r.accepts(path))


def read_mesh_file(path, where):
    """The raw mesh object of ``path`` (meshio's); SceneError naming ``where`` if it cannot be read."""
    return MeshioReader.read(path, where)
