"""VTU/PVD output for ParaView: the solid mesh, beam centrelines, mortar segments and
integration points, and ``.pvd`` collections that group them (docs/getting_started.md, "Where results go").

Every writer builds a :class:`meshio.Mesh` and writes it as an XML unstructured grid
(``.vtu``, binary, zlib-compressed). Files are written atomically: to a temporary name in the
target directory first, then renamed with :func:`os.replace`, so that a failed run never
leaves a half-written file behind (an existing file keeps its old content).

Curves are written as VTK ``line`` cells between consecutive samples; the samples of
neighbouring beam elements (or segments) are separate points, so the end point of one element
and the start point of the next are duplicated.

Files written by meshio are read back by ``meshio.read``, except files without any point
(meshio cannot read an empty piece; ParaView can).
"""
import os
import uuid
from pathlib import Path
from xml.sax.saxutils import quoteattr

import numpy as np

from ..elements.beam import evaluate as beam_functions
from ..mesh import BeamMesh, SolidMesh
from ..quadrature import gauss_legendre

#: Gauss points per sub-interval for arc lengths (the speed |r'| of a cubic is smooth: 10
#: points on an eighth of an element or on a segment are exact to round-off in practice)
ARC_LENGTH_GAUSS = 10
#: rows (elements or segments) evaluated at once, to bound the temporary memory
_CHUNK_ROWS = 8192
#: ``compression`` values of the writers: binary data compressed with zlib (meshio's default,
#: about 2.5x smaller files) or uncompressed (about 8x faster to write)
COMPRESSIONS = ("zlib", "lzma", None)

__all__ = ["write_solid", "write_beams", "write_segments", "write_integration_points",
           "write_mortar", "write_pvd", "sample_beams", "BeamSamples", "beam_fibres",
           "displacement_coefficients"]


# --------------------------------------------------------------------------------------------
# curve evaluation (vectorised over elements)
# --------------------------------------------------------------------------------------------
def _scaled_coefficients(beams, Q=None):
    """(m, 4, 3) coefficients with the element length folded in: ``r(η) = Σ_k B_k(η) Q̃_k``, where
    ``B`` are the centreline functions for L = 1 (:func:`~mortar1d3d.elements.beam.evaluate`).

    Only the tangent coefficients' functions (Hermite H2, H4) carry the length, as a factor.
    ``Q``: other coefficients in the layout of ``beams.coefficients()`` (e.g. a displacement's,
    from :func:`displacement_coefficients`) to scale instead of the reference curve's.
    """
    Q = beams.coefficients() if Q is None else np.array(Q, dtype=np.float64)
    for k, offset in enumerate(beams.element_type.function_offset):
        if offset > 0:
            Q[:, k] *= beams.lengths[:, None]
    return Q


def _apply(basis, Q):
    """Σ_k basis[..., k] Q[r, k, :] for a shared ``basis`` (n, 4) or per-row ``basis`` (r, n, 4).

    Returns (r, n, 3).
    """
    if basis.ndim == 2:     # one matrix product (BLAS): (n, 4) @ (4, r*3)
        r = len(Q)
        return (basis @ Q.transpose(1, 0, 2).reshape(4, 3 * r)).reshape(len(basis), r, 3).transpose(1, 0, 2)
    return np.einsum("rnk,rki->rni", basis, Q)


def _speed_integrals(element, Q, a, b):
    """∫_a^b |r'(η)| dη for every row of ``Q`` (r, 4, 3) and interval, by Gauss quadrature.

    ``a``, ``b``: shared intervals (n,) or per-row intervals (r, n). Returns (r, n).
    """
    t, w = gauss_legendre(ARC_LENGTH_GAUSS)
    a, b = np.asarray(a, dtype=np.float64), np.asarray(b, dtype=np.float64)
    half = 0.5 * (b - a)
    eta = (0.5 * (a + b))[..., None] + half[..., None] * t            # (..., n, q)
    shared = a.ndim == 1
    out = np.empty((len(Q),) + a.shape[-1:])
    if shared:
        dB = beam_functions(element, eta.reshape(-1), derivative=True)  # (n q, 4)
    for start in range(0, len(Q), _CHUNK_ROWS):
        rows = slice(start, start + _CHUNK_ROWS)
        Qc = Q[rows]
        if not shared:
            dB = beam_functions(element, eta[rows].reshape(len(Qc), -1), derivative=True)  # (r, n q, 4)
        speed = np.linalg.norm(_apply(dB, Qc), axis=2).reshape(len(Qc), -1, len(t))
        out[rows] = (speed @ w) * (half if shared else half[rows])
    return out


