"""The scene keys ``solid.mesh = { pipe = {...} }``, ``solid.mesh = { brick = {...} }`` and
``solid.mesh = { patches = [ {pipe = {...}}, {brick = {...}}, ... ] }``: an exact NURBS pipe (section), a
NURBS block, or several such patches joined where their control points coincide, as the scene's solid.

The pipe is :func:`~mortar1d3d.nurbs.hollow_cylinder` (about the z axis, from z = 0; quadratic by
default, ``degree`` one integer or three per direction, at least [1, 2, 1]: the exact geometry
degree-elevated, which leaves it unchanged), and the scene runs on its Bézier mesh
(:func:`~mortar1d3d.nurbs.bezier_mesh`): the solid's unknowns are the displacements of the ``nurbs27``
(``nurbs64``, ``nurbs125``) nodes (Bézier control points), i.e. the C⁰ space of the rational Bézier elements on the
exact geometry. It contains the smoother NURBS space of the patch
(``T`` maps one into the other) and is what every path of the model evaluates (the solid, the
mortar coupling, surface loads and output take rational elements).

Named node sets of the pipe (usable as ``solid:<name>`` by supports and loads): ``inner`` and
``outer`` (the cylindrical faces), ``start`` and ``end`` (the end faces z = 0 and z = length) and,
for a section (angle < 360°), ``cut_start`` and ``cut_end`` (the planes at the start angle and
start + angle). Each is the set of the nodes of the element faces on that surface, so a pressure on
it acts on exactly that surface and a support on it holds exactly that surface.

The brick is :func:`~mortar1d3d.nurbs.brick` (the box ``lower <= x <= upper``, all weights 1, degree 1 to
4, one or per direction, ``elements`` equal spans per direction: h-refinement by knot insertion), with the named sets of
a generated box: ``x_min``, ``x_max``, ``y_min``, ``y_max``, ``z_min``, ``z_max`` (its faces).

Degrees 1 to 4 are taken (per direction, mixed across patches); the elements are of the smallest
registered degree that is at least every patch's highest (2: ``nurbs27``, 3: ``nurbs64``, 4: ``nurbs125``),
every patch degree-elevated to it exactly; a degree above 4 is a SceneError saying so.

Several patches (:func:`patches_mesh`): a patch that meets another one without
shared control points is a SceneError naming it; each set name is the union over the patches of its
faces on the solid's boundary, and ``<name>_<k>`` patch k's own.
"""
import math

import numpy as np

from ..physics.surface import boundary_faces, face_nodes
from .generate import MAX_SEGMENT_ANGLE, _elevate_to, arc_segments, brick, hollow_cylinder
from .mesh import BEZIER_TYPES, bezier_mesh, common_degree, element_values
from .patch import NurbsSolid
from .solid import patch_face_set

#: keys of ``solid.mesh.pipe``
PIPE_KEYS = ("r_inner", "r_outer", "length", "angle", "start", "elements", "degree")
#: most elements a scene's pipe or brick generates (the box key's limit)
MAX_PIPE_ELEMENTS = 1_000_000
#: the lowest degrees of the exact pipe (radial, circumferential, axial): the circle needs 2
PIPE_LOWEST_DEGREES = (1, 2, 1)
#: keys of ``solid.mesh.brick``
BRICK_KEYS = ("lower", "upper", "elements", "degree")
#: set name -> patch face of :func:`brick` (parameter direction d along x_d)
BRICK_FACES = {f"{axis}_{side}": f"u{d}_{side}" for d, axis in enumerate("xyz") for side in ("min", "max")}
#: set name -> patch face of :func:`hollow_cylinder` (directions: 0 radial, 1 circumferential, 2 axial)
PIPE_FACES = {"inner": "u0_min", "outer": "u0_max", "cut_start": "u1_min", "cut_end": "u1_max",
              "start": "u2_min", "end": "u2_max"}


def validate_pipe(value, path="solid.mesh.pipe"):
    """The checked ``pipe`` table: radii, length, angle (degrees, default 360), start angle (default 0),
    ``elements = [radial, circumferential, axial]`` and ``degree`` (default 2; one integer or three, at least
    [1, 2, 1], at most 4). SceneError naming the key otherwise."""
    from ..scene import _fail, _number, _table

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
    degree = _degree(value.get("degree", 2), f"{path}.degree", PIPE_LOWEST_DEGREES)
    return {"r_inner": r_inner, "r_outer": r_outer, "length": length, "angle": angle, "start": start,
            "elements": elements, "degree": degree}


