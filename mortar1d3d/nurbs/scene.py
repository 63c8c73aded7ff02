"""The scene keys ``solid.mesh = { pipe = {...} }`` and ``solid.mesh = { brick = {...} }``: an exact NURBS
pipe (section) or a NURBS block as the scene's solid.

The pipe is :func:`~mortar1d3d.nurbs.hollow_cylinder` (about the z axis, from z = 0; quadratic, or
``degree = 3``: the exact quadratic geometry degree-elevated to cubic, which leaves it unchanged),
and the scene runs on its Bézier mesh (:func:`~mortar1d3d.nurbs.bezier_mesh`): the solid's unknowns
are the displacements of the ``nurbs27`` (``nurbs64``) nodes (Bézier control points), i.e. the C⁰ space of the
rational Bézier elements on the exact geometry. It contains the smoother NURBS space of the patch
(``T`` maps one into the other) and is what every path of the model evaluates (the solid, the
mortar coupling, surface loads and output take rational elements).

Named node sets of the pipe (usable as ``solid:<name>`` by supports and loads): ``inner`` and
``outer`` (the cylindrical faces), ``start`` and ``end`` (the end faces z = 0 and z = length) and,
for a section (angle < 360°), ``cut_start`` and ``cut_end`` (the planes at the start angle and
start + angle). Each is the set of the nodes of the element faces on that surface, so a pressure on
it acts on exactly that surface and a support on it holds exactly that surface.

The brick is :func:`~mortar1d3d.nurbs.brick` (the box ``lower <= x <= upper``, all weights 1, degree 2
or 3, ``elements`` equal spans per direction: h-refinement by knot insertion), with the named sets of
a generated box: ``x_min``, ``x_max``, ``y_min``, ``y_max``, ``z_min``, ``z_max`` (its faces).
"""
import math

import numpy as np

from ..physics.surface import face_nodes
from .generate import MAX_SEGMENT_ANGLE, arc_segments, brick, hollow_cylinder
from .mesh import BEZIER_TYPES, bezier_mesh
from .solid import patch_face_set

#: keys of ``solid.mesh.pipe``
PIPE_KEYS = ("r_inner", "r_outer", "length", "angle", "start", "elements", "degree")
#: most elements a scene's pipe or brick generates (the box key's limit)
MAX_PIPE_ELEMENTS = 1_000_000
#: keys of ``solid.mesh.brick``
BRICK_KEYS = ("lower", "upper", "elements", "degree")
#: set name -> patch face of :func:`brick` (parameter direction d along x_d)
BRICK_FACES = {f"{axis}_{side}": f"u{d}_{side}" for d, axis in enumerate("xyz") for side in ("min", "max")}
#: set name -> patch face of :func:`hollow_cylinder` (directions: 0 radial, 1 circumferential, 2 axial)
PIPE_FACES = {"inner": "u0_min", "outer": "u0_max", "cut_start": "u1_min", "cut_end": "u1_max",
              "start": "u2_min", "end": "u2_max"}


def validate_pipe(value, path="solid.mesh.pipe"):
    """The checked ``pipe`` table: radii, length, angle (degrees, default 360), start angle (default 0),
    ``elements = [radial, circumferential, axial]`` and ``degree`` (2 or 3, default 2). SceneError
    naming the key otherwise."""
    from ..scene import _fail, _integer, _list, _number, _table

    _table(value, path, PIPE_KEYS, required=("r_inner", "r_outer", "length", "elements"))
    r_inner = _number(value["r_inner"], f"{path}.r_inner", low=0.0, low_open=True)
    r_outer = _number(value["r_outer"], f"{path}.r_outer", low=0.0, low_open=True)
    if not r_outer > r_inner:
        _fail(f"{path}.r_outer", f"must be greater than r_inner ({r_inner}), got {r_outer}")
    length = _number(value["length"], f"{path}.length", low=0.0, low_open=True)
    angle = _number(value.get("angle", 360.0), f"{path}.angle", low=0.0, high=360.0, low_open=True)
    start = _number(value.get("start", 0.0), f"{path}.start")
    elements = _elements(value["elements"], f"{path}.elements")
    try:
        arc_segments(angle, elements[1])
    except ValueError:
        _fail(f"{path}.elements[1]", f"{elements[1]} element(s) cannot cover {angle}° with arcs of at most "
                                     f"{MAX_SEGMENT_ANGLE}°; use at least {math.ceil(angle / MAX_SEGMENT_ANGLE)}")
    degree = _integer(value.get("degree", 2), f"{path}.degree", min(BEZIER_TYPES), max(BEZIER_TYPES))
    return {"r_inner": r_inner, "r_outer": r_outer, "length": length, "angle": angle, "start": start,
            "elements": elements, "degree": degree}


