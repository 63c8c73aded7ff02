"""Beam meshes from the curve specifications of a scene (``beams[i].curve``).

A curve is a straight ``line``, a ``polyline`` (one element per segment), a ``helix`` or a
Python ``function`` with its ``derivative``; :func:`curve_mesh` samples it with the beam's
centreline element: nodal positions, and nodal tangents where the element has them (the
derivative's direction on smooth curves, averaged chord directions on polylines).
"""
import math

import numpy as np

from ..errors import MeshError, format_ids
from ..generate import _helix_frame
from ..mesh import BeamMesh, zero_length_elements


def chord_tangents(points):
    """(n, 3) unit tangents of the polyline through ``points`` (n, 3): the chord at either end, the
    mean of the two neighbouring chord directions inside.

    Raises MeshError if consecutive points coincide or the polyline folds back on itself.
    """
    n = len(points)
    zero = zero_length_elements(points, np.column_stack([np.arange(n - 1), np.arange(1, n)]))
    if zero.size:
        raise MeshError(f"beam elements of zero length (consecutive nodes coincide): {format_ids(zero)}")
    d = np.diff(points, axis=0)
    d /= np.linalg.norm(d, axis=1)[:, None]
    t = np.empty_like(points)
    t[0], t[-1] = d[0], d[-1]
    t[1:-1] = d[:-1] + d[1:]
    norm = np.linalg.norm(t[1:-1], axis=1)
    if (norm < 1e-12).any():
        raise MeshError("polyline folds back on itself (opposite consecutive segments)")
    t[1:-1] /= norm[:, None]
    return t


def _curve_functions(curve):
    """(f, df, t0, t1) of a smooth curve spec."""
    if "line" in curve:
        a, b = curve["line"]
        return (lambda t: a + t * (b - a)), (lambda t: b - a), 0.0, 1.0
    if "helix" in curve:
        h = curve["helix"]

        def sample(t):
            t = np.atleast_1d(t)
            pts, tan = [], []
            for ti in t:
                p, d = _helix_point(h, ti)
                pts.append(p)
                tan.append(d)
            return np.array(pts), np.array(tan)
        return (lambda t: sample(t)[0][0]), (lambda t: sample(t)[1][0]), 0.0, 1.0
    return curve["function"], curve["derivative"], float(curve["t"][0]), float(curve["t"][1])


def _helix_point(h, s):
    e1, e2 = _helix_frame(h["axis"][None, :])
    theta = h["phase"] + 2.0 * math.pi * h["turns"] * s
    p = h["centre"] + (s - 0.5) * h["length"] * h["axis"] + h["radius"] * (math.cos(theta) * e1[0] + math.sin(theta) * e2[0])
    d = h["length"] * h["axis"] + 2.0 * math.pi * h["turns"] * h["radius"] * (math.cos(theta) * e2[0] - math.sin(theta) * e1[0])
    return p, d


def curve_mesh(curve, n, element):
    """BeamMesh of a validated curve spec with ``n`` elements of ``element`` (a BeamElementType).

    Raises MeshError on a degenerate curve (coincident nodes, zero tangents).
    """
    tangents = element.has_tangents
    if "polyline" in curve:
        pts = curve["polyline"]
        elements = np.column_stack([np.arange(n), np.arange(1, n + 1)])
        return BeamMesh.hermite(pts, chord_tangents(pts), elements) if tangents else BeamMesh.lagrange(pts, elements)
    f, df, t0, t1 = _curve_functions(curve)
    if tangents:
        return BeamMesh.from_curve(f, df, t0, t1, n)
    t = np.linspace(t0, t1, n + 1)
    pts = np.array([np.asarray(f(ti), dtype=float).reshape(3) for ti in t])
    return BeamMesh.lagrange(pts, np.column_stack([np.arange(n), np.arange(1, n + 1)]))