class BeamSamples:
    """Sample points of beam centrelines (what :func:`write_beams` writes).

    Attributes
    ----------
    points : (n_elements * samples_per_element, 3) float64
        Reference centreline positions r(η), element after element.
    beam_element : (n,) int64
        Beam element of every sample.
    eta : (n,) float64
        Element parameter, ``linspace(-1, 1, samples_per_element)`` in every element.
    arc_length : (n,) float64
        ``∫_{-1}^{η} |r'| dη`` (0 at η = -1, the element length at η = +1 up to quadrature).
    tangent : (n, 3) float64
        Unit reference tangent ``r'/|r'|``.
    samples_per_element : int
    """

    __slots__ = ("points", "beam_element", "eta", "arc_length", "tangent", "samples_per_element")

    def __init__(self, points, beam_element, eta, arc_length, tangent, samples_per_element):
        self.points, self.beam_element, self.eta = points, beam_element, eta
        self.arc_length, self.tangent, self.samples_per_element = arc_length, tangent, samples_per_element

    def line_cells(self):
        """(n_elements * (samples_per_element - 1), 2) int64: line cells between consecutive samples."""
        s = self.samples_per_element
        m = len(self.points) // s
        first = (np.arange(m, dtype=np.int64)[:, None] * s + np.arange(s - 1)).reshape(-1)
        return np.column_stack([first, first + 1])


def displacement_coefficients(beams, d):
    """Per-element coefficients of a centreline displacement, in the layout of ``beams.coefficients()``.

    Parameters
    ----------
    beams : BeamMesh
    d : (n_centreline_dofs,) array_like of float
        Displacement of the centreline DOFs (docs/conventions.md §2 layout: per node the
        position, then for Hermite beams the tangent).

    Returns
    -------
    (n_elements, 4, 3) float64
        ``u(η) = Σ_k H_k(η) Q_k`` element by element; zero rows where the element has fewer functions.
    """
    d = np.asarray(d, dtype=np.float64)
    if d.shape != (beams.n_centreline_dofs,):
        raise ValueError(f"d: expected shape ({beams.n_centreline_dofs},), got {d.shape}")
    cols = beams.function_columns()
    return np.where((cols >= 0)[..., None], d.reshape(-1, 3)[np.maximum(cols, 0)], 0.0)


def beam_fibres(beams):
    """Fibre of every beam element and the arc length where the element starts along its fibre.

    A fibre is a connected chain of elements (elements that share a node belong to the same
    fibre); fibres are numbered 0, 1, ... in the order of their first element. Along a fibre the
    arc length adds up the reference lengths of its elements in element order, which is the order
    along the curve for every mesh the library generates (chains numbered from start to end).

    Parameters
    ----------
    beams : BeamMesh

    Returns
    -------
    fibre : (n_elements,) int64
    start : (n_elements,) float64
        Arc length from the fibre's first element's η = -1 to this element's η = -1.
    """
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    conn = beams.elements
    n = beams.n_nodes
    graph = coo_matrix((np.ones(conn.size), (np.repeat(conn[:, 0], conn.shape[1]), conn.ravel())), shape=(n, n))
    _, label = connected_components(graph, directed=False)
    raw = label[conn[:, 0]]
    labels, first, inverse = np.unique(raw, return_index=True, return_inverse=True)
    rank = np.empty(len(labels), dtype=np.int64)
    rank[np.argsort(first, kind="stable")] = np.arange(len(labels))
    fibre = rank[inverse].astype(np.int64)
    order = np.argsort(fibre, kind="stable")
    lengths = beams.lengths[order]
    before = np.cumsum(lengths) - lengths                       # length of all earlier elements in order
    fibre_begin = np.searchsorted(fibre[order], np.arange(len(labels)))
    start = np.empty(beams.n_elements)
    start[order] = before - before[fibre_begin][fibre[order]]
    return fibre, start


def _check_samples(name, value):
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < 2:
        raise ValueError(f"{name} must be an integer >= 2, got {value!r}")
    return int(value)


