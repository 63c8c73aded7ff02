"""Input files of 4C (``.4C.yaml``): read them into a :class:`~mortar1d3d.scene.Scene`, run and check them.

4C (github ``4C-multiphysics/4C``) is the open-source C++ code of the method's authors. Its
beam-to-solid volume meshtying regression tests are complete models with reference
displacements (``RESULT DESCRIPTION``). This module reads such a file (plain YAML, PyYAML),
turns it into a scene with the library's node orders and element types, and compares a solve
with the file's reference values (:func:`check`). The page ``docs/fourc.md`` lists what is
supported; everything else stops with a :class:`FourCError` that names the key and its value,
never with a silent approximation.

What maps to what:

==============================================  ===============================================
4C                                              scene
==============================================  ===============================================
``SOLID HEX8/HEX20/HEX27/TET4/TET10``           solid mesh (node orders permuted, det J checked)
``MAT_Struct_StVenantKirchhoff``                ``saint_venant_kirchhoff``
``BEAM3EB LINE2``                               ``model = "beam3eb"``, one beam per chain of elements
``BEAM3R LINE3``, Hermite centreline            ``model = "simo_reissner"``, ``force_rule = "lobatto3"``,
                                                ``virtual_spins = "lagrange"``, ``TRIADS`` as
                                                reference triads
``DESIGN SURF/VOL/POINT DIRICH CONDITIONS``     ``dirichlet`` on the condition's node set
``DESIGN SURF NEUMANN CONDITIONS``              ``traction`` (force per reference area)
``DESIGN LINE NEUMANN CONDITIONS`` (beams)      ``line`` load (force per reference length), ``line_moment``
                                                (moment components of a BEAM3R beam)
``DESIGN POINT NEUMANN CONDITIONS``             ``point`` load, or ``moment`` on BEAM3R nodes
``FUNCT<k>`` ``SYMBOLIC_FUNCTION_OF_...: a*t``  load factor ``t / MAXTIME`` (linear in t only)
``STRUCTURAL DYNAMIC`` (Statics)                ``analysis.steps = NUMSTEP``
``BEAM TO SOLID VOLUME MESHTYING``              ``coupling`` (see docs/fourc.md)
==============================================  ===============================================
"""
import math
import os
import re
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..errors import FourCError  # noqa: F401 (raised here; importable from here)
from .fourc_nurbs import KEY as _KNOTS, NURBS_ELEMENTS

__all__ = ["FourCError", "FourCInput", "read_4c", "scene_from_4c", "run", "check", "ResultEntry", "CheckRow",
           "CheckReport", "ENV_VAR", "input_folder", "FOURC_SOLID_NODES"]

#: environment variable naming the folder of 4C input files the tests and the conformance script use
ENV_VAR = "MORTAR1D3D_4C_INPUTS"


def input_folders(repository_root=None):
    """The folders of 4C input files: the existing ones of ``$MORTAR1D3D_4C_INPUTS`` (separated by
    ``os.pathsep``), else the folder ``shared/4c-inputs`` beside the repository's folder (in its
    parent folder) if it exists; an empty list when there is none."""
    env = os.environ.get(ENV_VAR)
    if env:
        return [Path(f) for f in env.split(os.pathsep) if f and Path(f).is_dir()]
    root = Path(repository_root) if repository_root else Path(__file__).resolve().parents[2]
    folder = root.parent / "shared" / "4c-inputs"
    return [folder] if folder.is_dir() else []


def input_folder(repository_root=None):
    """The first of :func:`input_folders`, or None."""
    folders = input_folders(repository_root)
    return folders[0] if folders else None


# ----------------------------------------------------------------------------------------------
# node orders: 4C's reference coordinates of its element nodes (facts of 4C's element
# definitions); the permutation to the library's order follows by matching coordinates
# ----------------------------------------------------------------------------------------------
_HEX_4C = np.array([
    [-1, -1, -1], [1, -1, -1], [1, 1, -1], [-1, 1, -1], [-1, -1, 1], [1, -1, 1], [1, 1, 1], [-1, 1, 1],
    # edges: the four of the bottom face, the four vertical ones, the four of the top face
    [0, -1, -1], [1, 0, -1], [0, 1, -1], [-1, 0, -1],
    [-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0],
    [0, -1, 1], [1, 0, 1], [0, 1, 1], [-1, 0, 1],
    # face centres: bottom, front (y = -1), right (x = 1), back, left, top; then the centre
    [0, 0, -1], [0, -1, 0], [1, 0, 0], [0, 1, 0], [-1, 0, 0], [0, 0, 1], [0, 0, 0]], dtype=float)
_TET_4C = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1],
                    [0.5, 0, 0], [0.5, 0.5, 0], [0, 0.5, 0], [0, 0, 0.5], [0.5, 0, 0.5], [0, 0.5, 0.5]])

#: 4C solid element name -> (library element type, 4C reference coordinates of its nodes)
FOURC_SOLID_NODES = {"HEX8": ("hexahedron", _HEX_4C[:8]), "HEX20": ("hexahedron20", _HEX_4C[:20]),
                     "HEX27": ("hexahedron27", _HEX_4C), "TET4": ("tetra", _TET_4C[:4]),
                     "TET10": ("tetra10", _TET_4C)}


def _permutation(fourc_name):
    """``perm`` with ``library_nodes = fourc_nodes[perm]`` for a 4C solid element type."""
    from ..elements.solid.dispatch import solid_element
    name, ref4c = FOURC_SOLID_NODES[fourc_name]
    ref = np.asarray(solid_element(name).reference_nodes, dtype=float)
    dist = np.linalg.norm(ref[:, None, :] - ref4c[None, :, :], axis=2)
    perm = dist.argmin(axis=1)
    if not (np.sort(perm) == np.arange(len(ref4c))).all() or dist.min(axis=1).max() > 1e-12:
        raise AssertionError(f"no node permutation from 4C's {fourc_name} to {name}")
    return perm


# ----------------------------------------------------------------------------------------------
# parsing
# ----------------------------------------------------------------------------------------------
def _fail(key, message):
    raise FourCError(f"{key}: {message}")


def _num(value, key):
    """A number of the file (PyYAML reads ``1e-10`` without a dot as a string)."""
    if isinstance(value, bool):
        _fail(key, f"expected a number, got {value!r}")
    try:
        return float(value)
    except (TypeError, ValueError):
        _fail(key, f"expected a number, got {value!r}")


def _param(params, name, mkey):
    """The number ``params[name]`` of material ``mkey``; a FourCError naming the key if it is missing."""
    if name not in params:
        _fail(f"{mkey}.{name}", "missing")
    return _num(params[name], f"{mkey}.{name}")


