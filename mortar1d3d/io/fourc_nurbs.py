"""NURBS solids of 4C input files: ``STRUCTURE KNOTVECTORS``, ``CP`` control points and ``SOLID NURBS27``
elements, read into a :class:`~mortar1d3d.nurbs.NurbsSolid` and the engine's Bézier mesh of it.

What the file says (facts of 4C's NURBS discretisation, ``Knotvector`` class):

* ``STRUCTURE KNOTVECTORS`` lists ``NURBS_DIMENSION 3`` and then, between ``BEGIN NURBSPATCH`` and
  ``END NURBSPATCH``, a patch ``ID`` and per parameter direction ``NUMKNOTS n``, ``DEGREE p``,
  ``TYPE Interpolated`` (an open knot vector; ``Periodic`` is not read here) and the n knots.
* A patch has ``n - 2p - 1`` elements per direction (one per knot interval from the p-th knot on,
  empty intervals included). Elements are numbered patch after patch; within a patch the element
  with Cartesian index (i, j, k) is the ``i + j n_u + k n_u n_v``-th (the first direction fastest),
  and file element ids start at 1.
* That element spans the knots ``U[i + p], U[i + p + 1]`` of the first direction (likewise j, k),
  and its control points are those of the patch's net at (i..i+p, j..j+p, k..k+p), listed with the
  first direction fastest: local index ``a + (p+1) b + (p+1)² c``.
* ``CP <id> COORD x y z w``: a control point and its weight. Control points shared by elements (of
  one patch or of neighbouring patches) carry one id: that is how 4C joins patches.

The reader rebuilds every patch's control net from its elements' lists (a net position listed with
two different ids, or by no element, is a :class:`~mortar1d3d.errors.FourCError` naming the element
or the patch), identifies control points by their id (:class:`~mortar1d3d.nurbs.NurbsSolid` with
``ids``), and checks every element geometrically: its points evaluated from 4C's definition
(Cox–de Boor on the element's own knots, its listed control points in 4C's order) must be the
points of the library's Bézier element of that span, else a FourCError naming the element id.
"""
import numpy as np

from ..errors import FourCError
from ..nurbs import knots as kv
from ..nurbs.basis import rational_local
from ..nurbs.mesh import bezier_mesh, element_values
from ..nurbs.patch import NurbsPatch, NurbsSolid

KEY = "STRUCTURE KNOTVECTORS"
#: 4C's NURBS solid element name -> degree per direction
NURBS_ELEMENTS = {"NURBS27": 2}
#: relative distance (to the solid's extent) at which an element's points count as its span's
GEOMETRY_TOL = 1e-12


def _fail(key, message):
    raise FourCError(f"{key}: {message}")


def _net_order(ids, degrees):
    """An element's control-point ids as listed by 4C (first direction fastest) as a
    (p0 + 1, p1 + 1, p2 + 1) block indexed like the control net."""
    p0, p1, p2 = degrees
    return np.asarray(ids, dtype=np.int64).reshape(p2 + 1, p1 + 1, p0 + 1).transpose(2, 1, 0)


def parse_knotvectors(lines):
    """The patches of a ``STRUCTURE KNOTVECTORS`` section: a list (by patch ID 1, 2, …) of
    ``(degrees (3,), knot vectors [3 arrays])``; FourCError naming the line otherwise."""
    items = [str(v).strip() for v in (lines or ())]
    if not items or items[0].split() != ["NURBS_DIMENSION", "3"]:
        _fail(KEY, f"expected 'NURBS_DIMENSION 3' first, got {items[0] if items else 'nothing'!r}")
    patches, pos = {}, 1

    def take(word):
        nonlocal pos
        if pos >= len(items) or items[pos].split()[0] != word or len(items[pos].split()) != 2:
            _fail(KEY, f"expected '{word} <value>' at entry {pos}, got {items[pos] if pos < len(items) else 'the end'!r}")
        pos += 1
        return items[pos - 1].split()[1]

    def take_int(word):
        value = take(word)
        try:
            return int(value)
        except ValueError:
            _fail(KEY, f"'{word} {value}' at entry {pos - 1}: expected an integer")

    while pos < len(items):
        if items[pos] != "BEGIN NURBSPATCH":
            _fail(KEY, f"expected 'BEGIN NURBSPATCH' at entry {pos}, got {items[pos]!r}")
        pos += 1
        pid = take_int("ID")
        degrees, knots = [], []
        for d in range(3):
            n = take_int("NUMKNOTS")
            degrees.append(take_int("DEGREE"))
            kind = take("TYPE")
            if kind != "Interpolated":
                _fail(f"{KEY}: patch {pid}, direction {d}", f"TYPE {kind!r} is not supported (only Interpolated, "
                                                             "an open knot vector)")
            try:
                knots.append(np.array([float(v) for v in items[pos:pos + n]]))
            except ValueError:
                _fail(f"{KEY}: patch {pid}, direction {d}", f"expected {n} knot values from entry {pos}")
            if len(knots[-1]) != n:
                _fail(f"{KEY}: patch {pid}, direction {d}", f"NUMKNOTS {n}, but the section ends after {len(knots[-1])}")
            pos += n
        if pos >= len(items) or items[pos] != "END NURBSPATCH":
            _fail(KEY, f"patch {pid}: expected 'END NURBSPATCH' at entry {pos}")
        pos += 1
        if pid in patches:
            _fail(KEY, f"patch ID {pid} given twice")
        patches[pid] = (tuple(degrees), knots)
    if sorted(patches) != list(range(1, len(patches) + 1)):
        _fail(KEY, f"patch IDs must be 1 … {len(patches)}, got {sorted(patches)}")
    return [patches[k] for k in range(1, len(patches) + 1)]