def _degree(value, path, lowest):
    """A checked degree: one integer for every direction or a list of three, each at least ``lowest[d]`` (the
    exact geometry's degree) and at most the highest registered rational Bézier degree. SceneError naming
    the key otherwise."""
    from ..scene import _fail, _integer, _list

    one = isinstance(value, (int, np.integer)) and not isinstance(value, bool)
    entries = [(path, value)] * 3 if one else [(f"{path}[{d}]", q) for d, q in enumerate(_list(value, path, 3))]
    out = []
    for d, (key, q) in enumerate(entries):
        q = _integer(q, key, low=-2 ** 62)
        if q > max(BEZIER_TYPES):
            _fail(key, f"degree {q} is above what the element registry has; supported are degrees "
                       f"{lowest[d]} to {max(BEZIER_TYPES)} per direction, elevated exactly to "
                       f"{', '.join(f'{t.name} (degree {p})' for p, t in sorted(BEZIER_TYPES.items()))}")
        if q < lowest[d]:
            _fail(key, f"degree {q} in direction {d}: must be at least {lowest[d]} (the exact geometry's degree there)")
        out.append(q)
    return out[0] if one else out


def _elements(value, path):
    """Three element counts >= 1 with at most MAX_PIPE_ELEMENTS in all; SceneError naming ``path`` otherwise."""
    from ..scene import _fail, _integer, _list

    elements = [_integer(c, f"{path}[{i}]", 1, MAX_PIPE_ELEMENTS) for i, c in enumerate(_list(value, path, 3))]
    if math.prod(elements) > MAX_PIPE_ELEMENTS:
        _fail(path, f"{elements} gives {math.prod(elements)} elements; at most {MAX_PIPE_ELEMENTS}")
    return elements


def validate_brick(value, path="solid.mesh.brick"):
    """The checked ``brick`` table: corners ``lower`` < ``upper``, ``elements = [nx, ny, nz]`` and ``degree``
    (default 2; one integer or three, 1 to 4). SceneError naming the key otherwise."""
    from ..scene import _fail, _list, _number, _table

    _table(value, path, BRICK_KEYS, required=("lower", "upper", "elements"))
    corners = [[_number(c, f"{path}.{key}[{i}]") for i, c in enumerate(_list(value[key], f"{path}.{key}", 3))]
               for key in ("lower", "upper")]
    if not all(hi > lo for lo, hi in zip(*corners)):
        _fail(f"{path}.upper", f"must be greater than lower in x, y and z, got {corners[1]} and {corners[0]}")
    elements = _elements(value["elements"], f"{path}.elements")
    degree = _degree(value.get("degree", 2), f"{path}.degree", (1, 1, 1))
    return {"lower": corners[0], "upper": corners[1], "elements": elements, "degree": degree}


def brick_mesh(spec):
    """The :class:`~mortar1d3d.SolidMesh` (with the sets ``x_min`` … ``z_max``) of a validated ``brick``
    table, and its :class:`~mortar1d3d.nurbs.BezierMesh`."""
    return patches_mesh([{"brick": spec}])


def _face_sets(mesh, patch, faces, boundary=None):
    """Named node sets of patch ``patch`` of a :class:`BezierMesh`: for ``faces`` (set name -> patch face),
    the nodes of the element faces on that patch face (only those in the set of element faces
    ``boundary``, pairs (element, local face), if given); empty sets are left out."""
    sets = {}
    for name, face in faces.items():
        element_faces = patch_face_set(mesh, patch, face)
        if boundary is not None:
            element_faces = element_faces[[(int(e), int(f)) in boundary for e, f in
                                           zip(element_faces["element"], element_faces["face"])]]
        if len(element_faces):
            local = face_nodes(int(element_faces["code"][0]), int(element_faces["face"][0]))   # one local face throughout
            sets[name] = np.unique(mesh.solid.connectivity[element_faces["element"][:, None], local[None, :]])
    return sets


def pipe_mesh(spec):
    """The :class:`~mortar1d3d.SolidMesh` (``nurbs27``, ``nurbs64`` or ``nurbs125``, with the named sets of the module docstring) of a
    validated ``pipe`` table, and its :class:`~mortar1d3d.nurbs.BezierMesh`."""
    return patches_mesh([{"pipe": spec}])


def _generate(kind, spec):
    """The one patch of a validated ``pipe`` or ``brick`` table."""
    if kind == "pipe":
        solid = hollow_cylinder(spec["r_inner"], spec["r_outer"], spec["length"], angle=spec["angle"],
                                elements=spec["elements"], start=spec["start"], degree=spec.get("degree", 2))
    else:
        solid = brick(spec["lower"], spec["upper"], spec["elements"], spec["degree"])
    return solid.patches[0]


def validate_patches(value, path="solid.mesh.patches"):
    """The checked ``patches`` list: one or more ``{ pipe = {...} }`` or ``{ brick = {...} }`` tables (of any
    degrees 1 to 4); SceneError naming the key otherwise."""
    from ..scene import _describe, _fail, _list

    items = _list(value, path)
    if not items:
        _fail(path, "expected at least one patch, e.g. [{ pipe = {...} }, { pipe = {...} }]")
    out = []
    for i, item in enumerate(items):
        if not (isinstance(item, dict) and len(item) == 1 and next(iter(item)) in PATCH_KINDS):
            _fail(f"{path}[{i}]", f"expected {{ pipe = {{...}} }} or {{ brick = {{...}} }}, got {_describe(item)}")
        (kind, table), = item.items()
        out.append({kind: NURBS_MESHES[kind][0](table, f"{path}[{i}].{kind}")})
    return out