def _shear_modulus(params, mkey):
    """``{"G": SHEARMOD}`` or ``{"nu": POISSONRATIO}`` of a beam material: 4C takes exactly one of them."""
    given = [name for name in ("SHEARMOD", "POISSONRATIO") if name in params]
    if len(given) != 1:
        _fail(mkey, f"expected exactly one of SHEARMOD and POISSONRATIO, got {given or 'neither'}")
    return {"G": _param(params, "SHEARMOD", mkey)} if given[0] == "SHEARMOD" else \
        {"nu": _param(params, "POISSONRATIO", mkey)}


@dataclass
class ResultEntry:
    """One ``RESULT DESCRIPTION`` entry: 4C's value for a node's displacement component.

    ``node`` is None and ``special`` True for 4C's own iteration counts (not comparable)."""

    index: int
    node: int
    quantity: str
    value: float
    tolerance: float
    special: bool = False


@dataclass
class FourCInput:
    """A parsed 4C input file (what :func:`scene_from_4c` needs of it).

    Attributes
    ----------
    path : Path
    data : dict
        The YAML sections as read.
    nodes : dict int -> (3,) float64
        ``NODE COORDS`` by 4C node id.
    solids : list of (element id, 4C type, node ids, material id)
    beams : list of (element id, 4C type, node ids, material id, rest of the line)
    sets : dict (kind, id) -> sorted node ids, kind in ``DNODE, DLINE, DSURF, DVOL``
    control_points : dict int -> ((3,) float64, float)
        NURBS control points (``CP`` lines of ``NODE COORDS``) by 4C id: position and weight.
    results : list of ResultEntry
    notes : list of str
        What the reader mapped to something other than the file's literal meaning (each one says
        what and why; :func:`check` prints them).
    """

    path: Path
    data: dict
    nodes: dict = field(default_factory=dict)
    solids: list = field(default_factory=list)
    beams: list = field(default_factory=list)
    sets: dict = field(default_factory=dict)
    control_points: dict = field(default_factory=dict)
    results: list = field(default_factory=list)
    notes: list = field(default_factory=list)


_SET_KIND = {"DNODE": "DNODE", "DPOINT": "DNODE", "DLINE": "DLINE", "DSURFACE": "DSURF", "DSURF": "DSURF",
             "DVOL": "DVOL", "DVOLUME": "DVOL"}


def read_4c(path):
    """Parse a ``.4C.yaml`` file: mesh, node sets and result description (no interpretation yet).

    Raises
    ------
    FourCError
        The file cannot be read, is not YAML, or a mesh line cannot be parsed (the key and the
        line are named).
    """
    import yaml
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except OSError as exc:
        raise FourCError(f"{path}: cannot be read: {exc.strerror or exc}") from None
    loader = getattr(yaml, "CSafeLoader", yaml.SafeLoader)
    try:
        data = yaml.load(text, Loader=loader)
    except yaml.YAMLError as exc:
        raise FourCError(f"{path}: not valid YAML: {exc}") from None
    if not isinstance(data, dict):
        raise FourCError(f"{path}: expected a YAML mapping of 4C sections")
    out = FourCInput(path=path, data=data)
    if "NODE COORDS" not in data:
        _fail("NODE COORDS", "missing (the file has no nodes)")
    for line in data["NODE COORDS"] or ():
        parts = str(line).split()
        if len(parts) >= 6 and parts[0] == "NODE" and parts[2] == "COORD":
            out.nodes[int(parts[1])] = np.array([float(v) for v in parts[3:6]])
        elif len(parts) >= 7 and parts[0] == "CP" and parts[2] == "COORD":
            # a NURBS control point: position and weight (mortar1d3d.io.fourc_nurbs)
            out.control_points[int(parts[1])] = (np.array([float(v) for v in parts[3:6]]), float(parts[6]))
        else:
            _fail("NODE COORDS", f"cannot parse {line!r}")
    for line in data.get("STRUCTURE ELEMENTS") or ():
        parts = str(line).split()
        if len(parts) < 3:
            _fail("STRUCTURE ELEMENTS", f"cannot parse {line!r}")
        eid, family, kind = int(parts[0]), parts[1], parts[2]
        try:
            mat_at = parts.index("MAT")
        except ValueError:
            _fail("STRUCTURE ELEMENTS", f"element {eid}: no MAT in {line!r}")
        ids = [int(v) for v in parts[3:mat_at]]
        material = int(parts[mat_at + 1])
        rest = parts[mat_at + 2:]
        if family in ("SOLID", "SOLIDH8", "SOLIDH27", "SOLIDH20", "SOLIDT4", "SOLIDT10"):
            if family != "SOLID":
                kind = {"SOLIDH8": "HEX8", "SOLIDH27": "HEX27", "SOLIDH20": "HEX20", "SOLIDT4": "TET4",
                        "SOLIDT10": "TET10"}[family]
            if kind not in FOURC_SOLID_NODES and kind not in NURBS_ELEMENTS:
                _fail("STRUCTURE ELEMENTS", f"element {eid}: solid element type {kind!r} is not supported; supported: "
                                            f"{', '.join([*FOURC_SOLID_NODES, *NURBS_ELEMENTS])}")
            if "KINEM" in rest and rest[rest.index("KINEM") + 1] != "nonlinear":
                _fail("STRUCTURE ELEMENTS", f"element {eid}: KINEM {rest[rest.index('KINEM') + 1]!r} is not "
                                            "supported (only nonlinear)")
            for word in rest[::2]:
                if word not in ("KINEM",):
                    _fail("STRUCTURE ELEMENTS", f"element {eid}: option {word!r} is not supported")
            out.solids.append((eid, kind, ids, material))
        elif family in ("BEAM3EB", "BEAM3R"):
            out.beams.append((eid, f"{family} {kind}", ids, material, rest))
        else:
            _fail("STRUCTURE ELEMENTS", f"element {eid}: element {family} {kind} is not supported")
    for key, value in data.items():
        if not key.endswith("-NODE TOPOLOGY"):
            continue
        for line in value or ():
            parts = str(line).split()
            if len(parts) != 4 or parts[0] != "NODE" or parts[2] not in _SET_KIND:
                _fail(key, f"cannot parse {line!r}")
            out.sets.setdefault((_SET_KIND[parts[2]], int(parts[3])), []).append(int(parts[1]))
    out.sets = {k: sorted(set(v)) for k, v in out.sets.items()}
    for i, entry in enumerate(data.get("RESULT DESCRIPTION") or ()):
        key = f"RESULT DESCRIPTION[{i}]"
        if not isinstance(entry, dict) or list(entry) != ["STRUCTURE"]:
            _fail(key, f"only STRUCTURE results are supported, got {entry!r}")
        r = entry["STRUCTURE"]
        if r.get("SPECIAL"):
            out.results.append(ResultEntry(i, None, str(r.get("QUANTITY")), _num(r.get("VALUE"), f"{key}.VALUE"),
                                           _num(r.get("TOLERANCE"), f"{key}.TOLERANCE"), special=True))
            continue
        if str(r.get("DIS", "structure")) != "structure":
            _fail(f"{key}.DIS", f"{r.get('DIS')!r} is not supported (only structure)")
        out.results.append(ResultEntry(i, int(r["NODE"]), str(r["QUANTITY"]), _num(r["VALUE"], f"{key}.VALUE"),
                                       _num(r["TOLERANCE"], f"{key}.TOLERANCE")))
    return out