def nurbs_solid(fc):
    """The :class:`~mortar1d3d.nurbs.NurbsSolid` of a parsed file's NURBS elements (see the module
    docstring): ``(solid, elements, nets)`` with ``elements[k]`` (n_u, n_v, n_w) the 4C element ids of
    patch k by Cartesian index and ``nets[k]`` its control net of 4C control-point ids."""
    if KEY not in fc.data:
        _fail(KEY, "missing: NURBS elements need the patches' knot vectors")
    patches = parse_knotvectors(fc.data[KEY])
    by_id = {eid: (kind, ids) for eid, kind, ids, _ in fc.solids}
    nets, element_ids, offset = [], [], 0
    for k, (degrees, knots) in enumerate(patches):
        pkey = f"{KEY}: patch {k + 1}"
        shape = tuple(len(U) - 2 * p - 1 for U, p in zip(knots, degrees))
        if min(shape) < 1:
            _fail(pkey, f"{[len(U) for U in knots]} knots of degrees {degrees} give no element")
        eids = offset + 1 + np.arange(int(np.prod(shape))).reshape(shape[::-1]).transpose(2, 1, 0)
        offset += eids.size
        net = np.zeros(tuple(n + p for n, p in zip(shape, degrees)), dtype=np.int64)   # 0: not listed yet
        for (i, j, m), eid in np.ndenumerate(eids):
            if int(eid) not in by_id:
                _fail(pkey, f"element {int(eid)} (span {(i, j, m)}) is missing from STRUCTURE ELEMENTS (NURBS elements "
                            "are numbered 1, 2, … patch after patch, the first direction fastest)")
            kind, ids = by_id[int(eid)]
            if (NURBS_ELEMENTS[kind],) * 3 != tuple(degrees):
                _fail(f"STRUCTURE ELEMENTS: element {int(eid)}", f"{kind} needs degree {NURBS_ELEMENTS[kind]} in every "
                                                                   f"direction; patch {k + 1} has degrees {degrees}")
            p0, p1, p2 = degrees
            if len(ids) != (p0 + 1) * (p1 + 1) * (p2 + 1):
                _fail(f"STRUCTURE ELEMENTS: element {int(eid)}", f"{kind} lists {(p0 + 1) * (p1 + 1) * (p2 + 1)} control "
                                                                   f"points, got {len(ids)}")
            listed = _net_order(ids, degrees)
            block = net[i:i + p0 + 1, j:j + p1 + 1, m:m + p2 + 1]
            clash = (block != 0) & (block != listed)
            if clash.any():
                a = tuple(int(v) for v in np.argwhere(clash)[0])
                _fail(f"STRUCTURE ELEMENTS: element {int(eid)}",
                      f"its control points do not match span {(i, j, m)} of patch {k + 1}: it lists control point "
                      f"{int(listed[a])} where a neighbouring element of the patch lists {int(block[a])}")
            block[...] = listed
        missing = [int(c) for c in np.unique(net) if c not in fc.control_points]
        if missing:
            _fail(f"{pkey}", f"control point(s) {missing[:5]} of its elements are not CP lines of NODE COORDS")
        nets.append(net)
        element_ids.append(eids)
    extra = sorted(eid for eid, (kind, _) in by_id.items() if kind in NURBS_ELEMENTS and not 1 <= eid <= offset)
    if extra:
        _fail("STRUCTURE ELEMENTS", f"NURBS element(s) {extra[:5]} lie beyond the {offset} elements the knot vectors "
                                    f"of {KEY} give")
    out = []
    for k, ((degrees, knots), net) in enumerate(zip(patches, nets)):
        control = np.array([fc.control_points[int(c)][0] for c in net.ravel()]).reshape(net.shape + (3,))
        weights = np.array([fc.control_points[int(c)][1] for c in net.ravel()]).reshape(net.shape)
        try:
            out.append(NurbsPatch(control, weights, tuple(knots), degrees))
        except ValueError as exc:
            _fail(f"{KEY}: patch {k + 1}", str(exc))
    try:
        solid = NurbsSolid(out, ids=[net.ravel() for net in nets])
    except ValueError as exc:
        _fail("NODE COORDS", str(exc))
    return solid, element_ids, nets


