"""A small clamped scene and its rigidly moved copies (tests/test_supports.py, tests/test_fuzz.py).

A block (hex8) clamped at one end with a torsion-free rebar inside, whose start is clamped
(position and tangent direction), loaded by a traction with axial and transverse parts on the
other end. :func:`clamped_scene` builds it moved by a rotation ``Q`` and a translation ``shift``:
supports and loads name mesh point sets, so the scene is the same whatever the orientation.
"""
import numpy as np

import mortar1d3d as m13
from mortar1d3d import SolidMesh, generate

SIZE = np.array([1.0, 0.2, 0.2])
REBAR = np.array([[0.0, 0.1, 0.06], [1.0, 0.1, 0.06]])
TRACTION = np.array([3e4, 1e4, -2e5])        # axial part: the clamped tangent has to stretch


def clamped_scene(Q=np.eye(3), shift=np.zeros(3), kinematics="linear", enforcement="penalty", solver="direct"):
    box = generate.box((0, 0, 0), SIZE, (4, 1, 1), "hexahedron")
    X = box.points
    sets = {"left": np.flatnonzero(X[:, 0] == 0.0), "right": np.flatnonzero(X[:, 0] == SIZE[0])}
    solid = SolidMesh(X @ Q.T + shift, {"hexahedron": box.cells["hexahedron"]}, point_sets=sets)
    rebar = REBAR @ Q.T + shift
    return m13.Scene(
        solid={"mesh": solid, "material": {"model": "saint_venant_kirchhoff", "E": 3e9, "nu": 0.2}},
        beams=[{"curve": {"line": rebar.tolist()}, "elements": 4, "section": {"E": 2e11, "radius": 0.01}}],
        coupling={"penalty": 3e11, "enforcement": enforcement},
        dirichlet=[{"on": "solid:left"}, {"on": "beam:0:start", "clamp": True}],
        load=[{"type": "traction", "on": "solid:right", "value": (Q @ TRACTION).tolist()}],
        analysis={"kinematics": kinematics, "steps": 2, "solver": solver, "rtol": 1e-12})


def rotation_error(reference, moved, Q):
    """Largest deviation of ``moved`` from ``reference`` rotated by ``Q``, per field, relative to
    the field's largest entry: displacements, tangent changes, λ and the support reactions."""
    out = {}
    for name in ("solid_displacement", "beam_displacement", "beam_tangent_displacement", "line_load"):
        a, b = getattr(reference, name), getattr(moved, name)
        out[name] = float(np.abs(b - a @ Q.T).max() / np.abs(a).max())
    a, b = np.array(reference.reactions), np.array(moved.reactions)
    out["reactions"] = float(np.abs(b - a @ Q.T).max() / np.abs(a).max())
    return out