# ----------------------------------------------------------------------------------------------
# interpretation
# ----------------------------------------------------------------------------------------------
#: sections that only steer 4C's output, parallel distribution or its own solvers: read and ignored
_IGNORED = ("TITLE", "PROBLEM SIZE", "IO", "IO/RUNTIME VTK OUTPUT", "IO/RUNTIME VTK OUTPUT/BEAMS",
            "IO/RUNTIME VTK OUTPUT/STRUCTURE", "IO/MONITOR STRUCTURE DBC", "SOLVER 1", "BINNING STRATEGY",
            "MESH PARTITIONING", "DISCRETISATION", "STRUCT NOX/Printing", "STRUCT NOX/Direction/Newton",
            "STRUCT NOX/Status Test", "BEAM INTERACTION", "BEAM CONTACT",
            "BEAM INTERACTION/BEAM TO SOLID VOLUME MESHTYING/RUNTIME VTK OUTPUT",
            "BEAM INTERACTION/BEAM TO SOLID SURFACE/RUNTIME VTK OUTPUT")
_MESH = ("NODE COORDS", "STRUCTURE ELEMENTS", _KNOTS, "RESULT DESCRIPTION", "MATERIALS",
         "BEAM INTERACTION/BEAM TO SOLID VOLUME MESHTYING LINE", "BEAM INTERACTION/BEAM TO SOLID VOLUME MESHTYING VOLUME")
_COUPLING = "BEAM INTERACTION/BEAM TO SOLID VOLUME MESHTYING"

_LINEAR_IN_T = re.compile(r"^\s*(?:([0-9.eE+-]+)\s*\*\s*)?t\s*$")


def _functions(data):
    """``{k: c}`` for every ``FUNCT<k>`` that is ``c * t`` (the only time dependence scenes express:
    loads in proportion to the load factor)."""
    out = {}
    for key, value in data.items():
        m = re.fullmatch(r"FUNCT(\d+)", key)
        if not m:
            continue
        if not isinstance(value, list) or len(value) != 1 or not isinstance(value[0], dict) or len(value[0]) != 1:
            _fail(key, f"only a single symbolic function of time is supported, got {value!r}")
        (kind, expr), = value[0].items()
        if kind not in ("SYMBOLIC_FUNCTION_OF_SPACE_TIME", "SYMBOLIC_FUNCTION_OF_TIME"):
            _fail(f"{key}.{kind}", "is not supported (only SYMBOLIC_FUNCTION_OF_[SPACE_]TIME)")
        match = _LINEAR_IN_T.match(str(expr))
        if not match:
            _fail(f"{key}.{kind}", f"{expr!r} is not supported: loads follow the load factor, so a function must "
                                   "be c * t")
        out[int(m.group(1))] = float(match.group(1)) if match.group(1) else 1.0
    return out


def _time(data):
    """(steps, final time) of ``STRUCTURAL DYNAMIC`` (statics only)."""
    key = "STRUCTURAL DYNAMIC"
    sd = data.get(key) or {}
    if str(sd.get("DYNAMICTYPE", "")) != "Statics":
        _fail(f"{key}.DYNAMICTYPE", f"{sd.get('DYNAMICTYPE')!r} is not supported (only Statics)")
    steps = int(sd.get("NUMSTEP", 1))
    dt = _num(sd.get("TIMESTEP", 1.0), f"{key}.TIMESTEP")
    final = _num(sd.get("MAXTIME", steps * dt), f"{key}.MAXTIME")
    if not math.isclose(steps * dt, final, rel_tol=1e-12):
        _fail(f"{key}.MAXTIME", f"{final} is not NUMSTEP × TIMESTEP = {steps} × {dt}: 4C would stop at "
                                f"{min(final, steps * dt)}; give consistent values")
    for k in ("PRESTRESS", "RESTART"):
        if sd.get(k) not in (None, "none", "None", 0):
            _fail(f"{key}.{k}", f"{sd.get(k)!r} is not supported")
    return steps, final


def _factor(functions, funct, value, key, final):
    """The value of a condition component at the end time (scene values are reached at load factor 1):
    ``value × f(final)`` with ``f = c t``; FUNCT 0 (constant) only for a zero value."""
    funct = int(funct or 0)
    if funct == 0:
        if value != 0.0:
            _fail(key, f"a constant nonzero value {value} (FUNCT 0) is not supported: scene loads and prescribed "
                       "values grow with the load factor")
        return 0.0
    if funct not in functions:
        _fail(key, f"FUNCT {funct} is not defined")
    return value * functions[funct] * final


def _condition_components(cond, key, functions, final, n_translational=3):
    """(components, values) of a DIRICH/NEUMANN entry; nonzero entries beyond the translations are
    an error naming the component."""
    numdof = int(cond.get("NUMDOF", 3))
    onoff = list(cond.get("ONOFF") or [0] * numdof)
    val = [_num(v, f"{key}.VAL") for v in (cond.get("VAL") or [0] * numdof)]
    funct = list(cond.get("FUNCT") or [0] * numdof)
    if cond.get("TYPE") not in (None, "Live"):
        _fail(f"{key}.TYPE", f"{cond.get('TYPE')!r} is not supported (only Live: a fixed vector)")
    comps, values = [], []
    for c in range(numdof):
        if not int(onoff[c]):
            continue
        if c >= n_translational:
            _fail(f"{key}.ONOFF[{c}]", "only the three translational components are supported here")
        comps.append(c)
        values.append(_factor(functions, funct[c], val[c], f"{key}.VAL[{c}]", final))
    return comps, values


def _chains(elements):
    """Beam elements (lists of end-node id pairs, in file order) joined into chains of node ids."""
    import collections
    adj = collections.defaultdict(list)
    for k, (a, b) in enumerate(elements):
        adj[a].append(k)
        adj[b].append(k)
    used, chains = set(), []
    for k0, (a0, b0) in enumerate(elements):
        if k0 in used:
            continue
        # walk back to the chain's start
        start, k = a0, k0
        seen = {k0}
        while len(adj[start]) == 2:
            k = next(j for j in adj[start] if j != k)
            if k in seen:
                break
            seen.add(k)
            a, b = elements[k]
            start = a if b == start else b
        nodes, ks, node, prev = [start], [], start, None
        while True:
            nxt = [j for j in adj[node] if j != prev and j not in used]
            if not nxt:
                break
            k = nxt[0]
            used.add(k)
            ks.append(k)
            a, b = elements[k]
            node = b if a == node else a
            nodes.append(node)
            prev = k
        chains.append((nodes, ks))
    return chains