def sample_beams(beams, samples_per_element=8):
    """Reference centreline positions, tangents and arc lengths at equally spaced η.

    Vectorised over the elements (no per-element Python loop).

    Parameters
    ----------
    beams : BeamMesh
    samples_per_element : int
        Samples per element (>= 2) at ``η = linspace(-1, 1, samples_per_element)``.

    Returns
    -------
    BeamSamples
        ``n_elements * samples_per_element`` samples, element-major.
    """
    if not isinstance(beams, BeamMesh):
        raise TypeError(f"beams must be a BeamMesh, got {type(beams).__name__}")
    s = _check_samples("samples_per_element", samples_per_element)
    element = beams.element_type
    Q = _scaled_coefficients(beams)
    m = len(Q)
    eta = np.linspace(-1.0, 1.0, s)
    points = _apply(beam_functions(element, eta), Q).reshape(-1, 3)
    d = _apply(beam_functions(element, eta, derivative=True), Q).reshape(-1, 3)
    norm = np.linalg.norm(d, axis=1, keepdims=True)
    tangent = d / np.where(norm > 0.0, norm, 1.0)
    arc = np.zeros((m, s))
    np.cumsum(_speed_integrals(element, Q, eta[:-1], eta[1:]), axis=1, out=arc[:, 1:])
    return BeamSamples(points=points, beam_element=np.repeat(np.arange(m, dtype=np.int64), s),
                       eta=np.tile(eta, m), arc_length=arc.reshape(-1), tangent=tangent,
                       samples_per_element=s)


# --------------------------------------------------------------------------------------------
# atomic writes
# --------------------------------------------------------------------------------------------
def _temporary_name(path):
    return path.with_name(f".{path.name}.{os.getpid()}.{uuid.uuid4().hex[:8]}.tmp")


def _atomic(path, write):
    """Call ``write(tmp)`` on a temporary file next to ``path``, then rename it to ``path``."""
    path = Path(path)
    tmp = _temporary_name(path)
    try:
        write(tmp)
        os.replace(tmp, path)
    except BaseException:
        try:
            os.remove(tmp)
        except FileNotFoundError:
            pass
        raise
    return path


def _check_compression(compression):
    if compression not in COMPRESSIONS:
        raise ValueError(f"compression must be one of {COMPRESSIONS}, got {compression!r}")
    return compression


def _write_vtu(path, mesh, compression):
    import meshio
    _check_compression(compression)
    if len(mesh.points) == 0:
        compression = None      # no compressed blocks of empty arrays
    return _atomic(path, lambda tmp: meshio.write(tmp, mesh, file_format="vtu", compression=compression))


def _data_dict(name, data, n, what):
    """Validate a ``{name: (n, ...) array}`` dict."""
    out = {}
    for key, value in (data or {}).items():
        arr = np.asarray(value)
        if arr.ndim == 0 or arr.shape[0] != n:
            raise ValueError(f"{name}[{key!r}]: expected {n} values (one per {what}), got shape {arr.shape}")
        out[str(key)] = arr
    return out