def check_elements(solid, mesh, element_ids, fc, points=3):
    """FourCError naming the 4C element whose points, by 4C's definition of the element, are not the
    points of the Bézier element of its span in ``mesh`` (:class:`~mortar1d3d.nurbs.BezierMesh`), at
    a lattice of ``points`` per direction in each element."""
    s = np.linspace(-1.0, 1.0, points)
    xi = np.stack(np.meshgrid(s, s, s, indexing="ij"), axis=-1).reshape(-1, 3)
    ours = element_values(mesh.solid, xi, mesh.solid.points)              # (n_elements, q, 3)
    extent = float(np.ptp(mesh.solid.points, axis=0).max())
    by_id = {eid: ids for eid, _, ids, _ in fc.solids}
    for k, patch in enumerate(solid.patches):
        spans = [kv.spans(U, p) for U, p in zip(patch.knots, patch.degrees)]
        in_patch = np.flatnonzero(mesh.element_patch == k)
        p0, p1, p2 = patch.degrees
        for (i, j, m), eid in np.ndenumerate(element_ids[k]):
            cart = (i, j, m)
            if any(U[c + p + 1] <= U[c + p] for U, p, c in zip(patch.knots, patch.degrees, cart)):
                continue                                                   # an empty span: no element
            rank = [int(np.searchsorted(sp_, c + p)) for sp_, c, p in zip(spans, cart, patch.degrees)]
            e = in_patch[np.ravel_multi_index(rank, patch.element_shape)]   # the mesh numbers a patch's spans so
            # 4C's element: local knots around its span, its listed control points in 4C's order
            local = [U[c + 1: c + 2 * p + 1] for U, p, c in zip(patch.knots, patch.degrees, cart)]
            listed = _net_order(by_id[int(eid)], patch.degrees).ravel()
            X = np.array([fc.control_points[int(c)][0] for c in listed])
            w = np.array([fc.control_points[int(c)][1] for c in listed])
            R, dR = np.empty(len(w)), np.empty((len(w), 3))
            theirs = np.empty((len(xi), 3))
            for q, x in enumerate(xi):
                rational_local(p0, p1, p2, x, local[0], local[1], local[2], w, R, dR)
                theirs[q] = R @ X
            gap = float(np.abs(theirs - ours[e]).max())
            if not gap <= GEOMETRY_TOL * extent:
                _fail(f"STRUCTURE ELEMENTS: element {int(eid)}", f"its points differ from those of span {cart} of patch "
                                                                   f"{k + 1} by {gap:.3g} (its control points do not "
                                                                   "match the span it claims)")


def nurbs_mesh(fc):
    """The :class:`~mortar1d3d.SolidMesh` of a file's NURBS solid (``nurbs27`` Bézier elements) and the row
    of each 4C control point among its nodes: ``(mesh, rows)``, ``rows`` {4C id: node row}.

    The library's scenes solve on the C⁰ space of the Bézier elements; that is 4C's NURBS space only
    where no patch has an interior knot of multiplicity below its degree (each patch one element per
    direction, or C⁰ joints): other patches are a FourCError saying so.
    """
    solid, element_ids, nets = nurbs_solid(fc)
    for k, patch in enumerate(solid.patches):
        for d, (U, p) in enumerate(zip(patch.knots, patch.degrees)):
            _, counts = np.unique(U[p + 1:-p - 1], return_counts=True)
            if (counts < p).any():
                _fail(f"{KEY}: patch {k + 1}, direction {d}",
                      f"interior knots of multiplicity below the degree {p} (a smooth NURBS space across elements); "
                      "scenes solve on the C0 space of the Bézier elements, which is larger, so the results would "
                      "not be 4C's: not supported")
    mesh = bezier_mesh(solid)
    check_elements(solid, mesh, element_ids, fc)
    # with C0 joints only, every control point is a Bézier point: its node's row of T is that unit vector
    T = mesh.T.tocsr()
    single = np.flatnonzero((np.diff(T.indptr) == 1) & np.isclose(T.data[np.minimum(T.indptr[:-1], T.nnz - 1)], 1.0))
    node_of = dict(zip(T.indices[T.indptr[single]].tolist(), single.tolist()))
    labels = np.zeros(solid.n_control, dtype=np.int64)                  # 4C id of every global control point
    for k, net in enumerate(nets):
        labels[solid.patch_ids[k]] = net.ravel()
    rows = {int(labels[c]): node for c, node in node_of.items()}
    return mesh.solid, rows


__all__ = ["parse_knotvectors", "nurbs_solid", "nurbs_mesh", "check_elements", "NURBS_ELEMENTS"]