def _materials(data):
    out = {}
    for i, entry in enumerate(data.get("MATERIALS") or ()):
        mid = int(entry["MAT"])
        rest = {k: v for k, v in entry.items() if k != "MAT"}
        if len(rest) != 1:
            _fail(f"MATERIALS[{i}]", f"expected one material law, got {list(rest)}")
        (law, params), = rest.items()
        out[mid] = (law, params or {}, f"MATERIALS[{i}].{law}")
    return out


def _material(materials, ids, what):
    """(law, parameters, key path) of the one material ``ids`` (a set) that ``what`` use."""
    if len(ids) != 1:
        _fail("STRUCTURE ELEMENTS", f"{what} use several materials {sorted(ids)}; one is supported")
    mat = next(iter(ids))
    if mat not in materials:
        _fail("MATERIALS", f"material {mat} of the {what} is not defined")
    return materials[mat]


def _beam3eb(info, X, connectivity, params, law, mkey):
    """Scene entry of a chain of BEAM3EB elements (straight: 4C takes each element's tangents along its chord)."""
    from ..mesh import BeamMesh
    eids = [i[0] for i in info]
    for eid, _, rest, _, _ in info:
        if rest:
            _fail("STRUCTURE ELEMENTS", f"element {eid}: options {' '.join(rest)!r} are not supported")
    if law != "MAT_BeamKirchhoffTorsionFreeElastHyper":
        _fail(mkey, "BEAM3EB needs MAT_BeamKirchhoffTorsionFreeElastHyper")
    chords = np.diff(X, axis=0)
    chords /= np.linalg.norm(chords, axis=1)[:, None]
    kink = np.linalg.norm(chords[1:] - chords[:-1], axis=1) if len(chords) > 1 else np.zeros(0)
    if kink.size and kink.max() > 1e-10:
        k = int(kink.argmax())
        _fail("STRUCTURE ELEMENTS", f"BEAM3EB elements {eids[k]} and {eids[k + 1]} meet at an angle: the "
                                    "torsion-free beam needs a straight reference centreline")
    mesh = BeamMesh.hermite(X, np.vstack([chords, chords[-1:]]), connectivity)
    E = _param(params, "YOUNG", mkey)
    return {"mesh": mesh, "model": "beam3eb", "section": {"EA": E * _param(params, "CROSSAREA", mkey),
                                                          "EI": E * _param(params, "MOMIN", mkey)}}


def _beam3r(info, nodes, X, connectivity, params, law, mkey):
    """Scene entry (``simo_reissner``) of a chain of BEAM3R elements with a Hermite centreline: the
    end nodes carry positions and tangents (the first base vector of their reference triads), every
    element's middle node a triad only; TRIADS are the reference rotation vectors of the element's
    nodes in its node order (end, end, middle)."""
    from ..mesh import BeamMesh
    from ..physics.rotations import exp
    for eid, _, rest, ids, kind in info:
        options = list(rest)
        if kind == "BEAM3R LINE3":
            if "HERMITE_CENTERLINE" not in options or options[options.index("HERMITE_CENTERLINE") + 1] != "true":
                _fail("STRUCTURE ELEMENTS", f"element {eid}: BEAM3R LINE3 without HERMITE_CENTERLINE true (a Lagrange "
                                            "centreline) is not supported")
            at = options.index("HERMITE_CENTERLINE")
            del options[at:at + 2]
        if len(ids) != 3:
            _fail("STRUCTURE ELEMENTS", f"element {eid}: expected three nodes (end, end, middle), got {len(ids)}")
        if len(options) != 10 or options[0] != "TRIADS":
            _fail("STRUCTURE ELEMENTS", f"element {eid}: expected TRIADS and nine numbers, got {' '.join(rest)!r}")
    if law != "MAT_BeamReissnerElastHyper":
        _fail(mkey, "BEAM3R needs MAT_BeamReissnerElastHyper")
    triad = np.empty((3, 3))
    n_nodes, n_el = len(nodes), len(info)
    triads = np.zeros((n_nodes + n_el, 3, 3))
    for e, (eid, _, rest, ids, _) in enumerate(info):
        psi = np.array([float(v) for v in rest[1:10]]).reshape(3, 3)
        forward = ids[0] == nodes[e]
        if not forward:
            _fail("STRUCTURE ELEMENTS", f"element {eid}: its nodes run against the beam's other elements")
        for slot, p in zip((e, e + 1, n_nodes + e), psi):
            exp(np.ascontiguousarray(p), triad)
            if slot < n_nodes and e > 0 and slot == e and np.abs(triads[slot] - triad).max() > 1e-8:
                _fail("STRUCTURE ELEMENTS", f"element {eid}: its triad at node {ids[0]} differs from the previous "
                                            "element's")
            triads[slot] = triad
    mesh = BeamMesh.hermite(X, triads[:n_nodes, :, 0], connectivity)
    section = {"E": _param(params, "YOUNG", mkey), **_shear_modulus(params, mkey),
               "A": _param(params, "CROSSAREA", mkey), "I2": _param(params, "MOMIN2", mkey),
               "I3": _param(params, "MOMIN3", mkey), "I_T": _param(params, "MOMINPOL", mkey),
               "shear_correction": _num(params.get("SHEARCORR", 1.0), f"{mkey}.SHEARCORR")}
    # 4C integrates the force (Γ) term of a Hermite-centreline BEAM3R with 3-point Gauss–Lobatto and
    # the moment term with 3-point Gauss (Beam3r::my_gauss_rule): the library's rule "lobatto3"; its
    # spin rows test with the Lagrange functions of the triad nodes (Jelenić & Crisfield 1999,
    # eq. (4.3)), not with the exact spin variation: virtual_spins "lagrange"
    return {"mesh": mesh, "model": "simo_reissner", "section": section, "triads": triads.tolist(),
            "force_rule": "lobatto3", "virtual_spins": "lagrange"}