def _elements(value, path):
    """Three element counts >= 1 with at most MAX_PIPE_ELEMENTS in all; SceneError naming ``path`` otherwise."""
    from ..scene import _fail, _integer, _list

    elements = [_integer(c, f"{path}[{i}]", 1, MAX_PIPE_ELEMENTS) for i, c in enumerate(_list(value, path, 3))]
    if math.prod(elements) > MAX_PIPE_ELEMENTS:
        _fail(path, f"{elements} gives {math.prod(elements)} elements; at most {MAX_PIPE_ELEMENTS}")
    return elements


def validate_brick(value, path="solid.mesh.brick"):
    """The checked ``brick`` table: corners ``lower`` < ``upper``, ``elements = [nx, ny, nz]`` and ``degree``
    (2 or 3, default 2). SceneError naming the key otherwise."""
    from ..scene import _fail, _integer, _list, _number, _table

    _table(value, path, BRICK_KEYS, required=("lower", "upper", "elements"))
    corners = [[_number(c, f"{path}.{key}[{i}]") for i, c in enumerate(_list(value[key], f"{path}.{key}", 3))]
               for key in ("lower", "upper")]
    if not all(hi > lo for lo, hi in zip(*corners)):
        _fail(f"{path}.upper", f"must be greater than lower in x, y and z, got {corners[1]} and {corners[0]}")
    elements = _elements(value["elements"], f"{path}.elements")
    degree = _integer(value.get("degree", 2), f"{path}.degree", min(BEZIER_TYPES), max(BEZIER_TYPES))
    return {"lower": corners[0], "upper": corners[1], "elements": elements, "degree": degree}


def brick_mesh(spec):
    """The :class:`~mortar1d3d.SolidMesh` (with the sets ``x_min`` … ``z_max``) of a validated ``brick``
    table, and its :class:`~mortar1d3d.nurbs.BezierMesh`."""
    mesh = bezier_mesh(brick(spec["lower"], spec["upper"], spec["elements"], spec["degree"]))
    mesh.solid.point_sets.update(_face_sets(mesh, BRICK_FACES))
    return mesh.solid, mesh


def _face_sets(mesh, faces):
    """Named node sets of a one-patch :class:`BezierMesh`: for ``faces`` (set name -> patch face), the nodes
    of the element faces on that patch face."""
    sets = {}
    for name, face in faces.items():
        element_faces = patch_face_set(mesh, 0, face)
        local = face_nodes(int(element_faces["code"][0]), int(element_faces["face"][0]))   # one local face throughout
        sets[name] = np.unique(mesh.solid.connectivity[element_faces["element"][:, None], local[None, :]])
    return sets


def pipe_mesh(spec):
    """The :class:`~mortar1d3d.SolidMesh` (``nurbs27`` or ``nurbs64``, with the named sets of the module docstring) of a
    validated ``pipe`` table, and its :class:`~mortar1d3d.nurbs.BezierMesh`."""
    solid = hollow_cylinder(spec["r_inner"], spec["r_outer"], spec["length"], angle=spec["angle"],
                            elements=spec["elements"], start=spec["start"], degree=spec.get("degree", 2))
    mesh = bezier_mesh(solid)
    closed = abs(spec["angle"] - 360.0) < 1e-12
    # the seam is inside a closed pipe
    faces = {name: face for name, face in PIPE_FACES.items() if not (closed and name.startswith("cut"))}
    mesh.solid.point_sets.update(_face_sets(mesh, faces))
    return mesh.solid, mesh


#: the NURBS keys of ``solid.mesh``: name -> (validate, build the SolidMesh and its BezierMesh)
NURBS_MESHES = {"pipe": (validate_pipe, pipe_mesh), "brick": (validate_brick, brick_mesh)}


__all__ = ["validate_pipe", "pipe_mesh", "validate_brick", "brick_mesh", "NURBS_MESHES", "PIPE_FACES", "PIPE_KEYS",
           "BRICK_FACES", "BRICK_KEYS"]