def patches_mesh(spec, path="solid.mesh.patches"):
    """The :class:`~mortar1d3d.SolidMesh` and :class:`~mortar1d3d.nurbs.BezierMesh` of a validated ``patches``
    list (or of one pipe or brick): the patches joined where their control points coincide.

    Named sets: the sets of each patch's kind (``inner``, …, ``x_min``, …) as the union over the patches of
    the nodes of element faces on that patch face that lie on the solid's boundary (a face joined to
    another patch is inside, so a closed pipe of three 120° patches has no ``cut_start``), and each
    patch's own as ``<name>_<k>`` (k: the patch's position in the list) where there are several patches.
    A patch that meets another one without sharing its control points (a non-conforming interface) is a
    SceneError naming both.
    """
    from ..scene import _fail

    kinds = [next(iter(entry)) for entry in spec]
    patches = [_generate(kind, entry[kind]) for kind, entry in zip(kinds, spec)]
    # one degree before joining: patches of other degrees share control points only once elevated alike
    p = common_degree([patch.degrees for patch in patches])
    solid = NurbsSolid([_elevate_to(patch, p) for patch in patches])
    mesh = bezier_mesh(solid)
    boundary = None                      # one patch: every patch face is on the boundary but a closed pipe's seam
    if len(spec) > 1:
        faces = boundary_faces(mesh.solid)
        boundary = set(zip(faces["element"].tolist(), faces["face"].tolist()))
        clash = _nonconforming(mesh, faces)
        if clash is not None:
            a, b, x = clash
            _fail(f"{path}[{a}]", f"meets patches[{b}] at {np.round(x, 12).tolist()} without sharing its control points "
                                  "there (a non-conforming interface: other element counts or positions along the "
                                  "shared face, or overlapping patches); patches are joined only where their control "
                                  "points coincide")
    sets = {}
    for k, kind in enumerate(kinds):
        named = PIPE_FACES if kind == "pipe" else BRICK_FACES
        if boundary is None and kind == "pipe" and abs(spec[k][kind]["angle"] - 360.0) < 1e-12:
            named = {name: face for name, face in named.items() if not name.startswith("cut")}
        own = _face_sets(mesh, k, named, boundary)
        for name, nodes in own.items():
            sets[name] = np.union1d(sets.get(name, np.zeros(0, np.int64)), nodes)
            if len(spec) > 1:
                sets[f"{name}_{k}"] = nodes
    mesh.solid.point_sets.update(sets)
    return mesh.solid, mesh


def _nonconforming(mesh, faces):
    """``(patch a, patch b, point)`` of a boundary face of patch a whose centre lies on an element of another
    patch b (there the two meet without shared control points), or None."""
    from ..geometry.projection import INSIDE, project_points

    solid = mesh.solid
    d = solid.blocks[0][0]
    centres = np.array([d.faces[f][3] for f in range(d.n_faces)])          # a hexahedron face's centre is ±e_axis
    # every element at every face centre once (n_elements, n_faces, 3), then each boundary face's own
    points = element_values(solid, centres, solid.points)[faces["element"], faces["face"]] if len(faces) \
        else np.zeros((0, 3))
    X = solid.points[solid.connectivity]                                   # control points bound each element
    lo, hi = X.min(axis=1), X.max(axis=1)
    tol = 1e-9 * float(np.ptp(solid.points, axis=0).max())
    for (e, x) in zip(faces["element"], points):
        a = int(mesh.element_patch[e])
        near = np.flatnonzero((mesh.element_patch != a) & (lo <= x + tol).all(axis=1) & (hi >= x - tol).all(axis=1))
        if len(near):
            _, status = project_points(solid, np.repeat(x[None], len(near), axis=0), near)
            hit = np.flatnonzero(status == INSIDE)
            if len(hit):
                return a, int(mesh.element_patch[near[hit[0]]]), x
    return None


#: the NURBS keys of ``solid.mesh``: name -> (validate, build the SolidMesh and its BezierMesh)
NURBS_MESHES = {"pipe": (validate_pipe, pipe_mesh), "brick": (validate_brick, brick_mesh),
                "patches": (validate_patches, patches_mesh)}
#: the kinds of patch an entry of ``solid.mesh.patches`` may be
PATCH_KINDS = ("pipe", "brick")


__all__ = ["validate_pipe", "pipe_mesh", "validate_brick", "brick_mesh", "validate_patches", "patches_mesh",
           "NURBS_MESHES", "PIPE_FACES", "PIPE_KEYS", "BRICK_FACES", "BRICK_KEYS", "PATCH_KINDS"]