def _twist_gauge(rot, key, on, beams, coupling, notes):
    """The scene's ``twist = true`` support for a Dirichlet condition on some rotation components of
    a BEAM3R node (``rot``: (component 0-2, value) pairs), where that condition only gauges the twist.

    A straight beam with g1 along its tangent and equal bending and shear stiffnesses about g2 and
    g3, tied to the solid by its centreline only, can turn all its cross-sections about their own
    axes at no energy cost, in any configuration. Fixing one spin component at a node removes that
    mode (4C's direct solver gets through the first iteration because the mode's right-hand side is
    zero); the centreline does not depend on how the mode is removed. Holding the twist about the
    node's reference tangent removes it for every configuration; the note in ``notes`` says so.
    Anything else (nonzero values, rotational coupling, a curved or anisotropic beam) is a
    FourCError naming the condition and the reason.
    """
    comps = [c + 3 for c, _ in rot]
    what = f"rotation components {comps} with values {[v for _, v in rot]}"
    if any(v != 0.0 for _, v in rot):
        _fail(f"{key}.VAL", f"{what}: a nonzero rotation is supported only for all three components together "
                            "(scenes prescribe a node's whole rotation vector)")
    if len(rot) != 1:
        _fail(f"{key}.ONOFF", f"{what}: beyond removing the free twist, two spin components hold the bending rotation "
                              "about a fixed axis (a constraint scenes cannot express); supported: one component "
                              "(a gauge of the twist) or all three")
    if str(coupling.get("ROTATION_COUPLING", "none")) != "none":
        _fail(f"{key}.ONOFF", f"{what}: with ROTATION_COUPLING the cross-sections are tied to the solid, so a single "
                              "rotation component is a real constraint, not a gauge of the twist; only all three "
                              "rotations held at zero are supported")
    beam = beams[int(on.split(":")[1])]
    section, mesh = beam["section"], beam["mesh"]
    if section["I2"] != section["I3"] or np.ndim(section["shear_correction"]) != 0:
        _fail(f"{key}.ONOFF", f"{what}: the beam's section is not the same about g2 and g3, so its twist is not free "
                              "and the condition is a real constraint; only all three rotations held at zero are "
                              "supported")
    t = mesh.tangents
    if np.abs(t - t[0]).max() > 1e-12 or np.abs(np.array(beam["triads"])[:, :, 0] - t[0]).max() > 1e-12:
        _fail(f"{key}.ONOFF", f"{what}: the beam is not straight along its triads' g1, so its twist is not free and "
                              "the condition is a real constraint; only all three rotations held at zero are "
                              "supported")
    notes.append(f"{key}: {what} (spins about global axes) at {on!r} only remove the beam's free twist (a straight "
                 "beam with an isotropic section, tied by its centreline only); read as twist = true there (the "
                 "triad does not turn about the node's reference tangent), which gives the same centreline")
    return {"on": on, "twist": True, "twist_key": f"{key}.ONOFF"}