# --------------------------------------------------------------------------------------------
# writers
# --------------------------------------------------------------------------------------------
def write_solid(path, solid, point_data=None, cell_data=None, *, compression="zlib"):
    """Write the solid mesh as ``.vtu`` (all blocks, VTK cell types incl. quadratic cells).

    Parameters
    ----------
    path : str or os.PathLike
        Output file (``.vtu``).
    solid : SolidMesh
    point_data : dict of {str: (n_nodes, ...) array_like}, optional
        Nodal fields, e.g. ``{"displacement": u}`` with u (n_nodes, 3).
    cell_data : dict, optional
        Element fields, each either one array (n_elements, ...) in the global element numbering
        (split over the blocks here) or a list with one array per block (meshio layout).
    compression : {"zlib", "lzma", None}
        Compression of the binary data (None: uncompressed, fastest to write).

    Returns
    -------
    pathlib.Path
        The file written. Cell data ``solid_element`` (int64, the global element number used by
        :attr:`MortarOperators.segments`) is always written, unless ``cell_data`` overrides it.
        Rational elements (``nurbs27``, ``nurbs64``, ``nurbs125``) are written as ``hexahedron27`` cells through their
        exact points at the lattice parameters ((p − 1)³ cells per span of degree p: one per
        ``nurbs27``, 8 per ``nurbs64``, 27 per ``nurbs125`` span, each with its span's cell data), the point data interpolated there
        (:func:`mortar1d3d.nurbs.mesh.sampled_cells`).
    """
    import meshio
    if not isinstance(solid, SolidMesh):
        raise TypeError(f"solid must be a SolidMesh, got {type(solid).__name__}")
    sizes = [len(c) for _, c in solid.blocks]
    splits = np.cumsum(sizes)[:-1]
    cells = {"solid_element": np.arange(solid.n_elements, dtype=np.int64)}
    cells.update(cell_data or {})
    blocks = {}
    for key, value in cells.items():
        if isinstance(value, (list, tuple)):
            parts = [np.asarray(v) for v in value]
            if len(parts) != len(sizes) or any(p.ndim == 0 or len(p) != n for p, n in zip(parts, sizes)):
                raise ValueError(f"cell_data[{key!r}]: expected one array per block with "
                                 f"{sizes} rows, got shapes {[p.shape for p in parts]}")
        else:
            arr = _data_dict("cell_data", {key: value}, solid.n_elements, "element")[str(key)]
            parts = np.split(arr, splits)
        blocks[str(key)] = parts
    point_data = _data_dict("point_data", point_data, solid.n_nodes, "solid node")
    if any(d.rational for d, _ in solid.blocks):
        # NURBS spans: their nodes are control points; write each span through its exact points
        from ..nurbs.mesh import sampled_cells
        points, cell_blocks, point_data = sampled_cells(solid, point_data)
        # a span of degree p is (p-1)³ cells: each of them carries its element's cell data
        blocks = {k: [np.repeat(part, len(c) // max(len(part), 1), axis=0) for part, (_, c) in zip(v, cell_blocks)]
                  for k, v in blocks.items()}
    else:
        points, cell_blocks = solid.points, [(d.name, c) for d, c in solid.blocks]
    mesh = meshio.Mesh(points, cell_blocks, point_data=point_data, cell_data=blocks)
    return _write_vtu(path, mesh, compression)


def write_beams(path, beams, samples_per_element=8, point_data=None, *, compression="zlib"):
    """Write the reference beam centrelines as polylines (``line`` cells) in a ``.vtu`` file.

    Every element is sampled at ``η = linspace(-1, 1, samples_per_element)`` (see
    :func:`sample_beams`); its samples are joined by ``samples_per_element - 1`` line cells.

    Parameters
    ----------
    path : str or os.PathLike
    beams : BeamMesh
    samples_per_element : int
        >= 2.
    point_data : dict, optional
        Extra fields, each an array with one row per written point,
        (n_elements * samples_per_element, ...) in the order of :func:`sample_beams`, or with
        one row per beam element, (n_elements, ...), repeated on the element's samples.
    compression : {"zlib", "lzma", None}
        Compression of the binary data (None: uncompressed, fastest to write).

    Returns
    -------
    pathlib.Path

    Notes
    -----
    Point data written: ``beam_element`` and ``fibre`` (int64, see :func:`beam_fibres`), ``eta``,
    ``arc_length`` (reference arc length from the start of the fibre), ``element_arc_length``
    (from η = -1 along the element), ``tangent`` (3 components, unit reference tangent). Cell
    data: ``beam_element``, ``fibre``.
    """
    import meshio
    samples = sample_beams(beams, samples_per_element)
    s = samples.samples_per_element
    n = len(samples.points)
    extra = {}
    for key, value in (point_data or {}).items():
        arr = np.asarray(value)
        if arr.ndim >= 1 and arr.shape[0] == beams.n_elements:
            arr = np.repeat(arr, s, axis=0)
        extra.update(_data_dict("point_data", {key: arr}, n, "sample point or beam element"))
    fibre, start = beam_fibres(beams)
    data = {"beam_element": samples.beam_element, "fibre": np.repeat(fibre, s), "eta": samples.eta,
            "arc_length": np.repeat(start, s) + samples.arc_length, "element_arc_length": samples.arc_length,
            "tangent": samples.tangent}
    data.update(extra)
    cells = samples.line_cells()
    mesh = meshio.Mesh(samples.points, [("line", cells)], point_data=data,
                       cell_data={"beam_element": [cells[:, 0] // s], "fibre": [fibre[cells[:, 0] // s]]})
    return _write_vtu(path, mesh, compression)


def write_segments(path, beams, ops, samples_per_segment=4, *, displacement=None, compression="zlib"):
    """Write the mortar segments ``[eta_start, eta_end]`` of ``ops`` as polylines (``.vtu``).

    Parameters
    ----------
    path : str or os.PathLike
    beams : BeamMesh
        The beams ``ops`` was assembled for.
    ops : MortarOperators
    samples_per_segment : int
        Equally spaced samples in η per segment (>= 2), joined by line cells.
    displacement : (n_elements, 4, 3) array_like, optional
        Beam displacement coefficients (:func:`displacement_coefficients`): written as point data
        ``displacement`` at the samples, so that *Warp By Vector* moves the segments with the beams.
    compression : {"zlib", "lzma", None}
        Compression of the binary data (None: uncompressed, fastest to write).

    Returns
    -------
    pathlib.Path

    Notes
    -----
    Every line cell carries the cell data of its segment: ``beam_element``, ``solid_element``,
    ``segment`` (row of ``ops.segments``), all int64, and ``length`` = ∫ ``|r0'|`` dη over the
    segment (float64). Point data: ``eta``. For element-based integration the "segments" are
    the (beam element, solid element) groups of points, from the first to the last point's η.
    """
    import meshio
    k = _check_samples("samples_per_segment", samples_per_segment)
    seg = ops.segments
    n_seg = len(seg)
    element = beams.element_type
    if n_seg and seg["beam_element"].max() >= beams.n_elements:
        raise ValueError("ops.segments refers to beam elements beyond the beam mesh: "
                         "were the operators assembled for these beams?")
    Q = _scaled_coefficients(beams)[seg["beam_element"]]
    a, b = seg["eta_start"], seg["eta_end"]
    eta = a[:, None] + (b - a)[:, None] * np.linspace(0.0, 1.0, k)        # (n_seg, k)
    eta[:, -1] = b                                                        # exact end point
    points = _apply(beam_functions(element, eta), Q).reshape(-1, 3) if n_seg else np.zeros((0, 3))
    length = _speed_integrals(element, Q, a[:, None], b[:, None])[:, 0] if n_seg else np.zeros(0)
    first = (np.arange(n_seg, dtype=np.int64)[:, None] * k + np.arange(k - 1)).reshape(-1)
    cells = np.column_stack([first, first + 1])
    owner = first // k
    cell_data = {"beam_element": [seg["beam_element"][owner].astype(np.int64)],
                 "solid_element": [seg["solid_element"][owner].astype(np.int64)],
                 "segment": [owner], "length": [length[owner]]}
    point_data = {"eta": eta.reshape(-1)}
    if displacement is not None:
        Qd = _scaled_coefficients(beams, displacement)[seg["beam_element"]]
        point_data["displacement"] = (_apply(beam_functions(element, eta), Qd).reshape(-1, 3) if n_seg
                                      else np.zeros((0, 3)))
    mesh = meshio.Mesh(points, [("line", cells)], point_data=point_data, cell_data=cell_data)
    return _write_vtu(path, mesh, compression)


def write_integration_points(path, ops, *, beams=None, displacement=None, compression="zlib"):
    """Write the integration points of ``ops`` as ``vertex`` cells (``.vtu``).

    Parameters
    ----------
    path : str or os.PathLike
    ops : MortarOperators
    beams : BeamMesh, optional
        The beams ``ops`` was assembled for; needed with ``displacement``.
    displacement : (n_elements, 4, 3) array_like, optional
        Beam displacement coefficients (:func:`displacement_coefficients`): written as point data
        ``displacement`` at every point, so that *Warp By Vector* moves the points with the beams.
    compression : {"zlib", "lzma", None}
        Compression of the binary data (None: uncompressed, fastest to write).

    Returns
    -------
    pathlib.Path

    Notes
    -----
    One point per row of ``ops.points``, at ``position`` (reference r0(η)), with point data
    ``weight`` (Gauss weight · segment Jacobian · ``|r0'|``), ``eta``, ``xi`` (3 components: solid
    parameter coordinates), ``beam_element``, ``solid_element``, ``status`` (int64).
    """
    import meshio
    p = ops.points
    n = len(p)
    data = {"weight": p["weight"], "eta": p["eta"], "xi": p["xi"],
            "beam_element": p["beam_element"].astype(np.int64),
            "solid_element": p["solid_element"].astype(np.int64),
            "status": p["status"].astype(np.int64)}
    if displacement is not None:
        if beams is None:
            raise ValueError("write_integration_points: displacement needs the beams")
        Qd = _scaled_coefficients(beams, displacement)[p["beam_element"]]
        basis = beam_functions(beams.element_type, p["eta"][:, None]) if n else np.zeros((0, 1, 4))
        data["displacement"] = _apply(basis, Qd).reshape(-1, 3)
    mesh = meshio.Mesh(np.ascontiguousarray(p["position"]),
                       [("vertex", np.arange(n, dtype=np.int64)[:, None])],
                       point_data={key: np.ascontiguousarray(v) for key, v in data.items()})
    return _write_vtu(path, mesh, compression)


def write_pvd(path, entries):
    """Write a ParaView collection file (``.pvd``).

    Parameters
    ----------
    path : str or os.PathLike
        Output file (``.pvd``).
    entries : iterable of (timestep, part, file)
        ``timestep`` (float), ``part`` (int) and ``file``, the data file's path relative to the
        directory of the ``.pvd`` (written with ``/`` separators). Entries with the same
        timestep and different parts are shown together; a time series repeats the parts for
        every timestep.

    Returns
    -------
    pathlib.Path
    """
    lines = ['<?xml version="1.0"?>',
             '<VTKFile type="Collection" version="0.1" byte_order="LittleEndian">',
             "  <Collection>"]
    for entry in entries:
        try:
            timestep, part, file = entry
        except (TypeError, ValueError):
            raise ValueError(f"pvd entries are (timestep, part, relative_file) tuples, got {entry!r}") from None
        timestep = float(timestep)
        if not np.isfinite(timestep):
            raise ValueError(f"pvd entry {entry!r}: timestep must be finite")
        if isinstance(part, bool) or not isinstance(part, (int, np.integer)) or part < 0:
            raise ValueError(f"pvd entry {entry!r}: part must be an integer >= 0")
        file = Path(file)
        if file.is_absolute():
            raise ValueError(f"pvd entry {entry!r}: the file must be relative to the .pvd's directory")
        lines.append(f"    <DataSet timestep={quoteattr(repr(timestep))} group=\"\" part=\"{int(part)}\" "
                     f"file={quoteattr(file.as_posix())}/>")
    lines += ["  </Collection>", "</VTKFile>", ""]
    return _write_text(path, "\n".join(lines))


def _write_text(path, text):
    """Write ``text`` (UTF-8) to ``path`` through a temporary file (no partial file on failure)."""
    def write(tmp):
        with open(tmp, "w", encoding="utf-8") as f:
            f.write(text)
    return _atomic(path, write)


def write_mortar(directory, beams, solid, ops, prefix="mortar", *, compression="zlib"):
    """Write solid, beams, segments and integration points, and a ``.pvd`` that groups them.

    Parameters
    ----------
    directory : str or os.PathLike
        Created (with parents) if needed.
    beams : BeamMesh
    solid : SolidMesh
    ops : MortarOperators
        Operators assembled for ``beams`` and ``solid``.
    prefix : str
        File name prefix.
    compression : {"zlib", "lzma", None}
        Compression of the binary data (None: uncompressed, fastest to write).

    Returns
    -------
    list of pathlib.Path
        ``<prefix>_solid.vtu`` (part 0), ``<prefix>_beams.vtu`` (part 1),
        ``<prefix>_segments.vtu`` (part 2), ``<prefix>_points.vtu`` (part 3), and last
        ``<prefix>.pvd`` referencing the four at timestep 0.
    """
    directory = Path(directory)
    directory.mkdir(parents=True, exist_ok=True)
    names = [f"{prefix}_solid.vtu", f"{prefix}_beams.vtu", f"{prefix}_segments.vtu", f"{prefix}_points.vtu"]
    _check_compression(compression)
    paths = [write_solid(directory / names[0], solid, compression=compression),
             write_beams(directory / names[1], beams, compression=compression),
             write_segments(directory / names[2], beams, ops, compression=compression),
             write_integration_points(directory / names[3], ops, compression=compression)]
    paths.append(write_pvd(directory / f"{prefix}.pvd", [(0.0, i, name) for i, name in enumerate(names)]))
    return paths