def scene_from_4c(source):
    """The :class:`~mortar1d3d.scene.Scene` of a 4C input file, and the map of its result nodes.

    Parameters
    ----------
    source : path or FourCInput

    Returns
    -------
    scene : Scene
    nodes : dict
        4C node id -> ``("solid", row)`` (row of ``Result.solid_displacement``) or
        ``("beam", row)`` (row of ``Result.beam_displacement``).

    Raises
    ------
    FourCError
        A section, key or value the library does not support: the message names it.
    """
    from ..mesh import SolidMesh
    from ..errors import MeshError
    from ..scene import Scene
    fc = source if isinstance(source, FourCInput) else read_4c(source)
    data = fc.data
    pt = data.get("PROBLEM TYPE") or {}
    if str(pt.get("PROBLEMTYPE", "Structure")) != "Structure":
        _fail("PROBLEM TYPE.PROBLEMTYPE", f"{pt.get('PROBLEMTYPE')!r} is not supported (only Structure)")
    known = set(_IGNORED) | set(_MESH) | {"PROBLEM TYPE", "STRUCTURAL DYNAMIC", _COUPLING}
    for key in data:
        if (key in known or key.endswith("-NODE TOPOLOGY") or re.fullmatch(r"FUNCT\d+", key)
                or (key.startswith("DESIGN ") and key.endswith(" CONDITIONS"))):
            continue
        _fail(key, "section not supported")
    functions = _functions(data)
    steps, final = _time(data)
    materials = _materials(data)

    # -- solid ----------------------------------------------------------------------------------
    if not fc.solids:
        _fail("STRUCTURE ELEMENTS", "no solid elements (beam-only models are not read)")
    solid_ids = sorted({n for _, _, ids, _ in fc.solids for n in ids})
    solid_row = {nid: k for k, nid in enumerate(solid_ids)}
    law, params, mkey = _material(materials, {m for *_, m in fc.solids}, "solid elements")
    if law != "MAT_Struct_StVenantKirchhoff":
        _fail(mkey, "solid material law not supported (only MAT_Struct_StVenantKirchhoff)")
    material = {"model": "saint_venant_kirchhoff", "E": _param(params, "YOUNG", mkey),
                "nu": _param(params, "NUE", mkey)}
    nurbs = [eid for eid, kind, _, _ in fc.solids if kind in NURBS_ELEMENTS]
    if nurbs and len(nurbs) != len(fc.solids):
        _fail("STRUCTURE ELEMENTS", f"NURBS elements ({nurbs[0]}, …) together with Lagrange solid elements are not "
                                    "supported")
    blocks = {}
    for eid, kind, ids, _ in fc.solids if not nurbs else ():
        if len(ids) != len(FOURC_SOLID_NODES[kind][1]):
            _fail("STRUCTURE ELEMENTS", f"element {eid}: {kind} needs {len(FOURC_SOLID_NODES[kind][1])} nodes, got "
                                        f"{len(ids)}")
        blocks.setdefault(kind, []).append([solid_row[n] for n in ids])
    cells = {}
    for kind, rows in blocks.items():
        cells[FOURC_SOLID_NODES[kind][0]] = np.asarray(rows, dtype=np.int64)[:, _permutation(kind)]
    try:
        if nurbs:
            from .fourc_nurbs import nurbs_mesh      # control points (CP) -> the Bézier mesh's nodes
            solid_mesh, solid_row = nurbs_mesh(fc)
        else:
            # SolidMesh proves det J > 0 in every element: the geometric check of the permutation
            solid_mesh = SolidMesh(np.array([fc.nodes[n] for n in solid_ids]), cells)
    except MeshError as exc:
        raise FourCError(f"STRUCTURE ELEMENTS: {exc}") from None
    for (kind, sid), ids in fc.sets.items():
        rows = [solid_row[n] for n in ids if n in solid_row]
        if rows:
            solid_mesh.point_sets[f"{kind.lower()}{sid}"] = np.asarray(rows, dtype=np.int64)

    # -- beams ----------------------------------------------------------------------------------
    beams, beam_rows, beam_of_node, rotation_beams = [], {}, {}, set()
    hermite_r = {"BEAM3R HERM2LINE3", "BEAM3R LINE3"}
    kinds = {k for _, k, *_ in fc.beams}
    if kinds - {"BEAM3EB LINE2"} - hermite_r:
        _fail("STRUCTURE ELEMENTS", f"beam elements {sorted(kinds - {'BEAM3EB LINE2'} - hermite_r)} are not "
                                    "supported (BEAM3EB LINE2; BEAM3R LINE3 with HERMITE_CENTERLINE true)")
    if len(kinds) > 1:
        _fail("STRUCTURE ELEMENTS", f"beam elements of several kinds {sorted(kinds)}; one kind per file is supported")
    if fc.beams:
        # end nodes of each element; BEAM3R LINE3 lists (end, end, middle): the middle node carries a triad only
        ends = [tuple(ids[:2]) for _, _, ids, _, _ in fc.beams]
        by_pair = {tuple(ids[:2]): (eid, mat, rest, ids, kind) for eid, kind, ids, mat, rest in fc.beams}
        row = 0
        for nodes, _ in _chains(ends):
            elements = [(nodes[k], nodes[k + 1]) for k in range(len(nodes) - 1)]
            info = [by_pair.get(e) or by_pair.get(e[::-1]) for e in elements]
            law, params, mkey = _material(materials, {i[1] for i in info}, f"beam elements {[i[0] for i in info]}")
            X = np.array([fc.nodes[n] for n in nodes])
            connectivity = np.column_stack([np.arange(len(nodes) - 1), np.arange(1, len(nodes))])
            index = len(beams)
            if info[0][4] == "BEAM3EB LINE2":
                beams.append(_beam3eb(info, X, connectivity, params, law, mkey))
            else:
                beams.append(_beam3r(info, nodes, X, connectivity, params, law, mkey))
                rotation_beams.add(index)
            for k, n in enumerate(nodes):
                beam_rows[n] = row + k
                beam_of_node[n] = (index, k, len(nodes))
            row += len(nodes)

    # -- conditions -----------------------------------------------------------------------------
    dirichlet, loads = [], []
    entity = {"POINT": "DNODE", "LINE": "DLINE", "SURF": "DSURF", "VOL": "DVOL"}

    def target(kind, eid, key):
        ids = fc.sets.get((entity[kind], eid))
        if not ids:
            _fail(key, f"design {kind.lower()} {eid} has no nodes ({entity[kind]}-NODE TOPOLOGY)")
        in_solid = [n for n in ids if n in solid_row]
        in_beam = [n for n in ids if n in beam_of_node]
        if in_solid and in_beam:
            _fail(key, f"design {kind.lower()} {eid} holds solid and beam nodes; one kind per condition is supported")
        if in_solid:
            return f"solid:{entity[kind].lower()}{eid}", "solid"
        beams_hit = {beam_of_node[n][0] for n in in_beam}
        if len(beams_hit) != 1:
            _fail(key, f"design {kind.lower()} {eid} spans beams {sorted(beams_hit)}; one beam per condition is "
                       "supported")
        b = beams_hit.pop()
        n_nodes = beam_of_node[in_beam[0]][2]
        local = sorted(beam_of_node[n][1] for n in in_beam)
        if len(local) == n_nodes:
            return f"beam:{b}", "beam"
        if local == [0]:
            return f"beam:{b}:start", "beam"
        if local == [n_nodes - 1]:
            return f"beam:{b}:end", "beam"
        _fail(key, f"design {kind.lower()} {eid} selects part of beam {b}; only whole beams or their ends are "
                   "supported")

    for key, value in data.items():
        m = re.fullmatch(r"DESIGN (POINT|LINE|SURF|VOL) (DIRICH|NEUMANN) CONDITIONS", key)
        if not m:
            if key.startswith("DESIGN ") and key.endswith(" CONDITIONS"):
                _fail(key, "condition not supported")
            continue
        kind, what = m.groups()
        for i, cond in enumerate(value or ()):
            ckey = f"{key}[{i}]"
            extra = set(cond) - {"E", "NUMDOF", "ONOFF", "VAL", "FUNCT", "TAG", "TYPE"}
            if extra:
                _fail(f"{ckey}.{sorted(extra)[0]}", "is not supported")
            on, body = target(kind, int(cond["E"]), f"{ckey}.E")
            framed = body == "beam" and int(on.split(":")[1]) in rotation_beams
            # a Hermite BEAM3R node's DOFs: position (3), rotation (3), tangent (3)
            comps, values = _condition_components(cond, ckey, functions, final, 6 if framed else 3)
            rot = [(c - 3, v) for c, v in zip(comps, values) if c >= 3]
            comps, values = [c for c in comps if c < 3], [v for c, v in zip(comps, values) if c < 3]
            if rot and what == "NEUMANN":
                vec = [0.0, 0.0, 0.0]
                for c, v in rot:
                    vec[c] = v
                if kind == "LINE" and on.count(":") == 1:
                    # BEAM3R: moment per reference length, spread with the triad nodes' Lagrange functions
                    loads.append({"type": "line_moment", "on": on, "value": vec})
                    if not comps:
                        continue
                    rot = []
                elif kind != "POINT":
                    _fail(f"{ckey}.ONOFF", f"moments distributed over a {kind.lower()} are not supported (point "
                                           "moments, and line moments along a whole BEAM3R beam)")
                else:
                    if comps:
                        _fail(ckey, "forces and moments in one condition are not supported")
                    loads.append({"type": "moment", "on": on, "value": vec})
                    continue
            if rot:
                if [c for c, _ in rot] != [0, 1, 2] or any(v != 0.0 for _, v in rot):
                    entry = _twist_gauge(rot, ckey, on, beams, data.get(_COUPLING) or {}, fc.notes)
                    if comps:
                        entry.update(components=["xyz"[c] for c in comps],
                                     value=[dict(zip(comps, values)).get(c, 0.0) for c in range(3)])
                    dirichlet.append(entry)
                    continue
                entry = {"on": on, "rotation": [0.0, 0.0, 0.0]}
                if comps:
                    vec = [0.0, 0.0, 0.0]
                    for c, v in zip(comps, values):
                        vec[c] = v
                    entry.update(components=["xyz"[c] for c in comps], value=vec)
                dirichlet.append(entry)
                continue
            if not comps:
                continue
            if what == "DIRICH":
                vec = [0.0, 0.0, 0.0]
                for c, v in zip(comps, values):
                    vec[c] = v
                dirichlet.append({"on": on, "components": ["xyz"[c] for c in comps], "value": vec})
                continue
            vec = [0.0, 0.0, 0.0]
            for c, v in zip(comps, values):
                vec[c] = v
            if kind == "SURF" and body == "solid":
                loads.append({"type": "traction", "on": on, "value": vec})
            elif kind == "LINE" and body == "beam":
                loads.append({"type": "line", "on": on, "value": vec})
            elif kind == "POINT":
                loads.append({"type": "point", "on": on, "value": vec})
            else:
                _fail(ckey, f"a {kind.lower()} Neumann condition on {body} nodes is not supported")

    held = {d["on"] for d in dirichlet if d.get("rotation") is not None}
    for d in dirichlet:
        if d.get("twist") and (d["on"] in held or d["on"].rsplit(":", 1)[0] in held):
            _fail(d["twist_key"], "a single rotation component at a node whose rotation another condition also "
                                  "holds is not a pure twist gauge; not supported")
    for d in dirichlet:
        d.pop("twist_key", None)
    if fc.notes:
        import warnings
        for note in fc.notes:
            warnings.warn(f"{fc.path.name}: {note}", UserWarning, stacklevel=2)
    coupling = _coupling(data.get(_COUPLING), bool(beams)) if beams else None
    if beams and (data.get(_COUPLING) or {}).get("ROTATION_COUPLING") in _PLANE_TRIADS:
        _check_plane_rotations(beams, data[_COUPLING]["ROTATION_COUPLING"])
    if beams:
        for key in ("BEAM INTERACTION/BEAM TO SOLID VOLUME MESHTYING LINE",
                    "BEAM INTERACTION/BEAM TO SOLID VOLUME MESHTYING VOLUME"):
            if not data.get(key):
                _fail(key, "missing: the beams are not tied to the solid")
            if isinstance(data[key], list) and len(data[key]) > 1:
                # 4C ties each line set only to the volume sets of its COUPLING_ID; here every beam is
                # tied to the whole solid, so several conditions would be read wrongly
                _fail(key, f"{len(data[key])} conditions (COUPLING_ID per beam/solid pair) are not supported: "
                           "one condition, tying every beam to the whole solid")
            # the library ties every beam to the whole solid: the condition's design set must hold them all
            entry = data[key][0] if isinstance(data[key], list) else data[key]
            kind, rows, what = (("DLINE", beam_rows, "beam") if key.endswith("LINE") else ("DVOL", solid_row, "solid"))
            ids = set(fc.sets.get((kind, entry.get("E") if isinstance(entry, dict) else None), ()))
            left = [n for n in rows if n not in ids]
            if left:
                _fail(f"{key}.E", f"design {kind[1:].lower()} {entry.get('E') if isinstance(entry, dict) else entry} "
                                  f"leaves out {len(left)} {what} nodes (e.g. node {left[0]}); only conditions on "
                                  f"every {what} node are supported (the library ties every beam to the whole solid)")
    analysis = {"kinematics": "nonlinear", "steps": steps, "solver": "direct"}
    scene = Scene(solid={"mesh": solid_mesh, "material": material}, beams=beams, coupling=coupling,
                  dirichlet=dirichlet, load=loads, analysis=analysis, base_dir=fc.path.parent,
                  name=fc.path.name.removesuffix(".yaml").removesuffix(".4C"))
    nodes = {nid: ("solid", r) for nid, r in solid_row.items()}
    nodes.update({nid: ("beam", r) for nid, r in beam_rows.items()})
    return scene, nodes


def _check_plane_rotations(beams, rotation="polar_decomposition_2d"):
    """4C's ``polar_decomposition_2d`` triad is ``exp((θ_R + |ψ0|) e_x)``: θ_R the angle of the polar
    rotation of F's y-z block, ψ0 the beam's reference rotation vector, which 4C requires to lie
    along x. That is the library's polar triad ``R Λ0`` where the reference triads turn about +x
    by an angle in [0, π) (so that |ψ0| is the angle) and F keeps the y-z plane (4C stops
    otherwise; the library's polar triad continues as the three-dimensional polar rotation).
    The same holds for 4C's ``deformation_gradient_{y,z,average}_2d``, ``exp((θ + |ψ0|) e_x)`` with θ
    the angle of F's turn of the y axis, the z axis or their mean: the library's ``plane_*`` triads
    ``exp(θ e_x) Λ0``."""
    key = f"{_COUPLING}.ROTATION_COUPLING"
    for i, b in enumerate(beams):
        if "triads" not in b:
            _fail(key, f"{rotation!r} couples cross-section rotations; beam {i} has none "
                       "(a BEAM3EB beam: use BEAM3R)")
        T = np.asarray(b["triads"], dtype=float)
        off = max(np.abs(T[:, 0, 0] - 1.0).max(), np.abs(T[:, 0, 1:]).max(), np.abs(T[:, 1:, 0]).max())
        if off > 1e-10 or np.any(np.arctan2(T[:, 2, 1], T[:, 1, 1]) < -1e-12):
            _fail(key, f"{rotation!r} needs reference triads that turn about +x only (a problem in the "
                       f"y-z plane); those of beam {i} do not")


#: 4C's plane rotational-coupling triads (rotations about x in the y-z plane) → the library's triads
_PLANE_TRIADS = {"polar_decomposition_2d": "polar", "deformation_gradient_y_2d": "plane_y",
                 "deformation_gradient_z_2d": "plane_z", "deformation_gradient_average_2d": "plane_average"}


def _coupling(block, has_beams):
    key = _COUPLING
    if block is None:
        _fail(key, "missing: the beams are not tied to the solid")
    block = dict(block)
    allowed = {"CONTACT_DISCRETIZATION", "CONSTRAINT_STRATEGY", "MORTAR_SHAPE_FUNCTION", "PENALTY_PARAMETER",
               "GEOMETRY_PAIR_STRATEGY", "GEOMETRY_PAIR_SEGMENTATION_SEARCH_POINTS", "GAUSS_POINTS",
               "LAGRANGE_FORMULATION", "ROTATION_COUPLING", "COUPLE_RESTART_STATE", "ROTATION_COUPLING_PENALTY_PARAMETER",
               "ROTATION_COUPLING_MORTAR_SHAPE_FUNCTION", "INTEGRATION_POINTS_CIRCUMFERENCE"}
    for k in block:
        if k not in allowed:
            _fail(f"{key}.{k}", f"{block[k]!r} is not supported")
    out = {}
    disc = str(block.get("CONTACT_DISCRETIZATION", "none"))
    if disc == "mortar":
        out["constraint"] = "mortar"
        shape = str(block.get("MORTAR_SHAPE_FUNCTION", "none"))
        if shape not in ("line2", "line3", "line4"):
            _fail(f"{key}.MORTAR_SHAPE_FUNCTION", f"{shape!r} is not supported (line2, line3, line4)")
        out["lm"] = shape
    elif disc == "gauss_point_to_segment":
        out["constraint"] = "gauss_point"
    else:
        _fail(f"{key}.CONTACT_DISCRETIZATION", f"{disc!r} is not supported (mortar, gauss_point_to_segment)")
    strategy = str(block.get("GEOMETRY_PAIR_STRATEGY", "segmentation"))
    if strategy == "segmentation":
        out["integration"] = "segment"
    elif strategy == "gauss_point_projection_without_boundary_segmentation":
        out["integration"] = "element"
    elif strategy == "gauss_point_projection_boundary_segmentation":
        out["integration"] = "element_boundary"
    else:
        _fail(f"{key}.GEOMETRY_PAIR_STRATEGY", f"{strategy!r} is not supported (segmentation, "
                                               "gauss_point_projection_without_boundary_segmentation, "
                                               "gauss_point_projection_boundary_segmentation)")
    out["search_points"] = int(block.get("GEOMETRY_PAIR_SEGMENTATION_SEARCH_POINTS", 6))
    out["n_gauss"] = int(block.get("GAUSS_POINTS", 6))
    constraint = str(block.get("CONSTRAINT_STRATEGY", "none"))
    if constraint == "penalty":
        out["enforcement"] = "penalty"
        out["penalty"] = _num(block.get("PENALTY_PARAMETER"), f"{key}.PENALTY_PARAMETER")
    elif constraint == "lagrange":
        form = str(block.get("LAGRANGE_FORMULATION", "saddlepoint"))
        if form in ("saddlepoint", "augmented"):
            # augmented: the added penalty term vanishes where the constraint holds, so the solution
            # is the saddle point's (it changes only 4C's linear systems)
            out["enforcement"] = "lagrange"
        elif form == "regularized":
            # the regularised constraint g − κ λ / ε = 0 gives λ = ε κ⁻¹ g: exactly the penalty method
            out["enforcement"] = "penalty"
            out["penalty"] = _num(block.get("PENALTY_PARAMETER"), f"{key}.PENALTY_PARAMETER")
        else:
            _fail(f"{key}.LAGRANGE_FORMULATION", f"{form!r} is not supported (saddlepoint, augmented, regularized)")
    else:
        _fail(f"{key}.CONSTRAINT_STRATEGY", f"{constraint!r} is not supported (penalty, lagrange)")
    rotation = str(block.get("ROTATION_COUPLING", "none"))
    # 4C's 3d_general treats the three deformed base vectors alike; its 3d_base_1 starts from the first;
    # its polar_decomposition_2d is the polar rotation of F in the y-z plane, the library's polar triad
    # there (the reader checks that the problem is that plane one: _check_plane_rotations)
    triads = {"deformation_gradient_3d_general": "deformation_gradient_symmetric",
              "deformation_gradient_3d_base_1": "deformation_gradient", **_PLANE_TRIADS,
              **{f"deformation_gradient_3d_local_{k}": f"deformation_gradient_local_{k}" for k in (1, 2, 3)}}
    if rotation in triads:
        rot = {"triad": triads[rotation], "enforcement": "penalty",
               "penalty": _num(block.get("ROTATION_COUPLING_PENALTY_PARAMETER"),
                               f"{key}.ROTATION_COUPLING_PENALTY_PARAMETER")}
        shape = str(block.get("ROTATION_COUPLING_MORTAR_SHAPE_FUNCTION", "none"))
        if out["constraint"] == "mortar":
            if shape not in ("line2", "line3"):
                _fail(f"{key}.ROTATION_COUPLING_MORTAR_SHAPE_FUNCTION", f"{shape!r} is not supported (line2, line3)")
            rot["lm"] = shape
            # 4C's mortar rotation pair: its beam forces use the plain Lagrange functions, not the
            # derivative of its constraint (physics/rotational_fourc.py)
            rot["forces"] = "fourc"
        else:
            # 4C's gauss_point_to_segment pair: the penalty ε/2 |ψ|² at each integration point. Its
            # forces equal the library's variational ones only where the rotations stay in one
            # plane (polar_decomposition_2d); 4C's own point-wise force form is not built
            if rotation not in _PLANE_TRIADS:
                _fail(f"{key}.ROTATION_COUPLING", f"{rotation!r} with CONTACT_DISCRETIZATION gauss_point_to_segment: "
                                                  "4C's point-wise rotational force form is not supported (only "
                                                  f"the plane triads {', '.join(_PLANE_TRIADS)}, where it equals "
                                                  "the library's)")
            rot["constraint"] = "gauss_point"
        out["rotational"] = rot
    elif rotation != "none":
        _fail(f"{key}.ROTATION_COUPLING", f"{rotation!r} is not supported ({', '.join(triads)})")
    if str(block.get("COUPLE_RESTART_STATE", "false")).lower() not in ("false", "no", "0"):
        _fail(f"{key}.COUPLE_RESTART_STATE", f"{block['COUPLE_RESTART_STATE']!r} is not supported")
    if out["constraint"] == "mortar" and out["enforcement"] == "penalty":
        out["negative_kappa"] = "keep"     # 4C couples every multiplier node of a pair, κ_j < 0 too (fourc.md)
    return out


# ----------------------------------------------------------------------------------------------
# run and check
# ----------------------------------------------------------------------------------------------
@dataclass
class CheckRow:
    """One compared ``RESULT DESCRIPTION`` entry."""

    entry: ResultEntry
    computed: float = float("nan")
    status: str = ""            # "pass", "FAIL" or "not comparable"

    @property
    def deviation(self):
        return abs(self.computed - self.entry.value) if self.status in ("pass", "FAIL") else float("nan")


@dataclass
class CheckReport:
    """What :func:`check` found: the rows, the result and the run time (s)."""

    path: Path
    rows: list
    result: object
    seconds: float
    notes: list = field(default_factory=list)

    @property
    def passed(self):
        return all(r.status != "FAIL" for r in self.rows)

    @property
    def max_deviation(self):
        values = [r.deviation for r in self.rows if r.status in ("pass", "FAIL")]
        return max(values) if values else float("nan")

    def table(self):
        lines = [f"{'node':>6}  {'quantity':<16} {'4C value':>24} {'computed':>24} {'deviation':>10} "
                 f"{'tolerance':>9}  status"]
        for r in self.rows:
            e = r.entry
            node = "-" if e.node is None else str(e.node)
            comp = "-" if r.status == "not comparable" else f"{r.computed:24.16e}"
            dev = "-" if r.status == "not comparable" else f"{r.deviation:10.2e}"
            lines.append(f"{node:>6}  {e.quantity:<16} {e.value:24.16e} {comp:>24} {dev:>10} {e.tolerance:9.1e}  "
                         f"{r.status}")
        lines += [f"note: {n}" for n in self.notes]
        return "\n".join(lines)


def run(path, progress=False):
    """Solve a 4C input file; returns ``(result, nodes, fourc_input)`` (see :func:`scene_from_4c`)."""
    from ..model import solve
    fc = read_4c(path)
    scene, nodes = scene_from_4c(fc)
    result = solve(scene, progress=progress)
    return result, nodes, fc


def check(path, progress=False):
    """Solve a 4C input file and compare every ``RESULT DESCRIPTION`` entry with its tolerance.

    Entries of type SPECIAL (4C's own Newton and linear-solver iteration counts) are reported as
    "not comparable" and never fail.

    Returns
    -------
    CheckReport
    """
    start = time.perf_counter()
    result, nodes, fc = run(path, progress=progress)
    seconds = time.perf_counter() - start
    rows = []
    for e in fc.results:
        if e.special:
            rows.append(CheckRow(e, status="not comparable"))
            continue
        if e.quantity not in ("dispx", "dispy", "dispz"):
            rows.append(CheckRow(e, status="not comparable"))
            continue
        if e.node not in nodes:
            _fail(f"RESULT DESCRIPTION[{e.index}].NODE", f"node {e.node} is not a node of the model")
        body, row = nodes[e.node]
        field_ = result.solid_displacement if body == "solid" else result.beam_displacement
        value = float(field_[row, "xyz".index(e.quantity[-1])])
        rows.append(CheckRow(e, value, "pass" if abs(value - e.value) <= e.tolerance else "FAIL"))
    return CheckReport(Path(path), rows, result, seconds, list(fc.notes))
